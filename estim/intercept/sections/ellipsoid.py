"""An ellipsoid per slab section
(:class:`kalman_vs_infoset.estim.intercept.slabs.sections.SectionBatch`).

Section ``j`` is ``E(c_j, P_j) = {c_j + P_j^(1/2) u : |u| <= 1}`` of the scaled plane
``p = (alpha, w)`` (:mod:`estim.intercept.slabs.sections`); the batch keeps the centres ``(n, 2)``
and shape matrices ``(n, 2, 2)``:

* bearing strip ``lo <= p_0 <= hi``: the optimal bounding ellipsoid update of Fogel &
  Huang (1982), minimum volume (default; vectorised, :func:`fogel_huang_volume`,
  checked against :meth:`estim.common.sets.Ellipsoid.intersect_strip`) or minimum trace (by
  that method, section by section);
* shear ``A = [[1, c], [0, 1]]``: ``E(A c, A P A^T)`` (exact);
* disturbance box ``[+-h_a] x [+-h_w]``: the Minkowski sums with the segments
  ``+-(h_a, 0)`` and ``+-(0, h_w)`` in turn (a segment: ``h = d d^T``), each by
  Schweppe's (1968) family ``P(p) = (1 + 1/p) P + (1 + p) d d^T``; the impulse band
  is one more such sum. Minimum trace: ``p = sqrt(tr P / |d|^2)``. Minimum volume
  (Kurzhanski & Valyi 1997; Chernousko 1994): in the plane, with a segment, the
  eigenvalues of ``d d^T`` relative to ``P`` are ``0`` and ``L = d^T P^-1 d``, and the
  optimality condition ``sum_i (q^2 - l_i) / (l_i + q) = 0`` (``q = 1/p``) reads
  ``2 q^2 + L q - L = 0``, so ``q = 2 L / (L + sqrt(L^2 + 8 L))`` in closed form (the
  tests check both against :meth:`kalman_vs_infoset.estim.common.sets.Ellipsoid.minkowski_sum`);
* support functions ``h(d) = c.d + sqrt(d^T P d)`` and support points
  ``c + P d / sqrt(d^T P d)``: exact.

The initial polygons enter as the minimum-volume ellipsoid ``E(c, 2 G G^T)`` of an
enclosing parallelogram ``c + G [-1, 1]^2``
(:func:`kalman_vs_infoset.estim.intercept.slabs.sections.enclosing_parallelograms`).

References
----------
Schweppe (1968), Fogel & Huang (1982), Chernousko (1994), Kurzhanski & Valyi (1997):
full entries in :mod:`kalman_vs_infoset.estim.common.sets.ellipsoid` and docs/references.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.common.sets import Ellipsoid, EmptyIntersectionError
from kalman_vs_infoset.estim.common.sets._ellipsoid_weights import volume_weights
from kalman_vs_infoset.estim.intercept.sections.options import ELLIPSOID
from kalman_vs_infoset.estim.intercept.slabs.sections import (
    BoolArray,
    FloatArray,
    IntArray,
    clip_slabs,
    enclosing_parallelograms,
)
from numpy.typing import ArrayLike

Criterion = Literal["volume", "trace"]
#: directions of the support points that stand for an ellipsoid's "vertices"
RING_POINTS = 32
_E0 = np.array([1.0, 0.0])


@dataclass(frozen=True)
class EllipsoidFamily:
    """Ellipsoids; ``criterion`` chooses the strip update (Fogel-Huang), ``sum_criterion``
    the member of Schweppe's family for the Minkowski sums."""

    criterion: Criterion = ELLIPSOID.criterion
    sum_criterion: Criterion = ELLIPSOID.sum_criterion

    def __post_init__(self) -> None:
        for c in (self.criterion, self.sum_criterion):
            if c not in ("volume", "trace"):
                raise ValueError(f"unknown criterion {c!r}")

    def from_polygons(self, polygons: ConvexPolygons) -> EllipsoidSections:
        centres, gens = enclosing_parallelograms(polygons)
        p = 2.0 * gens @ gens.transpose(0, 2, 1)  # the parallelogram's corners on it
        return EllipsoidSections(self, centres, covered(p, p))


