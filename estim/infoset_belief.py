"""The information set as a value: a stack of convex sections with range intervals.

The belief half of :mod:`estim.infoset` (the estimator, which builds and moves these
values, and the discretisations are described there). Sections live in the scaled
coordinates ``(alpha / alpha_scale_rad, w / w_scale_m)``, ``w = omega x^2 / e``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from estim.base import Belief, Extremes, StateFunction, Status
from estim.base import frozen_array as _frozen
from estim.base import frozen_view as _frozen_view
from estim.model import ChannelModel
from estim.polygons import ConvexPolygons

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class InformationSet(Belief):
    """An immutable stack of convex sections with their range intervals."""

    model: ChannelModel
    x_lo_m: FloatArray
    x_hi_m: FloatArray
    polygons: ConvexPolygons
    alpha_scale_rad: float
    w_scale_m: float
    status: Status = Status.OK
    contradictions: int = 0

    def __post_init__(self) -> None:
        lo, hi = _frozen(self.x_lo_m), _frozen(self.x_hi_m)
        if lo.ndim != 1 or lo.shape != hi.shape or len(lo) != self.polygons.n:
            raise ValueError("one range interval per section is required")
        if np.any(hi < lo):
            raise ValueError("section intervals need x_lo <= x_hi")
        object.__setattr__(self, "x_lo_m", lo)
        object.__setattr__(self, "x_hi_m", hi)

    @classmethod
    def _new(cls, like: InformationSet, x_lo, x_hi, polygons, **changes) -> InformationSet:
        """Internal constructor from fresh arrays (no copies, no checks): the hot path."""
        obj = object.__new__(cls)
        for name in ("model", "alpha_scale_rad", "w_scale_m", "status", "contradictions"):
            object.__setattr__(obj, name, changes.get(name, getattr(like, name)))
        object.__setattr__(obj, "x_lo_m", _frozen_view(x_lo))
        object.__setattr__(obj, "x_hi_m", _frozen_view(x_hi))
        object.__setattr__(obj, "polygons", polygons)
        return obj

    # -- Belief interface ------------------------------------------------------------
    @property
    def is_empty(self) -> bool:
        return self.polygons.n == 0

    @property
    def n_sections(self) -> int:
        return self.polygons.n

    @property
    def x_mid_m(self) -> FloatArray:
        return 0.5 * (self.x_lo_m + self.x_hi_m)

    def vertices(self, at: str = "mid") -> FloatArray:
        """Section vertices as rows ``(alpha, omega, x)`` with ``x`` at each
        section's ``"lo"``, ``"mid"`` or ``"hi"`` range."""
        xs = {"lo": self.x_lo_m, "mid": self.x_mid_m, "hi": self.x_hi_m}[at]
        x = xs[self.polygons.owner()]
        alpha = self.polygons.xy[:, 0] * self.alpha_scale_rad
        omega = self.model.omega_from_w(self.polygons.xy[:, 1] * self.w_scale_m, x)
        return np.column_stack([alpha, omega, x])

    def centre(self) -> FloatArray:
        """Mean over sections of the vertex centroid, as ``(alpha, omega, x)``."""
        if self.is_empty:
            return np.full(3, np.nan)
        own = self.polygons.owner()
        counts = self.polygons.counts
        cen = [np.bincount(own, weights=self.polygons.xy[:, k]) / counts for k in range(2)]
        x = float(self.x_mid_m.mean())
        alpha = float(cen[0].mean()) * self.alpha_scale_rad
        w = float(cen[1].mean()) * self.w_scale_m
        return np.array([alpha, float(self.model.omega_from_w(w, x)), x])

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the set, from the section vertices taken at both
        ends of each section's range interval.

        Exact for functions whose extremes over a section sit at a vertex and at an
        end of the interval: linear functions of ``(alpha, w)`` monotone in ``x``, and
        the miss forecast ``Pi = w + sign(w) nu (x/e)^2 / 2`` of seed 003 (for fixed
        ``x`` increasing in ``omega``, with a jump up at ``omega = 0``).
        """
        if self.is_empty:
            raise ValueError(f"extremes of an empty information set (status {self.status})")
        pts = self.vertices("hi")
        if np.any(self.x_hi_m > self.x_lo_m):
            pts = np.vstack([self.vertices("lo"), pts])
        values = np.asarray(fn(pts), dtype=float)
        i_min, i_max = int(np.argmin(values)), int(np.argmax(values))
        return Extremes(float(values[i_min]), pts[i_min], float(values[i_max]), pts[i_max])

    def contains(self, state: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``(alpha, omega, x)`` lies in the set.

        Slabs: the state is inside when a section whose interval contains ``x``
        contains ``(alpha, w)``. Points (zero-width intervals): between two sections
        the set is taken as the x-section of the convex hull of the neighbouring
        sections (a heuristic; exact at a section's own range). ``tol`` is a
        distance in the scaled coordinates (numerical tolerance).
        """
        alpha, omega, x = (float(v) for v in np.asarray(state, dtype=float))
        if self.is_empty:
            return False
        p = (
            alpha / self.alpha_scale_rad,
            float(self.model.zero_effort_miss_m(omega, x)) / self.w_scale_m,
        )
        span = max(float(self.x_hi_m.max() - self.x_lo_m.min()), 1.0)
        if np.all(self.x_hi_m == self.x_lo_m) and self.n_sections > 1:
            pts = self._interpolated(x, span * tol)
            if pts is None:
                return False
            scale = max(1.0, float(np.abs(pts).max()))
            hull = shapely.MultiPoint(pts).convex_hull
            return bool(shapely.distance(hull, shapely.Point(p)) <= tol * scale)
        idx = np.flatnonzero((self.x_lo_m <= x + tol * span) & (self.x_hi_m >= x - tol * span))
        scale = max(1.0, float(np.abs(self.polygons.xy).max()))
        return self.polygons.contains_point(idx, p, tol * scale)

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
        a = self.polygons.xy[:, 0] * self.alpha_scale_rad
        return float(a.min()), float(a.max())

    def x_range_m(self) -> tuple[float, float]:
        return float(self.x_lo_m.min()), float(self.x_hi_m.max())
