"""The node set as a value: exact slices of the information set and what lies between.

The estimator (:mod:`.estimator`) explains the model; this module holds the
immutable belief and answers the questions guidance and the harness ask of it. Per
closing-speed piece ``b`` (``u = 1/e`` in ``[u_lo, u_hi]``) the information set is a
convex body in ``(Y~, V~, tau)``; the belief stores its slices at the nodes'
times to go ``tau_j`` as polygons in ``(a, zs)`` (:mod:`.bounds`), and
bounds the body between nodes through the concavity of support functions.

Quantities in the package's coordinates, for a state of piece ``b`` at ``tau``::

    alpha = Y~ / tau            (bearing, rad)
    x     = e tau               (range along the axis, m), e = 1/u in the piece
    w     = (e / e_nom)^2 zs    (zero-effort miss omega x^2 / e_nom, m)
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from functools import cached_property
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.base import Belief, Extremes, StateFunction, Status
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.intercept.costs import MissForecast, ZeroEffortMiss
from kalman_vs_infoset.estim.intercept.model import ChannelModel, channel_state
from kalman_vs_infoset.estim.intercept.nodeset import _attained, _contains
from kalman_vs_infoset.estim.intercept.nodeset import _geometry as _ng
from kalman_vs_infoset.estim.intercept.nodeset import bounds as nb
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.arrays import readonly

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


#: the node set's array fields and their types (read-only; :func:`evolve` checks only
#: the changed ones)
_ARRAY_FIELDS = {"u_lo": float, "u_hi": float, "label_s": float, "hard_lo_s": float,
                 "hard_hi_s": float, "piece": np.int64}  # fmt: skip


def _check_nodes(piece, label_s, polygons: ConvexPolygons) -> None:
    if len(piece) != polygons.n or len(label_s) != polygons.n:
        raise ValueError("one piece index and one label per node polygon")


@dataclass(frozen=True, eq=False)
class NodeSet(Belief):
    """An immutable node set (see the module docstring).

    Attributes
    ----------
    model : ChannelModel
        Nominal closing speed ``e_nom``, bounds, threshold.
    u_lo, u_hi : arrays (bands,)
        Each piece's interval of ``u = 1/e`` (s/m).
    piece : int array (n,)
        Band of each node; nodes are sorted by piece, then by ``label_s``.
    label_s : array (n,)
        Each node's time to go at ``t = 0`` (s); now ``tau = label_s - t_s``.
    polygons : ConvexPolygons
        The exact slice of each node in ``(a, zs)``; empty = infeasible node.
    hard_lo_s, hard_hi_s : arrays (bands,)
        Labels outside which no state can lie (prior box, range measurements,
        threshold): the bounds never reach beyond them.
    t_s : float
        Time since the initial set (s).
    log : OpLog
        The operations applied since the initial set (replayed on new nodes).
    prior : tuple
        ``(y box, Vy box, x box)`` of the initial set, SI units.
    alpha_scale_rad : float
        ``a = alpha / alpha_scale_rad``.
    status : Status
        ``OK``, ``CONTRADICTION`` (the last measurement contradicted the model and
        was rejected), ``TERMINAL`` (every state passed under eps) or ``DIVERGED``.
    contradictions : int
        Number of rejected measurements so far.
    n_simplified : int
        Number of node slices outer-simplified so far (a prediction left them with
        more than the estimator's ``max_vertices``, when it has one).
    impulse_moment_m : float
        A band of relative width ``rel`` applies each impulse for every ``u`` of the
        band, which can widen ``w`` by about ``rel`` times this (m): each impulse
        ``k`` adds ``|k| tau``, ``tau`` the set's largest time to go (:mod:`.bands`).
    band_trial_after_s : float
        No split of a band for the impulses' spread is tried before this time (s, as
        ``t_s``): a trial that did not pay waits (:mod:`.bands`).
    live_band_target : int
        Live closing-speed bands the set keeps splitting towards, when more than the
        estimator started with (a paid trial of ``band_trials="extreme_bands"``
        doubles it; 0: the estimator's start).
    extreme_trial_after_s : float
        No trial at the set's extremes (``band_trials="extreme_bands"``) before this
        time (s): a clock of its own, so that these trials never delay the impulses'.
    extreme_trial_width_m : float
        The set's width of the miss (m) at the last trial at its extremes that did not
        pay: ``band_trials="auto"`` tries again before ``extreme_trial_after_s`` only
        when a range has narrowed the set below ``NARROWED`` of it (:mod:`.bands`).
    """

    model: ChannelModel
    u_lo: FloatArray
    u_hi: FloatArray
    piece: IntArray
    label_s: FloatArray
    polygons: ConvexPolygons
    hard_lo_s: FloatArray
    hard_hi_s: FloatArray
    t_s: float
    log: nb.OpLog
    prior: tuple
    alpha_scale_rad: float = 1.0e-4
    status: Status = Status.OK
    contradictions: int = 0
    n_simplified: int = 0
    impulse_moment_m: float = 0.0
    band_trial_after_s: float = -np.inf
    live_band_target: int = 0
    extreme_trial_after_s: float = -np.inf
    extreme_trial_width_m: float = np.inf

    def __post_init__(self) -> None:
        for name, kind in _ARRAY_FIELDS.items():
            object.__setattr__(self, name, readonly(getattr(self, name), kind, copy=None))
        _check_nodes(self.piece, self.label_s, self.polygons)

    # -- basic views -----------------------------------------------------------------
    @property
    def e_nom(self) -> float:
        return self.model.e

    @property
    def tau_s(self) -> FloatArray:
        return self.label_s - self.t_s

    @cached_property
    def live(self) -> NDArray[np.bool_]:
        return self.polygons.counts > 0

    @cached_property
    def is_empty(self) -> bool:  # asked several times a step by the loop and guidance
        return not bool(self.live.any())

    @property
    def n_sections(self) -> int:
        """Number of live nodes (exact slices)."""
        return int(self.live.sum())

    @property
    def n_vertices(self) -> int:
        return int(self.polygons.counts.sum())

    def trace_fields(self) -> dict[str, float]:
        """The set's size (:meth:`ConvexPolygons.size_fields`), with the slices
        outer-simplified so far past the vertex cap."""
        return self.polygons.size_fields(self.alpha_scale_rad, self.n_sections, self.n_simplified)

    # -- bounds between nodes --------------------------------------------------------
    @cached_property
    def _summary(self) -> dict[str, Any]:
        """Cells and their bounds (compiled: :func:`._geometry.summarise`)."""
        names = ("table", "tau4", "span", "piece", "zs", "w", "alpha", "per_piece")
        out = _ng.summarise(
            self.polygons.xy, self.polygons.offsets, self.label_s,
            np.ascontiguousarray(self.piece), float(self.t_s), self.u_lo, self.u_hi,
            self.hard_lo_s, self.hard_hi_s, self.alpha_scale_rad, self.e_nom, nb.BOUND_RTOL,
        )  # fmt: skip
        return dict(zip(names, out, strict=True))

    def w_bounds_m(self) -> tuple[float, float]:
        """The interval of the zero-effort miss ``w`` over the whole set (m)."""
        w = self._summary["w"]
        return float(w[:, 0].min()), float(w[:, 1].max())

    def alpha_range_rad(self) -> tuple[float, float]:
        a = self._summary["alpha"]
        return float(a[:, 0].min()), float(a[:, 1].max())

    def x_range_m(self) -> tuple[float, float]:
        s = self._summary
        return float((s["span"][:, 0] / self.u_hi[s["piece"]]).min()), float(
            (s["span"][:, 1] / self.u_lo[s["piece"]]).max()
        )

    # -- Belief interface ------------------------------------------------------------
    def centre(self) -> FloatArray:
        """The mean of the live nodes' vertex centroids, as ``(alpha, omega, x)``."""
        if self.is_empty:
            return np.full(3, np.nan)
        own = self.polygons.owner()
        cnt = np.maximum(self.polygons.counts, 1)
        cen = [np.bincount(own, weights=self.polygons.xy[:, k], minlength=len(cnt)) / cnt
               for k in range(2)]  # fmt: skip
        live = self.live
        e_mid = 2.0 / (self.u_lo + self.u_hi)[self.piece[live]]
        x = float(np.mean(self.tau_s[live] * e_mid))
        alpha = float(cen[0][live].mean()) * self.alpha_scale_rad
        w = float(cen[1][live].mean())
        return np.array([alpha, float(self.model.omega_from_w(w, x)), x])

    def extremes(self, fn: StateFunction) -> Extremes:
        """Sound min and max of ``fn`` over the whole set (nodes and cells between).

        Only :class:`~estim.intercept.costs.MissForecast` and
        :class:`~estim.intercept.costs.ZeroEffortMiss` (recognised by type) are bounded: the rows
        returned are representative states at the range where each bound is attained (``x = e_nom
        tau``, the cell's middle bearing). Between its nodes the set is known through bounds only,
        so any other function is refused (``TypeError``): its values at the node vertices would be
        inner values, not extremes. The coordinates have their own sound intervals
        (:meth:`alpha_range_rad`, :meth:`omega_range_radps`, :meth:`x_range_m`);
        :meth:`attained` gives the values of any function at the set's own points.
        """
        if self.is_empty:
            raise ValueError(f"extremes of an empty node set (status {self.status})")
        if isinstance(fn, MissForecast | ZeroEffortMiss):
            return self._forecast_extremes(isinstance(fn, MissForecast))
        raise TypeError(
            f"a node set bounds only MissForecast and ZeroEffortMiss over its whole body, "
            f"not {fn!r}; use attained(fn) for values at its own points, or "
            "alpha_range_rad / omega_range_radps / x_range_m for the coordinates"
        )

    def attained(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the exact slices' vertices, each at its state.

        The witnesses are vertices of the live node polygons (the exact slices, within
        the piece's hard limits) at both ends and the middle of the piece's closing
        speed (``x = tau / u``): states of the set. The forecast and zero-effort misses
        are monotone in ``u`` at a vertex (``Pi = (zs + sign(zs) nu tau^2 / 2) / (u
        e_nom)^2``), so for them the ends give the largest value a vertex takes. Between
        nodes the body may reach further than its vertices: the values are inner, never
        wider than :meth:`extremes` (which bounds them), and within the tightening
        tolerance of it after an update (``tighten_rtol`` of the estimator).
        """
        if self.is_empty:
            raise ValueError(f"attained values of an empty node set (status {self.status})")
        if type(fn) is MissForecast and fn.model == self.model:
            return self._forecast_attained()
        own = self.polygons.owner()
        piece, lab = self.piece[own], self.label_s[own]
        tol = 1e-9 * np.abs(lab)
        keep = (lab >= self.hard_lo_s[piece] - tol) & (lab <= self.hard_hi_s[piece] + tol)
        if not keep.any():
            raise ValueError("the node set has live nodes but none within its hard limits")
        xy, piece, tau = self.polygons.xy[keep], piece[keep], self.tau_s[own[keep]]
        pts = np.vstack([self._rows(xy, tau, u[piece]) for u in self._speeds()])
        vals = np.asarray(fn(pts), dtype=float)
        i_lo, i_hi = int(np.argmin(vals)), int(np.argmax(vals))
        return Extremes(float(vals[i_lo]), pts[i_lo], float(vals[i_hi]), pts[i_hi])

    def _forecast_attained(self) -> Extremes:
        """:meth:`attained` of the forecast miss, compiled (the game adversary's
        question every step): the same rows and values as the general path."""
        found, v_lo, row_lo, v_hi, row_hi = _attained.forecast_attained(
            self.polygons.xy, self.polygons.offsets, self.piece, self.label_s,
            float(self.t_s), self.hard_lo_s, self.hard_hi_s, self.u_lo, self.u_hi,
            float(self.e_nom), float(self.model.nu_mps2), float(self.alpha_scale_rad),
        )  # fmt: skip
        if not found:
            raise ValueError("the node set has live nodes but none within its hard limits")
        return Extremes(float(v_lo), row_lo, float(v_hi), row_hi)

    def _speeds(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``u`` per piece at the fast end, the middle and the slow end."""
        return self.u_lo, 0.5 * (self.u_lo + self.u_hi), self.u_hi

    def _rows(self, xy: FloatArray, tau: FloatArray, u: FloatArray) -> FloatArray:
        """Points ``(a, zs)`` of slices at ``tau`` as rows ``(alpha, omega, x)`` at
        ``u = 1/e`` (one per point): ``x = tau / u``, ``w = (e / e_nom)^2 zs``."""
        x = tau / u
        w = xy[:, 1] / (u * self.e_nom) ** 2
        alpha = xy[:, 0] * self.alpha_scale_rad
        return np.column_stack([alpha, self.model.omega_from_w(w, x), x])

    def omega_range_radps(self) -> tuple[float, float]:
        """A sound interval of the line-of-sight rate over the whole set (rad/s):
        ``omega = w e_nom / x^2`` with each cell's bounds of ``w`` and of ``x`` (an
        outer bound: the two are bounded apart)."""
        s = self._summary
        if len(s["w"]) == 0:
            raise ValueError("the node set has live nodes but no cell within its hard limits")
        x_lo = s["span"][:, 0] / self.u_hi[s["piece"]]
        x_hi = s["span"][:, 1] / self.u_lo[s["piece"]]
        w_lo, w_hi = s["w"][:, 0], s["w"][:, 1]
        with np.errstate(divide="ignore"):
            hi = np.where(w_hi > 0, w_hi / x_lo**2, w_hi / x_hi**2) * self.e_nom
            lo = np.where(w_lo < 0, w_lo / x_lo**2, w_lo / x_hi**2) * self.e_nom
        return float(lo.min()), float(hi.max())

    def _forecast_extremes(self, forecast: bool) -> Extremes:
        s = self._summary
        zs, w_lo, w_hi = s["zs"], s["w"][:, 0], s["w"][:, 1]
        if len(w_lo) == 0:
            raise ValueError("the node set has live nodes but no cell within its hard limits")
        # Pi = w + sign(w) nu (x/e_nom)^2/2, x in [tau_lo/u_hi, tau_hi/u_lo] (compiled)
        half_nu = 0.5 * self.model.nu_mps2 / self.e_nom**2
        i_lo, v_lo, i_hi, v_hi = _ng.forecast_extremes(
            s["span"], s["w"], s["piece"], self.u_lo, self.u_hi, half_nu, forecast
        )
        alpha = s["alpha"]

        def row(i: int, tau: float, w: float) -> FloatArray:
            x = self.e_nom * tau
            lo, hi = alpha[i, 0], alpha[i, 1]
            # a cell unbounded in bearing both ways has no middle: nan (without the
            # warning of inf - inf)
            a = np.nan if np.isinf(lo) and np.isinf(hi) and lo != hi else 0.5 * (lo + hi)
            return np.array([a, float(self.model.omega_from_w(w, x)), x])

        return Extremes(
            float(v_lo), row(i_lo, zs[i_lo, 3], w_lo[i_lo]),
            float(v_hi), row(i_hi, zs[i_hi, 1], w_hi[i_hi]),
        )  # fmt: skip

    def vertices(self) -> FloatArray:
        """Vertices of the live node polygons as rows ``(alpha, omega, x)`` at the
        piece's middle closing speed (``x = tau / u_mid``)."""
        own = self.polygons.owner()
        u_mid = self._speeds()[1][self.piece[own]]
        return self._rows(self.polygons.xy, self.tau_s[own], u_mid)

    def contains(self, state: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``(alpha, omega, x)`` lies in the set for some closing speed.

        For ``u = 1/e`` in a piece the state is the point ``s(u) = (alpha x u, omega x u
        - alpha)`` at ``tau = x u``: a segment in ``u``. Every edge normal ``d`` of the
        two nodes around a cell gives ``d.s(u) <= min(L_left, L_right)(x u)`` (the
        secant bounds of ``d``'s support), linear in ``u``; the state is inside when
        some ``u`` of the piece satisfies all of them in some cell (an outer test:
        sound, and exact at the nodes up to the directions used). ``tol`` is
        relative to each bound's magnitude.
        """
        if self.is_empty:
            return False
        alpha, omega, x = channel_state(state)
        if not (np.isfinite(alpha) and np.isfinite(omega) and np.isfinite(x)):
            return False  # (no bound would exclude a nan)
        s = self._summary
        return bool(
            _contains.contains_state(
                self.polygons.xy,
                self.polygons.offsets,
                np.ascontiguousarray(self.tau_s),
                self.live,
                s["piece"],
                s["span"],
                s["table"],
                s["tau4"],
                self.u_lo,
                self.u_hi,
                alpha,
                omega,
                x,
                float(tol),
                self.alpha_scale_rad,
                self.e_nom,
            )  # fmt: skip
        )


_FIELDS = tuple(f.name for f in fields(NodeSet))
_FIELD_NAMES = frozenset(_FIELDS)


def evolve(s: NodeSet, **changes: Any) -> NodeSet:
    """``dataclasses.replace(s, **changes)``, checking only the changed fields.

    The estimator makes several node sets a step; the fields it does not change are
    the set's own, read-only already, so they are neither copied nor checked again
    (``replace`` passes every field through ``__post_init__``: about a tenth of a
    quiet step's Python time). The cached views (``live``, the summary) are not
    carried over: they belong to ``s``.
    """
    unknown = changes.keys() - _FIELD_NAMES
    if unknown:
        raise TypeError(f"NodeSet has no field(s) {sorted(unknown)}")
    new = object.__new__(NodeSet)
    values = new.__dict__
    old = s.__dict__
    for name in _FIELDS:
        values[name] = old[name]
    for name, value in changes.items():
        kind = _ARRAY_FIELDS.get(name)
        values[name] = value if kind is None else readonly(value, kind, copy=None)
    if {"piece", "label_s", "polygons"} & changes.keys():
        _check_nodes(values["piece"], values["label_s"], values["polygons"])
    return new
