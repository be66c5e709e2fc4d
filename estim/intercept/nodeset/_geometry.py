"""Compiled (numba) geometry of the node set: bounds between nodes.

The derivation is in :mod:`.bounds`: for a fixed direction the support
function of the body's slices is concave along the body, so the secants of its
values at the nodes around a cell bound it there. :func:`summarise` answers, in one
pass over the cells, everything the node set is asked (the zero-effort miss, the
bearing, the range, per-piece extents); the containment test is in :mod:`._contains`.
"""

from __future__ import annotations

import numpy as np

from kalman_vs_infoset._jit import njit


@njit(cache=True)
def _support(xy, off, j, tau, p, q, scale, e_nom):
    """Max and min of ``p Y~ + q V~`` over node ``j``'s polygon (-inf/inf if empty)."""
    hi, lo = -np.inf, np.inf
    if j < 0:
        return hi, lo
    ca = scale * (p * tau - q)
    cz = q / (e_nom * tau)
    for v in range(off[j], off[j + 1]):
        val = xy[v, 0] * ca + xy[v, 1] * cz
        hi = max(hi, val)
        lo = min(lo, val)
    return hi, lo


@njit(cache=True)
def _secant(t4, f4, lo_s, hi_s, rtol):
    """Max over ``[lo_s, hi_s]`` of the concave bound from four samples (see
    :func:`.bounds.secant_bound`); returns the bound and its argument."""
    f0, f1, f2, f3 = f4[0], f4[1], f4[2], f4[3]
    t0, t1, t2, t3 = t4[0], t4[1], t4[2], t4[3]
    if not np.isfinite(f1) and not np.isfinite(f2):
        return -np.inf, lo_s
    has_l = np.isfinite(f0) and np.isfinite(f1) and t1 > t0
    has_r = np.isfinite(f2) and np.isfinite(f3) and t3 > t2
    s_l = (f1 - f0) / (t1 - t0) if has_l else 0.0
    s_r = (f3 - f2) / (t3 - t2) if has_r else 0.0
    best, arg = -np.inf, lo_s
    cands = np.empty(3)
    cands[0], cands[1], cands[2] = lo_s, hi_s, lo_s
    if has_l and has_r and s_l != s_r:
        tx = (f2 - f1 + s_l * t1 - s_r * t2) / (s_l - s_r)
        cands[2] = min(max(tx, lo_s), hi_s)
    for c in range(3):
        tt = cands[c]
        v = np.inf
        if has_l:
            v = min(v, f1 + s_l * (tt - t1))
        if has_r:
            v = min(v, f2 + s_r * (tt - t2))
        if v > best:
            best, arg = v, tt
    # the node values bound their own slice exactly
    if np.isfinite(f1) and lo_s <= t1 <= hi_s and not best >= f1:
        best, arg = f1, t1
    if np.isfinite(f2) and lo_s <= t2 <= hi_s and not best >= f2:
        best, arg = f2, t2
    if np.isfinite(best):
        best += rtol * abs(best)
    return best, arg


@njit(cache=True)
def _node_lines(xy, off, tau, scale, e_nom):
    """Every vertex as the line ``e_nom (Y~ + V~ tau) = A + B tau`` of its node, and
    where it meets the next vertex's line (``nan`` if parallel): the breakpoints of
    the node's upper envelope. Negating a line (the lower bounds) is exact, and
    leaves its breakpoints where they are."""
    n_v = xy.shape[0]
    a_line, b_line, cross = np.empty(n_v), np.empty(n_v), np.empty(n_v)
    for j in range(off.shape[0] - 1):
        for v in range(off[j], off[j + 1]):
            a = xy[v, 0] * scale
            a_line[v] = e_nom * a * tau[j]
            b_line[v] = xy[v, 1] / tau[j] - e_nom * a
        m = off[j + 1] - off[j]
        for v in range(m):
            i, w = off[j] + v, off[j] + (v + 1 if v + 1 < m else 0)
            db = b_line[i] - b_line[w]
            cross[i] = (a_line[w] - a_line[i]) / db if db != 0.0 else np.nan
    return a_line, b_line, cross


