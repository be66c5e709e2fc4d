"""Ellipsoids ``E(c, P) = {c + P^(1/2) u : |u| <= 1}`` and their outer-bounding calculus.

For a positive definite ``P`` this is ``{x : (x - c)^T P^-1 (x - c) <= 1}``; a singular
positive semidefinite ``P`` is allowed and gives a flat ellipsoid in the affine hull
``c + range(P)`` (a segment, a point, ...). Every operation returns an ellipsoid that
contains the exact result (an *outer* bound); the linear map is exact up to its own
rounding, which it covers, and the support function is exact.

Operations
----------
* :meth:`Ellipsoid.affine` -- ``A E + b = E(A c + b, A P A^T)``, exact but for the
  rounding of the product, which it covers (``+ delta I``, about 1e-15 of the scale).
* :meth:`Ellipsoid.minkowski_sum` -- Schweppe's (1968) family
  ``P(p) = (1 + 1/p) P1 + (1 + p) P2``, ``p > 0``, every member of which contains
  ``E1 + E2``. Minimum trace: ``p* = sqrt(tr P1 / tr P2)``. Minimum volume
  (Kurzhanski & Valyi 1997; Chernousko 1994): ``p*`` is the root in
  ``[sqrt(l_min), sqrt(l_max)]`` of ``sum_i 1/(l_i + p) = n / (p (p + 1))``, with ``l_i``
  the eigenvalues of ``P1`` relative to ``P2``.
* :meth:`Ellipsoid.intersect_strip` -- the optimal bounding ellipsoid (OBE) update of
  Fogel & Huang (1982). The measurement ``|a.x - b| <= r`` and the ellipsoid give, for
  every weight ``rho >= 0``, the outer ellipsoid
  ``(x-c)^T P^-1 (x-c) + rho (b - a.x)^2 / r^2 <= 1 + rho``, i.e. with ``e = b - a.c``,
  ``g = a^T P a``::

      c+ = c + rho e P a / (r^2 + rho g)
      P+ = delta (P - rho P a a^T P / (r^2 + rho g)),
      delta = 1 + rho - rho e^2 / (r^2 + rho g).

  ``rho`` is chosen to minimise the **volume** (default; Fogel & Huang's first criterion):
  with ``G = g/r^2``, ``eps = e^2/r^2`` and ``n = rank P``, ``d log det P+ / d rho = 0`` is
  the quadratic ``(n-1) G^2 rho^2 + G (2n - 1 + eps - G) rho + n (1 - eps) - G = 0``, whose
  positive root is taken when ``n (1 - eps) < G`` (otherwise ``rho = 0``, no update).
  ``criterion="trace"`` minimises ``tr P+`` instead (their second criterion): the optimum
  is among ``rho = 0`` and the positive roots of a cubic, written out in
  :func:`._ellipsoid_weights._trace_rho`. Before the update the strip is clipped to the
  range of ``a.x`` over the ellipsoid, which leaves the intersection unchanged and
  tightens the bound. A
  vanishing strip (a hyperplane) and a segment (rank-1 ``P``) are cut exactly. Each
  result covers its own rounding (the shape by ``+ delta I``, the centre by a ball, a
  segment's part lengthened): a thin cap or a segment almost normal to ``a`` otherwise
  left points of the exact intersection outside.
* :meth:`Ellipsoid.intersect_halfspace` -- ``a.x <= b`` as the slab between the
  ellipsoid's own minimum of ``a.x`` and ``b``, then the same update.
* :meth:`Ellipsoid.support` -- ``h(d) = c.d + sqrt(d^T P d)``;
  :meth:`Ellipsoid.extremes` -- ``c.d -/+ sqrt(d^T P d)``, both exact.

References
----------
F. C. Schweppe, "Recursive state estimation: unknown but bounded errors and system
inputs", IEEE Trans. Automatic Control 13(1), 1968.
E. Fogel & Y. F. Huang, "On the value of information in system identification --
bounded noise case", Automatica 18(2), 229-238, 1982.
F. L. Chernousko, *State Estimation for Dynamic Systems*, CRC Press, 1994.
A. B. Kurzhanski & I. Valyi, *Ellipsoidal Calculus for Estimation and Control*, 1997.
M. J. Todd, "On minimum volume ellipsoids containing part of a given ellipsoid",
Math. Oper. Res. 7(2), 1982 (the parallel-cut ellipsoid used as a worked example in the tests).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np
from kalman_vs_infoset.estim.common.sets._common import (
    ROUND_RTOL,
    EmptyIntersectionError,
    FloatArray,
    check_tol,
    clip_slab,
    directions,
    flat_along,
    halfspace_bound,
    matrix,
    points,
    strip_bounds,
    vector,
)
from kalman_vs_infoset.estim.common.sets._ellipsoid_weights import (
    _trace_rho,
    _volume_rho,
    _volume_sum_parameter,
)
from numpy.typing import ArrayLike

from kalman_vs_infoset.numerics.arrays import readonly

__all__ = ["Ellipsoid", "EmptyIntersectionError"]

Criterion = Literal["volume", "trace"]
_RANK_RTOL = 1e-12
#: eigenvalues under this fraction of the largest are rounding (a computed ``L L^T`` of
#: rank 1 has others of about 1e-16 of it); between it and ``_RANK_RTOL`` a set is thin,
#: not flat: :meth:`Ellipsoid.contains` reads those axes, and cuts keep them
_THIN_RTOL = 1e-14
#: a.P a under this fraction of |a|^2 tr P is rounding (the ellipsoid is flat along a)
FLAT_G_RTOL = 1e-13
#: the scales (largest diagonal entry of ``P``, largest ``|a_i|``) within which a strip
#: update is computed as given; beyond them it is computed on the problem rescaled by
#: powers of two (exact), whose squares and products neither overflow nor underflow
_SCALE_P = (2.0**-200, 2.0**200)
_SCALE_A = (2.0**-100, 2.0**100)
#: the radii whose square, a ball's shape, is a normal float
_BALL_RADIUS = (float(np.sqrt(np.finfo(float).tiny)), float(np.sqrt(np.finfo(float).max)))


class _OutOfRange(ValueError):
    """A result whose shape or centre is beyond the floating-point range."""


def _fro(x: FloatArray) -> float:
    """The Frobenius norm of ``x`` without overflow or underflow of its squares (numpy's
    is ``inf`` for entries above 1e154 and 0 below 1e-162, which made the rounding
    covers infinite, then NaN, or nothing): the same value as numpy's where that one is
    safely in range, otherwise ``s |x / s|`` with ``s`` the largest entry."""
    with np.errstate(over="ignore", under="ignore"):
        v = float(np.linalg.norm(x))
    if 1e-150 < v < 1e150:
        return v
    s = float(np.abs(x).max(initial=0.0))
    return s * float(np.linalg.norm(x / s)) if s > 0.0 else 0.0


@dataclass(frozen=True, eq=False)
class Ellipsoid:
    """The ellipsoid ``{c + P^(1/2) u : |u| <= 1}`` (immutable; arrays are read-only).

    Parameters
    ----------
    centre : array_like, shape (n,)
        ``n >= 1`` (``ValueError`` for an empty centre or one of two or more dimensions).
    shape : array_like, shape (n, n)
        Symmetric positive semidefinite; symmetrised on construction.
    """

    centre: FloatArray
    shape: FloatArray

    def __post_init__(self) -> None:
        c = vector(self.centre, name="centre")
        p = matrix(self.shape, c.size, c.size, "shape")
        with np.errstate(over="ignore"):
            sym = 0.5 * (p + p.T)
        # halves first where the sum overflows (entries near the float maximum)
        p = sym if np.isfinite(sym).all() else 0.5 * p + 0.5 * p.T
        lam = np.linalg.eigvalsh(p)
        if lam[0] < -1e-10 * max(1.0, lam[-1]):
            raise ValueError(f"shape must be positive semidefinite (eigenvalue {lam[0]:.3g})")
        object.__setattr__(self, "centre", readonly(c, copy=False))
        object.__setattr__(self, "shape", readonly(p, copy=False))

    @classmethod
    def _make(cls, c: FloatArray, p: FloatArray) -> Ellipsoid:
        """Internal constructor for results already known to be valid (no checks)."""
        obj = object.__new__(cls)
        object.__setattr__(obj, "centre", readonly(c, copy=False))
        object.__setattr__(obj, "shape", readonly(0.5 * (p + p.T), copy=False))
        return obj

    # -- construction ------------------------------------------------------------
    @classmethod
    def ball(cls, centre: ArrayLike, radius: float) -> Ellipsoid:
        """The ball ``|x - c| <= radius`` (``P = radius^2 I``; ``radius`` finite, ``>= 0``).

        ``ValueError`` for a radius above about 1.3e154, whose square overflows (it
        raised ``OverflowError``). Below about 1.5e-154 the square is not a normal float
        and is rounded up by one of its ulps, so that the ball holds the one asked for
        (under 1e-162 it became its centre).
        """
        c = vector(centre, name="centre")
        radius = float(radius)
        if not (np.isfinite(radius) and radius >= 0.0):
            raise ValueError(f"a ball needs a finite radius >= 0, got {radius}")
        if radius > _BALL_RADIUS[1]:
            raise ValueError(
                f"a ball's radius must be at most {_BALL_RADIUS[1]:.3g} (its square, the "
                f"shape, a float), got {radius:.3g}"
            )
        if 0.0 < radius < _BALL_RADIUS[0]:  # a subnormal square, rounded to its spacing
            return cls(c, np.nextafter(radius * radius, np.inf) * np.eye(c.size))
        return cls(c, radius**2 * np.eye(c.size))

    @classmethod
    def from_box(cls, lo: ArrayLike, hi: ArrayLike) -> Ellipsoid:
        """The minimum-volume ellipsoid containing the box ``[lo, hi]``:
        ``P = k diag(h^2)``, ``h`` the half-widths, ``k`` the number of nonzero ones."""
        lo = vector(lo, name="lo")
        hi = vector(hi, lo.size, "hi")
        if np.any(hi < lo):
            raise ValueError("a box needs lo <= hi")
        h = 0.5 * (hi - lo)
        return cls(0.5 * (lo + hi), max(int(np.count_nonzero(h)), 1) * np.diag(h**2))

    @property
    def dim(self) -> int:
        """Dimension ``n`` of the space."""
        return self.centre.size

    @cached_property
    def _eig(self) -> tuple[FloatArray, FloatArray]:
        lam, vec = np.linalg.eigh(self.shape)
        return np.clip(lam, 0.0, None), vec

    @cached_property
    def rank(self) -> int:
        """Number of eigenvalues of ``P`` above ``1e-12`` of the largest (a flat
        ellipsoid has rank below ``n``)."""
        lam = self._eig[0]
        return int(np.count_nonzero(lam > _RANK_RTOL * max(lam.max(initial=0.0), 1e-300)))

    # -- exact operations ----------------------------------------------------------
    def affine(self, a: ArrayLike, b: ArrayLike | None = None) -> Ellipsoid:
        """``{A x + b : x in E} = E(A c + b, A P A^T + delta I)`` (``A`` may be
        rectangular), ``delta`` the rounding of the computed ``A P A^T``.

        Each entry of the computed product is within ``k eps (|A| |P| |A|^T)`` of the
        exact one (two products over ``n`` terms and the symmetrisation: ``k = 2n + 2``
        is an upper bound), so the exact shape is at most ``delta``, that matrix's
        Frobenius norm, above the computed one in any direction (Weyl), and adding
        ``delta`` to every eigenvalue makes the result hold the exact image. Without it
        a thin image (an ill-conditioned ``A``: eigenvalues 3e-10 apart) left mapped
        points of the ellipsoid 7e-7 outside it in ``q``; ``delta`` is about ``1e-15``
        of the image's scale. ``ValueError`` when the image is beyond the floating-point
        range.
        """
        a = matrix(a, None, self.dim, "A")
        b_vec = 0.0 if b is None else vector(b, a.shape[0], "b")
        with np.errstate(over="ignore", invalid="ignore"):  # _finite refuses an overflow
            c = a @ self.centre + b_vec
            abs_a = np.abs(a)
            bound = abs_a @ np.abs(self.shape) @ abs_a.T
            delta = (2 * self.dim + 2) * np.finfo(float).eps * _fro(bound)
            p = a @ self.shape @ a.T + delta * np.eye(a.shape[0])
        return _finite(c, p, "the image")

    def translate(self, b: ArrayLike) -> Ellipsoid:
        """``E(c + b, P)``."""
        return Ellipsoid._make(self.centre + vector(b, self.dim, "b"), self.shape.copy())

    def support(self, d: ArrayLike) -> FloatArray | float:
        """``h(d) = max_{x in E} d.x = c.d + sqrt(d^T P d)``; ``d`` of shape (n,) or (k, n),
        finite (``ValueError``)."""
        d = directions(d, self.dim)
        quad = np.einsum("...i,ij,...j->...", d, self.shape, d)
        out = d @ self.centre + np.sqrt(np.clip(quad, 0.0, None))
        return float(out) if out.ndim == 0 else out

    def support_point(self, d: ArrayLike) -> FloatArray:
        """A maximiser of ``d.x`` over ``E``: ``c + P d / sqrt(d^T P d)``."""
        d = vector(d, self.dim, "d")
        pd = self.shape @ d
        s = np.sqrt(max(float(d @ pd), 0.0))
        return self.centre + (pd / s if s > 0 else 0.0)

    def extremes(self, d: ArrayLike) -> tuple[float, float]:
        """``(min, max)`` of ``d.x`` over ``E``."""
        d = vector(d, self.dim, "d")
        m, s = float(d @ self.centre), float(np.sqrt(max(float(d @ self.shape @ d), 0.0)))
        return m - s, m + s

    def interval_hull(self) -> tuple[FloatArray, FloatArray]:
        """The smallest box containing ``E``: ``c -/+ sqrt(diag P)``."""
        h = np.sqrt(np.clip(np.diag(self.shape), 0.0, None))
        return self.centre - h, self.centre + h

    def contains(self, x: ArrayLike, tol: float = 1e-9) -> bool | np.ndarray:
        """Whether ``x`` (shape (n,) or (k, n)) lies in ``E``, up to a relative ``tol``.

        In the eigenbasis of ``P``, ``sum z_i^2 / l_i <= (1 + tol)^2`` over the nonzero
        ``l_i`` and ``|z_i| <= tol max(sqrt(l_max), 1)`` plus a few ulps of the
        coordinates along the null directions (those under 1e-12 of ``l_max``, rounding
        for a flat set), each coordinate ``z_i`` taken those few ulps closer to the
        centre (rounding of the coordinates, as the other sets allow: sound, as the sum
        grows with each ``|z_i|``); or the same sum over the null directions too where
        their ``l_i`` are positive (thin axes, not flat ones), the flat ones held to the
        same few ulps. A point with a coordinate that is not finite is not in it.
        """
        check_tol(tol)
        x = points(x, self.dim)
        pts = np.atleast_2d(x)
        finite = np.asarray(np.isfinite(pts).all(axis=1))  # (an array: mypy)
        if not finite.all():  # not in it (as for the box and the zonotope), without
            pts = np.where(finite[:, None], pts, self.centre)  # NaN warnings on the way
        lam, vec = self._eig
        lam_max = lam.max(initial=0.0)
        z = (pts - self.centre) @ vec
        pos = lam > _RANK_RTOL * max(lam_max, 1e-300)
        scale = np.sqrt(lam_max) + 1e-300
        bound = (1.0 + tol) ** 2
        # off the hull: tol times the size, and a few ulps of the coordinates (far from
        # the origin they are rounded to more than that)
        ulps = ROUND_RTOL * (np.linalg.norm(pts, axis=1) + float(np.linalg.norm(self.centre)))
        slack = tol * max(scale, 1.0) + ulps
        # on the hull too: each coordinate those ulps closer to the centre (a boundary
        # point rounded to the coordinates of a set far from the origin lies that far
        # out; moved along the radius instead, a thin axis kept no slack)
        zs = np.sign(z) * np.maximum(np.abs(z) - ulps[:, None], 0.0)
        q = np.sum(zs[:, pos] ** 2 / lam[pos], axis=1)
        inside = (q <= bound) & (np.sqrt(np.sum(z[:, ~pos] ** 2, axis=1)) <= slack)
        # a set thinner than the rank threshold, not flat, holds its own thin points
        # (along every thin axis, whether or not other axes are flat)
        thin = ~pos & (lam > _THIN_RTOL * lam_max)
        if thin.any():
            flat_off = np.sqrt(np.sum(z[:, ~pos & ~thin] ** 2, axis=1))
            inside |= (q + np.sum(zs[:, thin] ** 2 / lam[thin], axis=1) <= bound) & (
                flat_off <= slack
            )
        inside &= finite
        return bool(inside[0]) if x.ndim == 1 else inside

    # -- outer bounds ----------------------------------------------------------------
    def minkowski_sum(self, other: Ellipsoid, criterion: Criterion = "trace") -> Ellipsoid:
        """An ellipsoid containing ``E1 + E2`` from ``P(p) = (1 + 1/p) P1 + (1 + p) P2``.

        ``criterion="trace"``: ``p = sqrt(tr P1 / tr P2)``. ``criterion="volume"``: the
        minimum-volume member (needs ``P1`` or ``P2`` nonsingular, otherwise falls back
        to the trace choice, as it does when the relative eigenvalues are beyond the
        floating-point range). Another family: ``TypeError``. ``ValueError`` when the
        sum is beyond the floating-point range.
        """
        if not isinstance(other, Ellipsoid):
            raise TypeError(f"minkowski_sum takes an Ellipsoid, got {type(other).__name__}")
        if other.dim != self.dim:
            raise ValueError("ellipsoids of different dimensions")
        p1, p2 = self.shape, other.shape
        with np.errstate(over="ignore", invalid="ignore"):  # refused below, by name
            c = self.centre + other.centre
            t1, t2 = np.trace(p1), np.trace(p2)
        if not (np.isfinite(t1) and np.isfinite(t2)):
            raise _OutOfRange(
                f"the sum is beyond the floating-point range (traces {t1:.3g} and {t2:.3g})"
            )
        c_scale = np.abs(self.centre) + np.abs(other.centre)
        if t1 <= 0.0 or t2 <= 0.0:  # a point: the sum is the other ellipsoid, shifted
            with np.errstate(over="ignore", invalid="ignore"):
                return _covered(c, p1 + p2, _fro(p1 + p2), c_scale)
        with np.errstate(over="ignore", under="ignore"):
            p = np.sqrt(t1 / t2)
        if not 1e-150 < p < 1e150:  # the ratio of the traces over- or underflowed
            p = np.sqrt(t1) / np.sqrt(t2)  # (a ball of 1 plus one of 1e-155: NaN)
        if criterion == "volume":
            p = _volume_sum_parameter(p1, p2, self.rank, other.rank, p)
        elif criterion != "trace":
            raise ValueError(f"unknown criterion {criterion!r}")
        w1, w2 = 1.0 + 1.0 / p, 1.0 + p
        # the sum of the centres and of the scaled shapes is rounded: a thin sum (two
        # intervals 2e-5 wide at 1e3) left its extreme points 5e-9 outside in q
        with np.errstate(over="ignore", invalid="ignore"):  # _covered refuses an overflow
            p_scale = w1 * _fro(p1) + w2 * _fro(p2)
            return _covered(c, w1 * p1 + w2 * p2, p_scale, c_scale)

    def intersect_strip(
        self, a: ArrayLike, b: float, r: float, criterion: Criterion = "volume"
    ) -> Ellipsoid:
        """An ellipsoid containing ``E ∩ {x : |a.x - b| <= r}`` (Fogel & Huang 1982).

        Raises :class:`EmptyIntersectionError` when the strip misses ``E``. At extreme
        scales the update is computed on the problem rescaled by powers of two (exact);
        when its result is beyond the floating-point range, ``E`` itself (which holds
        the intersection) is returned.
        """
        lo, hi = strip_bounds(b, r)
        return self._intersect_slab(vector(a, self.dim, "a"), lo, hi, criterion)

    def intersect_halfspace(
        self, a: ArrayLike, b: float, criterion: Criterion = "volume"
    ) -> Ellipsoid:
        """An ellipsoid containing ``E ∩ {x : a.x <= b}`` (same update)."""
        return self._intersect_slab(
            vector(a, self.dim, "a"), -np.inf, halfspace_bound(b), criterion
        )

    @cached_property
    def _is_segment(self) -> bool:
        """Rank 1 and flat across to rounding (:data:`_THIN_RTOL`): a set of rank 1 that
        is thin, not flat, is cut by the general update, which keeps its thin axes
        (:meth:`contains` reads them)."""
        lam = self._eig[0]
        return self.rank == 1 and (lam.size == 1 or lam[-2] <= _THIN_RTOL * lam[-1])

    def _cut_segment(self, a: FloatArray, lo: float, hi: float) -> Ellipsoid:
        """The part of the segment ``{c + t v : |t| <= 1}`` (rank-1 ``P = v v^T``) with
        ``lo <= a.x <= hi`` (the slab already clipped to it and not holding all of it).

        Along the segment ``a.x = m + t s`` with ``s = a.v``, so the part is
        ``t in [(lo - m) / s, (hi - m) / s]``. ``s`` is computed from ``v``, not as
        ``sqrt(a.P a)``, whose cancellation squares the conditioning (a segment almost
        normal to ``a`` lost 1e-5 of its length), and the part is lengthened by the
        rounding of ``m``, ``s``, the slab's ends and the new centre (in ``t``)."""
        lam, vec = self._eig
        v = np.sqrt(lam[-1]) * vec[:, -1]
        s = float(a @ v)
        if s == 0.0:  # normal to a to rounding: the slab touches all of it
            return self
        m = float(a @ self.centre)
        abs_a = np.abs(a)
        err_s = ROUND_RTOL * float(abs_a @ np.abs(v))
        err_m = ROUND_RTOL * float(abs_a @ np.abs(self.centre))
        t_lo, t_hi = sorted(((lo - m) / s, (hi - m) / s))
        # within [-1, 1]; a slab that touches an end to rounding leaves that end
        t_lo, t_hi = min(max(t_lo, -1.0), 1.0), max(min(t_hi, 1.0), -1.0)
        if t_lo > t_hi:
            t_lo = t_hi = 0.5 * (t_lo + t_hi)
        t_c, t_r = 0.5 * (t_lo + t_hi), 0.5 * (t_hi - t_lo)
        centre = self.centre + t_c * v
        t_err = (
            (max(abs(t_lo), abs(t_hi)) * err_s + err_m + ROUND_RTOL * (abs(lo) + abs(hi) + abs(m)))
            / abs(s)
            + ROUND_RTOL * (abs(t_c) + t_r)
            + ROUND_RTOL
            * float(np.linalg.norm(np.abs(self.centre) + np.abs(t_c * v)))
            / float(np.linalg.norm(v))
        )
        return Ellipsoid._make(centre, (t_r + t_err) ** 2 * np.outer(v, v))

    def _intersect_slab(self, a: FloatArray, lo: float, hi: float, criterion: str) -> Ellipsoid:
        """:meth:`_update`, on the problem rescaled by powers of two (exact) when ``P``
        or ``a`` is far from 1: at ``P = 1e300 I`` the products ``P a a^T P`` and the
        norms of the covers overflowed and the result was NaN. A result beyond the
        floating-point range (it can be larger than ``E`` across ``a``) gives ``E``."""
        if criterion not in ("volume", "trace"):
            raise ValueError(f"unknown criterion {criterion!r}")
        s_p = float(np.diag(self.shape).max())
        s_a = float(np.abs(a).max())
        k_a = k = 0
        s_c = float(np.abs(self.centre).max())
        if s_a > 0.0 and (not _SCALE_A[0] <= s_a <= _SCALE_A[1] or s_a * s_c > 2.0**800):
            k_a = int(np.frexp(s_a)[1])  # a.x in [lo, hi] is the same slab for a / 2^k_a
        if s_p > 0.0 and not _SCALE_P[0] <= s_p <= _SCALE_P[1]:
            k = int(np.frexp(s_p)[1]) // 2  # x = 2^k x': P = 4^k P', c = 2^k c'
        e = self
        if k or k_a:
            c = np.ldexp(self.centre, -k)
            if np.isfinite(c).all():
                e = Ellipsoid._make(c, np.ldexp(self.shape, -2 * k))
            else:  # the centre far beyond the size: kept as it is
                k = 0
            a = np.ldexp(a, -k_a)
            lo, hi = (float(np.ldexp(v, -(k + k_a))) for v in (lo, hi))
        try:
            out = e._update(a, lo, hi, criterion)
        except EmptyIntersectionError:
            if not (k or k_a):
                raise
            # the message in the given units, not the rescaled ones
            ends = np.ldexp(np.array([lo, hi, *e.extremes(a)]), k + k_a)
            raise EmptyIntersectionError(
                "slab [{:.6g}, {:.6g}] misses the set's range [{:.6g}, {:.6g}]".format(*ends)
            ) from None
        if out is e:
            return self
        out_c, out_p = out.centre, out.shape
        if k:  # back to the given scale (symmetric already; may overflow, checked below)
            with np.errstate(over="ignore"):
                out_c, out_p = np.ldexp(out_c, k), np.ldexp(out_p, 2 * k)
            out = object.__new__(Ellipsoid)
            object.__setattr__(out, "centre", readonly(out_c, copy=False))
            object.__setattr__(out, "shape", readonly(out_p, copy=False))
        if not (np.isfinite(out.centre).all() and np.isfinite(out.shape).all()):
            return self  # beyond the floating-point range: E holds the intersection
        return out

    def _update(self, a: FloatArray, lo: float, hi: float, criterion: str) -> Ellipsoid:
        """The strip update (see the module's docstring) at the scale given."""
        c, p = self.centre, self.shape
        pa = p @ a
        g = max(float(a @ pa), 0.0)
        m, half = float(a @ c), np.sqrt(g)
        # g = a.P a is rounded to about 1e-16 |a|^2 tr P (dg: 1e-13 |a|^2 tr P covers it
        # up to ~30 dimensions), so half = sqrt(g) by sqrt(g + dg) - sqrt(g): as large as
        # sqrt(dg) for a set flat along a, tiny for a thick one
        dg = FLAT_G_RTOL * float(a @ a) * max(float(np.trace(p)), 0.0)
        rounding = dg / (float(np.sqrt(g + dg)) + half) if dg > 0.0 else 0.0
        lo, hi = clip_slab(lo, hi, m - half, m + half, rounding)
        if (lo <= m - half and hi >= m + half) or flat_along(half, m, rounding):
            return self  # the slab holds the ellipsoid (or touches it where it is flat)
        y, r = 0.5 * (lo + hi), 0.5 * (hi - lo)
        e = y - m
        if self._is_segment:  # its part in the slab is a sub-segment (exact)
            return self._cut_segment(a, lo, hi)
        if r <= 1e-12 * half:  # a hyperplane: the section is an ellipsoid (exact)
            return _section(c, p, pa, g, e, r, ROUND_RTOL * (abs(y) + abs(m)))
        # the slab's middle and the set's a.x are rounded to their magnitudes: a slab so
        # much wider holds every point the exact one does
        r += ROUND_RTOL * (abs(y) + abs(m) + abs(e))
        gn, eps = g / r**2, e**2 / r**2
        if criterion == "volume":
            # a thin set of rank 1 (not a segment, above) is weighed as a flat disc: any
            # weight is sound, and the rank-1 formula has no root for it
            rho = _volume_rho(max(self.rank, min(self.dim, 2)), gn, eps)
        else:
            rho = _trace_rho(float(np.trace(p)), float(pa @ pa) / r**2, gn, eps)
        if rho <= 0.0:
            return self
        den = r * r + rho * g
        delta = 1.0 + rho - rho * e * e / den
        k = rho / den
        shape = delta * (p - k * np.outer(pa, pa))
        shift = (rho * e / den) * pa
        out = _covered(
            c + shift,
            shape,
            # P - k P a a^T P cancels along a down to r^2 / den of P: its rounding is of
            # P's scale, which delta multiplies (a thin cap cut from a round ellipsoid
            # left boundary points 1e-8 outside in q without it)
            delta * (float(np.linalg.norm(p)) + k * float(pa @ pa)),
            np.abs(c) + np.abs(shift),
        )
        # a cut barely past the threshold shrinks the size by less than the cover adds:
        # the input, which holds the intersection too, is then the smaller
        if criterion == "trace" and np.trace(out.shape) >= np.trace(p):
            return self
        if criterion == "volume" and self.rank == self.dim:
            if np.linalg.slogdet(out.shape)[1] >= np.linalg.slogdet(p)[1]:
                return self
        return out


