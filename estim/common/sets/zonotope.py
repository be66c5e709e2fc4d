"""Zonotopes ``Z(c, G) = {c + G xi : |xi|_inf <= 1}`` and strip-based state estimation.

``G`` is ``n x m``, one generator per column (``m = 0`` is the point ``c``). The linear
map, Minkowski sum, support function, interval hull and containment are exact; the
strip intersection and the order reduction return outer bounds.

Operations
----------
* :meth:`Zonotope.affine` -- ``A Z + b = Z(A c + b, A G)``.
* :meth:`Zonotope.minkowski_sum` -- ``Z(c1 + c2, [G1 G2])``.
* :meth:`Zonotope.intersect_strip` -- Alamo, Bravo & Camacho (2005): for a strip
  ``S = {x : |y - a.x| <= s}`` and *any* ``lam in R^n``,
  ``Z ∩ S ⊂ Z(c + lam (y - a.c), [(I - lam a^T) G, s lam])``. (Write ``x = c + G xi`` and
  ``y - a.x = s eta``, ``|eta| <= 1``; then ``x = c + lam (y - a.c) + (I - lam a^T) G xi
  - s lam eta``.) We use their choice that minimises the **Frobenius norm** of the new
  generator matrix (the "F-radius"): ``lam* = G G^T a / (a^T G G^T a + s^2)``. The strip
  is first clipped to the range of ``a.x`` over ``Z`` (same intersection, tighter
  bound), then widened by the rounding of ``y - a.c`` (which ``lam`` multiplies: the
  widened ``s lam`` covers it). Each update adds one generator; see :meth:`reduce`.
* :meth:`Zonotope.reduce` -- order reduction to at most ``max_generators`` columns
  (``>= n``): keep the ``max_generators - n`` largest generators and replace the others
  by their interval hull ``diag(sum |g|)`` (``n`` axis-aligned generators). Ranking by
  ``|g|_1 - |g|_inf`` is Girard's (2005) box method (default); ranking by ``|g|_2`` is
  Combastel's (2003).
* :meth:`Zonotope.support` -- ``h(d) = c.d + sum_j |g_j.d|``.
* :meth:`Zonotope.contains` -- exact membership, by the facet inequalities (all
  ``(n-1)``-subsets of generators) when there are few, otherwise by a linear programme
  (scipy HiGHS): ``min t`` subject to ``G xi = x - c``, ``|xi_j| <= t``; inside iff ``t <= 1``.
* :meth:`Zonotope.vertices_2d` -- the polygon of a planar zonotope, counter-clockwise,
  by summing generators sorted by angle (for plotting and exact comparisons).

References
----------
T. Alamo, J. M. Bravo & E. F. Camacho, "Guaranteed state estimation by zonotopes",
Automatica 41(6), 1035-1043, 2005.
A. Girard, "Reachability of uncertain linear systems using zonotopes", HSCC 2005,
LNCS 3414, 291-305.
C. Combastel, "A state bounding observer based on zonotopes", European Control
Conference, 2003.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from itertools import combinations
from math import comb
from typing import Literal

import numpy as np
from kalman_vs_infoset.estim.common.sets._common import (
    ROUND_RTOL,
    TOUCH_RTOL,
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
from numpy.typing import ArrayLike
from scipy.optimize import linprog

from kalman_vs_infoset.numerics.arrays import readonly

__all__ = ["EmptyIntersectionError", "Zonotope"]


@dataclass(frozen=True, eq=False)
class Zonotope:
    """The zonotope ``{c + G xi : |xi|_inf <= 1}`` (immutable; arrays are read-only).

    Parameters
    ----------
    centre : array_like, shape (n,)
        ``n >= 1`` (``ValueError`` for an empty centre or one of two or more dimensions,
        as for the box and the ellipsoid).
    generators : array_like, shape (n, m)
        One generator per column; ``m`` may be 0.
    """

    centre: FloatArray
    generators: FloatArray

    def __post_init__(self) -> None:
        c = vector(self.centre, name="centre")
        g = np.array(self.generators, dtype=float)
        if g.size == 0:
            g = np.zeros((c.size, 0))
        g = matrix(g, c.size, None, "generators")
        object.__setattr__(self, "centre", readonly(c, copy=False))
        object.__setattr__(self, "generators", readonly(g, copy=False))

    @classmethod
    def _make(cls, c: FloatArray, g: FloatArray) -> Zonotope:
        """Internal constructor: drops zero generators, no other checks."""
        obj = object.__new__(cls)
        keep = np.any(g != 0.0, axis=0)
        object.__setattr__(obj, "centre", readonly(c, copy=False))
        object.__setattr__(
            obj, "generators", readonly(np.ascontiguousarray(g[:, keep]), copy=False)
        )
        return obj

    @classmethod
    def from_box(cls, lo: ArrayLike, hi: ArrayLike) -> Zonotope:
        """The box ``[lo, hi]`` as ``Z((lo + hi)/2, diag((hi - lo)/2))``."""
        lo = vector(lo, name="lo")
        hi = vector(hi, lo.size, "hi")
        if np.any(hi < lo):
            raise ValueError("a box needs lo <= hi")
        return cls._make(0.5 * (lo + hi), np.diag(0.5 * (hi - lo)))

    @property
    def dim(self) -> int:
        """Dimension ``n`` of the space."""
        return self.centre.size

    @property
    def n_generators(self) -> int:
        """Number of generators (columns of ``G``)."""
        return self.generators.shape[1]

    # -- exact operations ----------------------------------------------------------
    def affine(self, a: ArrayLike, b: ArrayLike | None = None) -> Zonotope:
        """``{A x + b : x in Z} = Z(A c + b, A G)``."""
        a = matrix(a, None, self.dim, "A")
        c = a @ self.centre + (0.0 if b is None else vector(b, a.shape[0], "b"))
        return Zonotope._make(c, a @ self.generators)

    def translate(self, b: ArrayLike) -> Zonotope:
        """``Z(c + b, G)``."""
        return Zonotope._make(self.centre + vector(b, self.dim, "b"), self.generators)

    def minkowski_sum(self, other: Zonotope) -> Zonotope:
        """``Z1 + Z2 = Z(c1 + c2, [G1 G2])`` (another family: ``TypeError``)."""
        if not isinstance(other, Zonotope):
            raise TypeError(f"minkowski_sum takes a Zonotope, got {type(other).__name__}")
        if other.dim != self.dim:
            raise ValueError("zonotopes of different dimensions")
        g = np.hstack([self.generators, other.generators])
        return Zonotope._make(self.centre + other.centre, g)

    def support(self, d: ArrayLike) -> FloatArray | float:
        """``h(d) = c.d + sum_j |g_j.d|``; ``d`` of shape (n,) or (k, n), finite
        (``ValueError``)."""
        d = directions(d, self.dim)
        out = d @ self.centre + np.abs(d @ self.generators).sum(axis=-1)
        return float(out) if np.ndim(out) == 0 else out

    def extremes(self, d: ArrayLike) -> tuple[float, float]:
        """``(min, max)`` of ``d.x`` over ``Z``."""
        d = vector(d, self.dim, "d")
        m, s = float(d @ self.centre), float(np.abs(d @ self.generators).sum())
        return m - s, m + s

    def interval_hull(self) -> tuple[FloatArray, FloatArray]:
        """The smallest box containing ``Z``: ``c -/+ sum_j |g_j|``."""
        r = np.abs(self.generators).sum(axis=1)
        return self.centre - r, self.centre + r

    def contains(
        self, x: ArrayLike, tol: float = 1e-9, method: Literal["auto", "lp", "facets"] = "auto"
    ) -> bool | np.ndarray:
        """Whether ``x`` (shape (n,) or (k, n)) lies in ``Z``; exact up to ``tol`` times
        the zonotope's size and a few ulps of the coordinates (:data:`ROUND_RTOL`).

        ``"facets"``: for a full-dimensional ``Z`` every facet normal is orthogonal to
        ``n - 1`` generators, so ``Z = {x : |d.(x - c)| <= sum_j |d.g_j|}`` over the
        normals ``d`` of all ``(n-1)``-subsets of generators (vectorised over points;
        used by ``"auto"`` when there are at most 4096 subsets). ``"lp"``: the linear
        programme ``min t`` s.t. ``|G xi - (x - c)| <= tol s``, ``|xi_j| <= t``, inside
        iff ``t <= 1 + tol`` (``s`` the largest row sum of ``|G|``), solved by HiGHS to
        feasibility tolerances of 1e-10 (its default 1e-7 read vertices of flat zonotopes
        1e-8 outside); points outside the interval hull are rejected without it.

        A point with a coordinate that is not finite is not in it, as for the box and
        the ellipsoid (an infinite one made the programme's bounds infinite, which
        linprog refuses, and a zonotope of no generators held it by its own slack).
        """
        if method not in ("auto", "lp", "facets"):
            raise ValueError(f"method must be 'auto', 'lp' or 'facets', got {method!r}")
        check_tol(tol)
        x = points(x, self.dim)
        pts = np.atleast_2d(x)
        finite = np.asarray(np.isfinite(pts).all(axis=1))  # (an array: mypy)
        if not finite.all():  # answered below; the centre stands in for them meanwhile
            pts = np.where(finite[:, None], pts, self.centre)
        scale = max(float(np.abs(self.generators).sum(axis=1).max(initial=0.0)), 1.0)
        # and a few ulps of the coordinates: far from the origin (1e7) they are rounded
        # to more than tol times the zonotope's size
        slack = tol * scale + ROUND_RTOL * (
            np.abs(pts).sum(axis=1) + float(np.abs(self.centre).sum())
        )
        normals = self._facet_normals if method != "lp" else None
        if method == "facets" and normals is None:
            raise ValueError("facets need a full-dimensional zonotope with few generators")
        if normals is not None:
            h = np.abs(normals @ self.generators).sum(axis=1)
            dist = np.abs((pts - self.centre) @ normals.T) - h
            inside = np.all(dist <= slack[:, None], axis=1)
        else:
            lo, hi = self.interval_hull()
            inside = np.all((pts >= lo - slack[:, None]) & (pts <= hi + slack[:, None]), axis=1)
            for i in np.flatnonzero(inside):
                inside[i] = self._lp_norm(pts[i] - self.centre, slack[i]) <= 1.0 + tol
        inside &= finite
        return bool(inside[0]) if x.ndim == 1 else inside

    @cached_property
    def _facet_normals(self) -> FloatArray | None:
        """Unit normals of all ``(n-1)``-subsets of generators, or ``None`` when ``Z`` is
        flat or the subsets are too many. A subset of lower rank gives some normal of it,
        a valid but redundant inequality."""
        n, m = self.generators.shape
        if m < n or comb(m, n - 1) > 4096 or np.linalg.matrix_rank(self.generators) < n:
            return None
        if n == 1:
            return np.ones((1, 1))
        subsets = np.array(list(combinations(range(m), n - 1)))
        rows = self.generators.T[subsets]  # (k, n-1, n)
        return readonly(np.linalg.svd(rows, full_matrices=True)[2][:, -1, :], copy=False)

    def _lp_norm(self, d: FloatArray, slack: float) -> float:
        """``min |xi|_inf`` with ``|G xi - d| <= slack`` (``inf`` when infeasible).

        Each row ``|G_i xi - d_i| <= slack`` is divided by its own size (the same
        constraint): at coordinates of 1e7 HiGHS stopped on flat zonotopes with
        "numerical difficulties" (status 4), read as infeasible, and points deep inside
        were called outside. A status other than solved or infeasible is retried with
        the interior-point solver."""
        g = self.generators
        n, m = g.shape
        if m == 0:
            return 0.0 if np.all(np.abs(d) <= slack) else np.inf
        size = np.maximum(np.abs(g).max(axis=1), np.maximum(np.abs(d), slack))
        size = np.where(size > 0.0, size, 1.0)
        g, d, row_slack = g / size[:, None], d / size, slack / size
        eye, one = np.eye(m), np.ones((m, 1))
        a_ub = np.block([[eye, -one], [-eye, -one], [g, np.zeros((n, 1))], [-g, np.zeros((n, 1))]])
        b_ub = np.concatenate([np.zeros(2 * m), d + row_slack, row_slack - d])
        cost = np.zeros(m + 1)
        cost[-1] = 1.0
        for method in ("highs", "highs-ipm"):
            res = linprog(
                cost,
                A_ub=a_ub,
                b_ub=b_ub,
                bounds=[(None, None)] * m + [(0, None)],
                method=method,
                options={
                    "primal_feasibility_tolerance": 1e-10,
                    "dual_feasibility_tolerance": 1e-10,
                },
            )
            if res.status == 0:
                return float(res.fun)
            if res.status == 2:  # infeasible: outside
                return np.inf
        return np.inf  # neither solver decided: outside, as an infeasible programme

    def vertices_2d(self) -> FloatArray:
        """Vertices of a planar zonotope, counter-clockwise, shape (k, 2).

        Generators are flipped into the upper half-plane and sorted by angle; the walk
        from ``c - sum g`` adds ``2 g`` in that order, then subtracts it.
        """
        if self.dim != 2:
            raise ValueError("vertices_2d needs a planar zonotope")
        g = self.generators.T.copy()
        if len(g) == 0:
            return self.centre[None, :].copy()
        flip = (g[:, 1] < 0) | ((g[:, 1] == 0) & (g[:, 0] < 0))
        g[flip] *= -1.0
        g = g[np.argsort(np.arctan2(g[:, 1], g[:, 0]), kind="stable")]
        steps = np.vstack([2.0 * g, -2.0 * g])
        start = self.centre - g.sum(axis=0)
        return start + np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)[:-1]])

    # -- outer bounds ----------------------------------------------------------------
    def intersect_strip(self, a: ArrayLike, b: float, r: float) -> Zonotope:
        """A zonotope containing ``Z ∩ {x : |a.x - b| <= r}`` (Alamo et al. 2005, F-radius
        choice of ``lam``). Raises :class:`EmptyIntersectionError` if the strip misses."""
        lo, hi = strip_bounds(b, r)
        return self._intersect_slab(vector(a, self.dim, "a"), lo, hi)

    def intersect_halfspace(self, a: ArrayLike, b: float) -> Zonotope:
        """A zonotope containing ``Z ∩ {x : a.x <= b}`` (the same update on the slab
        between the zonotope's minimum of ``a.x`` and ``b``)."""
        return self._intersect_slab(vector(a, self.dim, "a"), -np.inf, halfspace_bound(b))

    def _intersect_slab(self, a: FloatArray, lo: float, hi: float) -> Zonotope:
        c, g = self.centre, self.generators
        ga = g.T @ a
        m, half = float(a @ c), float(np.abs(ga).sum())
        # |a.g_i| is rounded to about 1e-16 |a| |g_i|: generously, TOUCH_RTOL of the sum
        rounding = TOUCH_RTOL * float(np.linalg.norm(a)) * float(np.linalg.norm(g, axis=0).sum())
        lo, hi = clip_slab(lo, hi, m - half, m + half, rounding)
        if (lo <= m - half and hi >= m + half) or flat_along(half, m, rounding):
            return self  # the slab holds the zonotope (or touches it where it is flat)
        y, s = 0.5 * (lo + hi), 0.5 * (hi - lo)
        # y - m is rounded to their magnitudes, and lam multiplies that error along lam
        # (by 45 for a cut almost along a generator): the strip's own generator covers it
        s += ROUND_RTOL * (abs(y) + abs(m))
        gga = g @ ga
        lam = gga / (float(ga @ ga) + s * s)
        new_g = np.hstack([g - np.outer(lam, ga), (s * lam)[:, None]])
        return Zonotope._make(c + lam * (y - m), new_g)

    def reduce(
        self, max_generators: int, method: Literal["girard", "combastel"] = "girard"
    ) -> Zonotope:
        """A zonotope with at most ``max_generators`` generators containing ``Z``.

        The ``m - max_generators + n`` smallest generators (ranked by ``|g|_1 - |g|_inf``
        for Girard, ``|g|_2`` for Combastel) are replaced by the ``n`` generators of
        their interval hull.
        """
        n, m = self.generators.shape
        if isinstance(max_generators, bool) or int(max_generators) != max_generators:
            raise ValueError(f"max_generators must be an integer, got {max_generators!r}")
        max_generators = int(max_generators)
        if max_generators < n:
            raise ValueError(f"max_generators must be at least the dimension {n}")
        if m <= max_generators:
            return self
        g = self.generators
        if method == "girard":
            rank = np.abs(g).sum(axis=0) - np.abs(g).max(axis=0)
        elif method == "combastel":
            rank = np.linalg.norm(g, axis=0)
        else:
            raise ValueError(f"unknown reduction method {method!r}")
        order = np.argsort(rank, kind="stable")
        n_boxed = m - max_generators + n
        boxed, kept = order[:n_boxed], np.sort(order[n_boxed:])
        box = np.diag(np.abs(g[:, boxed]).sum(axis=1))
        return Zonotope._make(self.centre, np.hstack([g[:, kept], box]))
