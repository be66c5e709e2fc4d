"""Compiled (numba) loops behind :class:`kalman_vs_infoset.estim.common.polygons.ConvexPolygons`.

Each function takes the whole ragged batch -- vertices ``xy`` (M, 2), CCW, and
``offsets`` (n + 1) -- and returns a new batch; one call handles every polygon, so
the Python-level cost of an operation is one call whatever the number of
sections. (Pure numpy versions of the same kernels needed ~30 array calls each
and cost about ten times more for 29 sections; the per-polygon loop is only cheap
once compiled.) Correctness is tested against shapely.
"""

from __future__ import annotations

import numpy as np

from kalman_vs_infoset._jit import njit
from kalman_vs_infoset.numerics.arrays import readonly


@njit(cache=True)
def _scale_of(xy, s0, m):
    """The largest coordinate magnitude of one polygon, ``xy[s0:s0 + m]``, and at least
    1: rounding tolerances are the polygon's own (a batch's largest polygon set them for
    all before, and dropped a small polygon's area as duplicates)."""
    s = 1.0
    for i in range(s0, s0 + m):
        for j in range(2):
            a = abs(xy[i, j])
            if a > s:
                s = a
    return s


@njit(cache=True)
def _dedupe_tail(out, start, k, tol):
    """Remove consecutive (cyclic) duplicates in out[start:k]; keep one vertex."""
    if k - start <= 1:
        return k
    w = start + 1
    for r in range(start + 1, k):
        if abs(out[r, 0] - out[w - 1, 0]) > tol or abs(out[r, 1] - out[w - 1, 1]) > tol:
            out[w, 0] = out[r, 0]
            out[w, 1] = out[r, 1]
            w += 1
    while w - start > 1 and (
        abs(out[w - 1, 0] - out[start, 0]) <= tol and abs(out[w - 1, 1] - out[start, 1]) <= tol
    ):
        w -= 1
    return w


@njit(cache=True)
def clip_halfplanes(xy, offsets, nx, ny, bound):
    """Sutherland-Hodgman of polygon i against ``nx[i] x + ny[i] y <= bound[i]``."""
    n = offsets.shape[0] - 1
    # each edge writes at most two vertices: a convex polygon gets m + 1 at most, but
    # signs that alternate (vertices on the line within rounding, or NaN) get more
    out = np.empty((2 * xy.shape[0] + 1, 2))
    new_off = np.zeros(n + 1, dtype=np.int64)
    k = 0
    for i in range(n):
        s0 = offsets[i]
        m = offsets[i + 1] - s0
        tol = 1e-15 * _scale_of(xy, s0, m)
        start = k
        for j in range(m):
            a = s0 + j
            c = s0 + (j + 1) % m
            sa = xy[a, 0] * nx[i] + xy[a, 1] * ny[i] - bound[i]
            sc = xy[c, 0] * nx[i] + xy[c, 1] * ny[i] - bound[i]
            ina = sa <= 0.0
            if ina:
                out[k, 0] = xy[a, 0]
                out[k, 1] = xy[a, 1]
                k += 1
            if ina != (sc <= 0.0):
                t = sa / (sa - sc)  # in [0, 1]: s changes sign along the edge
                out[k, 0] = xy[a, 0] + t * (xy[c, 0] - xy[a, 0])
                out[k, 1] = xy[a, 1] + t * (xy[c, 1] - xy[a, 1])
                k += 1
        k = _dedupe_tail(out, start, k, tol)
        new_off[i + 1] = k
    return out[:k].copy(), new_off