@njit(cache=True)
def _envelopes_at(a_line, b_line, start, stop, t):
    """Indices of the largest and of the smallest of the lines ``a + b t`` of
    vertices ``start .. stop - 1`` at ``t`` (the first on ties; -1 if none compares):
    the upper envelope of the lines and the upper envelope of their negations, whose
    values are exactly the negated values, in one pass."""
    best_hi, arg_hi = -np.inf, -1
    best_lo, arg_lo = np.inf, -1
    for v in range(start, stop):
        val = a_line[v] + b_line[v] * t
        if val > best_hi:
            best_hi, arg_hi = val, v
        if val < best_lo:
            best_lo, arg_lo = val, v
    return arg_hi, arg_lo


@njit(cache=True)
def _line(a_line, b_line, v):
    """Line ``v``'s ``(a, b)``; ``nan`` for none (-1: no line compared)."""
    if v < 0:
        return np.nan, np.nan
    return a_line[v], b_line[v]


@njit(cache=True)
def _sort_head(a, n):
    """Sort ``a[:n]`` in place (insertion sort for the usual handful of breakpoints in
    a cell, no allocation; numpy's sort beyond that)."""
    if n > 32:
        a[:n] = np.sort(a[:n])
        return
    for i in range(1, n):
        v = a[i]
        j = i - 1
        while j >= 0 and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


@njit(cache=True)
def _quad(l0, l1, d0, d1, s0, s1):
    """Coefficients of ``(l0 + l1 t) + (d0 + d1 t)(s0 + s1 t)`` in powers of ``t``."""
    return l0 + d0 * s0, l1 + d0 * s1 + d1 * s0, d1 * s1


@njit(cache=True)
def _side_coefs(a_line, b_line, v_in, v_out, s0, s1, sign):
    """The quadratic of one side's secant bound (:func:`_quad`) from the lines ``v_in``
    and ``v_out``, times ``sign``: for the lower bound (``-1``) the coefficients the
    negated lines give, which are exactly the negated ones (negation is exact)."""
    l0, l1 = _line(a_line, b_line, v_in)
    o0, o1 = _line(a_line, b_line, v_out)
    c0, c1, c2 = _quad(l0, l1, l0 - o0, l1 - o1, s0, s1)
    return sign * c0, sign * c1, sign * c2


@njit(cache=True)
def _max_on_segment(coef, p, q, best, arg, cand):
    """Raise ``(best, arg)`` to the maximum over ``[p, q]`` of the minimum of the two
    sides' quadratics ``coef`` (2, 3) (a side with an infinite constant term is
    absent): at the ends, each quadratic's vertex and where the two cross."""
    nc = 0
    cand[nc] = p
    cand[nc + 1] = q
    nc += 2
    for side in range(2):
        if np.isfinite(coef[side, 0]) and coef[side, 2] != 0.0:
            tv = -coef[side, 1] / (2.0 * coef[side, 2])
            if p < tv < q:
                cand[nc] = tv
                nc += 1
    if np.isfinite(coef[0, 0]) and np.isfinite(coef[1, 0]):
        ea = coef[0, 2] - coef[1, 2]
        eb = coef[0, 1] - coef[1, 1]
        ec = coef[0, 0] - coef[1, 0]
        if ea != 0.0:
            disc = eb * eb - 4.0 * ea * ec
            if disc >= 0.0:
                r = np.sqrt(disc)
                near = (-eb + r) / (2.0 * ea) if eb >= 0.0 else (-eb - r) / (2.0 * ea)
                for root in ((-eb + r) / (2.0 * ea), (-eb - r) / (2.0 * ea)):
                    if p < root < q:
                        cand[nc] = root
                        nc += 1
                # With sides of almost equal curvature (ea near 0) the form above loses
                # the root near -ec/eb to cancellation, and the crossing it misses can
                # be where the bound is attained (a 0.4 m too tight lower bound of zs,
                # the truth outside it, was found so). Its stable twin, ec over the
                # other root's numerator, is tried too where the two differ.
                far = -0.5 * (eb + r) if eb >= 0.0 else -0.5 * (eb - r)
                if far != 0.0:
                    root = ec / far
                    if p < root < q and abs(root - near) > 1e-9 * abs(root):
                        cand[nc] = root
                        nc += 1
        elif eb != 0.0:
            root = -ec / eb
            if p < root < q:
                cand[nc] = root
                nc += 1
    for c in range(nc):
        t = cand[c]
        val = np.inf
        for side in range(2):
            if np.isfinite(coef[side, 0]):
                val = min(val, coef[side, 0] + coef[side, 1] * t + coef[side, 2] * t * t)
        if val > best:
            best, arg = val, t
    return best, arg


