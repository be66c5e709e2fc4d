"""The convex-section information set of one guidance channel (docs/models.md §1.4, seed 003).

The information set is the set of all states ``(alpha, omega, x)`` compatible with
the measurement and control history. It is stored as a stack of x-sections; each
section ``j`` is a convex polygon of ``(alpha, omega)`` together with the range
interval ``[x_lo_j, x_hi_j]`` it stands for. The value itself is
:class:`kalman_vs_infoset.estim.intercept.slabs.belief.InformationSet` (re-exported here); this
module holds the estimator that builds and moves it.

Two discretisations share the code:

* ``"points"`` -- the seed's: N sections at single ranges ``x_j`` (zero-width
  intervals) moving with the nominal closing speed ``e``. Exact for a state whose
  range is one of the ``x_j`` and whose closing speed is ``e``; a true range
  between sections, or a true closing speed other than ``e`` (folded by the seed
  into ``nu``), is not covered, and near the target the seed's ``nu`` does not
  cover it either.
* ``"slabs"`` (default) -- the same N sections, each standing for a whole range
  interval: together they partition the a-priori range box, and every operation
  is taken over the interval (and over the closing-speed interval
  ``[e_lo, e_hi]``), so the union of the sections contains every state compatible
  with the data. This is what makes the guarantee hold for the full nonlinear
  truth (tested, and counted in every experiment).

Coordinates. ``alpha`` (~1e-3 rad) and ``omega`` (~1e-5 rad/s early, ~1e-2 rad/s
near the target) differ by orders of magnitude and ``omega`` sweeps four decades
over an engagement. Polygons are kept in the scaled coordinates
``(alpha / alpha_scale_rad, w / w_scale_m)`` with ``w = omega x^2 / e`` the
zero-effort miss (nominal ``e``): a bearing strip is a unit-scale slab and the
prediction is a shear of determinant 1. ``d(omega x^2)/dt = v x`` holds for any
closing speed, so ``w`` evolves independently of the true closing speed; only the
range does not.

Operations on all sections at once
(:class:`kalman_vs_infoset.estim.intercept.slabs.sections.SectionBatch`: convex polygons,
:class:`~estim.common.polygons.ConvexPolygons`, by default; the slab set may hold an ellipsoid, a
zonotope or a box per section instead, :mod:`kalman_vs_infoset.estim.intercept.sections`, with every
operation below an outer bound of the same exact one):

* bearing update: clip with ``|alpha - alpha_m| <= bound(x_lo_j)`` (the widest
  strip over the interval, since the bound shrinks with range);
* range update: intersect the intervals with ``[d_m/(1+b), d_m/(1-b)]``, drop
  sections left empty;
* control ``k``: ``w += k x / e`` for ``x`` in the interval: a shift by the
  interval's middle and a Minkowski sum with a vertical segment;
* prediction: ``x_lo -= e_hi Delta``, ``x_hi -= e_lo Delta``, the shear
  ``alpha += c w`` with ``c = e Delta / (x0 x1)`` taken at the interval's middle
  plus a horizontal segment covering the other ``c`` of the interval, and the
  disturbance ``|v| <= nu`` (the seed's discrete-time opponent, constant over a
  step) as a box; sections entirely under ``eps`` are dropped (threshold).

What ``nu`` must cover, and what the slabs add to it. For the truth,
``alpha = atan2(y, x)`` and the planar angular momentum
``rho^2 omega = x Vy - y Vx`` (``rho^2 = x^2 + y^2 = x^2 / cos^2 alpha``; exact,
whatever the other channel does) give

    d(omega x^2)/dt = x cos(alpha) a_perp - 2 omega^2 x^2 tan(alpha),

``a_perp`` the relative acceleration across the line of sight (differential
gravity, ~1e-7 m/s^2 here). The auxiliary model has ``d(omega x^2)/dt = v x``, so
the truth is one of its motions with ``v = cos(alpha) a_perp - 2 omega^2 x tan(alpha)``:
the second term is the kinematic term the linear model neglects. It is negligible
far out, but grows like ``w^2 e^2 / x^3`` near the target and where the line of
sight swings (a 9 km offset at 800 km with saturated guidance took the truth out of
a set built with ``nu`` alone). The slab set therefore adds to ``nu``, per section
and step, a bound of that term over the section and the step, written through the
planar angular momentum ``h``
(:func:`~kalman_vs_infoset.estim.intercept.kinematic.kinematic_margin_mps2`), and widens an impulse
by the same geometry: an
impulse ``k`` changes ``omega`` by ``k cos^2(alpha) / x``, not ``k / x``. The seed's
point sections keep the seed's ``nu``.

An empty intersection means the measurement contradicts the model: the update is
rejected (the predicted set is kept), ``contradictions`` is incremented and the
status becomes ``Status.CONTRADICTION``; the caller counts it. When every section has
passed under ``eps`` the set is empty with status ``Status.TERMINAL``. When a slab
set's zero-effort-miss bound exceeds ``DIVERGED_W_PER_X`` times its range (the
kinematic margin of wide slabs near ``eps`` feeding on itself: the set knows nothing
any more) the set is emptied with status ``Status.DIVERGED``; the caller counts it.

A control (an impulse, :class:`~kalman_vs_infoset.estim.intercept.model.Impulse` or m/s) enters
:meth:`InformationSetEstimator.predict`: it acts at the start of the predicted step.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.base import Estimator, Status
from kalman_vs_infoset.estim.common import _kernels as _k
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.intercept.kinematic import (
    DIVERGED_W_PER_X,
    MAX_BEARING_RAD,
    STRIP_MARGIN,
    kinematic_margin,
    range_x_interval,
)
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    Impulse,
    Range,
    check_step,
    impulse_parts,
)
from kalman_vs_infoset.estim.intercept.slabs.belief import InformationSet
from kalman_vs_infoset.estim.intercept.slabs.options import DEFAULTS
from kalman_vs_infoset.estim.intercept.slabs.sections import PolygonFamily, SectionFamily
from numpy.typing import NDArray

__all__ = ["InformationSet", "InformationSetEstimator"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class InformationSetEstimator(Estimator[InformationSet, ChannelPrior]):
    """Set-membership estimator of one channel; configuration only.

    Parameters
    ----------
    model : ChannelModel
        Nominal closing speed, disturbance bound, measurement bounds, threshold.
    n_sections : int
        Number of sections of the initial set (seed: 29).
    sections : {"slabs", "points"}
        Discretisation (module docstring): ``"slabs"`` is guaranteed, ``"points"``
        is the seed's.
    closing_speed_mps : (float, float) or None
        Interval of the true closing speed; ``None`` means the nominal ``e`` exactly
        (the seed's model). Used by ``"slabs"`` only.
    alpha_scale_rad, w_scale_m : float
        Coordinate scales of the stored polygons.
    simplify_rel_area, max_vertices : float, int
        Outer simplification after each prediction: edges whose removal adds less
        than ``simplify_rel_area`` of a section's area are removed, and sections are
        kept to ``max_vertices`` vertices (conservatively: the set only grows).
    kinematic_margin : bool
        The set of the two-body motion: add the bound of the neglected kinematic term
        to ``nu`` (module docstring; ``"slabs"`` only), widen a wide prior box by
        the exact bearing and rate of its Cartesian states (:meth:`initial`), and
        spread an impulse by its geometry (``k cos^2(alpha)``: :meth:`_impulse`). Off
        reproduces the set of the auxiliary model, with the model's ``nu`` alone,
        which holds a two-body truth only while that term stays under ``nu``.
    split_ratio, max_sections : float, int
        ``"slabs"`` only: before each prediction a slab with ``x_hi / x_lo`` above
        ``split_ratio`` is split into copies over geometric sub-intervals of at most
        that ratio (the union is unchanged, so nothing is lost), while the set has
        at most ``max_sections`` sections. Thin slabs keep the link between range
        and zero-effort miss that a wide slab loses near the target (module
        docstring); ``split_ratio = inf`` turns splitting off.
    family : SectionFamily or None
        The set held per section (:mod:`kalman_vs_infoset.estim.intercept.slabs.sections`): None for
        convex polygons (simplified with ``simplify_rel_area`` and ``max_vertices``), or an
        ellipsoid, zonotope or box family (:mod:`kalman_vs_infoset.estim.intercept.sections`;
        ``"slabs"`` only). The initial polygons are converted by the family (an outer bound); every
        later operation is the family's.
    """

    model: ChannelModel = field(default_factory=ChannelModel)
    n_sections: int = DEFAULTS.n_sections
    sections: str = "slabs"
    closing_speed_mps: tuple[float, float] | None = None
    alpha_scale_rad: float = 1.0e-4
    w_scale_m: float = 1.0
    simplify_rel_area: float = 1.0e-6
    max_vertices: int = 16
    kinematic_margin: bool = DEFAULTS.kinematic_margin
    split_ratio: float = DEFAULTS.split_ratio
    max_sections: int = DEFAULTS.max_sections
    family: SectionFamily | None = None

    def __post_init__(self) -> None:
        if self.n_sections < 1:
            raise ValueError("n_sections must be >= 1")
        if self.sections not in ("slabs", "points"):
            raise ValueError("sections must be 'slabs' or 'points'")
        if self.closing_speed_mps is not None:
            lo, hi = self.closing_speed_mps
            if not 0 < lo <= hi:
                raise ValueError("closing_speed_mps must be an interval 0 < lo <= hi")
        if not (self.alpha_scale_rad > 0 and self.w_scale_m > 0):
            raise ValueError("scales must be positive")
        if self.max_vertices < 4:
            raise ValueError("max_vertices must be >= 4")
        if not self.split_ratio > 1.0:
            raise ValueError("split_ratio must be > 1 (inf: no splitting)")
        if self.max_sections < self.n_sections:
            raise ValueError("max_sections must be >= n_sections")
        if self.family is not None and self.sections != "slabs":
            raise ValueError("other set families than polygons need sections='slabs'")

    @property
    def section_family(self) -> SectionFamily:
        """The family of the sections (:class:`estim.intercept.slabs.sections.PolygonFamily` by
        default)."""
        if self.family is None:
            return PolygonFamily(self.simplify_rel_area, self.max_vertices)
        return self.family

    @cached_property
    def _drift(self) -> ChannelModel:
        """The model whose drifts off a constant closing speed the sets take
        (:attr:`ChannelModel.range_drift_m`): none for the seed's point sections, which
        assume ``c = e``."""
        if self.sections != "points":
            return self.model
        return replace(self.model, closing_drift_mps=0.0, range_drift_m=0.0)

    @property
    def speed_interval(self) -> tuple[float, float]:
        if self.sections == "points":
            return self.model.e, self.model.e
        # every closing speed the truth reaches (the interval, widened by its drift)
        return self._drift.drifted_speeds(self.closing_speed_mps)

    # -- construction ----------------------------------------------------------------
    def initial(self, prior: ChannelPrior | None = None, **box: Any) -> InformationSet:
        """The initial set of the a-priori box (:meth:`from_boxes`; the prior's closing
        speed is not used: the set's propagation takes ``closing_speed_mps``).

        ``initial(lateral_m=..., lateral_vel_mps=..., x_m=...)`` is short for
        ``initial(ChannelPrior(...))``. With ``kinematic_margin`` (the set of the
        two-body motion) the box is first widened where the exact bearing and
        line-of-sight rate of a Cartesian state leave it
        (:meth:`ChannelPrior.auxiliary_box`: only for boxes wide against their range);
        a set of the auxiliary model takes the box as it is.
        """
        prior = ChannelPrior(**box) if prior is None else prior
        if self.kinematic_margin:
            # the box of the coordinates the sections take, holding every Cartesian state
            prior = prior.auxiliary_box(self.speed_interval[1])
        prior = prior.drifted(self._drift)
        return self.from_boxes(prior.lateral_m, prior.lateral_vel_mps, prior.x_m)

    def from_boxes(
        self,
        lateral_m: tuple[float, float],
        lateral_vel_mps: tuple[float, float],
        x_m: tuple[float, float],
    ) -> InformationSet:
        """The initial set from the boxes ``B`` (position) and ``D`` (velocity).

        With the true closing speed ``c`` the zero-effort miss of ``(y, Vy, x)`` is
        ``w = omega x^2 / e = (c y + Vy x) / e`` (``omega x^2 = Vy x + c y``, ``e`` the
        nominal speed). At fixed ``x`` and ``c`` the small-angle map ``(y, Vy) ->
        (alpha, w) = (y/x, (c y + Vy x)/e)`` is linear with determinant ``1/e > 0``;
        over ``c`` in the speed interval the image is the convex hull of the eight
        corners ``(y, Vy, c)`` (``w`` is bilinear in ``(y, c)``; taken at ``c = e``
        alone it misses the box's corners). A slab takes the hull at its
        middle range plus a box covering the change over the interval:
        ``|y| |1/x - 1/x_mid|`` in ``alpha`` and ``|Vy| |x - x_mid| / e`` in ``w``.
        """
        (y0, y1), (v0, v1), (xa, xb) = lateral_m, lateral_vel_mps, x_m
        if not (y0 <= y1 and v0 <= v1 and 0 < xa <= xb):
            raise ValueError("boxes must be [lo, hi] with lo <= hi and positive range")
        n = self.n_sections
        if self.sections == "points" or xb == xa:
            x_lo = x_hi = np.linspace(xa, xb, n) if xb > xa else np.array([xa])
        else:
            edges = np.linspace(xa, xb, n + 1)
            x_lo, x_hi = edges[:-1], edges[1:]
        xm = 0.5 * (x_lo + x_hi)
        c_lo, c_hi = self.speed_interval
        corners = np.array(np.meshgrid([y0, y1], [v0, v1], [c_lo, c_hi])).reshape(3, -1)
        y, vy, c = (np.tile(row, len(xm)) for row in corners)
        xx = np.repeat(xm, 8)
        xy = np.column_stack(
            [y / xx / self.alpha_scale_rad, (c * y + vy * xx) / self.model.e / self.w_scale_m]
        )
        polys = ConvexPolygons._make(*_k.convex_hulls(xy, np.arange(0, 8 * len(xm) + 1, 8)))
        if np.any(x_hi > x_lo):
            y_abs, v_abs = max(abs(y0), abs(y1)), max(abs(v0), abs(v1))
            d_inv = np.maximum(1 / x_lo - 1 / xm, 1 / xm - 1 / x_hi)
            spread_a = y_abs * d_inv / self.alpha_scale_rad * (1 + 1e-9)
            spread_w = v_abs * (x_hi - x_lo) / 2 / self.model.e / self.w_scale_m * (1 + 1e-9)
            zeros = np.zeros_like(xm)
            polys = polys.minkowski_segment(np.column_stack([spread_a, zeros]))
            polys = polys.minkowski_segment(np.column_stack([zeros, spread_w]))
        return InformationSet(
            self.model, x_lo, x_hi, self.section_family.from_polygons(polys),
            self.alpha_scale_rad, self.w_scale_m,
        )  # fmt: skip

    # -- Estimator interface ---------------------------------------------------------
    def update(self, belief: InformationSet, measurement: Bearing | Range) -> InformationSet:
        """Intersect with a bearing strip, or with a range interval."""
        if belief.is_empty:
            return belief
        if isinstance(measurement, Bearing):
            # widest strip over the interval (the bound shrinks with range); outward
            # rounding so floating-point error never cuts off a state on the edge
            half = self.model.bearing_bound(belief.x_lo_m) / self.alpha_scale_rad
            half = half * (1.0 + STRIP_MARGIN) + STRIP_MARGIN
            centre = measurement.alpha_rad / self.alpha_scale_rad
            clipped, keep = belief.sections.clip_alpha(centre - half, centre + half)
            if keep.all():
                return InformationSet._new(belief, belief.x_lo_m, belief.x_hi_m, clipped)
            if not keep.any():
                return self._contradiction(belief)
            return self._select(belief, keep, sections=clipped)
        if isinstance(measurement, Range):
            return self._update_range(belief, measurement)
        raise TypeError(f"unsupported measurement {type(measurement).__name__}")

    def _update_range(self, belief: InformationSet, measurement: Range) -> InformationSet:
        lo, hi = range_x_interval(self._drift, measurement)
        if self.sections == "points":
            inside = (belief.x_lo_m >= lo) & (belief.x_hi_m <= hi)
            if not inside.any():
                return self._contradiction(belief)
            # keep one neighbour each side so that a true range between two
            # sections stays bracketed for the interpolating containment test
            idx = np.flatnonzero(inside)
            keep = np.zeros(belief.n_sections, dtype=bool)
            keep[max(idx[0] - 1, 0) : idx[-1] + 2] = True
            return self._select(belief, keep)
        x_lo, x_hi = np.maximum(belief.x_lo_m, lo), np.minimum(belief.x_hi_m, hi)
        keep = x_lo <= x_hi
        if not keep.any():
            return self._contradiction(belief)
        return replace(self._select(belief, keep), x_lo_m=x_lo[keep], x_hi_m=x_hi[keep])

    def _impulse(self, belief: InformationSet, control: float | Impulse) -> InformationSet:
        """Apply impulse ``k`` (m/s, relative velocity): ``omega += k/x``, ``w += k x/e``
        (with ``kinematic_margin``, the two-body motion's ``omega += k cos^2(alpha)/x``).

        ``control`` may be an :class:`~estim.intercept.model.Impulse` whose magnitude is only
        known to ``+-dk``: the set is then widened by ``dk x/e`` in ``w``.
        """
        k, dk = impulse_parts(control)
        if (k == 0.0 and dk == 0.0) or belief.is_empty:
            return belief
        scale = k / self.model.e / self.w_scale_m
        half = abs(scale) * 0.5 * (belief.x_hi_m - belief.x_lo_m)
        half = half + dk * belief.x_hi_m / self.model.e / self.w_scale_m
        if self.sections != "points" and self.kinematic_margin:
            # the two-body motion's change is omega += k cos^2(alpha)/x: widen by
            # k sin^2(alpha) x/e (the auxiliary model alone has omega += k/x exactly)
            a_abs, _ = belief.sections.abs_max()
            sin2 = np.sin(np.minimum(a_abs * self.alpha_scale_rad, 0.5 * np.pi)) ** 2
            half = half + (abs(k) + dk) * sin2 * belief.x_hi_m / self.model.e / self.w_scale_m
        sections = belief.sections.shift_band(scale * belief.x_mid_m, half)
        return InformationSet._new(belief, belief.x_lo_m, belief.x_hi_m, sections)

    def predict(
        self, belief: InformationSet, dt_s: float, control: float | Impulse | None = None
    ) -> InformationSet:
        """Apply the impulse ``control`` (at the step's start; :meth:`_impulse`), then move
        every section over ``dt_s``: exact shear at the interval's middle, a segment for
        the rest of the interval, the disturbance box; threshold at eps."""
        check_step(dt_s)
        if control is not None:
            belief = self._impulse(belief, control)
        if belief.is_empty:
            return belief
        if self.sections != "points":
            belief = self._split(belief)
        e_lo, e_hi = self.speed_interval
        eps = self._drift.eps_sets_m
        x_lo1, x_hi1 = belief.x_lo_m - e_hi * dt_s, belief.x_hi_m - e_lo * dt_s
        keep = x_hi1 >= eps
        if not keep.all():
            belief = self._select(belief, keep)
            x_lo1, x_hi1 = x_lo1[keep], x_hi1[keep]
            if belief.is_empty:
                return replace(belief, status=Status.TERMINAL)
        x_lo1 = np.maximum(x_lo1, eps)  # states that pass under eps leave the set
        # shear coefficient c = e dt / (x0 x1) over the interval's states
        x0_lo = np.maximum(belief.x_lo_m, eps + e_lo * dt_s)
        c_hi = self.model.e * dt_s / (x0_lo * x_lo1)
        c_lo = self.model.e * dt_s / (belief.x_hi_m * x_hi1)
        ratio = self.w_scale_m / self.alpha_scale_rad
        nu = self.model.nu_mps2
        sections = belief.sections
        points = self.sections == "points"
        if not points:
            a_abs, w_abs = sections.abs_max()
        if not points and self.kinematic_margin:
            # the kinematic term the linear model neglects (module docstring)
            nu = nu + kinematic_margin(
                w_abs * self.w_scale_m, a_abs * self.alpha_scale_rad, x_lo1,
                belief.x_hi_m, dt_s, self.model.e, nu, MAX_BEARING_RAD,
            )  # fmt: skip
        g_alpha = nu * dt_s**2 / (2.0 * x_lo1) / self.alpha_scale_rad
        g_w = nu * dt_s * (belief.x_hi_m + x_hi1) / (2.0 * self.model.e) / self.w_scale_m
        if not points and not np.all(
            (w_abs + g_w) * self.w_scale_m <= DIVERGED_W_PER_X * belief.x_hi_m
        ):
            # a zero-effort miss of a thousand ranges (or an overflow): the set says
            # nothing any more and would overflow in a few steps (wide slabs near
            # eps, whose nearest states swing at rad/s); reported, not propagated
            return replace(
                self._select(belief, np.zeros(belief.n_sections, bool)), status=Status.DIVERGED
            )
        if not points:
            # the other shears of the interval, as a horizontal segment
            g_alpha = g_alpha + 0.5 * (c_hi - c_lo) * ratio * w_abs
        # shear at the middle; then the disturbance (the seed's exact segment of
        # constant disturbances for points, a box for slabs); the representation's
        # own outer bound (polygons: a simplification bounding the vertex count)
        moved = sections.shear_add(0.5 * (c_lo + c_hi) * ratio, g_alpha, g_w, segment=points)
        return InformationSet._new(belief, x_lo1, x_hi1, moved)

    # -- internals -------------------------------------------------------------------
    def _split(self, belief: InformationSet) -> InformationSet:
        """Split wide slabs into geometric pieces (``split_ratio``, ``max_sections``)."""
        lo_all = np.maximum(belief.x_lo_m, self._drift.eps_sets_m)  # no zero range
        ratio = belief.x_hi_m / lo_all
        wide = ratio > self.split_ratio
        if not wide.any() or belief.n_sections >= self.max_sections:
            return belief
        pieces = np.ones(belief.n_sections, dtype=np.int64)
        pieces[wide] = np.ceil(np.log(ratio[wide]) / np.log(self.split_ratio)).astype(np.int64)
        room = self.max_sections - belief.n_sections
        extra = pieces - 1
        if extra.sum() > room:
            # not enough room: split the sections nearest the target first
            order = np.argsort(belief.x_lo_m)
            take = np.minimum(
                extra[order], np.maximum(room - np.cumsum(extra[order]) + extra[order], 0)
            )
            extra[order] = take
            pieces = extra + 1
        idx = np.repeat(np.arange(belief.n_sections), pieces)
        # piece j of k covers x_lo (x_hi/x_lo)^(j/k) .. x_lo (x_hi/x_lo)^((j+1)/k)
        j = np.arange(idx.size) - np.repeat(np.cumsum(pieces) - pieces, pieces)
        k = pieces[idx]
        lo, r = lo_all[idx], ratio[idx]
        x_lo = np.where(j == 0, belief.x_lo_m[idx], lo * r ** (j / k))
        x_hi = np.where(j == k - 1, belief.x_hi_m[idx], lo * r ** ((j + 1) / k))
        return InformationSet._new(belief, x_lo, x_hi, belief.sections.select(idx))

    @staticmethod
    def _select(belief: InformationSet, keep, sections=None) -> InformationSet:
        chosen = (belief.sections if sections is None else sections).select(keep)
        return InformationSet._new(belief, belief.x_lo_m[keep], belief.x_hi_m[keep], chosen)

    @staticmethod
    def _contradiction(belief: InformationSet) -> InformationSet:
        return replace(
            belief, status=Status.CONTRADICTION, contradictions=belief.contradictions + 1
        )