@njit(cache=True)
def minkowski_segment(xy, offsets, gx, gy):
    """Polygon i plus the segment [-g_i, g_i] (see ConvexPolygons.minkowski_segment)."""
    n = offsets.shape[0] - 1
    out = np.empty((2 * xy.shape[0], 2))
    new_off = np.zeros(n + 1, dtype=np.int64)
    k = 0
    for i in range(n):
        s0 = offsets[i]
        m = offsets[i + 1] - s0
        scale = _scale_of(xy, s0, m)
        g0, g1 = gx[i], gy[i]
        if g0 == 0.0 and g1 == 0.0:
            for j in range(m):
                out[k, 0] = xy[s0 + j, 0]
                out[k, 1] = xy[s0 + j, 1]
                k += 1
            new_off[i + 1] = k
            continue
        side = np.empty(m)
        flat = True
        tol = 1e-14 * scale * max(abs(g0), abs(g1))
        for j in range(m):
            a = s0 + j
            c = s0 + (j + 1) % m
            cr = g0 * (xy[c, 1] - xy[a, 1]) - g1 * (xy[c, 0] - xy[a, 0])
            side[j] = 1.0 if cr > 0.0 else -1.0
            if abs(cr) > tol:
                flat = False
        for j in range(m):
            a = s0 + j
            if flat:  # a point or a segment along g: both ends of every vertex
                sp, sc = -1.0, 1.0
            else:
                sp, sc = side[(j - 1) % m], side[j]
            out[k, 0] = xy[a, 0] + sp * g0
            out[k, 1] = xy[a, 1] + sp * g1
            k += 1
            if sc != sp:
                out[k, 0] = xy[a, 0] + sc * g0
                out[k, 1] = xy[a, 1] + sc * g1
                k += 1
        new_off[i + 1] = k
    return out[:k].copy(), new_off


@njit(cache=True)
def _orient_sorted(pts, i, j, k):
    """Orientation of ``(pts[i], pts[j], pts[k])`` computed with the lowest index first,
    so that every ordering of the same three points gets exactly the same magnitude
    (the two chains of the hull then never both keep a nearly collinear point)."""
    a, b, c = i, j, k
    sign = 1.0
    if a > b:
        a, b = b, a
        sign = -sign
    if b > c:
        b, c = c, b
        sign = -sign
    if a > b:
        a, b = b, a
        sign = -sign
    cr = (pts[b, 0] - pts[a, 0]) * (pts[c, 1] - pts[a, 1]) - (pts[b, 1] - pts[a, 1]) * (
        pts[c, 0] - pts[a, 0]
    )
    return sign * cr


@njit(cache=True)
def convex_hulls(xy, offsets):
    """Convex hull of every polygon's vertices (CCW, collinear points dropped).

    An outer operation (the hull contains the polygon). Rounding can leave a
    vertex a hair reflex after a shear (a cross product of -1e-11 on a 2e4 scale);
    the outer simplification would then extend that fold into a visible one, so the
    prediction takes the hull first (Andrew's monotone chain, insertion sort: a
    section has tens of vertices at most)."""
    n = offsets.shape[0] - 1
    out = np.empty((xy.shape[0], 2))
    new_off = np.zeros(n + 1, dtype=np.int64)
    k = 0
    for i in range(n):
        s0 = offsets[i]
        m = offsets[i + 1] - s0
        pts = xy[s0 : s0 + m].copy()
        for a in range(1, m):  # sort by (x, y)
            px, py = pts[a, 0], pts[a, 1]
            b = a - 1
            while b >= 0 and (pts[b, 0] > px or (pts[b, 0] == px and pts[b, 1] > py)):
                pts[b + 1, 0] = pts[b, 0]
                pts[b + 1, 1] = pts[b, 1]
                b -= 1
            pts[b + 1, 0] = px
            pts[b + 1, 1] = py
        if m < 3:
            for a in range(m):
                out[k, 0] = pts[a, 0]
                out[k, 1] = pts[a, 1]
                k += 1
            new_off[i + 1] = k
            continue
        hull = np.empty(2 * m, dtype=np.int64)  # indices into pts
        h = 0
        for a in range(m):  # lower chain
            while h >= 2 and _orient_sorted(pts, hull[h - 2], hull[h - 1], a) <= 0.0:
                h -= 1
            hull[h] = a
            h += 1
        low = h + 1
        for a in range(m - 2, -1, -1):  # upper chain
            while h >= low and _orient_sorted(pts, hull[h - 2], hull[h - 1], a) <= 0.0:
                h -= 1
            hull[h] = a
            h += 1
        # the last point repeats the first; at most m (a NaN coordinate makes every
        # orientation test fail and both chains keep every point: 2 m - 2 of them)
        h = min(max(h - 1, 1), m)
        for a in range(h):
            out[k, 0] = pts[hull[a], 0]
            out[k, 1] = pts[hull[a], 1]
            k += 1
        new_off[i + 1] = k
    return out[:k].copy(), new_off