@njit(cache=True)
def _zem_bound_cell(lines, off, nodes, t4, lo_s, hi_s, rtol, pts, cand, coef, span):
    """Max over ``tau`` in ``[lo_s, hi_s]`` of the bound of ``zs`` and of ``-zs`` (see
    :func:`zem_bounds`): ``(up, arg_up, dn, arg_dn)``, the bound of ``-zs`` as the
    same computation on the negated lines gives it (both in one pass over the lines).
    ``pts``, ``cand`` (8), ``coef`` (2, 2, 3) and ``span`` (4, 2) are scratch."""
    a_line, b_line, cross = lines[0], lines[1], lines[2]
    for k in range(4):
        j = nodes[k]
        span[k, 0] = off[j] if j >= 0 else 0
        span[k, 1] = off[j + 1] if j >= 0 else 0
    n1, n2 = span[1, 1] - span[1, 0], span[2, 1] - span[2, 0]
    if n1 == 0 and n2 == 0:
        return -np.inf, lo_s, -np.inf, lo_s
    has_l = span[0, 1] > span[0, 0] and n1 > 0 and t4[1] > t4[0]
    has_r = n2 > 0 and span[3, 1] > span[3, 0] and t4[3] > t4[2]
    if not has_l and not has_r:
        if n1 > 0 and lo_s == hi_s == t4[1]:  # a lone node: its own slice
            vh, vl = _envelopes_at(a_line, b_line, span[1, 0], span[1, 1], t4[1])
            ah, bh = _line(a_line, b_line, vh)
            al, bl = _line(a_line, b_line, vl)
            return ah + bh * t4[1], lo_s, -(al + bl * t4[1]), lo_s
        return np.inf, lo_s, np.inf, lo_s
    # breakpoints: where the largest (or smallest) line of a node changes (consecutive
    # vertices tie; negating the lines leaves them where they are)
    pts[0], pts[1] = lo_s, hi_s
    npts = 2
    for k in range(4):
        for i in range(span[k, 0], span[k, 1]):
            tx = cross[i]
            if lo_s < tx < hi_s:
                pts[npts] = tx
                npts += 1
    _sort_head(pts, npts)
    h_l = t4[1] - t4[0]
    h_r = t4[3] - t4[2]
    best_up, arg_up = -np.inf, lo_s
    best_dn, arg_dn = -np.inf, lo_s
    for s in range(npts - 1):
        p, q = pts[s], pts[s + 1]
        if q < p:
            continue
        mid = 0.5 * (p + q)
        coef[:] = 0.0
        for side in range(2):
            k_in, k_out = (1, 0) if side == 0 else (2, 3)
            if (side == 0 and not has_l) or (side == 1 and not has_r):
                coef[0, side, 0] = coef[1, side, 0] = np.inf
                continue
            ih, il = _envelopes_at(a_line, b_line, span[k_in, 0], span[k_in, 1], mid)
            oh, ol = _envelopes_at(a_line, b_line, span[k_out, 0], span[k_out, 1], mid)
            if side == 0:  # secant through nodes i-1, i, extended to the right
                s0, s1 = -t4[1] / h_l, 1.0 / h_l
            else:  # secant through nodes i+2, i+1, extended to the left
                s0, s1 = t4[2] / h_r, -1.0 / h_r
            c0, c1, c2 = _side_coefs(a_line, b_line, ih, oh, s0, s1, 1.0)
            coef[0, side, 0], coef[0, side, 1], coef[0, side, 2] = c0, c1, c2
            c0, c1, c2 = _side_coefs(a_line, b_line, il, ol, s0, s1, -1.0)
            coef[1, side, 0], coef[1, side, 1], coef[1, side, 2] = c0, c1, c2
        best_up, arg_up = _max_on_segment(coef[0], p, q, best_up, arg_up, cand)
        best_dn, arg_dn = _max_on_segment(coef[1], p, q, best_dn, arg_dn, cand)
    # the node values bound their own slice exactly
    for k in (1, 2):
        if span[k, 1] > span[k, 0] and lo_s <= t4[k] <= hi_s:
            vh, vl = _envelopes_at(a_line, b_line, span[k, 0], span[k, 1], t4[k])
            ah, bh = _line(a_line, b_line, vh)
            al, bl = _line(a_line, b_line, vl)
            f_up, f_dn = ah + bh * t4[k], -(al + bl * t4[k])
            if not best_up >= f_up:
                best_up, arg_up = f_up, t4[k]
            if not best_dn >= f_dn:
                best_dn, arg_dn = f_dn, t4[k]
    if np.isfinite(best_up):
        best_up += rtol * (abs(best_up) + 1e-300)
    if np.isfinite(best_dn):
        best_dn += rtol * (abs(best_dn) + 1e-300)
    return best_up, arg_up, best_dn, arg_dn