def _covered(c: FloatArray, p: FloatArray, p_scale: float, c_scale: FloatArray) -> Ellipsoid:
    """``E(c, p)`` grown to hold the exact result whose computed shape ``p`` is rounded
    by at most :data:`ROUND_RTOL` ``p_scale`` per entry (``+ delta I``, Weyl, as
    :meth:`Ellipsoid.affine`) and whose computed centre ``c`` by :data:`ROUND_RTOL`
    ``c_scale`` per coordinate (the Minkowski sum with a ball of that radius, the
    minimum-trace member of Schweppe's family). ``ValueError`` when the result is
    beyond the floating-point range."""
    n = c.size
    p = p + (n * ROUND_RTOL * p_scale) * np.eye(n)
    c_rad = ROUND_RTOL * c_scale
    rad2 = float(np.sum(c_rad**2))
    tr = float(np.trace(p))
    if tr > 0.0 and c_rad.any():
        ratio = tr / (n * rad2) if rad2 > 0.0 else np.inf
        if rad2 > 1e-290 and ratio < 1e290:
            q = np.sqrt(ratio)
            p = (1.0 + 1.0 / q) * p + ((1.0 + q) * rad2) * np.eye(n)
        else:  # the squares under- or overflow: the same member, (1 + q) rad^2 = rad^2 +
            # rad sqrt(tr / n), from the radius (a set of 1e-140 at 1e-140: NaN)
            rad, root = _fro(c_rad), np.sqrt(tr) / np.sqrt(n)
            p = (1.0 + rad / root) * p + (rad * (rad + root)) * np.eye(n)
    return _finite(c, p, "the result")


