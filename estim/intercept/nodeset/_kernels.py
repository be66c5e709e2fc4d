"""Compiled (numba) operations of the node set (:mod:`.estimator`).

:func:`apply_ops` runs a sequence of recorded operations (bearing strip, impulse,
range interval, prediction with threshold) on a batch of node polygons, each node
through all of them in two scratch buffers: one step's operations on the live nodes,
or the whole log on new nodes when a piece is refined. The bounds between nodes are
in :mod:`._geometry`.
"""

from __future__ import annotations

import numpy as np
from kalman_vs_infoset.estim.common._kernels import _dedupe_tail, simplify_polygon

from kalman_vs_infoset._jit import njit

#: operation codes of the log
BEARING, IMPULSE, RANGE, PREDICT = 0, 1, 2, 3
#: turns smaller than this (rad) are rounding: such vertices are dropped after a
#: prediction (the triangle lost is 1e-13 of an edge high, far under the strips' 1e-9
#: outward margin)
HULL_TURN_RAD = 1e-13


@njit(cache=True)
def _hull_into(src, m, dst, tol):
    """The vertices of ``src[:m]`` (a CCW polygon, convex up to rounding) that turn left
    by more than ``tol`` (rad), written to ``dst`` (a stack pass from the lowest-x vertex:
    linear time, no allocation): duplicate, collinear and rounding-reflex vertices go.
    Returns their number."""
    if m < 3:
        for j in range(m):
            dst[j, 0], dst[j, 1] = src[j, 0], src[j, 1]
        return m
    first = 0
    for v in range(1, m):
        if src[v, 0] < src[first, 0] or (src[v, 0] == src[first, 0] and src[v, 1] < src[first, 1]):
            first = v
    h = 0
    v = first - 1
    for _ in range(m + 1):
        v = v + 1 if v + 1 < m else 0  # (first + r) % m without a division a vertex
        px, py = src[v, 0], src[v, 1]
        while h >= 2:
            ax, ay = dst[h - 2, 0], dst[h - 2, 1]
            bx, by = dst[h - 1, 0], dst[h - 1, 1]
            ux, uy, wx, wy = bx - ax, by - ay, px - ax, py - ay
            # a turn by less than tol rad is rounding: without it a sliver (a polygon
            # flat to rounding along the disturbance) doubles its vertices every step
            cross = ux * wy - uy * wx
            uu, ww = ux * ux + uy * uy, wx * wx + wy * wy
            # sqrt(uu ww) <= (uu + ww) / 2: a clear left turn needs no square root
            if cross > tol * (uu + ww) or cross > tol * np.sqrt(uu * ww):
                break
            h -= 1
        dst[h, 0], dst[h, 1] = px, py
        h += 1
    return h - 1  # the last point repeats the first


@njit(cache=True)
def _clip_tol(bound):
    """Distance under which :func:`_clip1` merges consecutive vertices (rounding of a
    clip against ``bound``)."""
    return 1e-15 * max(abs(bound), 1.0)


@njit(cache=True)
def _clip1(src, m, nx, ny, bound, dst):
    """Sutherland-Hodgman of one polygon against ``nx x + ny y <= bound`` (``nx`` or
    ``ny`` zero: a strip's side; the rounding scale is taken from ``bound``)."""
    k = 0
    for j in range(m):
        c = j + 1 if j + 1 < m else 0
        sa = src[j, 0] * nx + src[j, 1] * ny - bound
        sb = src[c, 0] * nx + src[c, 1] * ny - bound
        if sa <= 0.0:
            dst[k, 0], dst[k, 1] = src[j, 0], src[j, 1]
            k += 1
        if (sa <= 0.0) != (sb <= 0.0):
            t = sa / (sa - sb)
            dst[k, 0] = src[j, 0] + t * (src[c, 0] - src[j, 0])
            dst[k, 1] = src[j, 1] + t * (src[c, 1] - src[j, 1])
            k += 1
    return _dedupe_tail(dst, 0, k, _clip_tol(bound))


@njit(cache=True)
def _inside(src, m, nx, ny, bound):
    """Whether :func:`_clip1` of ``src[:m]`` against ``nx x + ny y <= bound`` keeps
    every vertex (the same test, vertex by vertex): then it only copies them and drops
    duplicates."""
    for j in range(m):
        if not src[j, 0] * nx + src[j, 1] * ny - bound <= 0.0:
            return False
    return True


