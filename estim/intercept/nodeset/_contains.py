"""Compiled (numba) containment test of the node set (:func:`contains_state`).

A cell admits a state when some ``u`` of its piece puts the state inside the secant
bound of every direction taken from the normals of the cell's node polygons (the
bounds between nodes of :mod:`.bounds`, with the support values of
:func:`._geometry._support`): an outer test, sound, exact at the nodes up to the
directions used.
"""

from __future__ import annotations

import numpy as np
from kalman_vs_infoset.estim.intercept.nodeset._geometry import _support

from kalman_vs_infoset._jit import njit


@njit(cache=True, error_model="numpy")  # x / 0 is inf, as in numpy
def _cell_normals(xy, off, tau, live, table, scale, e_nom, p_out, q_out):
    """Outward edge normals of the two cell-end polygons (``table[1]``, ``table[2]``)
    as ``(Y~, V~)`` directions ``(p, q)``: ``n . (a, zs) = n_a Y~ / (tau scale) + n_z
    e_nom (Y~ + V~ tau)``. A point gives the four axis directions, a segment its two
    normals and both directions along it. Returns their number."""
    n = 0
    nrm = np.empty((4, 2))
    for k in (1, 2):
        j = table[k]
        if j < 0 or not live[j]:
            continue
        t = tau[j]
        m = off[j + 1] - off[j]
        count = 4 if m == 1 else (3 * m if m == 2 else m)
        for r in range(count):
            if m == 1:  # (1, 0), (-1, 0), (0, 1), (0, -1)
                nrm[0, 0] = (1.0, -1.0, 0.0, 0.0)[r]
                nrm[0, 1] = (0.0, 0.0, 1.0, -1.0)[r]
            else:
                v = off[j] + r % m
                w = off[j] + (r % m + 1) % m
                ex, ey = xy[w, 0] - xy[v, 0], xy[w, 1] - xy[v, 1]
                if r < m:  # the edge's normal
                    nrm[0, 0], nrm[0, 1] = ey, -ex
                elif r < 2 * m:  # a segment: along it, both ways
                    nrm[0, 0], nrm[0, 1] = ex, ey
                else:
                    nrm[0, 0], nrm[0, 1] = -ex, -ey
            if nrm[0, 0] == 0.0 and nrm[0, 1] == 0.0:
                continue
            p_out[n] = nrm[0, 0] / (t * scale) + nrm[0, 1] * e_nom
            q_out[n] = nrm[0, 1] * e_nom * t
            n += 1
    return n


@njit(cache=True, error_model="numpy")  # x / 0 is inf, as in numpy
def _cell_admits(xy, off, tau, p, q, nd, table, tau4, alpha, omega, x, lo_u, hi_u, tol,
                 scale, e_nom):  # fmt: skip
    """Whether some ``u`` in ``[lo_u, hi_u]`` puts the state inside every secant bound
    of the directions ``(p, q)[:nd]`` on the cell (``contains``)."""
    hi4 = np.empty((nd, 4))
    for d in range(nd):
        for k in range(4):
            j = table[k]
            tj = tau[j] if j >= 0 else 1.0
            hi4[d, k] = _support(xy, off, j, tj, p[d], q[d], scale, e_nom)[0]
    for left in (True, False):
        i0, i1 = (0, 1) if left else (3, 2)
        t0, t1 = tau4[i0], tau4[i1]
        for d in range(nd):
            f0, f1 = hi4[d, i0], hi4[d, i1]
            if not (np.isfinite(f0) and np.isfinite(f1)):
                continue
            big = 0.0
            for k in range(4):
                if np.isfinite(hi4[d, k]):
                    big = max(big, abs(hi4[d, k]))
            slope = (f1 - f0) / (t1 - t0)
            # d.s(u) = A u + B <= f1 + slope (x u - t1) + tol scale  <=>  k u <= r
            k_u = p[d] * alpha * x + q[d] * omega * x - slope * x
            r = f1 - slope * t1 - -q[d] * alpha + tol * (big + 1e-300)
            if k_u == 0.0 and r < 0.0:
                return False
            if k_u > 0.0:
                hi_u = min(hi_u, r / k_u)
            elif k_u < 0.0:
                lo_u = max(lo_u, r / k_u)
    return lo_u <= hi_u * (1 + 1e-12) + 1e-300


@njit(cache=True, error_model="numpy")  # x / 0 is inf, as in numpy
def contains_state(xy, off, tau, live, cpiece, span, table, tau4, u_lo, u_hi, alpha, omega,
                   x, tol, scale, e_nom):  # fmt: skip
    """The containment test of :meth:`.belief.NodeSet.contains` over the
    cells of a summary (see there)."""
    vmax = 1
    for j in range(off.shape[0] - 1):
        vmax = max(vmax, off[j + 1] - off[j])
    p, q = np.empty(2 * (3 * vmax + 4)), np.empty(2 * (3 * vmax + 4))
    for c in range(cpiece.shape[0]):
        b = cpiece[c]
        lo_u = max(u_lo[b], span[c, 0] / x)
        hi_u = min(u_hi[b], span[c, 1] / x)
        if lo_u > hi_u * (1 + 1e-12):
            continue
        nd = _cell_normals(xy, off, tau, live, table[c], scale, e_nom, p, q)
        if nd == 0:
            continue
        if _cell_admits(xy, off, tau, p, q, nd, table[c], tau4[c], alpha, omega, x, lo_u,
                        hi_u, tol, scale, e_nom):  # fmt: skip
            return True
    return False