@njit(cache=True)
def simplify_polygon(buf, m, rel_tol, max_vertices):
    """Outer simplification of one convex CCW polygon ``buf[:m]``, in place: greedily
    remove the edge whose removal (extending its two neighbours to their
    intersection) adds the least area, while that area is below ``rel_tol`` x the
    polygon's area or the polygon has more than ``max_vertices`` vertices (``rel_tol
    < 0``: only the count). The result contains the polygon. Returns the new count."""
    while m >= 4:
        area = 0.0
        for j in range(m):
            c = (j + 1) % m
            area += buf[j, 0] * buf[c, 1] - buf[c, 0] * buf[j, 1]
        area = 0.5 * abs(area)
        best, best_j, bx, by = np.inf, -1, 0.0, 0.0
        for j in range(m):
            p, c, d = (j - 1) % m, (j + 1) % m, (j + 2) % m
            dpx, dpy = buf[j, 0] - buf[p, 0], buf[j, 1] - buf[p, 1]
            dnx, dny = buf[d, 0] - buf[c, 0], buf[d, 1] - buf[c, 1]
            den = dpx * dny - dpy * dnx
            # neighbours that turn by pi or more never meet outside; parallel ones up to
            # rounding (a sine under 1e-12) would meet 1e12 edges away: a rotated
            # parallelogram asked for 3 vertices became a triangle of 1e16, not holding it
            if den <= 1e-12 * np.hypot(dpx, dpy) * np.hypot(dnx, dny):
                continue
            ex, ey = buf[c, 0] - buf[j, 0], buf[c, 1] - buf[j, 1]
            t = (ex * dny - ey * dnx) / den
            if t < 0.0:
                continue
            x_pt, y_pt = buf[j, 0] + t * dpx, buf[j, 1] + t * dpy
            added = 0.5 * abs(ex * (y_pt - buf[j, 1]) - ey * (x_pt - buf[j, 0]))
            if added < best:
                best, best_j, bx, by = added, j, x_pt, y_pt
        if best_j < 0 or not (best <= rel_tol * area or m > max_vertices):
            break
        # v_j <- X, delete v_{j+1}
        buf[best_j, 0] = bx
        buf[best_j, 1] = by
        drop = (best_j + 1) % m
        for r in range(drop, m - 1):
            buf[r, 0] = buf[r + 1, 0]
            buf[r, 1] = buf[r + 1, 1]
        m -= 1
    return m


@njit(cache=True)
def simplify(xy, offsets, rel_tol, max_vertices):
    """Outer simplification (see ConvexPolygons.simplify) of every polygon
    (:func:`simplify_polygon`)."""
    n = offsets.shape[0] - 1
    out = np.empty((xy.shape[0], 2))
    new_off = np.zeros(n + 1, dtype=np.int64)
    k = 0
    for i in range(n):
        s0 = offsets[i]
        buf = xy[s0 : offsets[i + 1]].copy()
        m = simplify_polygon(buf, offsets[i + 1] - s0, rel_tol, max_vertices)
        for j in range(m):
            out[k, 0] = buf[j, 0]
            out[k, 1] = buf[j, 1]
            k += 1
        new_off[i + 1] = k
    return out[:k].copy(), new_off


