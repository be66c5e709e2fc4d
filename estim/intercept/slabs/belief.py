"""The information set as a value: a stack of convex sections with range intervals.

The belief half of :mod:`estim.intercept.slabs.estimator` (the estimator, which builds and moves
these values, and the discretisations are described there). Sections live in the scaled
coordinates ``(alpha / alpha_scale_rad, w / w_scale_m)``, ``w = omega x^2 / e``, held
by any set representation of :mod:`kalman_vs_infoset.estim.intercept.slabs.sections` (convex
polygons by default; ellipsoids, zonotopes or boxes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from kalman_vs_infoset.estim.base import Belief, Extremes, StateFunction, Status, state_values
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.intercept.costs import MissForecast, ZeroEffortMiss
from kalman_vs_infoset.estim.intercept.model import ChannelModel, channel_state
from kalman_vs_infoset.estim.intercept.slabs.sections import (
    PolygonFamily,
    PolygonSections,
    SectionBatch,
)
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.arrays import readonly

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class InformationSet(Belief):
    """An immutable stack of convex sections with their range intervals.

    ``sections`` is a :class:`kalman_vs_infoset.estim.intercept.slabs.sections.SectionBatch` (a
    :class:`~kalman_vs_infoset.estim.common.polygons.ConvexPolygons` is taken as the polygon batch).
    """

    model: ChannelModel
    x_lo_m: FloatArray
    x_hi_m: FloatArray
    sections: SectionBatch
    alpha_scale_rad: float
    w_scale_m: float
    status: Status = Status.OK
    contradictions: int = 0

    def __post_init__(self) -> None:
        if isinstance(self.sections, ConvexPolygons):
            object.__setattr__(self, "sections", PolygonSections(PolygonFamily(), self.sections))
        lo, hi = readonly(self.x_lo_m), readonly(self.x_hi_m)
        if lo.ndim != 1 or lo.shape != hi.shape or len(lo) != self.sections.n:
            raise ValueError("one range interval per section is required")
        if np.any(hi < lo):
            raise ValueError("section intervals need x_lo <= x_hi")
        object.__setattr__(self, "x_lo_m", lo)
        object.__setattr__(self, "x_hi_m", hi)

    @classmethod
    def _new(cls, like: InformationSet, x_lo, x_hi, sections, **changes) -> InformationSet:
        """Internal constructor from fresh arrays (no copies, no checks): the hot path."""
        obj = object.__new__(cls)
        for name in ("model", "alpha_scale_rad", "w_scale_m", "status", "contradictions"):
            object.__setattr__(obj, name, changes.get(name, getattr(like, name)))
        object.__setattr__(obj, "x_lo_m", readonly(x_lo, copy=False))
        object.__setattr__(obj, "x_hi_m", readonly(x_hi, copy=False))
        object.__setattr__(obj, "sections", sections)
        return obj

    @property
    def polygons(self) -> ConvexPolygons:
        """The sections as convex polygons (the polygon representation only)."""
        if not isinstance(self.sections, PolygonSections):
            raise AttributeError(f"{type(self.sections).__name__} sections are not polygons")
        return self.sections.polygons

    def trace_fields(self) -> dict[str, float]:
        """The set's size (:meth:`ConvexPolygons.size_fields`) when its sections are
        polygons; ellipsoids, zonotopes and boxes report none."""
        if not isinstance(self.sections, PolygonSections):
            return {}
        return self.polygons.size_fields(self.alpha_scale_rad * self.w_scale_m, self.n_sections)

    # -- Belief interface ------------------------------------------------------------
    @property
    def is_empty(self) -> bool:
        return self.sections.n == 0

    @property
    def n_sections(self) -> int:
        return self.sections.n

    @property
    def x_mid_m(self) -> FloatArray:
        return 0.5 * (self.x_lo_m + self.x_hi_m)

    def vertices(self, at: str = "mid", points: str = "boundary") -> FloatArray:
        """Section vertices as rows ``(alpha, omega, x)`` with ``x`` at each
        section's ``"lo"``, ``"mid"`` or ``"hi"`` range (``points="w"``: only the points
        of least and largest ``w`` of each section, where the representation has them;
        an ellipsoid's "vertices" are support points on a ring of directions)."""
        xs = {"lo": self.x_lo_m, "mid": self.x_mid_m, "hi": self.x_hi_m}[at]
        if points == "w":
            xy, own = self.sections.w_extreme_points()
        else:
            xy, own = self.sections.boundary_points()
        x = xs[own]
        alpha = xy[:, 0] * self.alpha_scale_rad
        omega = self.model.omega_from_w(xy[:, 1] * self.w_scale_m, x)
        return np.column_stack([alpha, omega, x])

    def centre(self) -> FloatArray:
        """Mean over sections of the section centre (the polygons' vertex centroid), as
        ``(alpha, omega, x)``."""
        if self.is_empty:
            return np.full(3, np.nan)
        cen = self.sections.centres()
        x = float(self.x_mid_m.mean())
        alpha = float(cen[:, 0].mean()) * self.alpha_scale_rad
        w = float(cen[:, 1].mean()) * self.w_scale_m
        return np.array([alpha, float(self.model.omega_from_w(w, x)), x])

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the set, from points of each section taken at both
        ends of its range interval.

        The miss forecast ``Pi = w + sign(w) nu (x/e)^2 / 2`` of seed 003 and the
        zero-effort miss ``w`` (:mod:`estim.intercept.costs`, recognised by type) depend on ``w``
        and ``x`` only; at fixed ``x`` they are nondecreasing in ``w`` (``Pi`` jumps up at
        ``w = 0``) and at fixed ``w`` monotone in ``x``, so over a section and its interval
        their extremes sit at the section's points of least and largest ``w`` (support
        points) at an end of the interval: exact for every representation. Any other
        function is evaluated at the sections' boundary points: exact for functions
        linear in ``(alpha, w)`` and monotone in ``x`` over polygons, zonotopes and boxes
        (vertices), an inner approximation over ellipsoids.
        """
        if self.is_empty:
            raise ValueError(f"extremes of an empty information set (status {self.status})")
        kind = "w" if isinstance(fn, MissForecast | ZeroEffortMiss) else "boundary"
        pts = self.vertices("hi", kind)
        if np.any(self.x_hi_m > self.x_lo_m):
            pts = np.vstack([self.vertices("lo", kind), pts])
        values = state_values(fn, pts)
        i_min, i_max = int(np.argmin(values)), int(np.argmax(values))
        return Extremes(float(values[i_min]), pts[i_min], float(values[i_max]), pts[i_max])

    def contains(self, state: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``(alpha, omega, x)`` lies in the set.

        Slabs: the state is inside when a section whose interval contains ``x``
        contains ``(alpha, w)``. Points (zero-width intervals): between two sections
        the set is taken as the x-section of the convex hull of the neighbouring
        sections (a heuristic; exact at a section's own range; polygons only). ``tol``
        is a relative numerical tolerance (of the polygons' magnitude in the scaled
        coordinates; each representation's own for the others).
        """
        alpha, omega, x = channel_state(state)
        if self.is_empty:
            return False
        p = (
            alpha / self.alpha_scale_rad,
            float(self.model.zero_effort_miss_m(omega, x)) / self.w_scale_m,
        )
        span = max(float(self.x_hi_m.max() - self.x_lo_m.min()), 1.0)
        if np.all(self.x_hi_m == self.x_lo_m) and self.n_sections > 1 and self._is_polygons:
            pts = self._interpolated(x, span * tol)
            if pts is None:
                return False
            scale = max(1.0, float(np.abs(pts).max()))
            hull = shapely.MultiPoint(pts).convex_hull
            return bool(shapely.distance(hull, shapely.Point(p)) <= tol * scale)
        idx = np.flatnonzero((self.x_lo_m <= x + tol * span) & (self.x_hi_m >= x - tol * span))
        return self.sections.contains(idx, p, tol)

    @property
    def _is_polygons(self) -> bool:
        return isinstance(self.sections, PolygonSections)

    def _interpolated(self, x: float, x_tol: float) -> FloatArray | None:
        xs = self.x_lo_m
        if x < xs[0] - x_tol or x > xs[-1] + x_tol:
            return None
        j = int(np.clip(np.searchsorted(xs, x) - 1, 0, len(xs) - 2))
        lam = float(np.clip((x - xs[j]) / (xs[j + 1] - xs[j]), 0.0, 1.0))
        a, b = self.polygons.polygon(j), self.polygons.polygon(j + 1)
        if lam in (0.0, 1.0):
            return a if lam == 0.0 else b
        return ((1 - lam) * a[:, None, :] + lam * b[None, :, :]).reshape(-1, 2)

    # -- summaries -------------------------------------------------------------------
    def alpha_range_rad(self) -> tuple[float, float]:
        lo, hi = self.sections.alpha_bounds()
        return lo * self.alpha_scale_rad, hi * self.alpha_scale_rad

    def x_range_m(self) -> tuple[float, float]:
        return float(self.x_lo_m.min()), float(self.x_hi_m.max())
