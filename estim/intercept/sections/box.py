"""An interval box per slab section
(:class:`kalman_vs_infoset.estim.intercept.slabs.sections.SectionBatch`).

Section ``j`` is ``[lo_j, hi_j]`` of the scaled plane ``p = (alpha, w)``
(:mod:`kalman_vs_infoset.estim.intercept.slabs.sections`), vectorised over the sections. The
operations are those of :class:`kalman_vs_infoset.estim.common.sets.Box` written for all sections at
once (interval arithmetic; Jaulin et al. 2001, ch. 2 and 4):

* the bearing strip ``lo <= p_0 <= hi`` is axis-aligned: the box's contraction by
  it is the exact intersection ``[max(lo_0, lo), min(hi_0, hi)]`` in ``p_0``, and
  leaves ``p_1`` unchanged;
* the shear ``p_0 += c p_1`` is the interval hull ``p_0 + c [lo_1, hi_1]``: the
  correlation between ``alpha`` and ``w`` that the shear creates is lost at every
  step, so bearings never narrow ``w`` (what an axis-aligned interval observer
  cannot learn: the box is the family's baseline);
* the disturbance box and the impulse band are exact Minkowski sums.

References
----------
L. Jaulin, M. Kieffer, O. Didrit & E. Walter, *Applied Interval Analysis*, Springer,
2001.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.intercept.slabs.sections import (
    BoolArray,
    FloatArray,
    IntArray,
    clip_slabs,
)
from numpy.typing import ArrayLike


@dataclass(frozen=True)
class BoxFamily:
    """Axis-aligned boxes (no options): the initial polygon's bounding box."""

    def from_polygons(self, polygons: ConvexPolygons) -> BoxSections:
        b = polygons.bounds()
        if np.isnan(b).any():
            raise ValueError("an empty polygon has no bounding box")
        return BoxSections(self, b[:, :2].copy(), b[:, 2:].copy())


@dataclass(frozen=True, eq=False)
class BoxSections:
    """Boxes ``[lo_j, hi_j]``, arrays ``(n, 2)`` (read-only)."""

    family: BoxFamily
    lo: FloatArray
    hi: FloatArray

    def __post_init__(self) -> None:
        for name in ("lo", "hi"):
            getattr(self, name).setflags(write=False)

    @property
    def n(self) -> int:
        return self.lo.shape[0]

    def select(self, index: ArrayLike) -> BoxSections:
        idx = np.asarray(index)
        return BoxSections(self.family, self.lo[idx], self.hi[idx])

    def clip_alpha(self, lo: FloatArray, hi: FloatArray) -> tuple[BoxSections, BoolArray]:
        a_lo, a_hi, keep = clip_slabs(lo, hi, self.lo[:, 0], self.hi[:, 0])
        new_lo, new_hi = self.lo.copy(), self.hi.copy()
        new_lo[:, 0], new_hi[:, 0] = a_lo, np.maximum(a_hi, a_lo)
        return BoxSections(self.family, new_lo, new_hi), keep

    def shear_add(self, shear, half_a, half_w, segment: bool = False) -> BoxSections:
        # p_0 + c [lo_1, hi_1]: the interval product's ends; the box (or the segment,
        # whose interval hull is the same box) added exactly
        t1, t2 = shear * self.lo[:, 1], shear * self.hi[:, 1]
        lo = np.column_stack([self.lo[:, 0] + np.minimum(t1, t2) - half_a, self.lo[:, 1] - half_w])
        hi = np.column_stack([self.hi[:, 0] + np.maximum(t1, t2) + half_a, self.hi[:, 1] + half_w])
        return BoxSections(self.family, lo, hi)

    def shift_band(self, dw: FloatArray, half_w: FloatArray) -> BoxSections:
        lo, hi = self.lo.copy(), self.hi.copy()
        lo[:, 1] += dw - half_w
        hi[:, 1] += dw + half_w
        return BoxSections(self.family, lo, hi)

    def abs_max(self) -> tuple[FloatArray, FloatArray]:
        m = np.maximum(np.abs(self.lo), np.abs(self.hi))
        return m[:, 0], m[:, 1]

    def w_extreme_points(self) -> tuple[FloatArray, IntArray]:
        a = 0.5 * (self.lo[:, 0] + self.hi[:, 0])
        pts = np.stack([np.column_stack([a, self.lo[:, 1]]), np.column_stack([a, self.hi[:, 1]])])
        return pts.transpose(1, 0, 2).reshape(-1, 2), np.repeat(np.arange(self.n), 2)

    def boundary_points(self) -> tuple[FloatArray, IntArray]:
        lo, hi = self.lo, self.hi
        corners = np.stack(
            [lo, np.column_stack([hi[:, 0], lo[:, 1]]), hi, np.column_stack([lo[:, 0], hi[:, 1]])]
        )
        return corners.transpose(1, 0, 2).reshape(-1, 2), np.repeat(np.arange(self.n), 4)

    def centres(self) -> FloatArray:
        return 0.5 * (self.lo + self.hi)

    def contains(self, index: ArrayLike, point: ArrayLike, rel_tol: float) -> bool:
        idx = np.asarray(index, dtype=np.int64)
        if idx.size == 0:
            return False
        p = np.asarray(point, dtype=float)
        slack = rel_tol * max(1.0, float(np.abs(self.lo).max()), float(np.abs(self.hi).max()))
        inside = np.all((self.lo[idx] - slack <= p) & (p <= self.hi[idx] + slack), axis=1)
        return bool(inside.any())

    def alpha_bounds(self) -> tuple[float, float]:
        return float(self.lo[:, 0].min()), float(self.hi[:, 0].max())