@njit(cache=True)
def _segment1(src, m, g0, g1, dst, scale, want_scale):
    """One convex polygon plus the segment ``[-g, g]``: at most ``m + 2`` vertices,
    convex and winding once (``scale`` is the largest coordinate of ``src`` in
    magnitude; the callers have it from their own pass). Returns the number of
    vertices and, if ``want_scale``, the same for ``dst`` (else 0).

    Each vertex moves by ``+g`` or ``-g`` by the side of ``g`` its edges face: by the
    sign of the cross product ``g x edge``. On a convex polygon those signs form one
    run of ``+`` and one of ``-`` (cyclically), and the two vertices where the run
    changes take both ends of the segment. Edges almost parallel to ``g`` may get
    their sign from rounding; if that breaks the two runs (a polygon with many short
    edges along ``g``), a zigzag output would wind several times around, so the runs
    are then taken from the extremes of ``g x p`` over the vertices instead: the
    ``+`` run from the vertex of least ``g x p`` to the one of greatest (the exact
    Minkowski sum of the convex polygon, whatever the rounding).
    """
    if m == 0:
        return 0, 0.0
    if g0 == 0.0 and g1 == 0.0:
        for j in range(m):
            dst[j, 0], dst[j, 1] = src[j, 0], src[j, 1]
        return m, scale
    tol = 1e-14 * scale * max(abs(g0), abs(g1))
    # one pass for the usual polygon (two sign runs, not flat); it also finds out
    # whether the polygon is flat along g or its signs break into more runs, and then
    # the sum is written again by _segment1_rare (the same output as three passes)
    crc = g0 * (src[0, 1] - src[m - 1, 1]) - g1 * (src[0, 0] - src[m - 1, 0])
    changes = 0  # sign changes between consecutive edges, cyclically
    flat = True
    k = 0
    out_scale = 0.0
    for j in range(m):
        c = j + 1 if j + 1 < m else 0
        crp = crc
        crc = g0 * (src[c, 1] - src[j, 1]) - g1 * (src[c, 0] - src[j, 0])
        flat = flat and not abs(crc) > tol
        sp = 1.0 if crp > 0.0 else -1.0
        sc = 1.0 if crc > 0.0 else -1.0
        changes += sc != sp
        dst[k, 0], dst[k, 1] = src[j, 0] + sp * g0, src[j, 1] + sp * g1
        if want_scale:
            out_scale = max(out_scale, abs(dst[k, 0]), abs(dst[k, 1]))
        k += 1
        if sc != sp:
            dst[k, 0], dst[k, 1] = src[j, 0] + sc * g0, src[j, 1] + sc * g1
            if want_scale:
                out_scale = max(out_scale, abs(dst[k, 0]), abs(dst[k, 1]))
            k += 1
    if flat or changes != 2:
        return _segment1_rare(src, m, g0, g1, dst, flat, want_scale)
    return k, out_scale


