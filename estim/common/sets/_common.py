"""Helpers shared by the set representations: array checks, slabs, emptiness."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: Relative tolerance below which a slab that misses a set by rounding is taken to touch it.
TOUCH_RTOL = 1e-12

#: A bound on the relative rounding of the few operations behind one computed number
#: (the outer updates widen their results by it times the magnitudes involved).
ROUND_RTOL = 8 * np.finfo(float).eps


class EmptyIntersectionError(ValueError):
    """The intersection is empty: the measurement is inconsistent with the set."""


def vector(x: ArrayLike, n: int | None = None, name: str = "vector") -> FloatArray:
    """A finite 1-D float copy of ``x`` (of length ``n`` when given; a number is a vector
    of length 1). ``ValueError`` for an array of two or more dimensions (a ``(2, 2)``
    bound was flattened into a 4-D box) and for an empty one (a set of dimension 0:
    its operations failed deep in numpy or scipy)."""
    v = np.array(x, dtype=float)
    if v.ndim > 1:
        raise ValueError(f"{name} must be one-dimensional (shape (n,)), got shape {v.shape}")
    v = v.reshape(-1)
    if n is not None and v.size != n:
        raise ValueError(f"{name} must have length {n}, got {v.size}")
    if v.size == 0:
        raise ValueError(f"{name} must have at least one coordinate (dimension >= 1), got none")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be finite")
    return v


def directions(d: ArrayLike, n: int) -> FloatArray:
    """``d`` as finite float directions of dimension ``n`` (shape (n,) or (k, n)), for a
    support function: the same checks as :func:`vector` for one direction (a NaN
    direction gave a NaN support, another length a numpy matmul error)."""
    a = points(d, n, "d")
    if not np.isfinite(a).all():
        raise ValueError("d must be finite")
    return a


def check_tol(tol: float) -> None:
    """A containment tolerance must be finite and ``>= 0`` (``ValueError``)."""
    if not (np.isfinite(tol) and tol >= 0):
        raise ValueError(f"tol must be finite and >= 0, got {tol!r}")


def points(x: ArrayLike, n: int, name: str = "points") -> FloatArray:
    """``x`` as float points of dimension ``n`` (shape (n,) or (k, n)), for a containment
    test: a point of another dimension is an error, not broadcast against the set. NaN
    is kept (never inside: every comparison with it is false)."""
    a = np.asarray(x, dtype=float)
    if a.ndim not in (1, 2) or a.shape[-1] != n:
        raise ValueError(f"{name} must have shape ({n},) or (k, {n}), got {a.shape}")
    return a


def matrix(m: ArrayLike, rows: int | None, cols: int | None, name: str) -> FloatArray:
    """A finite 2-D float copy of ``m`` with the given shape (``None``: any number of
    columns, or of rows but at least one)."""
    a = np.array(m, dtype=float)
    if a.ndim != 2 or (rows is not None and a.shape[0] != rows):
        raise ValueError(f"{name} must be a 2-D array with {rows} rows, got shape {a.shape}")
    if rows is None and a.shape[0] == 0:  # an image of dimension 0
        raise ValueError(f"{name} must have at least one row, got shape {a.shape}")
    if cols is not None and a.shape[1] != cols:
        raise ValueError(f"{name} must have {cols} columns, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite")
    return a


def strip_bounds(b: float, r: float) -> tuple[float, float]:
    """``{x : |a.x - b| <= r}`` as the slab ``lo <= a.x <= hi``."""
    b, r = float(b), float(r)
    if not (np.isfinite(b) and np.isfinite(r)) or r < 0:
        raise ValueError(f"a strip needs a finite centre and a finite radius >= 0, got {b}, {r}")
    return b - r, b + r


def halfspace_bound(b: float) -> float:
    """The bound of ``{x : a.x <= b}``: a number, ``+inf`` (no cut) included, not NaN."""
    b = float(b)
    if np.isnan(b):
        raise ValueError("a halfspace needs a bound that is a number (or +inf), got nan")
    return b


def flat_along(half: float, m: float, rounding: float) -> bool:
    """Whether a set whose ``a.x`` spans ``m +- half`` is flat along ``a`` (a point, or a
    segment or section normal to ``a``): ``half`` is within ``rounding`` (the absolute
    rounding of ``half`` as the family computes it) plus :data:`TOUCH_RTOL` of ``|m|``.
    A slab that :func:`clip_slab` found touching such a set holds it to rounding, and
    the update formulas, which divide by ``half``, would return NaN or a set moved by
    rounding noise divided by ``half``."""
    return not half > TOUCH_RTOL * abs(m) + rounding


def clip_slab(
    lo: float, hi: float, set_lo: float, set_hi: float, rounding: float = 0.0
) -> tuple[float, float]:
    """The slab ``[lo, hi]`` clipped to the set's range ``[set_lo, set_hi]`` of ``a.x``.

    The set's intersection with the clipped slab is the same set, and the clipped slab
    is the tighter measurement to feed an outer update. Raises
    :class:`EmptyIntersectionError` when the ranges are disjoint by more than rounding:
    :data:`TOUCH_RTOL` of their scale, plus ``rounding``, the absolute rounding of the
    set's range as its family computes it (a strip through a point of a set flat along
    ``a`` may miss its computed range by that much). The scale is the set's range and
    the slab's finite ends: the slab's ends are rounded to their own magnitude (a strip
    of radius 1e-3 whose edge touches a point at 1e-8 missed it by 1e-19, which the
    set's scale alone took for a miss).
    """
    new_lo, new_hi = max(lo, set_lo), min(hi, set_hi)
    if new_lo > new_hi:
        ends = [abs(v) for v in (lo, hi) if np.isfinite(v)]
        scale = max(abs(set_lo), abs(set_hi), set_hi - set_lo, *ends, 1e-300)
        if new_lo - new_hi > TOUCH_RTOL * scale + rounding:
            raise EmptyIntersectionError(
                f"slab [{lo:.6g}, {hi:.6g}] misses the set's range [{set_lo:.6g}, {set_hi:.6g}]"
            )
        new_lo = new_hi = 0.5 * (new_lo + new_hi)
    return new_lo, new_hi