@njit(cache=True)
def zem_bounds(xy, off, tau, table, tau4, lo_s, hi_s, scale, e_nom, rtol):
    """Bounds of ``zs = e_nom (Y~ + V~ tau)`` over every cell, in the direction of
    each ``tau``.

    At a fixed ``tau`` the zero-effort miss is the support of the slice in the
    direction ``(1, tau)``; for that fixed direction the support is concave along the
    body, so the secants of its values at the four nodes around the cell bound it
    at ``tau``. Node ``k``'s value in direction ``(1, tau)`` is the upper envelope of
    its vertices' lines ``A_v + B_v tau`` (linear between breakpoints), so the bound
    is a minimum of two quadratics of ``tau`` between breakpoints, maximised exactly
    (ends, vertices, crossings). Returns ``(m, 4)``: ``zs_hi, arg_hi, zs_lo, arg_lo``.
    """
    m = table.shape[0]
    pts = np.empty(xy.shape[0] + 2)
    cand, coef, span = np.empty(8), np.zeros((2, 2, 3)), np.empty((4, 2), dtype=np.int64)
    out = np.empty((m, 4))
    # a node's lines serve the (up to) four cells around it
    lines = _node_lines(xy, off, tau, scale, e_nom)
    for c in range(m):
        up, a_up, dn, a_dn = _zem_bound_cell(
            lines, off, table[c], tau4[c], lo_s[c], hi_s[c], rtol, pts, cand, coef, span
        )
        out[c, 0], out[c, 1], out[c, 2], out[c, 3] = up, a_up, -dn, a_dn
    return out


#: a secant's outer node is at least this fraction of the distance it is extrapolated
#: over from the near node: its slope divides the rounding of the two nodes' slices by
#: their spacing, and 1e-5 keeps a few ulps of rounding under ``BOUND_RTOL`` (a pair a
#: rounding error apart once cut the truth out of the long cell beside it). Concavity
#: allows any node beyond the near one; in the runs checked the nearest always
#: qualified (docs/infoset.md).
MAX_SECANT_REACH = 1.0e5


@njit(cache=True)
def _outer_node(label, piece, near, step, reach):
    """The node beyond node ``near`` (``step = -1``: before it, ``+1``: after it) of its
    piece nearest to it whose spacing from it is at least ``reach / MAX_SECANT_REACH``,
    ``reach`` the distance its secant is extrapolated over; -1 if none."""
    n = label.shape[0]
    j = near + step
    while 0 <= j < n and piece[j] == piece[near]:
        if abs(label[near] - label[j]) * MAX_SECANT_REACH >= reach:
            return j
        j += step
    return -1


