"""What the slab information set holds per section: the protocol and the polygon batch.

The slab discretisation of :mod:`kalman_vs_infoset.estim.intercept.slabs.estimator` keeps, for every
range interval ``[x_lo_j, x_hi_j]``, one convex set of the scaled coordinates
``p = (alpha / alpha_scale_rad, w / w_scale_m)``. Everything the estimator does to
those sets is a handful of operations, applied to all sections at once; a set
representation that offers them (:class:`SectionBatch`) plugs into the estimator
unchanged, with the same slabs, shears, disturbance, impulse geometry, kinematic
margin, splitting, range intervals and threshold:

* ``clip_alpha(lo, hi)``: an outer bound of ``S_j ∩ {lo_j <= p_0 <= hi_j}`` (a bearing
  strip), and which sections are left non-empty;
* ``shear_add(c, h_a, h_w)``: an outer bound of ``A_j S_j + [-h_a, h_a] x [-h_w, h_w]``
  with ``A_j = [[1, c_j], [0, 1]]`` (the prediction: ``alpha += c w``, then the
  disturbance box; ``segment=True``: the segment ``[-(h_a, h_w), (h_a, h_w)]``);
* ``shift_band(d, h)``: an outer bound of ``S_j + (0, d_j) + {0} x [-h_j, h_j]``
  (an impulse, known to ``+-`` a band);
* ``abs_max()``: the support functions ``max |p_0|`` and ``max |p_1|`` over each
  section (they size the kinematic margin and the impulse geometry);
* ``w_extreme_points()``: for each section a point of least and one of largest
  ``p_1`` (the support points in ``-/+ e_1``): a function of ``w`` alone that is
  nondecreasing, such as the miss forecast ``Pi = w + sign(w) nu (x/e)^2 / 2`` at a
  fixed ``x``, has its extremes over the section there, exactly;
* ``boundary_points()``: points among which a function linear in ``p`` has its
  extremes (the vertices of a polygon, zonotope or box; an ellipsoid has none, and
  gives support points on a ring of directions: an inner approximation);
* ``contains``, ``centres``, ``select``, ``alpha_bounds``, ``magnitude``.

Every operation returns a set containing the exact result (an outer bound), which is
all the soundness argument of :mod:`kalman_vs_infoset.estim.intercept.slabs.estimator` uses.
Implementations: :class:`PolygonSections` (the exact convex polygons of the original set, compiled
kernels), :class:`kalman_vs_infoset.estim.intercept.sections.ellipsoid.EllipsoidSections`,
:class:`kalman_vs_infoset.estim.intercept.sections.zonotope.ZonotopeSections` and
:class:`estim.intercept.sections.box.BoxSections`. A *family* (:class:`SectionFamily`) is the
configuration that builds a batch from the initial polygons; a batch carries its
family, so the operations know how to reduce (vertex count, generators, criteria).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, Self

import numpy as np
from kalman_vs_infoset.estim.common import _kernels as _k
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.common.sets._common import TOUCH_RTOL
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]


class SectionBatch(Protocol):
    """``n`` convex sets of the scaled plane ``p = (alpha, w)``, one per slab (module
    docstring). Values: every operation returns a new batch."""

    @property
    def n(self) -> int:
        """Number of sections."""
        ...

    def select(self, index: ArrayLike) -> Self:
        """The sections chosen by a boolean mask or an index array (repeats allowed)."""
        ...

    def clip_alpha(self, lo: FloatArray, hi: FloatArray) -> tuple[Self, BoolArray]:
        """Outer bound of each section cut by ``lo_j <= p_0 <= hi_j``, and a mask of the
        sections the cut leaves non-empty (the others are to be dropped)."""
        ...

    def shear_add(
        self, shear: FloatArray, half_a: FloatArray, half_w: FloatArray, segment: bool = False
    ) -> Self:
        """Outer bound of ``p_0 += shear_j p_1`` plus the box ``[+-half_a] x [+-half_w]``
        (``segment``: plus the segment ``+-(half_a, half_w)``)."""
        ...

    def shift_band(self, dw: FloatArray, half_w: FloatArray) -> Self:
        """Outer bound of the section moved by ``(0, dw_j)`` plus ``{0} x [+-half_w_j]``."""
        ...

    def abs_max(self) -> tuple[FloatArray, FloatArray]:
        """``max |p_0|`` and ``max |p_1|`` over each section."""
        ...

    def w_extreme_points(self) -> tuple[FloatArray, IntArray]:
        """Points ``(M, 2)`` and their sections: each section's extremes of ``p_1``."""
        ...

    def boundary_points(self) -> tuple[FloatArray, IntArray]:
        """Points ``(M, 2)`` and their sections: vertices, or a ring of support points."""
        ...

    def centres(self) -> FloatArray:
        """A centre of each section, ``(n, 2)``."""
        ...

    def contains(self, index: ArrayLike, point: ArrayLike, rel_tol: float) -> bool:
        """Whether ``point`` lies in one of the sections ``index`` (``rel_tol``: relative
        to the batch's magnitude, or to the set's own size for an ellipsoid)."""
        ...

    def alpha_bounds(self) -> tuple[float, float]:
        """Least and largest ``p_0`` over all sections."""
        ...