@njit(cache=True)
def _moved_segment1(src, m, sheared, shear, dx, dz, g0, g1, dst, want_scale):
    """:func:`_segment1` of ``src[:m]`` after a move of its vertices (in place: ``x +=
    shear y + dx`` if ``sheared``, then ``y += dz``), in the same pass: each vertex is
    moved as the pass first reads it, and the rounding scale (the moved polygon's
    largest coordinate, which only the flatness test needs) is complete after it. The
    output is the separate move's and :func:`_segment1`'s, bit for bit (one pass fewer a
    prediction and an impulse: engagements cost 0.95 of their CPU time). Its loop repeats
    :func:`_segment1`'s, as :func:`_segment1_rare`'s does: a shared compiled helper made
    the kernel slower. Returns the number of vertices, the output's scale if
    ``want_scale`` (else 0) and the moved polygon's scale."""
    if m == 0:
        return 0, 0.0, 0.0
    if g0 == 0.0 and g1 == 0.0:
        big = 0.0
        for j in range(m):
            if sheared:
                src[j, 0] += shear * src[j, 1] + dx
            src[j, 1] += dz
            big = max(big, abs(src[j, 0]), abs(src[j, 1]))
            dst[j, 0], dst[j, 1] = src[j, 0], src[j, 1]
        return m, big, big
    last = m - 1
    if sheared:
        src[0, 0] += shear * src[0, 1] + dx
    src[0, 1] += dz
    big = max(0.0, abs(src[0, 0]), abs(src[0, 1]))
    if last > 0:
        if sheared:
            src[last, 0] += shear * src[last, 1] + dx
        src[last, 1] += dz
    crc = g0 * (src[0, 1] - src[last, 1]) - g1 * (src[0, 0] - src[last, 0])
    changes = 0
    worst = 0.0  # the largest |cross|: the polygon is flat along g if it is within tol
    k = 0
    out_scale = 0.0
    for j in range(m):
        c = j + 1 if j + 1 < m else 0
        if 0 < c < last:  # vertices 0 and m - 1 were moved before the pass
            if sheared:
                src[c, 0] += shear * src[c, 1] + dx
            src[c, 1] += dz
            big = max(big, abs(src[c, 0]), abs(src[c, 1]))
        crp = crc
        crc = g0 * (src[c, 1] - src[j, 1]) - g1 * (src[c, 0] - src[j, 0])
        if abs(crc) > worst:
            worst = abs(crc)
        sp = 1.0 if crp > 0.0 else -1.0
        sc = 1.0 if crc > 0.0 else -1.0
        changes += sc != sp
        dst[k, 0], dst[k, 1] = src[j, 0] + sp * g0, src[j, 1] + sp * g1
        if want_scale:
            out_scale = max(out_scale, abs(dst[k, 0]), abs(dst[k, 1]))
        k += 1
        if sc != sp:
            dst[k, 0], dst[k, 1] = src[j, 0] + sc * g0, src[j, 1] + sc * g1
            if want_scale:
                out_scale = max(out_scale, abs(dst[k, 0]), abs(dst[k, 1]))
            k += 1
    if last > 0:
        big = max(big, abs(src[last, 0]), abs(src[last, 1]))
    flat = not worst > 1e-14 * big * max(abs(g0), abs(g1))
    if flat or changes != 2:
        k, out_scale = _segment1_rare(src, m, g0, g1, dst, flat, want_scale)
    return k, out_scale, big


@njit(cache=True)
def _segment1_rare(src, m, g0, g1, dst, flat, want_scale):
    """:func:`_segment1` for a polygon flat along ``g`` (every vertex takes both ends)
    or whose edge signs break into more than two runs (the runs taken from the extremes
    of ``g x p``)."""
    i_lo, i_hi = 0, 0
    if not flat:
        s_lo, s_hi = np.inf, -np.inf
        for j in range(m):
            sj = g0 * src[j, 1] - g1 * src[j, 0]
            if sj < s_lo:
                s_lo, i_lo = sj, j
            if sj > s_hi:
                s_hi, i_hi = sj, j
    # the vertex loop repeats _segment1's: a shared compiled helper (even inlined)
    # made the kernel three times slower (measured on 1,653 recorded calls)
    k = 0
    out_scale = 0.0
    for j in range(m):
        if flat:
            sp, sc = -1.0, 1.0
        else:
            # edges i_lo .. i_hi - 1 (cyclically) rise in g x p: their vertices take +g
            sp = 1.0 if (j - 1 - i_lo) % m < (i_hi - i_lo) % m else -1.0
            sc = 1.0 if (j - i_lo) % m < (i_hi - i_lo) % m else -1.0
        dst[k, 0], dst[k, 1] = src[j, 0] + sp * g0, src[j, 1] + sp * g1
        if want_scale:
            out_scale = max(out_scale, abs(dst[k, 0]), abs(dst[k, 1]))
        k += 1
        if sc != sp:
            dst[k, 0], dst[k, 1] = src[j, 0] + sc * g0, src[j, 1] + sc * g1
            if want_scale:
                out_scale = max(out_scale, abs(dst[k, 0]), abs(dst[k, 1]))
            k += 1
    return k, out_scale


@njit(cache=True)
def _room(buf, m, need):
    """``buf`` if it has ``need`` rows, else a larger buffer holding its first ``m``
    rows: every write of the kernels below stays within a buffer sized from a bound
    on its output (a clip writes at most ``2 m`` vertices, a segment sum ``m + 2``,
    the hull pass ``m + 1``)."""
    if need <= buf.shape[0]:
        return buf
    grown = np.empty((2 * need, 2))
    grown[:m] = buf[:m]
    return grown