@njit(cache=True)
def summarise(xy, off, label, piece, t, u_lo, u_hi, hard_lo, hard_hi, scale, e_nom, rtol):
    """Everything the node set is asked, in one pass over its cells.

    A cell is a pair of consecutive nodes of one piece with at least one live end,
    its part of ``tau`` clipped to the piece's hard limits. Returns

    * ``table`` (m, 4): nodes ``i-1, i, i+1, i+2`` around each cell (-1: none), the
      outer two farther out where the nearest is too close (:func:`_outer_node`);
    * ``tau4`` (m, 4): their times to go (dummies for missing neighbours);
    * ``span`` (m, 2): the cell's part of ``tau``; ``cpiece`` (m,): its piece;
    * ``zs`` (m, 4): bounds of ``zs`` with their taus (:func:`zem_bounds`);
    * ``w`` (m, 2): bounds of ``w = (e/e_nom)^2 zs`` over the piece's ``e``;
    * ``alpha`` (m, 2): bounds of the bearing ``Y~ / tau``;
    * ``per_piece`` (pieces, 6): bounds of ``w``, of ``alpha`` and of ``tau`` over each
      piece's cells (inf, -inf pairs when it has none).
    """
    n = off.shape[0] - 1
    m_max = 2 * n
    table = np.full((m_max, 4), -1, dtype=np.int64)
    tau4 = np.empty((m_max, 4))
    span = np.empty((m_max, 2))
    cpiece = np.empty(m_max, dtype=np.int64)
    m = 0
    for i in range(n - 1):
        p = piece[i]
        if piece[i + 1] != p:
            continue
        if off[i + 1] == off[i] and off[i + 2] == off[i + 1]:
            continue  # both ends empty: nothing in between
        lo = max(label[i] - t, hard_lo[p] - t)
        hi = min(label[i + 1] - t, hard_hi[p] - t)
        if lo > hi:
            continue
        table[m, 1], table[m, 2] = i, i + 1
        tau4[m, 1], tau4[m, 2] = label[i] - t, label[i + 1] - t
        # the secants' outer nodes: the nearest ones far enough from the cell's ends
        j = _outer_node(label, piece, i, -1, hi - (label[i] - t))
        table[m, 0] = j
        tau4[m, 0] = label[j] - t if j >= 0 else tau4[m, 1] - 1.0
        j = _outer_node(label, piece, i + 1, 1, (label[i + 1] - t) - lo)
        table[m, 3] = j
        tau4[m, 3] = label[j] - t if j >= 0 else tau4[m, 2] + 1.0
        span[m, 0], span[m, 1] = lo, hi
        cpiece[m] = p
        m += 1
    for i in range(n):  # a live node alone in its piece is a cell of its own
        p = piece[i]
        if off[i + 1] == off[i]:
            continue
        alone = (i == 0 or piece[i - 1] != p) and (i == n - 1 or piece[i + 1] != p)
        if alone:
            table[m, 1] = i
            tau4[m, 0], tau4[m, 1] = label[i] - t - 1.0, label[i] - t
            tau4[m, 2], tau4[m, 3] = label[i] - t + 1.0, label[i] - t + 2.0
            span[m, 0] = span[m, 1] = label[i] - t
            cpiece[m] = p
            m += 1
    table, tau4, span, cpiece = table[:m], tau4[:m], span[:m], cpiece[:m]
    tau = label - t
    zs = zem_bounds(xy, off, tau, table, tau4, span[:, 0], span[:, 1], scale, e_nom, rtol)
    w = np.empty((m, 2))
    alpha = np.empty((m, 2))
    n_p = u_lo.shape[0]
    per_piece = np.empty((n_p, 6))
    for p in range(n_p):
        for k in range(3):
            per_piece[p, 2 * k] = np.inf
            per_piece[p, 2 * k + 1] = -np.inf
    f_hi = np.empty(4)
    f_lo = np.empty(4)
    # each node's extent in Y~ serves the (up to) four cells around it: once per node
    y_hi, y_lo = np.empty(n), np.empty(n)
    for j in range(n):
        y_hi[j], y_lo[j] = _support(xy, off, j, tau[j], 1.0, 0.0, scale, e_nom)
    for c in range(m):
        p = cpiece[c]
        big = (1.0 / (u_lo[p] * e_nom)) ** 2
        small = (1.0 / (u_hi[p] * e_nom)) ** 2
        w[c, 1] = zs[c, 0] * (big if zs[c, 0] > 0 else small)
        w[c, 0] = zs[c, 2] * (big if zs[c, 2] < 0 else small)
        for k in range(4):
            j = table[c, k]  # tau4[c, k] is tau[j] for a node, and a missing one has none
            f_hi[k] = y_hi[j] if j >= 0 else -np.inf
            f_lo[k] = -y_lo[j] if j >= 0 else -np.inf
        y_up = _secant(tau4[c], f_hi, span[c, 0], span[c, 1], rtol)[0]
        y_dn = -_secant(tau4[c], f_lo, span[c, 0], span[c, 1], rtol)[0]
        # Y~ / tau is monotone in tau on each secant: both ends of the part suffice
        alpha[c, 1] = max(y_up / span[c, 0], y_up / span[c, 1])
        alpha[c, 0] = min(y_dn / span[c, 0], y_dn / span[c, 1])
        per_piece[p, 0] = min(per_piece[p, 0], w[c, 0])
        per_piece[p, 1] = max(per_piece[p, 1], w[c, 1])
        per_piece[p, 2] = min(per_piece[p, 2], alpha[c, 0])
        per_piece[p, 3] = max(per_piece[p, 3], alpha[c, 1])
        per_piece[p, 4] = min(per_piece[p, 4], span[c, 0])
        per_piece[p, 5] = max(per_piece[p, 5], span[c, 1])
    return table, tau4, span, cpiece, zs, w, alpha, per_piece