class SectionFamily(Protocol):
    """A set representation's configuration: builds its batch from the initial polygons."""

    def from_polygons(self, polygons: ConvexPolygons) -> SectionBatch:
        """A batch whose section ``j`` contains polygon ``j``."""
        ...


# -- the polygon batch: the original information set ------------------------------------
@dataclass(frozen=True)
class PolygonFamily:
    """Exact convex polygons (:class:`kalman_vs_infoset.estim.common.polygons.ConvexPolygons`), kept
    to ``max_vertices`` by an outer simplification that also removes edges adding less
    than ``simplify_rel_area`` of a section's area."""

    simplify_rel_area: float = 1.0e-6
    max_vertices: int = 16

    def from_polygons(self, polygons: ConvexPolygons) -> PolygonSections:
        return PolygonSections(self, polygons)


@dataclass(frozen=True, eq=False)
class PolygonSections:
    """The slab set's own sections: a batch of convex polygons and compiled kernels.

    ``shear_add`` is one kernel (shear, Minkowski sums, convex hull, outer
    simplification; :func:`estim.common._kernels.predict_sections`); the polygons are exact
    up to that simplification and rounding.
    """

    family: PolygonFamily
    polygons: ConvexPolygons

    def _with(self, polygons: ConvexPolygons) -> PolygonSections:
        return PolygonSections(self.family, polygons)

    @property
    def n(self) -> int:
        return self.polygons.n

    def select(self, index: ArrayLike) -> PolygonSections:
        return self._with(self.polygons.select(index))

    def clip_alpha(self, lo: FloatArray, hi: FloatArray) -> tuple[PolygonSections, BoolArray]:
        clipped = self.polygons.clip_slab(0, lo, hi)
        return self._with(clipped), clipped.counts > 0

    def shear_add(self, shear, half_a, half_w, segment: bool = False) -> PolygonSections:
        p = self.polygons
        xy, off = _k.predict_sections(
            p.xy, p.offsets, shear, half_a, half_w, segment,
            self.family.simplify_rel_area, self.family.max_vertices,
        )  # fmt: skip
        return self._with(ConvexPolygons._make(xy, off))

    def shift_band(self, dw: FloatArray, half_w: FloatArray) -> PolygonSections:
        return self._with(self.polygons.shift_band(dw, half_w))

    def abs_max(self) -> tuple[FloatArray, FloatArray]:
        return _k.section_abs_max(self.polygons.xy, self.polygons.offsets)

    def w_extreme_points(self) -> tuple[FloatArray, IntArray]:
        # every vertex (a superset of the two support points): the order and the ties
        # of the original set's extremes are kept
        return self.boundary_points()

    def boundary_points(self) -> tuple[FloatArray, IntArray]:
        return self.polygons.xy, self.polygons.owner()

    def centres(self) -> FloatArray:
        own, counts = self.polygons.owner(), self.polygons.counts
        xy = self.polygons.xy
        return np.column_stack([np.bincount(own, weights=xy[:, k]) / counts for k in range(2)])

    def contains(self, index: ArrayLike, point: ArrayLike, rel_tol: float) -> bool:
        scale = max(1.0, float(np.abs(self.polygons.xy).max()))
        return self.polygons.contains_point(index, point, rel_tol * scale)

    def alpha_bounds(self) -> tuple[float, float]:
        a = self.polygons.xy[:, 0]
        return float(a.min()), float(a.max())