@njit(cache=True)
def _schedule(u_lo, u_hi, hard_lo, hard_hi, t, kinds, pa, pb, eps):
    """Time at the start of every operation and the hard label limits after it."""
    n_ops = kinds.shape[0]
    n_p = u_lo.shape[0]
    times = np.empty(n_ops + 1)
    lo = np.empty((n_ops + 1, n_p))
    hi = np.empty((n_ops + 1, n_p))
    lo[0], hi[0] = hard_lo, hard_hi
    times[0] = t
    for o in range(n_ops):
        lo[o + 1], hi[o + 1] = lo[o], hi[o]
        times[o + 1] = times[o]
        if kinds[o] == RANGE:
            for b in range(n_p):
                lo[o + 1, b] = max(lo[o, b], pa[o] * u_lo[b] + times[o])
                hi[o + 1, b] = min(hi[o, b], pb[o] * u_hi[b] + times[o])
        elif kinds[o] == PREDICT:
            times[o + 1] = times[o] + pa[o]
            for b in range(n_p):
                # every state of a node under eps for all e of its piece leaves the set
                lo[o + 1, b] = max(lo[o, b], eps * u_lo[b] + times[o + 1])
    return times, lo, hi


@njit(cache=True)
def _impulse_dv(k, dk, u_lo, u_hi, cos2):
    """Interval of the ``V~`` increment ``(k +- dk) u cos^2(alpha)`` for ``u`` in
    ``[u_lo, u_hi]`` and ``cos^2(alpha) >= cos2`` (one piece)."""
    e0, e1 = k * u_lo * cos2, k * u_hi
    return min(e0, e1) - dk * u_hi, max(e0, e1) + dk * u_hi


