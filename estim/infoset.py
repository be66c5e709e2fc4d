"""The convex-section information set of one guidance channel (SPEC 1.4, seed 003).

The information set is the set of all states ``(alpha, omega, x)`` compatible with
the measurement and control history. It is stored as a stack of x-sections: for
each of N range values ``x_j`` a convex polygon of ``(alpha, omega)``.

Coordinates. ``alpha`` (~1e-3 rad) and ``omega`` (~1e-5 rad/s early, ~1e-2 rad/s
near the target) differ by orders of magnitude and ``omega`` sweeps four decades
over an engagement. Polygons are therefore kept in the scaled coordinates
``(alpha / alpha_scale_rad, w / w_scale_m)`` with ``w = omega x^2 / e`` the
zero-effort miss: a bearing strip stays a unit-scale slab, the prediction is a
shear of determinant 1, and all polygon operations are well conditioned.

Operations (all sections at once through :class:`~estim.polygons.ConvexPolygons`):

* bearing update: clip every section with ``|alpha - alpha_m| <= bound(x_j)``;
* range update: drop sections outside ``[d_m/(1+b), d_m/(1-b)]`` (keeping the
  outermost neighbours, so a true range between two sections stays bracketed);
* control: ``omega += k/x``, i.e. ``w += k x / e``;
* prediction: ``x_j -> x_j - e Delta``, exact linear map, Minkowski sum with the
  segment of constant disturbances ``|v| <= nu`` (the seed's discrete-time
  opponent: ``v`` constant over a step), then drop sections that passed under
  ``eps`` (threshold).

An empty intersection means the measurement contradicts the model: the update
is rejected (the predicted set is kept), ``contradictions`` is incremented and the
status becomes ``"contradiction"``; the caller counts it. When every section has
passed under ``eps`` the set is empty with status ``"terminal"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from estim.base import Belief, Estimator, Extremes, StateFunction
from estim.model import Bearing, ChannelModel, Range
from estim.polygons import ConvexPolygons

FloatArray = NDArray[np.float64]

#: relative outward margin of bearing strips (outward rounding, ~1e-13 rad)
STRIP_MARGIN = 1.0e-9

#: relative margin on the lower range bound: x = d cos(angle) <= d, with off-axis
#: angles below 0.014 rad (1 - cos = 1e-4); keeps the truth's x inside the interval
RANGE_COS_MARGIN = 1.0e-4


@dataclass(frozen=True, eq=False)
class InformationSet(Belief):
    """An immutable stack of convex x-sections (see module docstring)."""

    model: ChannelModel
    x_m: FloatArray
    polygons: ConvexPolygons
    alpha_scale_rad: float
    w_scale_m: float
    status: str = "ok"
    contradictions: int = 0

    def __post_init__(self) -> None:
        x = np.array(self.x_m, dtype=float)
        if x.ndim != 1 or len(x) != self.polygons.n:
            raise ValueError("one range per section is required")
        if np.any(np.diff(x) <= 0):
            raise ValueError("section ranges must be strictly increasing")
        x.setflags(write=False)
        object.__setattr__(self, "x_m", x)

    # -- Belief interface ------------------------------------------------------------
    @property
    def is_empty(self) -> bool:
        return self.polygons.n == 0

    @property
    def n_sections(self) -> int:
        return self.polygons.n

    def vertices(self) -> FloatArray:
        """All section vertices as rows ``(alpha, omega, x)``."""
        x = self.x_m[self.polygons.owner()]
        alpha = self.polygons.xy[:, 0] * self.alpha_scale_rad
        omega = self.model.omega_from_w(self.polygons.xy[:, 1] * self.w_scale_m, x)
        return np.column_stack([alpha, omega, x])

    def centre(self) -> FloatArray:
        """Mean over sections of the vertex centroid, as ``(alpha, omega, x)``."""
        if self.is_empty:
            return np.full(3, np.nan)
        own = self.polygons.owner()
        counts = self.polygons.counts
        cen = np.stack(
            [np.bincount(own, weights=self.polygons.xy[:, k]) / counts for k in range(2)], axis=1
        )
        x = float(self.x_m.mean())
        alpha = float(cen[:, 0].mean()) * self.alpha_scale_rad
        w = float(cen[:, 1].mean()) * self.w_scale_m
        return np.array([alpha, float(self.model.omega_from_w(w, x)), x])

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the vertices of all sections.

        Exact for functions whose extremes over a convex section lie at vertices:
        linear or convex functions, and the miss forecast ``Pi``, which for fixed
        ``x`` is increasing in ``omega`` (linear on each side of ``omega = 0`` with a
        jump up there), so its max and min sit at the extreme-``omega`` vertices.
        """
        if self.is_empty:
            raise ValueError(f"extremes of an empty information set (status {self.status})")
        pts = self.vertices()
        values = np.asarray(fn(pts), dtype=float)
        i_min, i_max = int(np.argmin(values)), int(np.argmax(values))
        return Extremes(float(values[i_min]), pts[i_min], float(values[i_max]), pts[i_max])

    def contains(self, state: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``(alpha, omega, x)`` lies in the set.

        Between two sections the set is taken as the x-section of the convex hull
        of the two neighbouring sections (the Minkowski combination
        ``(1 - l) S_j + l S_j+1``); at a section's own range this is the section.
        ``tol`` is a distance in the scaled coordinates (numerical tolerance).
        """
        alpha, omega, x = (float(v) for v in np.asarray(state, dtype=float))
        if self.is_empty:
            return False
        xs = self.x_m
        span = max(float(xs[-1] - xs[0]), 1.0)
        if x < xs[0] - tol * span or x > xs[-1] + tol * span:
            return False
        j = int(np.clip(np.searchsorted(xs, x) - 1, 0, max(len(xs) - 2, 0)))
        if len(xs) == 1:
            pts = self.polygons.polygon(0)
        else:
            lam = float(np.clip((x - xs[j]) / (xs[j + 1] - xs[j]), 0.0, 1.0))
            a, b = self.polygons.polygon(j), self.polygons.polygon(j + 1)
            if lam == 0.0:
                pts = a
            elif lam == 1.0:
                pts = b
            else:
                pts = ((1 - lam) * a[:, None, :] + lam * b[None, :, :]).reshape(-1, 2)
        p = np.array(
            [alpha / self.alpha_scale_rad, self.model.zero_effort_miss_m(omega, x) / self.w_scale_m]
        )
        hull = shapely.MultiPoint(pts).convex_hull
        scale = max(1.0, float(np.abs(pts).max()))
        return bool(shapely.distance(hull, shapely.Point(p)) <= tol * scale)

    # -- summaries -------------------------------------------------------------------
    def alpha_range_rad(self) -> tuple[float, float]:
        a = self.polygons.xy[:, 0] * self.alpha_scale_rad
        return float(a.min()), float(a.max())

    def x_range_m(self) -> tuple[float, float]:
        return float(self.x_m[0]), float(self.x_m[-1])


@dataclass(frozen=True)
class InformationSetEstimator(Estimator[InformationSet]):
    """Set-membership estimator of one channel; configuration only.

    Parameters
    ----------
    model : ChannelModel
        Closing speed, disturbance bound, measurement bounds, threshold eps.
    n_sections : int
        Number of x-sections of the initial set (seed: 29).
    alpha_scale_rad, w_scale_m : float
        Coordinate scales of the stored polygons (see module docstring).
    simplify_rel_area, max_vertices : float, int
        Outer simplification after each prediction: edges whose removal adds less
        than ``simplify_rel_area`` of a section's area are removed, and sections are
        kept to ``max_vertices`` vertices (conservatively: the set only grows).
    """

    model: ChannelModel = field(default_factory=ChannelModel)
    n_sections: int = 29
    alpha_scale_rad: float = 1.0e-4
    w_scale_m: float = 1.0
    simplify_rel_area: float = 1.0e-6
    max_vertices: int = 16

    def __post_init__(self) -> None:
        if self.max_vertices < 4:
            raise ValueError("max_vertices must be >= 4")
        if self.n_sections < 1:
            raise ValueError("n_sections must be >= 1")
        if not (self.alpha_scale_rad > 0 and self.w_scale_m > 0):
            raise ValueError("scales must be positive")

    def initial(
        self,
        lateral_m: tuple[float, float],
        lateral_vel_mps: tuple[float, float],
        x_m: tuple[float, float],
    ) -> InformationSet:
        """The initial set from the boxes ``B`` (position) and ``D`` (velocity).

        For fixed ``x`` the small-angle map ``(y, Vy) -> (alpha, w) = (y/x, y + Vy x/e)``
        is linear with determinant ``1/e > 0``, so the box maps to a parallelogram
        (counter-clockwise corners map to counter-clockwise vertices).
        """
        (y0, y1), (v0, v1), (xa, xb) = lateral_m, lateral_vel_mps, x_m
        if not (y0 <= y1 and v0 <= v1 and 0 < xa <= xb):
            raise ValueError("boxes must be [lo, hi] with lo <= hi and positive range")
        xs = np.linspace(xa, xb, self.n_sections) if xb > xa else np.array([xa])
        corners = np.array([[y0, v0], [y1, v0], [y1, v1], [y0, v1]])
        y = np.tile(corners[:, 0], len(xs))
        vy = np.tile(corners[:, 1], len(xs))
        xx = np.repeat(xs, 4)
        alpha = y / xx / self.alpha_scale_rad
        w = (y + vy * xx / self.model.e) / self.w_scale_m
        offsets = np.arange(0, 4 * len(xs) + 1, 4)
        polys = ConvexPolygons(np.column_stack([alpha, w]), offsets)._dedupe()
        return InformationSet(self.model, xs, polys, self.alpha_scale_rad, self.w_scale_m)

    def from_sections(self, x_m: ArrayLike, sections: list[ArrayLike]) -> InformationSet:
        """A set from explicit ``(alpha, omega)`` CCW polygons at ranges ``x_m`` (tests)."""
        xs = np.asarray(x_m, dtype=float)
        scaled = []
        for x, sec in zip(xs, sections, strict=True):
            s = np.asarray(sec, dtype=float).reshape(-1, 2)
            w = self.model.zero_effort_miss_m(s[:, 1], x)
            scaled.append(np.column_stack([s[:, 0] / self.alpha_scale_rad, w / self.w_scale_m]))
        polys = ConvexPolygons.from_list(scaled)
        return InformationSet(self.model, xs, polys, self.alpha_scale_rad, self.w_scale_m)

    # -- Estimator interface ---------------------------------------------------------
    def update(self, belief: InformationSet, measurement: Bearing | Range) -> InformationSet:
        """Intersect with a bearing strip, or drop sections outside a range interval."""
        if belief.is_empty:
            return belief
        if isinstance(measurement, Bearing):
            # outward rounding: a relative 1e-9 (~1e-13 rad) so that floating-point
            # error never cuts off a state lying exactly on the strip's edge
            half = self.model.bearing_bound(belief.x_m) / self.alpha_scale_rad
            half = half * (1.0 + STRIP_MARGIN) + STRIP_MARGIN
            centre = measurement.alpha_rad / self.alpha_scale_rad
            clipped = belief.polygons.clip_slab(0, centre - half, centre + half)
            keep = clipped.nonempty()
            if not keep.any():
                return replace(
                    belief, status="contradiction", contradictions=belief.contradictions + 1
                )
            return replace(belief, polygons=clipped.select(keep), x_m=belief.x_m[keep])
        if isinstance(measurement, Range):
            return self._update_range(belief, measurement.range_m)
        raise TypeError(f"unsupported measurement {type(measurement).__name__}")

    def _update_range(self, belief: InformationSet, range_m: float) -> InformationSet:
        b = self.model.range_rel_bound
        lo = range_m / (1.0 + b) * (1.0 - RANGE_COS_MARGIN)
        hi = range_m / (1.0 - b)
        inside = (belief.x_m >= lo) & (belief.x_m <= hi)
        n = belief.n_sections
        if inside.any():
            # keep one neighbour on each side so that the true range stays bracketed
            idx = np.flatnonzero(inside)
            keep = np.zeros(n, dtype=bool)
            keep[max(idx[0] - 1, 0) : min(idx[-1] + 2, n)] = True
        else:
            below, above = np.flatnonzero(belief.x_m < lo), np.flatnonzero(belief.x_m > hi)
            if len(below) == 0 or len(above) == 0:
                return replace(
                    belief, status="contradiction", contradictions=belief.contradictions + 1
                )
            keep = np.zeros(n, dtype=bool)
            keep[[below[-1], above[0]]] = True  # the interval falls between two sections
        return replace(belief, polygons=belief.polygons.select(keep), x_m=belief.x_m[keep])

    def shift(self, belief: InformationSet, control: float) -> InformationSet:
        """Apply impulse ``k`` (m/s, relative velocity): ``omega += k/x``, ``w += k x/e``."""
        k = float(control)
        if k == 0.0 or belief.is_empty:
            return belief
        dw = k * belief.x_m / self.model.e / self.w_scale_m
        offset = np.column_stack([np.zeros_like(dw), dw])
        return replace(belief, polygons=belief.polygons.translate(offset))

    def predict(self, belief: InformationSet, dt_s: float) -> InformationSet:
        """Move every section from ``x`` to ``x - e dt`` (exact map + disturbance segment).

        Sections that pass under ``eps`` during the step are dropped (threshold).
        """
        if belief.is_empty:
            return belief
        x1_all = belief.x_m - self.model.e * dt_s
        keep = x1_all >= self.model.eps_m
        if not keep.all():
            belief = replace(belief, polygons=belief.polygons.select(keep), x_m=belief.x_m[keep])
            if belief.is_empty:
                return replace(belief, status="terminal")
        c = self.model.step_coefficients(belief.x_m, dt_s)
        shear = np.zeros((belief.n_sections, 2, 2))
        shear[:, 0, 0] = shear[:, 1, 1] = 1.0
        shear[:, 0, 1] = c["a_w"] * self.w_scale_m / self.alpha_scale_rad
        nu = self.model.nu_mps2
        g = np.column_stack(
            [nu * c["g_alpha"] / self.alpha_scale_rad, nu * c["g_w"] / self.w_scale_m]
        )
        polys = belief.polygons.affine(shear).minkowski_segment(g)
        # every step adds two edges; an outer simplification keeps the vertex count
        # bounded without ever losing a state (the result contains the exact sum)
        polys = polys.simplify(self.simplify_rel_area, self.max_vertices)
        return replace(belief, polygons=polys, x_m=c["x1"])
