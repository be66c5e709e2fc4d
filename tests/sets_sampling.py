"""Random sets and points inside them, for the brute-force containment tests of estim.common.sets.

Every sampler returns interior points *and* extreme points (the sphere for an
ellipsoid, sign vertices for a zonotope, corners for a box), so that an outer bound
that cuts a corner is caught.
"""

from __future__ import annotations

import numpy as np
from kalman_vs_infoset.estim.common.sets import Box, Ellipsoid, Zonotope


def random_ellipsoid(rng: np.random.Generator, n: int, rank: int | None = None) -> Ellipsoid:
    rank = n if rank is None else rank
    f = rng.normal(size=(n, rank)) * rng.uniform(0.2, 2.0, size=rank)
    return Ellipsoid(rng.normal(size=n) * 3.0, f @ f.T)


def random_zonotope(rng: np.random.Generator, n: int, m: int) -> Zonotope:
    return Zonotope(rng.normal(size=n) * 3.0, rng.normal(size=(n, m)))


def random_box(rng: np.random.Generator, n: int) -> Box:
    c = rng.normal(size=n) * 3.0
    r = rng.uniform(0.1, 2.0, size=n)
    return Box(c - r, c + r)


def sample_ellipsoid(e: Ellipsoid, rng: np.random.Generator, k: int = 400) -> np.ndarray:
    """Points of ``e`` (half on its boundary). The eigenvalues a rank-deficient shape
    has at rounding level (+-1e-18 for a segment) are zeroed, as ``Ellipsoid.rank``
    reads them: their square roots (1e-9) put samples off the set's affine hull, and a
    strip nearly parallel to the hull then crossed them 1e-7 beyond the exact
    intersection (``make fuzz``, seed 20261204001)."""
    lam, vec = np.linalg.eigh(e.shape)
    lam = np.where(lam > 1e-12 * max(lam.max(), 1e-300), lam, 0.0)
    root = vec * np.sqrt(lam)
    u = rng.normal(size=(k, e.dim))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    u[k // 2 :] *= rng.uniform(size=(k - k // 2, 1)) ** (1.0 / e.dim)  # half on the sphere
    return e.centre + u @ root.T


def sample_zonotope(z: Zonotope, rng: np.random.Generator, k: int = 400) -> np.ndarray:
    m = z.n_generators
    xi = rng.uniform(-1.0, 1.0, size=(k, m))
    xi[: k // 2] = np.sign(xi[: k // 2])  # half are vertices (sign vectors)
    return z.centre + xi @ z.generators.T


def sample_box(b: Box, rng: np.random.Generator, k: int = 400) -> np.ndarray:
    u = rng.uniform(size=(k, b.dim))
    u[: k // 2] = np.round(u[: k // 2])  # half are corners
    return b.lo + u * (b.hi - b.lo)


def cutting_strip(
    pts: np.ndarray, rng: np.random.Generator, min_frac: float = 0.02
) -> tuple[np.ndarray, float, float]:
    """A random strip ``|a.x - b| <= r`` that cuts the point cloud's range of ``a.x``."""
    a = rng.normal(size=pts.shape[1])
    s = pts @ a
    lo, hi = s.min(), s.max()
    b = rng.uniform(lo, hi)
    r = rng.uniform(min_frac, 0.6) * (hi - lo)
    return a, float(b), float(r)


def points_in_slab(pts: np.ndarray, a: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Sample points of a convex set inside ``lo <= a.x <= hi`` plus points where the
    segments joining an inside and an outside sample cross the slab's boundary
    (inside the set by convexity, on the boundary of the exact intersection)."""
    s = pts @ a
    inside = (s >= lo) & (s <= hi)
    ins, outs = pts[inside], pts[~inside]
    if len(ins) == 0 or len(outs) == 0:
        return ins
    n = min(len(ins), len(outs))
    p, q = ins[:n], outs[:n]
    sp, sq = p @ a, q @ a
    level = np.where(sq > hi, hi, lo)
    t = (level - sp) / (sq - sp)
    return np.vstack([ins, p + t[:, None] * (q - p)])


def edge_slab(ax: float, cut: str, width: float = 0.0) -> tuple[float, float]:
    """A slab with ``a.x = ax`` on its edge: the halfspace ``below`` or ``above`` it, a
    ``thin_strip`` of ``width`` above it, or the ``plane`` through it."""
    return {
        "below": (-np.inf, ax),
        "above": (ax, np.inf),
        "thin_strip": (ax, ax + width),
        "plane": (ax, ax),
    }[cut]


def cut_by_slab(s, a: np.ndarray, lo: float, hi: float, *args):
    """``s`` (any set family) cut by ``lo <= a.x <= hi``: a halfspace where one end is
    infinite, a strip otherwise (``args``: the family's options, e.g. a criterion)."""
    if np.isinf(lo):
        return s.intersect_halfspace(a, hi, *args)
    if np.isinf(hi):
        return s.intersect_halfspace(-a, -lo, *args)
    return s.intersect_strip(a, 0.5 * (lo + hi), 0.5 * (hi - lo), *args)