@njit(cache=True)
def apply_ops(
    xy, off, label, piece, u_lo, u_hi, hard_lo, hard_hi, t,
    kinds, pa, pb, q_lo, q_hi,
    scale, e_nom, eps, bb_end, bb_start, bb_ref, strip_margin, vcap, impulse_per_piece,
):  # fmt: skip
    """Apply the operations ``kinds[o]`` in order to the node polygons.

    Parameters (per operation ``o``): ``BEARING``: ``pa`` = measured bearing (rad);
    ``IMPULSE``: ``q_lo, q_hi`` = the interval of the ``V~`` increment per piece, as
    recorded; with ``impulse_per_piece``, ``pa, pb`` = the impulse ``k +- dk`` (m/s) and
    ``q_lo`` = the least ``cos^2`` of the bearing per piece, the interval formed over
    the node's own piece's ``u`` (:func:`_impulse_dv`, as :func:`impulse_interval`
    records it: a band split after the impulse gives each half its own spread);
    ``RANGE``: ``pa, pb`` = the interval of ``x`` (m); ``PREDICT``: ``pa`` = step (s),
    ``q_lo, q_hi`` = the interval of ``v u`` per piece. Nodes have labels ``label`` (time to go
    at ``t = 0``) and pieces ``piece``; ``hard_lo, hard_hi`` (per piece, labels) are
    narrowed by range intervals and the threshold. Each node runs through all the
    operations in two scratch buffers (no allocation per operation). A polygon
    that a prediction leaves with more than ``vcap`` vertices is outer-simplified to
    ``vcap`` (``_kernels.simplify_polygon``). Returns the polygons, the time, the
    hard limits and the number of such simplifications.
    """
    n = off.shape[0] - 1
    n_ops = kinds.shape[0]
    times, h_lo, h_hi = _schedule(u_lo, u_hi, hard_lo, hard_hi, t, kinds, pa, pb, eps)
    floor = 1e-3 * min(bb_start, bb_end)
    vmax = 4
    for i in range(n):
        vmax = max(vmax, off[i + 1] - off[i])
    cap = 2 * vmax + 16  # grown as needed below
    a_buf = np.empty((cap, 2))
    b_buf = np.empty((cap, 2))
    out = np.empty((off[n] + 4 * n + 16, 2))
    new_off = np.zeros(n + 1, dtype=np.int64)
    k_out = 0
    n_simplified = 0
    for i in range(n):
        m = off[i + 1] - off[i]
        for j in range(m):
            a_buf[j, 0], a_buf[j, 1] = xy[off[i] + j, 0], xy[off[i] + j, 1]
        b = piece[i]
        for o in range(n_ops):
            if m == 0:
                break
            a_buf = _room(a_buf, m, 2 * m + 8)
            b_buf = _room(b_buf, 0, 2 * m + 8)
            kind = kinds[o]
            tau = label[i] - times[o]
            if kind == BEARING:
                # widest strip over the piece: the bound at its smallest range
                x = tau / u_hi[b]
                a = max(bb_end + (bb_start - bb_end) * x / bb_ref, floor)
                h = a / scale * (1.0 + strip_margin) + strip_margin
                c = pa[o] / scale
                # the two clips' tolerances (their bounds are c + h and -(c - h))
                tol_hi, tol_lo = _clip_tol(c + h), _clip_tol(-(c - h))
                tol = max(tol_hi, tol_lo)
                x_lo, x_hi = a_buf[0, 0], a_buf[0, 0]
                close = False  # consecutive vertices (cyclic) within the clips' tolerance
                for j in range(m):
                    x_lo, x_hi = min(x_lo, a_buf[j, 0]), max(x_hi, a_buf[j, 0])
                    k = j + 1 if j + 1 < m else 0
                    if abs(a_buf[k, 0] - a_buf[j, 0]) <= tol:
                        close = close or abs(a_buf[k, 1] - a_buf[j, 1]) <= tol
                if x_hi <= c + h and x_lo >= c - h:
                    # inside the strip: the clips would only copy and drop duplicates
                    if close:
                        m = _dedupe_tail(a_buf, 0, m, tol_hi)
                        m = _dedupe_tail(a_buf, 0, m, tol_lo)
                    continue
                # a side the polygon lies within is a clip that only copies and drops
                # duplicates: that, in place (the same vertices, half the passes)
                if x_hi <= c + h:
                    if close:
                        m = _dedupe_tail(a_buf, 0, m, tol_hi)
                    m = _clip1(a_buf, m, -1.0, 0.0, -(c - h), b_buf)
                    a_buf, b_buf = b_buf, a_buf
                    continue
                m = _clip1(a_buf, m, 1.0, 0.0, c + h, b_buf)
                a_buf = _room(a_buf, 0, 2 * m + 8)
                if m > 0 and x_lo >= c - h and _inside(b_buf, m, -1.0, 0.0, -(c - h)):
                    m = _dedupe_tail(b_buf, 0, m, tol_lo)
                    a_buf, b_buf = b_buf, a_buf
                else:
                    m = _clip1(b_buf, m, -1.0, 0.0, -(c - h), a_buf) if m > 0 else 0
            elif kind == IMPULSE:
                d_lo, d_hi = q_lo[o, b], q_hi[o, b]
                if impulse_per_piece:
                    d_lo, d_hi = _impulse_dv(pa[o], pb[o], u_lo[b], u_hi[b], q_lo[o, b])
                zs = e_nom * tau
                dy = 0.5 * (d_lo + d_hi) * zs
                g = 0.5 * (d_hi - d_lo) * zs
                m, _, _ = _moved_segment1(a_buf, m, False, 0.0, 0.0, dy, 0.0, g, b_buf, False)
                a_buf, b_buf = b_buf, a_buf
            elif kind == RANGE:
                if label[i] < h_lo[o + 1, b] or label[i] > h_hi[o + 1, b]:
                    m = 0
            else:  # PREDICT
                dt = pa[o]
                t1 = tau - dt
                if t1 <= 0.0 or label[i] < h_lo[o + 1, b]:
                    m = 0
                    break
                # v u in [q_lo, q_hi]: its middle moves the node, its half-width spreads it
                mid = 0.5 * (q_lo[o, b] + q_hi[o, b])
                nu_s = 0.5 * (q_hi[o, b] - q_lo[o, b])
                shear = dt / (tau * t1) / (e_nom * scale)
                ca, cz = dt * dt / (2.0 * t1) / scale, dt * (tau + t1) / 2.0 * e_nom
                ga, gz = nu_s * ca, nu_s * cz
                m, big, _ = _moved_segment1(
                    a_buf, m, True, shear, mid * ca, mid * cz, ga, gz, b_buf, True
                )
                # a disturbance that varies within the step (the kinematic term does)
                # reaches +-nu dt^2/4 off the constant one's segment in Y~ (V~ fixed)
                gz2 = nu_s * dt * dt / 4.0 * e_nom
                m, _ = _segment1(b_buf, m, 0.5 * ga, gz2, a_buf, big, False)
                m = _hull_into(a_buf, m, b_buf, HULL_TURN_RAD)
                a_buf, b_buf = b_buf, a_buf
                if m > vcap:  # outer simplification to the cap (sound)
                    m = simplify_polygon(a_buf, m, -1.0, vcap)
                    n_simplified += 1
        if k_out + m > out.shape[0]:
            grown = np.empty((2 * (k_out + m), 2))
            grown[:k_out] = out[:k_out]
            out = grown
        for j in range(m):
            out[k_out, 0], out[k_out, 1] = a_buf[j, 0], a_buf[j, 1]
            k_out += 1
        new_off[i + 1] = k_out
    return out[:k_out].copy(), new_off, times[n_ops], h_lo[n_ops], h_hi[n_ops], n_simplified