@njit(cache=True)
def forecast_extremes(span, w, cpiece, u_lo, u_hi, half_nu, forecast):
    """The cells of the lowest and the highest bound of the zero-effort miss ``w``
    (``forecast``: of the forecast miss ``w + sign(w) nu (x/e_nom)^2 / 2``, ``half_nu
    = nu / (2 e_nom^2)``, ``x`` in ``[tau_lo / u_hi, tau_hi / u_lo]``), and the bounds:
    ``i_lo, v_lo, i_hi, v_hi`` (first index on ties; a ``nan`` wins, as in numpy)."""
    i_lo, i_hi = 0, 0
    v_lo, v_hi = np.inf, -np.inf
    nan_lo, nan_hi = False, False
    for c in range(w.shape[0]):
        hi, lo = w[c, 1], w[c, 0]
        if forecast:
            p = cpiece[c]
            c_max = half_nu * (span[c, 1] / u_lo[p]) ** 2
            c_min = half_nu * (span[c, 0] / u_hi[p]) ** 2
            hi = hi + c_max if hi >= 0 else hi - c_min
            lo = lo - c_max if lo <= 0 else lo + c_min
        if not nan_hi and (hi > v_hi or hi != hi or c == 0):
            i_hi, v_hi, nan_hi = c, hi, hi != hi
        if not nan_lo and (lo < v_lo or lo != lo or c == 0):
            i_lo, v_lo, nan_lo = c, lo, lo != lo
    return i_lo, v_lo, i_hi, v_hi


@njit(cache=True)
def zs_extent(xy, off, i):
    """Smallest and largest ``zs`` of node ``i``'s polygon (``inf, -inf`` when empty)."""
    lo, hi = np.inf, -np.inf
    for v in range(off[i], off[i + 1]):
        lo, hi = min(lo, xy[v, 1]), max(hi, xy[v, 1])
    return lo, hi
