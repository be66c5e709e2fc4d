"""A batch of convex polygons stored as one ragged vertex array, with exact kernels.

The information set keeps one convex polygon per x-section and applies the same
operation to all of them every step. Doing that through GEOS costs about a
millisecond per operation for 29 sections; here each operation is one call of a
compiled kernel (:mod:`kalman_vs_infoset.estim.common._kernels`) over the concatenated vertices:

* :meth:`ConvexPolygons.clip_halfplanes` -- Sutherland-Hodgman against one
  half-plane per polygon (a strip is two of them);
* :meth:`ConvexPolygons.affine` -- a per-polygon affine map;
* :meth:`ConvexPolygons.minkowski_segment` -- Minkowski sum with a centred
  segment ``[-g, g]`` per polygon (two new edges parallel to ``g``);
* :meth:`ConvexPolygons.simplify` -- outer (conservative) vertex reduction;
* :meth:`ConvexPolygons.translate`, :meth:`ConvexPolygons.select`.

Vertices are counter-clockwise. Degenerate polygons (a segment, a point) are
allowed and handled by every kernel; an emptied polygon has zero vertices
(:meth:`nonempty`, :meth:`select`). The kernels are tested against shapely.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import cast

import numpy as np
from kalman_vs_infoset.estim.common import _kernels as _k
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.arrays import readonly

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _offsets(counts: IntArray) -> IntArray:
    out = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    return out


@dataclass(frozen=True, eq=False)
class ConvexPolygons:
    """``n`` convex polygons; polygon ``i`` is ``xy[offsets[i]:offsets[i + 1]]`` (CCW)."""

    xy: FloatArray
    offsets: IntArray

    def __post_init__(self) -> None:
        if getattr(self, "_trusted", False):
            return
        xy = np.ascontiguousarray(self.xy, dtype=float).reshape(-1, 2)
        offsets = np.asarray(self.offsets, dtype=np.int64)
        if offsets.ndim != 1 or offsets.size < 1 or offsets[0] != 0 or offsets[-1] != len(xy):
            raise ValueError("offsets must start at 0 and end at the number of vertices")
        if np.any(np.diff(offsets) < 0):
            raise ValueError("offsets must be non-decreasing")
        object.__setattr__(self, "xy", readonly(xy, copy=False))
        object.__setattr__(self, "offsets", readonly(offsets, copy=False))

    @classmethod
    def _make(cls, xy: FloatArray, offsets: IntArray) -> ConvexPolygons:
        """Internal constructor for kernel outputs: arrays already valid, no checks."""
        obj = object.__new__(cls)
        object.__setattr__(obj, "_trusted", True)
        object.__setattr__(obj, "xy", readonly(xy, copy=False))
        object.__setattr__(obj, "offsets", readonly(offsets, copy=False))
        return obj

    # -- construction and views ------------------------------------------------------
    @classmethod
    def from_list(cls, polygons: Sequence[ArrayLike]) -> ConvexPolygons:
        """From a list of ``(m_i, 2)`` CCW vertex arrays (``m_i`` may be 0)."""
        arrays = [np.asarray(p, dtype=float).reshape(-1, 2) for p in polygons]
        counts = np.array([len(a) for a in arrays], dtype=np.int64)
        xy = np.concatenate(arrays) if arrays else np.zeros((0, 2))
        return cls(xy, np.concatenate([[0], np.cumsum(counts)]))

    @property
    def n(self) -> int:
        return len(self.offsets) - 1

    # index arrays are derived once per (immutable) batch and cached
    @cached_property
    def counts(self) -> IntArray:
        return readonly(self.offsets[1:] - self.offsets[:-1], copy=False)

    @cached_property
    def _owner(self) -> IntArray:
        return readonly(np.repeat(np.arange(self.n), self.counts), copy=False)

    def owner(self) -> IntArray:
        """Index of the polygon each vertex belongs to."""
        return self._owner

    @cached_property
    def _next(self) -> IntArray:
        nxt = np.arange(1, len(self.xy) + 1)
        nonempty = self.counts > 0
        nxt[self.offsets[1:][nonempty] - 1] = self.offsets[:-1][nonempty]
        return readonly(nxt, copy=False)

    def next_index(self) -> IntArray:
        """Index of the next vertex (cyclically) within the same polygon."""
        return self._next

    def polygon(self, i: int) -> FloatArray:
        return self.xy[self.offsets[i] : self.offsets[i + 1]]

    # -- kernels ---------------------------------------------------------------------
    def clip_halfplanes(self, normal: ArrayLike, bound: ArrayLike) -> ConvexPolygons:
        """Intersect polygon ``i`` with the half-plane ``normal[i] . p <= bound[i]``.

        Sutherland-Hodgman: every vertex ``v`` emits itself when inside, then the
        crossing point of the edge ``v -> next`` when the edge crosses the line.
        Consecutive duplicates are removed.
        """
        if len(self.xy) == 0:
            return self
        normal = np.broadcast_to(np.asarray(normal, dtype=float), (self.n, 2))
        bound = np.broadcast_to(np.asarray(bound, dtype=float), (self.n,))
        xy, off = _k.clip_halfplanes(
            self.xy, self.offsets, np.ascontiguousarray(normal[:, 0]),
            np.ascontiguousarray(normal[:, 1]), np.ascontiguousarray(bound),
        )  # fmt: skip
        return ConvexPolygons._make(xy, off)

    def clip_slab(self, axis: int, lo: ArrayLike, hi: ArrayLike) -> ConvexPolygons:
        """Intersect polygon ``i`` with ``lo[i] <= p[axis] <= hi[i]``."""
        if len(self.xy) == 0:
            return self
        lo = np.ascontiguousarray(np.broadcast_to(np.asarray(lo, dtype=float), (self.n,)))
        hi = np.ascontiguousarray(np.broadcast_to(np.asarray(hi, dtype=float), (self.n,)))
        return ConvexPolygons._make(*_k.clip_slab(self.xy, self.offsets, axis, lo, hi))

    def shift_band(self, dy: FloatArray, half_y: FloatArray) -> ConvexPolygons:
        """Translate polygon ``i`` by ``(0, dy[i])`` and add ``[-(0, h_i), (0, h_i)]``."""
        if len(self.xy) == 0:
            return self
        return ConvexPolygons._make(*_k.shift_band(self.xy, self.offsets, dy, half_y))

    def contains_point(self, index: ArrayLike, point: ArrayLike, tol: float) -> bool:
        """Whether ``point`` lies within ``tol`` of one of the polygons ``index``."""
        idx = np.ascontiguousarray(index, dtype=np.int64)
        p = np.asarray(point, dtype=float)
        return bool(_k.polygon_contains(self.xy, self.offsets, idx, float(p[0]), float(p[1]), tol))

    def affine(self, matrix: ArrayLike, offset: ArrayLike = (0.0, 0.0)) -> ConvexPolygons:
        """``p -> matrix[i] @ p + offset[i]``; ``det(matrix[i]) > 0`` keeps the orientation."""
        matrix = np.broadcast_to(np.asarray(matrix, dtype=float), (self.n, 2, 2))
        if np.any(np.linalg.det(matrix) <= 0):
            raise ValueError("affine maps must have a positive determinant (orientation)")
        offset = np.broadcast_to(np.asarray(offset, dtype=float), (self.n, 2))
        own = self.owner()
        xy = np.einsum("ijk,ik->ij", matrix[own], self.xy) + offset[own]
        return ConvexPolygons._make(xy, self.offsets)

    def translate(self, offset: ArrayLike) -> ConvexPolygons:
        offset = np.broadcast_to(np.asarray(offset, dtype=float), (self.n, 2))
        return ConvexPolygons._make(self.xy + offset[self.owner()], self.offsets)

    def minkowski_segment(self, half: ArrayLike) -> ConvexPolygons:
        """Minkowski sum of polygon ``i`` with the segment ``[-half[i], half[i]]``.

        The boundary of ``P + [-g, g]`` is the boundary of ``P`` with every edge
        whose outward normal has a positive component along ``g`` moved by ``+g``,
        every other edge by ``-g``, and two edges ``2g`` inserted where the side
        changes. Edge ``k`` (``v_k -> v_k+1``, CCW) has outward normal component
        ``cross(g, e_k)`` along ``g``. A vertex between edges of different sides is
        emitted twice. A polygon whose edges are all parallel to ``g`` (a point, a
        segment along ``g``) emits ``v - g, v + g`` for every vertex: the result is
        the degenerate hull of the right points.
        """
        if len(self.xy) == 0:
            return self
        g = np.broadcast_to(np.asarray(half, dtype=float), (self.n, 2))
        xy, off = _k.minkowski_segment(
            self.xy, self.offsets, np.ascontiguousarray(g[:, 0]), np.ascontiguousarray(g[:, 1])
        )
        return ConvexPolygons._make(xy, off)

    def simplify(self, rel_area_tol: float = 1e-6, max_vertices: int = 24) -> ConvexPolygons:
        """Outer (conservative) simplification: the result contains the input.

        An edge ``k`` is removed by extending its neighbours ``k-1`` and ``k+1`` to
        their intersection ``X`` (possible when they turn by less than pi); this
        adds the triangle ``(v_k, X, v_k+1)``. Edges are removed while that area is below
        ``rel_area_tol`` times the polygon's area -- or unconditionally while the
        polygon has more than ``max_vertices`` vertices (greedy, cheapest edge
        first). The added area is invariant under the affine prediction maps, so
        the tolerance is too.
        """
        if len(self.xy) == 0:
            return self
        xy, off = _k.simplify(self.xy, self.offsets, float(rel_area_tol), int(max_vertices))
        return ConvexPolygons._make(xy, off)

    def select(self, mask_or_index: ArrayLike) -> ConvexPolygons:
        """Keep the polygons chosen by a boolean mask or an index array (order kept)."""
        idx = np.asarray(mask_or_index)
        if idx.dtype == bool:
            idx = np.flatnonzero(idx)
        counts = self.counts[idx]
        if len(idx) > 1:
            # the usual selections (a mask, a split, an insert) are a few runs of
            # consecutive polygons: copied as slices, not vertex by vertex
            cut = np.flatnonzero(idx[1:] - idx[:-1] != 1) + 1
            if len(cut) < 16 and idx.min() >= 0:
                first = idx[np.concatenate(([0], cut))]
                stop = idx[np.concatenate((cut - 1, [len(idx) - 1]))] + 1
                off = self.offsets
                parts = [self.xy[off[a] : off[b]] for a, b in zip(first, stop, strict=True)]
                return ConvexPolygons._make(np.concatenate(parts), _offsets(counts))
        starts = self.offsets[:-1][idx]
        vert = np.repeat(starts - np.cumsum(counts) + counts, counts) + np.arange(counts.sum())
        return ConvexPolygons._make(self.xy[vert], _offsets(counts))

    def nonempty(self) -> NDArray[np.bool_]:
        return self.counts > 0

    def bounds(self) -> FloatArray:
        """``(n, 4)`` array ``(xmin, ymin, xmax, ymax)``; NaN rows for empty polygons."""
        out = np.full((self.n, 4), np.nan)
        ne = self.nonempty()
        if ne.any():
            starts = self.offsets[:-1][ne]
            out[ne, :2] = np.minimum.reduceat(self.xy, starts, axis=0)
            out[ne, 2:] = np.maximum.reduceat(self.xy, starts, axis=0)
        return out

    def areas(self) -> FloatArray:
        """Shoelace areas (zero for degenerate and empty polygons)."""
        nxt = self.next_index()
        cr = self.xy[:, 0] * self.xy[nxt, 1] - self.xy[nxt, 0] * self.xy[:, 1]
        # float64 in, float64 out (numpy's stubs only promise a floating type)
        return cast(FloatArray, 0.5 * np.bincount(self.owner(), weights=cr, minlength=self.n))

    def size_fields(self, scale_radm: float, n_sections: int, n_simplified: int = 0) -> dict:
        """A polygon set's size for a trace (``Belief.trace_fields``): live sections,
        vertices, the largest section's area in rad m (``scale_radm``: the area of a
        unit square of the stored coordinates) and the sections outer-simplified so far
        (the names: ``SIZE_FIELDS`` in :mod:`kalman_vs_infoset.estim.intercept.slabs.options`,
        which the registrations declare)."""
        areas = self.areas()
        return {
            "n_sections": float(n_sections),
            "n_vertices": float(np.sum(self.counts)),
            "area_max_radm": float(areas.max() * scale_radm) if areas.size else 0.0,
            "n_simplified": float(n_simplified),
        }