@njit(cache=True)
def impulse_interval(per, u_lo, u_hi, e_nom, k, dk):
    """Interval of the ``V~`` increment of an impulse ``k +- dk`` per piece, the least
    ``cos^2`` of the bearing per piece, and (in place) the per-piece bounds of ``w`` in
    ``per`` moved by it (the formulas are
    :meth:`.estimator.NodeSetEstimator._impulse`'s). A piece without cells
    (``inf`` bounds) gets ``nan`` bounds of ``w``: it is skipped downstream."""
    n = u_lo.shape[0]
    lo, hi, cos2 = np.empty(n), np.empty(n), np.empty(n)
    for b in range(n):
        a_abs = max(abs(per[b, 2]), abs(per[b, 3]))
        sin2 = np.sin(min(a_abs, 0.5 * np.pi)) ** 2
        cos2[b] = 1.0 - sin2
        lo[b], hi[b] = _impulse_dv(k, dk, u_lo[b], u_hi[b], cos2[b])
        f0, f1 = (1.0 / (u_hi[b] * e_nom)) ** 2, (1.0 / (u_lo[b] * e_nom)) ** 2
        p_min, p_max, nan = np.inf, -np.inf, False
        for t in (max(per[b, 4], 0.0), max(per[b, 5], 0.0)):
            for d in (lo[b], hi[b]):
                for f in (f0, f1):
                    v = e_nom * t * d * f
                    nan = nan or v != v
                    p_min, p_max = min(p_min, v), max(p_max, v)
        if nan:
            per[b, 0], per[b, 1] = np.nan, np.nan
        else:
            per[b, 0] += min(p_min, 0.0)
            per[b, 1] += max(p_max, 0.0)
    return lo, hi, cos2


@njit(cache=True)
def prior_points(label, u_lo, u_hi, y0, y1, v0, v1, xa, xb, scale, e_nom):
    """The box's corners ``(y, Vy)`` scaled by both ends of each node's ``u`` interval
    ``[max(tau / x_hi, u_lo), min(tau / x_lo, u_hi)]``, in ``(a, zs)`` at ``tau =
    label`` (8 points a node; none where the interval is empty): their hull is the
    node's prior slice (:meth:`.estimator.NodeSetEstimator.initial`)."""
    n = label.shape[0]
    xy = np.empty((8 * n, 2))
    off = np.zeros(n + 1, dtype=np.int64)
    corners = ((y0, v0), (y1, v0), (y1, v1), (y0, v1))
    k = 0
    for i in range(n):
        tau = label[i]
        u1 = max(tau / xb, u_lo[i])
        u2 = min(tau / xa, u_hi[i])
        if u1 <= u2 * (1 + 1e-12):
            for u in (u1, u2):
                for y, v in corners:
                    yt, vt = u * y, u * v
                    xy[k, 0], xy[k, 1] = yt / tau / scale, (yt + vt * tau) * e_nom
                    k += 1
        off[i + 1] = k
    return xy[:k], off