def _finite(c: FloatArray, p: FloatArray, what: str) -> Ellipsoid:
    """``E(c, p)``, or ``ValueError`` (:class:`_OutOfRange`) naming the scale when ``c`` or
    ``p`` is beyond the floating-point range (it was returned as NaN or infinite)."""
    if not (np.isfinite(p).all() and np.isfinite(c).all()):
        raise _OutOfRange(
            f"{what} is beyond the floating-point range (its shape's scale exceeds "
            f"{np.finfo(float).max:.3g}, or its centre's does): rescale the problem"
        )
    return Ellipsoid._make(c, p)


def _section(
    c: FloatArray, p: FloatArray, pa: FloatArray, g: float, e: float, r: float, err_e: float
) -> Ellipsoid:
    """The section of ``E(c, p)`` by the slab ``a.x in y +- r`` (``r`` under 1e-12 of the
    ellipsoid's half-width along ``a``; ``e = y - a.c`` to within ``err_e``), taken as
    the hyperplane section at ``y``: ``E(c + e/g P a, (1 - e^2/g) (P - P a a^T P / g))``,
    ``g = a.P a``. The factor is widened by its rounding and by its change over the
    slab (near a touch it cancels to a rounding difference), and the result covers the
    rounding of the matrix, which cancels along ``a``, and of the centre."""
    shift = (e / g) * pa
    ratio = e * e / g
    f = max(1.0 - ratio, 0.0)
    # rounding of 1 - e^2/g (g itself to about 1e-15 here), then the slab's width
    df = ROUND_RTOL * (1.0 + 4.0 * ratio) + 2.0 * abs(e) * err_e / g
    df += (2.0 * abs(e) * r + r * r) / g
    scale = f + df
    flat = p - np.outer(pa, pa) / g
    return _covered(
        c + shift,
        scale * flat,
        scale * (float(np.linalg.norm(p)) + float(pa @ pa) / g),
        np.abs(c) + np.abs(shift),
    )