def segment_sum(shape: FloatArray, d: FloatArray, criterion: Criterion) -> FloatArray:
    """Shape of an ellipsoid containing ``E(0, P_j) + [-d_j, d_j]`` for every ``j``
    (module docstring: Schweppe's family, minimum volume or trace, closed form).

    Parameters
    ----------
    shape : (n, 2, 2) array
    d : (n, 2) array
        Half-segments; a zero one leaves its shape unchanged.
    """
    dd = d[:, :, None] * d[:, None, :]
    t2 = (d * d).sum(axis=1)
    t1 = np.trace(shape, axis1=1, axis2=2)
    live = (t2 > 0.0) & (t1 > 0.0)
    # trace: q = 1/p = sqrt(|d|^2 / tr P)
    q = np.sqrt(np.where(live, t2, 0.0) / np.where(live, t1, 1.0))
    if criterion == "volume":
        det = shape[:, 0, 0] * shape[:, 1, 1] - shape[:, 0, 1] * shape[:, 1, 0]
        adj_quad = shape[:, 1, 1] * d[:, 0] ** 2 - 2 * shape[:, 0, 1] * d[:, 0] * d[:, 1]
        adj_quad = adj_quad + shape[:, 0, 0] * d[:, 1] ** 2
        full = live & (det > 1e-300) & (det > 1e-12 * t1 * t1)
        big_l = np.where(full, adj_quad / np.where(full, det, 1.0), 1.0)
        q_vol = 2.0 * big_l / (big_l + np.sqrt(big_l * big_l + 8.0 * big_l))
        q = np.where(full, q_vol, q)  # a flat P: the trace member (as the library does)
    q = np.where(live, q, 1.0)
    out = (1.0 + q)[:, None, None] * shape + (1.0 + 1.0 / q)[:, None, None] * dd
    # a point (tr P = 0): the segment itself; no segment: unchanged
    out = np.where((t1 <= 0.0)[:, None, None], shape + dd, out)
    return np.where((t2 <= 0.0)[:, None, None], shape, out)


def _trace(p: FloatArray) -> FloatArray:
    return p[:, 0, 0] + p[:, 1, 1]


def _det(p: FloatArray) -> FloatArray:
    return p[:, 0, 0] * p[:, 1, 1] - p[:, 0, 1] * p[:, 1, 0]


