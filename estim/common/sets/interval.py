"""Interval boxes ``[lo, hi] = {x : lo <= x <= hi}`` (componentwise).

Operations
----------
* :meth:`Box.affine` -- the interval hull of ``A [lo, hi] + b``: with centre ``m`` and
  radius ``h``, ``[A m + b -/+ |A| h]`` (interval arithmetic; the hull is exact, the
  box is an outer bound of the parallelotope ``A B``), widened by a bound on its own
  rounding.
* :meth:`Box.minkowski_sum` -- ``[lo1 + lo2, hi1 + hi2]`` (exact).
* :meth:`Box.intersect_strip` -- interval constraint propagation on
  ``y - s <= a.x <= y + s``. Each coordinate is contracted by the backward step
  ``a_i x_i in [y - s - sum_{j != i} max a_j x_j, y + s - sum_{j != i} min a_j x_j]``, the
  sums taken over the *input* box. For one linear constraint this single
  (Jacobi) pass is the exact interval hull of ``box ∩ strip``: the projection onto ``x_i``
  of ``box ∩ strip`` is exactly that interval, because the other coordinates range over a
  product set independently of ``x_i``. (Iterating cannot improve it; hull consistency.)
* :meth:`Box.intersect_halfspace` -- the same with ``a.x <= b``.
* :meth:`Box.support` -- ``h(d) = m.d + h.|d|``; :meth:`Box.contains`.

Rounding is not directed: results are outer bounds in exact arithmetic; the affine
image and the contraction widen their bounds by a bound on its own rounding (a few ulps of the terms
``a_i x_i``), so that it holds the exact hull at any distance from the origin.

References
----------
L. Jaulin, M. Kieffer, O. Didrit & E. Walter, *Applied Interval Analysis*, Springer,
2001 (ch. 4, contractors for linear constraints; forward-backward propagation).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from kalman_vs_infoset.estim.common.sets._common import (
    ROUND_RTOL,
    EmptyIntersectionError,
    FloatArray,
    check_tol,
    clip_slab,
    directions,
    halfspace_bound,
    matrix,
    points,
    strip_bounds,
    vector,
)
from numpy.typing import ArrayLike

from kalman_vs_infoset.numerics.arrays import readonly

__all__ = ["Box", "EmptyIntersectionError"]


@dataclass(frozen=True, eq=False)
class Box:
    """The box ``[lo, hi]`` (immutable; arrays are read-only; ``lo <= hi``)."""

    lo: FloatArray
    hi: FloatArray

    def __post_init__(self) -> None:
        lo = vector(self.lo, name="lo")
        hi = vector(self.hi, lo.size, "hi")
        if np.any(hi < lo):
            raise ValueError("a box needs lo <= hi")
        object.__setattr__(self, "lo", readonly(lo, copy=False))
        object.__setattr__(self, "hi", readonly(hi, copy=False))

    @classmethod
    def _make(cls, lo: FloatArray, hi: FloatArray) -> Box:
        obj = object.__new__(cls)
        object.__setattr__(obj, "lo", readonly(lo, copy=False))
        object.__setattr__(obj, "hi", readonly(hi, copy=False))
        return obj

    @classmethod
    def from_centre(cls, centre: ArrayLike, radius: ArrayLike) -> Box:
        """The box ``[c - r, c + r]`` (``radius`` a number or one per axis, ``>= 0``)."""
        c = vector(centre, name="centre")
        r = np.broadcast_to(np.asarray(radius, dtype=float), c.shape)
        if np.any(r < 0):
            raise ValueError("radius must be >= 0")
        return cls(c - r, c + r)

    @property
    def dim(self) -> int:
        """Dimension ``n`` of the space."""
        return self.lo.size

    @property
    def centre(self) -> FloatArray:
        """Midpoint ``(lo + hi) / 2``."""
        return 0.5 * (self.lo + self.hi)

    @property
    def radius(self) -> FloatArray:
        """Half-widths ``(hi - lo) / 2`` per axis."""
        return 0.5 * (self.hi - self.lo)

    def affine(self, a: ArrayLike, b: ArrayLike | None = None) -> Box:
        """An outer bound of ``{A x + b : x in box}``: ``A m + b -/+ (|A| h + e)``.

        ``e`` bounds the rounding of the computed centre, radius, the two products and
        the sums: ``(n + 4) eps (|A| max(|lo|, |hi|) + |b|)`` (a dot product of length
        ``n`` is within ``n eps`` of its terms' magnitudes; Higham, *Accuracy and
        Stability of Numerical Algorithms*, 2002, sec. 3.1), so that the bound holds in
        floating point too, not only in exact arithmetic.
        """
        a = matrix(a, None, self.dim, "A")
        b_vec = np.zeros(a.shape[0]) if b is None else vector(b, a.shape[0], "b")
        abs_a = np.abs(a)
        m = a @ self.centre + b_vec
        h = abs_a @ self.radius
        magnitude = abs_a @ np.maximum(np.abs(self.lo), np.abs(self.hi)) + np.abs(b_vec)
        h = h + (self.dim + 4) * np.finfo(float).eps * (magnitude + np.abs(m))
        return Box._make(m - h, m + h)

    def translate(self, b: ArrayLike) -> Box:
        """``{x + b : x in box}`` (``b`` finite, of the box's dimension)."""
        b = vector(b, self.dim, "b")
        return Box._make(self.lo + b, self.hi + b)

    def minkowski_sum(self, other: Box) -> Box:
        """``{x + y : x in self, y in other}`` of two boxes: ``[lo1 + lo2, hi1 + hi2]``
        (another family: ``TypeError``; convert it with its ``interval_hull``)."""
        if not isinstance(other, Box):
            raise TypeError(f"minkowski_sum takes a Box, got {type(other).__name__}")
        if other.dim != self.dim:
            raise ValueError("boxes of different dimensions")
        return Box._make(self.lo + other.lo, self.hi + other.hi)

    def support(self, d: ArrayLike) -> FloatArray | float:
        """``h(d) = m.d + h.|d|``; ``d`` of shape (n,) or (k, n), finite (``ValueError``)."""
        d = directions(d, self.dim)
        out = d @ self.centre + np.abs(d) @ self.radius
        return float(out) if np.ndim(out) == 0 else out

    def extremes(self, d: ArrayLike) -> tuple[float, float]:
        """``(min, max)`` of ``d.x`` over the box: ``d.m -/+ |d|.h``."""
        d = vector(d, self.dim, "d")
        m, s = float(d @ self.centre), float(np.abs(d) @ self.radius)
        return m - s, m + s

    def interval_hull(self) -> tuple[FloatArray, FloatArray]:
        """``(lo, hi)``, for the same interface as the other families."""
        return self.lo, self.hi

    def contains(self, x: ArrayLike, tol: float = 1e-9) -> bool | np.ndarray:
        """Whether ``x`` (shape (n,) or (k, n)) lies in the box, up to ``tol`` times the
        largest of 1 and the box's half-width, and a few ulps of the coordinates (as the
        other sets: far from the origin they are rounded to more than that). A point
        with a coordinate that is not finite is not in it (an infinite one was, by
        its own rounding slack); ``ValueError`` for a negative or non-finite ``tol``."""
        check_tol(tol)
        x = points(x, self.dim)
        slack = tol * max(float(self.radius.max(initial=0.0)), 1.0) + ROUND_RTOL * (
            np.abs(x) + np.maximum(np.abs(self.lo), np.abs(self.hi))
        )
        inside = np.all((x >= self.lo - slack) & (x <= self.hi + slack) & np.isfinite(x), axis=-1)
        return bool(inside) if x.ndim == 1 else inside

    def intersect_strip(self, a: ArrayLike, b: float, r: float) -> Box:
        """The interval hull of ``box ∩ {x : |a.x - b| <= r}`` (one contraction pass).

        Raises :class:`EmptyIntersectionError` when the strip misses the box.
        """
        lo, hi = strip_bounds(b, r)
        return self._intersect_slab(vector(a, self.dim, "a"), lo, hi)

    def intersect_halfspace(self, a: ArrayLike, b: float) -> Box:
        """The interval hull of ``box ∩ {x : a.x <= b}``."""
        return self._intersect_slab(vector(a, self.dim, "a"), -np.inf, halfspace_bound(b))

    def _intersect_slab(self, a: FloatArray, lo: float, hi: float) -> Box:
        # forward: the range of each term a_i x_i and of their sum
        t1, t2 = a * self.lo, a * self.hi
        tlo, thi = np.minimum(t1, t2), np.maximum(t1, t2)
        s_lo, s_hi = float(tlo.sum()), float(thi.sum())
        lo, hi = clip_slab(lo, hi, s_lo, s_hi)
        if lo <= s_lo and hi >= s_hi:
            return self
        # backward: a_i x_i in [lo - (others' max), hi - (others' min)] ∩ [tlo_i, thi_i]
        # widened by their rounding (the sums and differences are rounded to the terms'
        # magnitudes: at coordinates of 1e8 a point on the slab's edge fell 1e-8 outside)
        err = ROUND_RTOL * (float(np.abs(tlo).sum() + np.abs(thi).sum()) + abs(s_lo) + abs(s_hi))
        new_tlo = np.maximum(tlo, lo - (s_hi - thi) - err)
        new_thi = np.minimum(thi, hi - (s_lo - tlo) + err)
        new_thi = np.maximum(new_thi, new_tlo)  # touching within rounding
        nz = a != 0.0
        a_safe = np.where(nz, a, 1.0)
        x1, x2 = new_tlo / a_safe, new_thi / a_safe
        # the quotients are rounded too (half an ulp each)
        x_err = ROUND_RTOL * np.maximum(np.abs(x1), np.abs(x2))
        new_lo = np.where(nz, np.minimum(x1, x2) - x_err, self.lo)
        new_hi = np.where(nz, np.maximum(x1, x2) + x_err, self.hi)
        # the contraction never leaves the input box (guards rounding at the edges)
        new_lo = np.clip(new_lo, self.lo, self.hi)
        new_hi = np.clip(new_hi, new_lo, self.hi)
        return Box._make(new_lo, new_hi)
