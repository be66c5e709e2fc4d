"""The forecast miss over the node slices' vertices, compiled (the game adversary asks
for it every step: :meth:`.belief.NodeSet.attained` with a
:class:`~estim.intercept.costs.MissForecast`).

The arithmetic is the numpy path's, operation for operation (``x = tau / u``, ``w =
zs / (u e)^2``, ``omega = w e / x^2``, ``Pi = omega x t + sign(omega) nu t^2 / 2`` with
``t = x / e``), in the same order of rows (the three speeds of a piece, each over the
kept vertices), so both give the same extremes to the last bit (a test compares them).
"""

from __future__ import annotations

import numpy as np

from kalman_vs_infoset._jit import njit


@njit(cache=True)
def _sign(v):
    if v > 0.0:
        return 1.0
    if v < 0.0:
        return -1.0
    return 0.0 if v == 0.0 else v  # +0.0 for either zero, nan for nan (np.sign)


@njit(cache=True)
def forecast_attained(
    xy, off, piece, label, t, hard_lo, hard_hi, u_lo, u_hi, e_nom, nu, alpha_scale
):  # fmt: skip
    """Rows ``(alpha, omega, x)`` of the smallest and largest forecast miss over the
    vertices of nodes within their piece's hard limits, at the fast end, the middle and
    the slow end of the piece's ``u`` (in that order; the first row on a tie, the first
    ``nan`` if any, as ``np.argmin``/``np.argmax``). Returns ``(found, v_lo, row_lo,
    v_hi, row_hi)``; ``found`` is False when no vertex is kept."""
    n = off.shape[0] - 1
    v_lo, v_hi = np.nan, np.nan
    row_lo, row_hi = np.full(3, np.nan), np.full(3, np.nan)
    found, nan_seen = False, False  # found: a first row was taken
    for k in range(3):
        for i in range(n):
            p = piece[i]
            lab = label[i]
            tol = 1e-9 * abs(lab)
            if not (lab >= hard_lo[p] - tol and lab <= hard_hi[p] + tol):
                continue
            if k == 0:
                u = u_lo[p]
            elif k == 1:
                u = 0.5 * (u_lo[p] + u_hi[p])
            else:
                u = u_hi[p]
            tau = lab - t
            x = tau / u
            ue = u * e_nom
            for j in range(off[i], off[i + 1]):
                w = xy[j, 1] / (ue * ue)
                omega = w * e_nom / (x * x)
                t_go = x / e_nom
                val = omega * x * t_go + _sign(omega) * nu * (t_go * t_go) / 2.0
                if nan_seen:
                    continue
                if not found or val != val:
                    # the first row starts both ends; the first nan is both ends for
                    # good (np.argmin / np.argmax)
                    found, nan_seen = True, val != val
                    v_lo, v_hi = val, val
                    row_lo[0], row_lo[1], row_lo[2] = xy[j, 0] * alpha_scale, omega, x
                    row_hi[:] = row_lo
                    continue
                if val < v_lo:
                    v_lo = val
                    row_lo[0], row_lo[1], row_lo[2] = xy[j, 0] * alpha_scale, omega, x
                if val > v_hi:
                    v_hi = val
                    row_hi[0], row_hi[1], row_hi[2] = xy[j, 0] * alpha_scale, omega, x
    return found, v_lo, row_lo, v_hi, row_hi