def _eigenvalues(p: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Largest and smallest eigenvalue of each symmetric 2 x 2 in ``p`` (closed form; the
    smallest carries an error of ~1e-16 of the largest and may come out negative)."""
    tr = _trace(p)
    det = _det(p)
    disc = np.sqrt(np.clip(0.25 * tr * tr - det, 0.0, None))
    return 0.5 * tr + disc, 0.5 * tr - disc


def fogel_huang_volume(
    c: FloatArray, p: FloatArray, lo: FloatArray, hi: FloatArray, cut: BoolArray
) -> tuple[FloatArray, FloatArray]:
    """Fogel & Huang's minimum-volume update of ``E(c_j, P_j)`` by the slab ``lo_j <=
    p_0 <= hi_j``, already clipped to the ellipsoid's range of ``p_0``, for the sections
    ``cut`` (the others are returned unchanged):
    :meth:`kalman_vs_infoset.estim.common.sets.Ellipsoid. intersect_strip` with ``a = e_0``,
    vectorised over the sections (its special cases included: a segment and a vanishing slab are cut
    exactly).

    With ``g = P_00``, ``e = y - c_0`` and ``r`` the slab's centre offset and half-width,
    ``G = g / r^2``, ``eps = e^2 / r^2`` and ``n = rank P``, the weight ``rho`` is the
    positive root of ``(n-1) G^2 rho^2 + G (2n - 1 + eps - G) rho + n (1 - eps) - G``
    (0 when ``n (1 - eps) >= G``), and ``c+ = c + rho e P a / (r^2 + rho g)``, ``P+ =
    delta (P - rho P a a^T P / (r^2 + rho g))``, ``delta = 1 + rho - rho e^2 / (r^2 + rho g)``.
    """
    c, p = c.copy(), p.copy()
    idx = np.flatnonzero(cut)
    if idx.size == 0:
        return c, p
    cc, pp = c[idx], p[idx]
    g = pp[:, 0, 0]
    pa = pp[:, :, 0]
    y, r = 0.5 * (lo[idx] + hi[idx]), 0.5 * (hi[idx] - lo[idx])
    e = y - cc[:, 0]
    # rank as estim.common.sets.ellipsoid (relative 1e-12)
    lam_max, lam_min = _eigenvalues(pp)
    lam_min = np.clip(lam_min, 0.0, None)
    flat = lam_min <= 1e-12 * np.maximum(lam_max, 1e-300)
    n = np.where(flat, 1.0, 2.0)
    papa = pa[:, :, None] * pa[:, None, :]
    gs = np.where(g > 0, g, 1.0)
    # a segment: its part in the slab (exact)
    seg_c = cc + (e / gs)[:, None] * pa
    seg_p = (r * r / gs)[:, None, None] * pp
    # a vanishing slab: the section by a line (exact)
    hyp_p = (1.0 - e * e / gs)[:, None, None] * (pp - papa / gs[:, None, None])
    # the general case
    rs = np.where(r > 0, r, 1.0)
    rho = volume_weights(n, g / (rs * rs), e * e / (rs * rs))
    den = r * r + rho * g
    dens = np.where(den > 0, den, 1.0)
    delta = 1.0 + rho - rho * e * e / dens
    gen_c = cc + (rho * e / dens)[:, None] * pa
    gen_p = delta[:, None, None] * (pp - (rho / dens)[:, None, None] * papa)
    hyper = ~flat & (r <= 1e-12 * np.sqrt(g))
    new_c = np.where(flat[:, None], seg_c, np.where(hyper[:, None], seg_c, gen_c))
    new_p = np.where(flat[:, None, None], seg_p, np.where(hyper[:, None, None], hyp_p, gen_p))
    c[idx], p[idx] = new_c, 0.5 * (new_p + new_p.transpose(0, 2, 1))
    return c, p


#: smallest eigenvalue kept, relative to the largest: float64 resolves a shape matrix's
#: small eigenvalue only to about 1e-16 of the large one, and below 1e-12
#: (:data:`estim.common.sets.ellipsoid._RANK_RTOL`) an ellipsoid counts as flat, whose
#: strip update (a segment's, exact for a segment) then cuts a thin ellipsoid by up to
#: twenty times its width. Targeted bearing errors drove Fig. 5's sections to a ratio
#: of 7e-14.
MIN_EIGEN_RATIO = 1e-11
#: the rounding of an operation on a shape matrix, relative to the trace of its input
#: and output, added to both eigenvalues after each operation: the computed shape then
#: holds the exact one (in the thin direction the rounding is ~1e-16 of the input's
#: scale, however thin the result; a strip update at a ratio of 1e-10 missed the
#: intersection by 1e-7 of q)
ROUNDING_COVER = 1e-13


def covered(p_in: FloatArray, p_out: FloatArray, gain: FloatArray | float = 1.0) -> FloatArray:
    """``p_out`` (an operation's result on ``p_in``) with its rounding covered and its
    conditioning floored (:func:`floor_eigenvalues`); ``gain`` multiplies the input's
    scale where the operation multiplies its rounding (a strip update: :func:`growth`)."""
    scale = np.maximum(np.abs(_trace(p_in)) * gain, np.abs(_trace(p_out)))
    return floor_eigenvalues(p_out, ROUNDING_COVER * scale)


def growth(p_in: FloatArray, p_out: FloatArray) -> FloatArray:
    """The largest ``lam`` with ``P_out - lam P_in`` singular per section (at least 1;
    1 where ``P_in`` is flat): the factor ``delta`` of a strip update, which multiplies
    the rounding of ``P - k P a a^T P`` (it cancels along ``a`` down to ``r^2 / den`` of
    ``P``). An estimate is enough: it only scales the rounding cover."""
    det_in, det_out = _det(p_in), _det(p_out)
    # det(P_out - lam P_in) = det_in lam^2 - b lam + det_out, b = tr(adj(P_in) P_out)
    b = (p_in[:, 1, 1] * p_out[:, 0, 0] + p_in[:, 0, 0] * p_out[:, 1, 1]
         - p_in[:, 0, 1] * p_out[:, 1, 0] - p_in[:, 1, 0] * p_out[:, 0, 1])  # fmt: skip
    ok = det_in > 0.0
    d = np.where(ok, det_in, 1.0)
    lam = (b + np.sqrt(np.clip(b * b - 4.0 * d * det_out, 0.0, None))) / (2.0 * d)
    return np.where(ok & np.isfinite(lam), np.maximum(lam, 1.0), 1.0)


def floor_eigenvalues(p: FloatArray, cover: FloatArray | float = 0.0) -> FloatArray:
    """``P + max(cover, k lam_max - lam_min) I`` per section (``k`` =
    :data:`MIN_EIGEN_RATIO`; ``cover`` absolute, per section or one): a superset of
    ``E(c, P)`` (sound) with no eigenvalue under ``k`` times the largest; with ``cover
    = 0``, ``P`` unchanged when already so conditioned."""
    if p.shape[0] == 0:
        return p
    lam_max, lam_min = _eigenvalues(p)  # lam_min's error (~1e-16 lam_max): under the floor
    add = np.maximum(np.clip(MIN_EIGEN_RATIO * lam_max - lam_min, 0.0, None), cover)
    if not np.any(add > 0.0):
        return p
    out = np.array(p, dtype=float, copy=True)
    out[:, 0, 0] += add
    out[:, 1, 1] += add
    return out


@dataclass(frozen=True, eq=False)
class EllipsoidSections:
    """Ellipsoids ``E(centre_j, shape_j)``: ``(n, 2)`` and ``(n, 2, 2)`` (read-only)."""

    family: EllipsoidFamily
    centre: FloatArray
    shape: FloatArray

    def __post_init__(self) -> None:
        object.__setattr__(self, "shape", floor_eigenvalues(self.shape))
        for name in ("centre", "shape"):
            getattr(self, name).setflags(write=False)

    @property
    def n(self) -> int:
        return self.centre.shape[0]

    def ellipsoid(self, j: int) -> Ellipsoid:
        """Section ``j`` as an :class:`kalman_vs_infoset.estim.common.sets.Ellipsoid`."""
        return Ellipsoid._make(self.centre[j].copy(), self.shape[j].copy())

    def select(self, index: ArrayLike) -> EllipsoidSections:
        idx = np.asarray(index)
        return EllipsoidSections(self.family, self.centre[idx], self.shape[idx])

    def clip_alpha(self, lo: FloatArray, hi: FloatArray) -> tuple[EllipsoidSections, BoolArray]:
        c, p = self.centre, self.shape
        g = np.clip(p[:, 0, 0], 0.0, None)
        half = np.sqrt(g)
        s_lo, s_hi, keep = clip_slabs(lo, hi, c[:, 0] - half, c[:, 0] + half)
        cut = keep & ~((s_lo <= c[:, 0] - half) & (s_hi >= c[:, 0] + half))
        if self.family.criterion == "volume":
            new_c, new_p = fogel_huang_volume(c, p, s_lo, s_hi, cut)
            new_p = covered(p, new_p, growth(p, new_p))
            return EllipsoidSections(self.family, new_c, new_p), keep
        new_c, new_p = c.copy(), p.copy()
        for j in np.flatnonzero(cut):  # the minimum-trace weight: a cubic per section
            b, r = 0.5 * (s_lo[j] + s_hi[j]), 0.5 * (s_hi[j] - s_lo[j])
            try:
                e = self.ellipsoid(int(j)).intersect_strip(_E0, b, r, "trace")
            except EmptyIntersectionError:  # pragma: no cover - clipped to the set above
                keep[j] = False
                continue
            new_c[j], new_p[j] = e.centre, e.shape
        # the update multiplies its rounding by delta (up to thousands for the trace
        # weight of a thin section cut across: 5e-9 of q uncovered with the input's scale)
        new_p = covered(p, new_p, growth(p, new_p))
        return EllipsoidSections(self.family, new_c, new_p), keep

    def shear_add(self, shear, half_a, half_w, segment: bool = False) -> EllipsoidSections:
        c = self.centre.copy()
        c[:, 0] += shear * c[:, 1]
        a = np.zeros((self.n, 2, 2))
        a[:, 0, 0] = a[:, 1, 1] = 1.0
        a[:, 0, 1] = shear
        p = a @ self.shape @ a.transpose(0, 2, 1)
        zeros = np.zeros_like(half_a)
        crit = self.family.sum_criterion
        if segment:
            p = segment_sum(p, np.column_stack([half_a, half_w]), crit)
        else:
            p = segment_sum(p, np.column_stack([half_a, zeros]), crit)
            p = segment_sum(p, np.column_stack([zeros, half_w]), crit)
        return EllipsoidSections(
            self.family, c, covered(self.shape, 0.5 * (p + p.transpose(0, 2, 1)))
        )

    def shift_band(self, dw: FloatArray, half_w: FloatArray) -> EllipsoidSections:
        c = self.centre.copy()
        c[:, 1] += dw
        d = np.column_stack([np.zeros_like(half_w), half_w])
        p = segment_sum(self.shape, d, self.family.sum_criterion)
        return EllipsoidSections(self.family, c, covered(self.shape, p))

    def _radius(self) -> FloatArray:
        return np.sqrt(np.clip(np.diagonal(self.shape, axis1=1, axis2=2), 0.0, None))

    def abs_max(self) -> tuple[FloatArray, FloatArray]:
        m = np.abs(self.centre) + self._radius()
        return m[:, 0], m[:, 1]

    def _support_points(self, d: FloatArray) -> FloatArray:
        """Support points ``(n, k, 2)`` in the directions ``d`` ``(k, 2)``."""
        pd = np.einsum("nij,kj->nki", self.shape, d)
        s = np.sqrt(np.clip(np.einsum("nki,ki->nk", pd, d), 0.0, None))
        return self.centre[:, None, :] + pd / np.where(s > 0, s, 1.0)[:, :, None]

    def w_extreme_points(self) -> tuple[FloatArray, IntArray]:
        pts = self._support_points(np.array([[0.0, -1.0], [0.0, 1.0]]))
        return pts.reshape(-1, 2), np.repeat(np.arange(self.n), 2)

    def boundary_points(self) -> tuple[FloatArray, IntArray]:
        t = np.linspace(0.0, 2.0 * np.pi, RING_POINTS, endpoint=False)
        pts = self._support_points(np.column_stack([np.cos(t), np.sin(t)]))
        return pts.reshape(-1, 2), np.repeat(np.arange(self.n), RING_POINTS)

    def centres(self) -> FloatArray:
        return self.centre.copy()

    def contains(self, index: ArrayLike, point: ArrayLike, rel_tol: float) -> bool:
        idx = np.asarray(index)
        return any(bool(self.ellipsoid(int(j)).contains(point, rel_tol)) for j in idx)

    def alpha_bounds(self) -> tuple[float, float]:
        r = self._radius()[:, 0]
        return float((self.centre[:, 0] - r).min()), float((self.centre[:, 0] + r).max())
