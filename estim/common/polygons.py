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
(:meth:`nonempty`, :meth:`select`). The kernels are tested against shapely. The public
constructor copies and checks its input (finite, counter-clockwise, convex); the
kernels' outputs are built without either (``ConvexPolygons._make``: the hot path).
"""

from __future__ import annotations

import numbers
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


def _no_nan(name: str, values: FloatArray) -> FloatArray:
    """``values`` (a bound or a segment; infinities are bounds too), refused if NaN: a
    NaN bound emptied every polygon silently (each vertex compared as outside)."""
    if np.isnan(values).any():
        raise ValueError(f"{name} must not be NaN")
    return values


#: The largest ``max_vertices`` of :meth:`ConvexPolygons.simplify`: the kernel's int64
#: (2**70 failed in numba's typing; any cap above a polygon's count is no cap anyway).
MAX_VERTICES_CAP = int(np.iinfo(np.int64).max)


def _vertex_cap(value: object) -> int:
    """``max_vertices`` as an int in ``[3, MAX_VERTICES_CAP]``: an integer, or a float
    of integral value (``3.0``); ``ValueError`` for anything else (a bool, ``None``,
    NaN, infinity, ``3.5``, a string)."""
    if isinstance(value, numbers.Integral) and not isinstance(value, (bool, np.bool_)):
        cap = int(value)
    elif isinstance(value, (float, np.floating)) and float(value).is_integer():
        cap = int(value)
    else:
        cap = None
    if cap is None or not 3 <= cap <= MAX_VERTICES_CAP:
        raise ValueError(
            f"max_vertices must be an integer >= 3 and at most 2**63 - 1, got {value!r}"
        )
    return cap


def _offsets(counts: IntArray) -> IntArray:
    out = np.zeros(len(counts) + 1, dtype=np.int64)
    np.cumsum(counts, out=out[1:])
    return out


#: Rounding tolerance of the public constructor's checks, relative to a polygon's
#: largest coordinate ``scale``: a turn is to the right when its cross product is below
#: ``-RTOL_SHAPE * scale * (|e_in| + |e_out|)`` (an edge is a difference of coordinates,
#: so its rounding grows with their magnitude, not with the polygon's size), and an
#: edge shorter than ``RTOL_SHAPE * scale`` has no direction (a repeated vertex). The
#: kernels' outputs turn right nowhere (measured over the polygon, section and node-set
#: tests and Fig. 3/5 engagements); the margin is for the caller's own rounding, e.g. of
#: anisotropic maps (about 1e-16 times their condition number).
RTOL_SHAPE = 1e-10


def _check_shape(xy: FloatArray, offsets: IntArray) -> None:
    """Check that every polygon of a batch is counter-clockwise and convex.

    Vectorised over all vertices: edges shorter than the rounding tolerance
    (:data:`RTOL_SHAPE`) are dropped; then at every remaining vertex the turn from
    the incoming to the outgoing edge must be left or straight (cross product not
    below the tolerance), and the turns of one polygon must add up to one revolution
    at most (a star polygon turns left everywhere but winds around twice). Points,
    segments, collinear and repeated vertices pass: clipping and the Minkowski sums
    produce them, and a polygon whose vertices are all collinear stands for their
    hull in every kernel, in any order (``minkowski_segment`` of a segment along
    ``g`` emits ``a - g, a + g, b - g, b + g``).

    Parameters
    ----------
    xy : numpy.ndarray, shape (m, 2)
        Finite vertices.
    offsets : numpy.ndarray of int64, shape (n + 1,)
        Valid offsets (non-decreasing from 0 to ``m``).

    Raises
    ------
    ValueError
        Naming the first polygon that is clockwise or not convex.
    """
    counts = offsets[1:] - offsets[:-1]
    n_poly = len(counts)
    nonempty = counts > 0
    if not nonempty.any():
        return
    owner = np.repeat(np.arange(n_poly), counts)
    scale = np.zeros(n_poly)
    scale[nonempty] = np.maximum.reduceat(np.abs(xy).max(axis=1), offsets[:-1][nonempty])
    edge = xy[_next_within(offsets, counts)] - xy  # edge k: vertex k -> its successor
    length = np.hypot(edge[:, 0], edge[:, 1])
    keep = length > RTOL_SHAPE * scale[owner]
    edge, length, owner = edge[keep], length[keep], owner[keep]
    kept_counts = np.bincount(owner, minlength=n_poly)
    nxt = _next_within(_offsets(kept_counts), kept_counts)
    # turn from edge j to the next kept edge of its polygon (at the vertex between them)
    cross = edge[:, 0] * edge[nxt, 1] - edge[:, 1] * edge[nxt, 0]
    dot = edge[:, 0] * edge[nxt, 0] + edge[:, 1] * edge[nxt, 1]
    tol = RTOL_SHAPE * scale[owner] * (length + length[nxt])
    right = np.flatnonzero(cross < -tol)
    if right.size:
        i = int(owner[right[0]])
        if _signed_area(xy[offsets[i] : offsets[i + 1]]) < 0:
            raise ValueError(
                f"polygon {i} is clockwise; vertices must be counter-clockwise "
                "(reverse its vertex order)"
            )
        raise ValueError(f"polygon {i} is not convex (it turns right at a vertex)")
    # straight turns (within rounding) are 0 forwards and pi backwards (a segment's ends)
    straight = np.abs(cross) <= tol
    turn = np.where(straight, np.where(dot < 0, np.pi, 0.0), np.arctan2(cross, dot))
    # a convex polygon turns around once (2 pi), a star polygon twice or more (4 pi);
    # a collinear one (no turn but straight ones) turns back and forth freely
    winding = np.bincount(owner, weights=turn, minlength=n_poly) / (2 * np.pi)
    bends = np.bincount(owner, weights=~straight, minlength=n_poly) > 0
    twice = np.flatnonzero((winding > 1.5) & bends)
    if twice.size:
        i = int(twice[0])
        raise ValueError(f"polygon {i} is not convex (it winds around {winding[i]:.0f} times)")


def _next_within(offsets: IntArray, counts: IntArray) -> IntArray:
    """Index of each vertex's successor (cyclically) within its polygon."""
    nxt = np.arange(1, offsets[-1] + 1)
    nonempty = counts > 0
    nxt[offsets[1:][nonempty] - 1] = offsets[:-1][nonempty]
    return nxt