@njit(cache=True)
def clip_slab(xy, offsets, axis, lo, hi):
    """Polygon i intersected with ``lo[i] <= p[axis] <= hi[i]`` (both lines, one call)."""
    n = offsets.shape[0] - 1
    zeros = np.zeros(n)
    ones = np.ones(n)
    if axis == 0:
        xy1, off1 = clip_halfplanes(xy, offsets, ones, zeros, hi)
        return clip_halfplanes(xy1, off1, -ones, zeros, -lo)
    xy1, off1 = clip_halfplanes(xy, offsets, zeros, ones, hi)
    return clip_halfplanes(xy1, off1, zeros, -ones, -lo)


@njit(cache=True)
def shift_band(xy, offsets, dy, half_y):
    """Translate polygon i by (0, dy[i]) and add the segment [-(0, h_i), (0, h_i)]."""
    n = offsets.shape[0] - 1
    moved = xy.copy()
    for i in range(n):
        for j in range(offsets[i], offsets[i + 1]):
            moved[j, 1] += dy[i]
    return minkowski_segment(moved, offsets, np.zeros(n), half_y)


@njit(cache=True)
def predict_sections(xy, offsets, shear, ga, gw, points, rel_tol, max_vertices):
    """The information set's prediction on scaled coordinates (see
    kalman_vs_infoset.estim.intercept.slabs.estimator): ``alpha += shear[i] w``, then the
    disturbance -- the segment ``(ga, gw)`` for the seed's point sections, else the box ``[+-ga] x
    [+-gw]`` -- then simplification."""
    n = offsets.shape[0] - 1
    moved = xy.copy()
    for i in range(n):
        for j in range(offsets[i], offsets[i + 1]):
            moved[j, 0] += shear[i] * moved[j, 1]
    if points:
        xy2, off2 = minkowski_segment(moved, offsets, ga, gw)
    else:
        xy1, off1 = minkowski_segment(moved, offsets, ga, np.zeros(n))
        xy2, off2 = minkowski_segment(xy1, off1, np.zeros(n), gw)
    xy3, off3 = convex_hulls(xy2, off2)
    return simplify(xy3, off3, rel_tol, max_vertices)


@njit(cache=True)
def _boundary_distance(xy, s0, m, px, py):
    """Distance from the point to the segments between consecutive vertices of the
    polygon ``xy[s0:s0 + m]`` (its boundary; a point or a segment: itself)."""
    best = np.inf
    for j in range(m):
        a = s0 + j
        c = s0 + (j + 1) % m
        ex, ey = xy[c, 0] - xy[a, 0], xy[c, 1] - xy[a, 1]
        ll = ex * ex + ey * ey
        t = 0.0 if ll == 0.0 else ((px - xy[a, 0]) * ex + (py - xy[a, 1]) * ey) / ll
        t = min(max(t, 0.0), 1.0)
        dx, dy = px - xy[a, 0] - t * ex, py - xy[a, 1] - t * ey
        best = min(best, np.sqrt(dx * dx + dy * dy))
    return best


