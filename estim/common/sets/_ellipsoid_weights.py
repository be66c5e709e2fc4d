"""The weights of the ellipsoidal calculus (:mod:`.ellipsoid`): Fogel & Huang's (1982)
strip-update weight ``rho`` under the volume and trace criteria, and Schweppe's (1968)
minimum-volume Minkowski-sum parameter ``p`` (Kurzhanski & Valyi 1997). Each is a
scalar root of the criterion's stationarity condition, written out below; the batched
volume weight serves the slab and attitude ellipsoids' vectorised updates.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import brentq


def _volume_rho(n: int, gn: float, eps: float) -> float:
    """Fogel & Huang's minimum-volume weight (normalised ``G = g/r^2``, ``eps = e^2/r^2``)."""
    a0 = n * (1.0 - eps) - gn
    if a0 >= 0.0:
        return 0.0  # the strip does not cut enough to shrink the volume
    a1 = gn * (2 * n - 1 + eps - gn)
    a2 = (n - 1) * gn * gn
    # a2 > 0 > a0: one positive root; the stable form of it avoids cancellation
    disc = np.sqrt(a1 * a1 - 4.0 * a2 * a0)
    return (-2.0 * a0) / (a1 + disc) if a1 >= 0 else (disc - a1) / (2.0 * a2)


def volume_weights(n, gn, eps):
    """:func:`_volume_rho` over arrays (``n``, ``gn``, ``eps`` broadcast): the batched
    strip updates of the slab and attitude ellipsoids. Zero where the strip does not
    cut enough to shrink the volume."""
    a0 = n * (1.0 - eps) - gn
    a1 = gn * (2 * n - 1 + eps - gn)
    a2 = (n - 1) * gn * gn
    disc = np.sqrt(np.clip(a1 * a1 - 4.0 * a2 * a0, 0.0, None))
    a2s = np.where(a2 > 0, a2, 1.0)
    den = np.where(a1 + disc > 0, a1 + disc, 1.0)
    rho = np.where(a1 >= 0, -2.0 * a0 / den, (disc - a1) / (2.0 * a2s))
    return np.where(a0 >= 0.0, 0.0, rho)


def _trace_rho(tr: float, mn: float, gn: float, eps: float) -> float:
    """Minimum-trace weight. With ``D = 1 + G rho``, ``tr P+ = A(rho) B(rho) / D^2`` where
    ``A = G rho^2 + (1 + G - eps) rho + 1`` and ``B = T + (T G - M) rho`` (``T = tr P``,
    ``M = |P a|^2 / r^2``); stationary points are the roots of ``(A B)' D - 2 G A B``."""
    b1 = tr * gn - mn
    n3, n2, n1, n0 = gn * b1, gn * tr + (1.0 + gn - eps) * b1, (1.0 + gn - eps) * tr + b1, tr
    # (A B)' D - 2 G A B, expanded (the rho^3 terms of the two products partly cancel)
    roots = np.roots([gn * n3, 3.0 * n3, 2.0 * n2 - gn * n1, n1 - 2.0 * gn * n0])
    real = roots.real[np.abs(roots.imag) < 1e-9 * (1.0 + np.abs(roots))]
    cands = np.concatenate([[0.0], real[real > 0.0]])
    size = (((n3 * cands + n2) * cands + n1) * cands + n0) / (1.0 + gn * cands) ** 2
    return float(cands[np.argmin(size)])


def _volume_sum_parameter(p1, p2, rank1: int, rank2: int, fallback: float) -> float:
    n = p1.shape[0]
    if rank2 == n:
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            lam = eigh(p1, p2, eigvals_only=True)
        flip = False
    elif rank1 == n:
        with np.errstate(over="ignore", under="ignore", invalid="ignore"):
            lam = eigh(p2, p1, eigvals_only=True)
        flip = True
    else:
        return fallback
    if not (np.isfinite(lam).all() and lam.max() < 1e290):
        # relative eigenvalues beyond the float range (a ball of 1 plus one of 1e-155:
        # 1e310): the trace choice, sound as any member
        return fallback
    lam = np.clip(lam, 0.0, None)
    lo, hi = np.sqrt(lam.min()), np.sqrt(lam.max())
    if hi - lo <= 1e-12 * hi:
        p = hi
    else:
        # sum (p^2 - l_i)/(l_i + p) = 0  <=>  sum 1/(l_i + p) = n / (p (p + 1))
        def f(q: float) -> float:
            return float(np.sum((q * q - lam) / (lam + q)))

        # f <= 0 at sqrt(l_min) and tends to minus the number of l_i > 0 as q -> 0+
        # (f(0) itself is 0/0 for a singular P1); a floor of 1e-9 hi could lie past the
        # root (l = 1e-20, 1e20: f = 9 there) and brentq then found no sign change
        a = lo if lo > 0.0 else 1e-9 * hi
        while f(a) > 0.0 and a > 1e-300:
            a *= 1e-3
        if f(a) >= 0.0:
            p = a
        elif f(hi) <= 0.0:  # rounding at the top end
            p = hi
        else:
            p = brentq(f, a, hi, xtol=1e-14 * hi, rtol=1e-12)
    return 1.0 / p if flip else p