def _signed_area(ring: FloatArray) -> float:
    """Shoelace area of one polygon, relative to its first vertex (less rounding)."""
    d = ring - ring[0]
    return 0.5 * float(np.sum(d[:-1, 0] * d[1:, 1] - d[1:, 0] * d[:-1, 1]))


@dataclass(frozen=True, eq=False)
class ConvexPolygons:
    """``n`` convex polygons; polygon ``i`` is ``xy[offsets[i]:offsets[i + 1]]`` (CCW).

    Parameters
    ----------
    xy : array_like, shape (m, 2)
        The vertices of all polygons, one after the other; copied, so the batch does
        not change when the caller's array does.
    offsets : array_like of int, shape (n + 1,)
        Where each polygon's vertices start, then ``m``; copied.

    Raises
    ------
    ValueError
        When a vertex is not finite, the offsets do not rise from 0 to ``m`` (each
        polygon's vertex count is ``offsets[i + 1] - offsets[i] >= 0``), or a polygon is
        clockwise or not convex, beyond a rounding tolerance relative to its largest
        coordinate (:data:`RTOL_SHAPE`). Empty polygons, points, segments and
        collinear or repeated vertices are allowed.

    Notes
    -----
    The kernels' outputs are built by :meth:`_make`, which neither copies nor checks
    (their arrays are fresh and valid by construction): the checks cost only here.
    """

    xy: FloatArray
    offsets: IntArray

    def __post_init__(self) -> None:
        if getattr(self, "_trusted", False):
            return
        # a copy (C order, as the kernels want): the caller's array may change later
        xy = np.array(self.xy, dtype=np.float64, order="C")
        if xy.size == 0:
            xy = xy.reshape(0, 2)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f"xy must have shape (m, 2), got {xy.shape}")
        given = np.asarray(self.offsets)
        if given.ndim != 1 or given.size < 1:
            raise ValueError("offsets must be a 1-D array of n + 1 vertex indices")
        if given.dtype.kind not in "iu" and not (
            given.dtype.kind == "f" and np.all(np.isfinite(given) & (given == np.round(given)))
        ):
            raise ValueError(f"offsets must be integers, got {given.dtype}")
        offsets = np.array(given, dtype=np.int64)
        if offsets[0] != 0 or offsets[-1] != len(xy):
            raise ValueError(
                f"offsets must start at 0 and end at the number of vertices ({len(xy)}), "
                f"got {offsets[0]} and {offsets[-1]}"
            )
        if np.any(np.diff(offsets) < 0):
            raise ValueError("offsets must be non-decreasing")
        bad = np.flatnonzero(~np.isfinite(xy).all(axis=1))
        if bad.size:
            i = int(np.searchsorted(offsets, bad[0], side="right")) - 1
            raise ValueError(f"vertex {bad[0]} (polygon {i}) is not finite: {xy[bad[0]]}")
        _check_shape(xy, offsets)
        xy.setflags(write=False)
        offsets.setflags(write=False)
        object.__setattr__(self, "xy", xy)
        object.__setattr__(self, "offsets", offsets)

    @classmethod
    def _make(cls, xy: FloatArray, offsets: IntArray) -> ConvexPolygons:
        """Internal constructor for kernel outputs: arrays already valid and fresh, so
        neither checked nor copied (the hot path; the public constructor does both)."""
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
        return readonly(_next_within(self.offsets, self.counts), copy=False)

    def next_index(self) -> IntArray:
        """Index of the next vertex (cyclically) within the same polygon."""
        return self._next

    def polygon(self, i: int) -> FloatArray:
        """The vertices of polygon ``i`` (negative ``i`` counts from the end, as for a
        list; ``IndexError`` outside ``range(-n, n)``, ``TypeError`` for an index that
        is not an integer: ``1.5`` and ``True`` quietly read polygon 1)."""
        if not isinstance(i, numbers.Integral) or isinstance(i, (bool, np.bool_)):
            raise TypeError(f"polygon index must be an integer, got {i!r}")
        j = int(i)
        if not -self.n <= j < self.n:
            raise IndexError(f"polygon index {i} out of range for {self.n} polygons")
        j %= self.n
        return self.xy[self.offsets[j] : self.offsets[j + 1]]

    # -- kernels ---------------------------------------------------------------------
    def clip_halfplanes(self, normal: ArrayLike, bound: ArrayLike) -> ConvexPolygons:
        """Intersect polygon ``i`` with the half-plane ``normal[i] . p <= bound[i]``.

        Sutherland-Hodgman: every vertex ``v`` emits itself when inside, then the
        crossing point of the edge ``v -> next`` when the edge crosses the line.
        Consecutive duplicates are removed.
        """
        if len(self.xy) == 0:
            return self
        normal = _no_nan("normal", np.broadcast_to(np.asarray(normal, dtype=float), (self.n, 2)))
        bound = _no_nan("bound", np.broadcast_to(np.asarray(bound, dtype=float), (self.n,)))
        xy, off = _k.clip_halfplanes(
            self.xy, self.offsets, np.ascontiguousarray(normal[:, 0]),
            np.ascontiguousarray(normal[:, 1]), np.ascontiguousarray(bound),
        )  # fmt: skip
        return ConvexPolygons._make(xy, off)

    def clip_slab(self, axis: int, lo: ArrayLike, hi: ArrayLike) -> ConvexPolygons:
        """Intersect polygon ``i`` with ``lo[i] <= p[axis] <= hi[i]`` (``axis`` 0 or 1)."""
        if axis not in (0, 1):
            raise ValueError(f"axis must be 0 (x) or 1 (y), got {axis!r}")
        if len(self.xy) == 0:
            return self
        lo = _no_nan("lo", np.broadcast_to(np.asarray(lo, dtype=float), (self.n,)))
        hi = _no_nan("hi", np.broadcast_to(np.asarray(hi, dtype=float), (self.n,)))
        lo, hi = np.ascontiguousarray(lo), np.ascontiguousarray(hi)
        return ConvexPolygons._make(*_k.clip_slab(self.xy, self.offsets, axis, lo, hi))

    def shift_band(self, dy: FloatArray, half_y: FloatArray) -> ConvexPolygons:
        """Translate polygon ``i`` by ``(0, dy[i])`` and add ``[-(0, h_i), (0, h_i)]``.

        ``dy`` and ``half_y`` are one value per polygon (or one for all). Raises
        ``ValueError`` for another length, a value that is not finite, or a negative
        ``half_y`` (the kernel reads them unchecked, one per polygon)."""
        dy, half_y = (self._per_polygon(v, name) for v, name in ((dy, "dy"), (half_y, "half_y")))
        if not (half_y >= 0).all():
            raise ValueError(f"half_y must be >= 0, got {float(half_y.min())!r}")
        if len(self.xy) == 0:
            return self
        return ConvexPolygons._make(*_k.shift_band(self.xy, self.offsets, dy, half_y))

    def _per_polygon(self, value: ArrayLike, name: str) -> FloatArray:
        """``value`` as one finite float per polygon (a scalar is taken for all; an
        array already of that form is passed on as it is: the kernels' types)."""
        v = np.asarray(value, dtype=float)
        if v.ndim == 0:
            v = np.full(self.n, float(v))
        if v.shape != (self.n,):
            raise ValueError(
                f"{name} must hold one value per polygon ({self.n}), got shape {v.shape}"
            )
        if not np.isfinite(v).all():
            raise ValueError(f"{name} must be finite")
        return np.ascontiguousarray(v)

    def contains_point(self, index: ArrayLike, point: ArrayLike, tol: float) -> bool:
        """Whether ``point`` lies within ``tol`` of one of the polygons ``index``.

        Raises ``ValueError`` for a point that is not two finite numbers, a negative or
        non-finite ``tol`` and ``IndexError`` for an index outside ``range(n)`` (the
        kernel reads the offsets unchecked, and a NaN point compared as inside).
        """
        idx = np.ascontiguousarray(np.atleast_1d(index), dtype=np.int64)
        if idx.ndim != 1:
            raise ValueError(f"index must be one-dimensional, got shape {idx.shape}")
        if idx.size and (idx.min() < 0 or idx.max() >= self.n):
            raise IndexError(f"polygon index out of range(0, {self.n}): {idx.min()}..{idx.max()}")
        p = np.asarray(point, dtype=float)
        if p.shape != (2,) or not np.isfinite(p).all():
            raise ValueError(f"point must be two finite numbers, got {point!r}")
        if not (np.isfinite(tol) and tol >= 0):
            raise ValueError(f"tol must be finite and >= 0, got {tol!r}")
        return bool(_k.polygon_contains(self.xy, self.offsets, idx, float(p[0]), float(p[1]), tol))

    def affine(self, matrix: ArrayLike, offset: ArrayLike = (0.0, 0.0)) -> ConvexPolygons:
        """``p -> matrix[i] @ p + offset[i]``; ``det(matrix[i]) > 0`` keeps the orientation."""
        matrix = np.broadcast_to(np.asarray(matrix, dtype=float), (self.n, 2, 2))
        offset = np.broadcast_to(np.asarray(offset, dtype=float), (self.n, 2))
        if not (np.isfinite(matrix).all() and np.isfinite(offset).all()):
            raise ValueError("affine maps and offsets must be finite")
        if np.any(np.linalg.det(matrix) <= 0):
            raise ValueError("affine maps must have a positive determinant (orientation)")
        own = self.owner()
        xy = np.einsum("ijk,ik->ij", matrix[own], self.xy) + offset[own]
        return ConvexPolygons._make(xy, self.offsets)

    def translate(self, offset: ArrayLike) -> ConvexPolygons:
        offset = np.broadcast_to(np.asarray(offset, dtype=float), (self.n, 2))
        if not np.isfinite(offset).all():
            raise ValueError("offset must be finite")
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
        if not np.isfinite(g).all():
            raise ValueError("half must be finite")
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
        the tolerance is too. ``ValueError`` for a ``max_vertices`` that is not an
        integer from 3 to ``2**63 - 1`` (:data:`MAX_VERTICES_CAP`) or a negative or
        non-finite ``rel_area_tol``.
        """
        if not (np.isfinite(rel_area_tol) and rel_area_tol >= 0):
            raise ValueError(f"rel_area_tol must be finite and >= 0, got {rel_area_tol!r}")
        cap = _vertex_cap(max_vertices)
        if len(self.xy) == 0:
            return self
        xy, off = _k.simplify(self.xy, self.offsets, float(rel_area_tol), cap)
        return ConvexPolygons._make(xy, off)

    def select(self, mask_or_index: ArrayLike) -> ConvexPolygons:
        """Keep the polygons chosen by a boolean mask or an index array (order kept).

        An empty sequence (``[]``, which numpy reads as floats) selects no polygons;
        ``ValueError`` for an index that is not one-dimensional, ``TypeError`` for one
        that is neither boolean nor integer, ``IndexError`` for a mask of another length
        or an index outside ``range(-n, n)`` (numpy's)."""
        idx = np.asarray(mask_or_index)
        if idx.ndim != 1:
            raise ValueError(
                f"mask_or_index must be a 1-D boolean mask or index array, got shape {idx.shape}"
            )
        if idx.dtype == bool:
            if idx.shape != (self.n,):  # (a shorter mask kept its first polygons)
                raise IndexError(f"a mask of {idx.shape} for {self.n} polygons")
            idx = np.flatnonzero(idx)
        elif idx.dtype.kind not in "iu":
            if idx.size:
                raise TypeError(
                    f"mask_or_index must be a boolean mask or integer indices, got {idx.dtype}"
                )
            idx = np.zeros(0, dtype=np.int64)  # [] (read as floats): no polygons
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
        """Shoelace areas (zero for degenerate and empty polygons), about each polygon's
        first vertex (on raw coordinates the sum cancels for a small polygon far from
        the origin)."""
        nxt = self.next_index()
        owner = self.owner()
        rel = self.xy - self.xy[self.offsets[:-1][owner]]
        cr = rel[:, 0] * rel[nxt, 1] - rel[nxt, 0] * rel[:, 1]
        # float64 in, float64 out (numpy's stubs only promise a floating type)
        return cast(FloatArray, 0.5 * np.bincount(owner, weights=cr, minlength=self.n))

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