@njit(cache=True)
def polygon_contains(xy, offsets, index, px, py, tol):
    """Whether the point lies within distance ``tol`` of one of the polygons ``index``.

    Convex CCW polygon: inside when the point is left of (or on) every edge; else, and
    for a point or a segment, when its distance to the boundary is at most ``tol``. (A
    test "within ``tol`` of every edge's line" accepted points far beyond a sharp
    corner: ``tol / sin(theta / 2)`` away at an angle ``theta``.)
    """
    for ii in range(index.shape[0]):
        i = index[ii]
        s0 = offsets[i]
        m = offsets[i + 1] - s0
        if m == 0:
            continue
        # twice the area, about the first vertex: on raw coordinates the shoelace sum of a
        # small polygon far from the origin cancels to <= 0 and read it as degenerate
        x0, y0 = xy[s0, 0], xy[s0, 1]
        area2 = 0.0
        for j in range(1, m - 1):
            area2 += (xy[s0 + j, 0] - x0) * (xy[s0 + j + 1, 1] - y0) - (xy[s0 + j + 1, 0] - x0) * (
                xy[s0 + j, 1] - y0
            )
        if m >= 3 and area2 > 0.0:
            inside = True
            for j in range(m):
                a = s0 + j
                c = s0 + (j + 1) % m
                ex, ey = xy[c, 0] - xy[a, 0], xy[c, 1] - xy[a, 1]
                if ex * (py - xy[a, 1]) - ey * (px - xy[a, 0]) < 0.0:
                    inside = False
                    break
            if inside:
                return True
        if _boundary_distance(xy, s0, m, px, py) <= tol:
            return True
    return False


@njit(cache=True)
def section_abs_max(xy, offsets):
    """Largest ``|x|`` and ``|y|`` of every polygon (0 for an empty one), one pass."""
    n = offsets.shape[0] - 1
    ax, ay = np.zeros(n), np.zeros(n)
    for i in range(n):
        for j in range(offsets[i], offsets[i + 1]):
            ax[i] = max(ax[i], abs(xy[j, 0]))
            ay[i] = max(ay[i], abs(xy[j, 1]))
    return ax, ay


@njit(cache=True)
def take_polygons(xy_a, off_a, xy_b, off_b, index):
    """The polygons ``index`` of two batches in one: ``i < n_a`` is polygon ``i`` of
    ``a``, ``i >= n_a`` polygon ``i - n_a`` of ``b`` (vertices copied, not computed)."""
    n_a = off_a.shape[0] - 1
    n = index.shape[0]
    off = np.zeros(n + 1, dtype=np.int64)
    for k in range(n):
        i = index[k]
        if i < n_a:
            off[k + 1] = off[k] + off_a[i + 1] - off_a[i]
        else:
            off[k + 1] = off[k] + off_b[i - n_a + 1] - off_b[i - n_a]
    xy = np.empty((off[n], 2))
    for k in range(n):
        i = index[k]
        w = off[k]
        if i < n_a:
            for v in range(off_a[i], off_a[i + 1]):
                xy[w, 0], xy[w, 1] = xy_a[v, 0], xy_a[v, 1]
                w += 1
        else:
            for v in range(off_b[i - n_a], off_b[i - n_a + 1]):
                xy[w, 0], xy[w, 1] = xy_b[v, 0], xy_b[v, 1]
                w += 1
    return xy, off


def warm_up() -> None:
    """Load every kernel (from numba's on-disk cache, or compile) in this process.

    Worker processes forked afterwards inherit the loaded machine code instead of
    each loading it again (about a second per process). Numba compiles one version
    per argument type and read-only arrays are a type of their own: the set's
    polygons are read-only, so each kernel is loaded with the argument kinds it
    meets in use as well as with plain arrays."""

    def ro(a):  # a read-only copy of the same dtype
        return readonly(a, a.dtype)

    xy = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    off = np.array([0, 4], dtype=np.int64)
    one, zero = np.ones(1), np.zeros(1)
    idx = np.zeros(1, dtype=np.int64)
    for p, o in ((xy, off), (ro(xy), ro(off))):
        clip_slab(p, o, 0, zero, one)
        clip_slab(p, o, 0, ro(zero), ro(one))
        shift_band(p, o, zero, one)
        minkowski_segment(p, o, zero, one)
        predict_sections(p, o, zero, one, one, False, 1e-6, 16)
        predict_sections(p, o, zero, one, one, True, 1e-6, 16)
        polygon_contains(p, o, idx, 0.5, 0.5, 1e-9)
        section_abs_max(p, o)
        convex_hulls(p, o)
        take_polygons(p, o, p, o, idx)
        take_polygons(p, o, xy, off, idx)