# -- shared helpers of the other families -------------------------------------------------
def clip_slabs(
    lo: FloatArray, hi: FloatArray, set_lo: FloatArray, set_hi: FloatArray
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Vectorised :func:`estim.common.sets._common.clip_slab`: the slabs ``[lo, hi]`` clipped to
    the sets' ranges ``[set_lo, set_hi]``; a gap within ``TOUCH_RTOL`` of the set's scale
    is a touch (the midpoint), a wider one an empty intersection (``keep`` false)."""
    new_lo, new_hi = np.maximum(lo, set_lo), np.minimum(hi, set_hi)
    gap = new_lo - new_hi
    scale = np.maximum.reduce([np.abs(set_lo), np.abs(set_hi), set_hi - set_lo])
    keep = gap <= TOUCH_RTOL * np.maximum(scale, 1e-300)
    touch = keep & (gap > 0)
    mid = 0.5 * (new_lo + new_hi)
    return np.where(touch, mid, new_lo), np.where(touch, mid, new_hi), keep


def enclosing_parallelograms(polygons: ConvexPolygons) -> tuple[FloatArray, FloatArray]:
    """A parallelogram containing each polygon, with a pair of vertical sides.

    In the sheared coordinate ``v = p_1 - s p_0`` a polygon lies in
    ``[a_min, a_max] x [v_min, v_max]``; the parallelogram's area ``(a_max - a_min)
    (v_max - v_min)`` is least for the slope ``s`` of one of the polygon's edges (the
    vertical width of a convex polygon is a convex piecewise-linear function of ``s``
    whose breaks are its edge slopes), so every edge slope is tried. For the initial
    sections (trapezoids with vertical sides, plus a thin box) this is tight.

    Returns
    -------
    centres : (n, 2) array
    generators : (n, 2, 2) array
        ``((a_max - a_min)/2) (1, s)`` and ``(0, (v_max - v_min)/2)``.
    """
    n = polygons.n
    centres, gens = np.zeros((n, 2)), np.zeros((n, 2, 2))
    for i in range(n):  # once per estimator run: the initial set
        v = polygons.polygon(i)
        if len(v) == 0:
            raise ValueError("an empty polygon has no enclosing parallelogram")
        edges = np.roll(v, -1, axis=0) - v
        flat = np.abs(edges[:, 0]) > 1e-12 * max(1.0, float(np.abs(v[:, 0]).max()))
        slopes = np.concatenate([[0.0], edges[flat, 1] / edges[flat, 0]])
        sheared = v[None, :, 1] - slopes[:, None] * v[None, :, 0]
        s = slopes[int(np.argmin(np.ptp(sheared, axis=1)))]
        a_lo, a_hi = float(v[:, 0].min()), float(v[:, 0].max())
        u = v[:, 1] - s * v[:, 0]
        v_lo, v_hi = float(u.min()), float(u.max())
        ra, rv = 0.5 * (a_hi - a_lo), 0.5 * (v_hi - v_lo)
        ac = 0.5 * (a_lo + a_hi)
        centres[i] = (ac, 0.5 * (v_lo + v_hi) + s * ac)
        # outward by far more than the rounding of the sheared coordinates
        a_mag = float(np.abs(v[:, 0]).max())
        w_mag = float(np.abs(v[:, 1]).max()) + abs(s) * a_mag
        ra, rv = ra + 1e-12 * (ra + a_mag), rv + 1e-12 * (rv + w_mag)
        gens[i] = [[ra, 0.0], [s * ra, rv]]
    return centres, gens
