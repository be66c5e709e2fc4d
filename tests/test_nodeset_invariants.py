"""The node set's slices stay convex polygons winding once, bounded in size, and the
compiled kernel stays within its buffers (seed 003's auxiliary model, worst-case
schedules from the corners of the a-priori box).

References: the winding number and turns of every stored polygon computed here with
numpy, shapely's convex hull for the segment sum and for containment of the outer
simplification, brute force over the edges for the least-area removal, and numba's
own bounds checking (``NUMBA_BOUNDSCHECK=1``) for the buffers.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.common import _kernels as _k
from kalman_vs_infoset.estim.intercept.nodeset import _kernels as _nk
from nodeset_schedules import (
    BOX_CORNERS,
    DENT_TOL,
    ROOT,
    SIGNS,
    assert_convex_once,
    corner_state,
    run_schedule,
    switch_times,
    winding_and_turn,
)

#: the corner runs of the outside check: (scenario, (Y, V, x, e) in m, m/s, m, m/s)
CORNERS = {
    "kp_fig5": (-10e3, -100.0, 5301.3e3, 57.9e3),
    "kp_fig3": (-10e3, -100.0, 6301.3e3, 58.0e3),
}


#: the property tests' approach: from 801-951 km (~15 s) in 1 s steps (twice the
#: scenarios' 0.5 s: a coarser schedule of the same shape, at two thirds of the CPU time)
SHORT_APPROACH = ["estimator.x_km=[801.3, 951.3]", "truth.x_km=[801.3, 951.3]", "model.dt_s=1.0"]


#: the kp_fig5 corner run is shared by the corner test and the bounds-checking replay
#: (one worker under xdist: both read one module-scoped run)
_KP_FIG5_CORNER = pytest.mark.xdist_group("nodeset_kp_fig5_corner")


@pytest.fixture(scope="module")
def kp_fig5_corner_run():
    """The kp_fig5 corner schedule (below), checked after every operation, with every
    ``apply_ops`` call recorded: ``(result, [(input size, args, output), ...])``. At
    most 32 live closing-speed bands (the default is 64): the kernel's calls are the
    same kind either way, and this unguided run at the error bounds reaches both caps,
    so 64 doubles its cost (6.2 -> 12.4 CPU-s)."""
    calls = []
    real = _nk.apply_ops

    def record(*args):
        out = real(*args)
        calls.append((sum(int(np.size(a)) for a in args[:2]), args, out))
        return out

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(_nk, "apply_ops", record)
        r = run_schedule(
            "kp_fig5", CORNERS["kp_fig5"], [80.0], [20.0, 90.0],
            overrides=["estimator.infoset.max_bands=32"],
        )  # fmt: skip
    return r, calls


@pytest.mark.parametrize(
    "scenario",
    [pytest.param(s, marks=[_KP_FIG5_CORNER] * (s == "kp_fig5")) for s in sorted(CORNERS)],
)
def test_corner_schedule_runs_to_the_threshold_convex_and_with_the_truth(scenario, request):
    """Seed 003's set from the box corner, bearing error -a until 80 s then +a, the
    disturbance -nu, +nu from 20 s, -nu from 90 s: this schedule once wrote past a
    kernel buffer (the interpreter aborted after the update at 80 s) and wound the
    slices 41 times around. Now every slice is convex and winds once after every
    operation, no slice has more vertices than the operations can add (the prior's
    hull at most 8, a bearing strip 2 per step, a prediction's two segment sums 4; a
    zigzag once grew slices to 438 000 vertices), the run reaches the threshold and
    the truth is never outside."""
    if scenario == "kp_fig5":
        r = request.getfixturevalue("kp_fig5_corner_run")[0]
    else:
        r = run_schedule(scenario, CORNERS[scenario], [80.0], [20.0, 90.0])
    x0, e = CORNERS[scenario][2], CORNERS[scenario][3]
    assert r["steps"] >= int((x0 - 5e3) / e / 0.5) - 1
    assert r["outside"] == 0
    assert r["max_vertices"] <= 8 + 6 * r["steps"]
    assert r["n_simplified"] == 0  # no cap by default: every slice exact


@settings(max_examples=50, deadline=None)
@given(
    corner=BOX_CORNERS,
    error_switch_s=switch_times(4),
    disturbance_switch_s=switch_times(4),
    signs=SIGNS,
    scenario=st.sampled_from(["kp_fig3", "kp_fig5"]),
)
# found by `make fuzz` (seed 5120261205): from the corner at the fast end of the
# closing speeds, the last bearing (error flipped to -a at 16 s) left the lowest band
# one live node and a sliver of states narrower than the spacing of its re-grid, whose
# nodes were all empty; the piece was dropped with the truth in it
@example(corner=(True, True, True, True), error_switch_s=[16.0], disturbance_switch_s=[],
         signs=(1.0, 1.0), scenario="kp_fig5")  # fmt: skip
# a search of a brute force over such schedules: a band split left two live nodes of
# one piece 4e-15 s apart, and the secant through them cut the truth out of the end
# cell beside them (5 steps outside)
@example(corner=(False, False, True, True), error_switch_s=[4.96, 6.569, 9.191],
         disturbance_switch_s=[9.642], signs=(-1.0, 1.0), scenario="kp_fig5")  # fmt: skip
def test_slices_stay_convex_and_wind_once_after_every_operation(
    corner, error_switch_s, disturbance_switch_s, signs, scenario
):
    """Errors and disturbances at their bounds switching at random times, from any
    corner of a (shortened, ~15 s) a-priori box: after every update and prediction
    every stored slice is convex and winds once, and the truth stays inside."""
    x_box = (801.3e3, 951.3e3)
    e_box = (57.9e3, 58.1e3) if scenario == "kp_fig5" else (58.0e3, 58.0e3)
    r = run_schedule(
        scenario, corner_state(corner, x_box, e_box), error_switch_s, disturbance_switch_s,
        *signs,
        overrides=SHORT_APPROACH,
    )  # fmt: skip
    assert r["outside"] == 0
    assert r["steps"] >= 12


@settings(max_examples=25, deadline=None)
@given(
    corner=BOX_CORNERS,
    error_switch_s=switch_times(4),
    disturbance_switch_s=switch_times(4),
    signs=SIGNS,
)
def test_range_finder_schedules_keep_the_truth_while_bands_split(
    corner, error_switch_s, disturbance_switch_s, signs
):
    """With the range finder (Fig. 5's, 5 % at the bound, switching with the bearing
    error): the slices stay convex, the truth stays inside after every update, also
    when the closing-speed bands split (their halves are recomputed)."""
    x_box, e_box = (801.3e3, 951.3e3), (57.9e3, 58.1e3)
    r = run_schedule(
        "kp_fig5_range", corner_state(corner, x_box, e_box), error_switch_s,
        disturbance_switch_s, *signs,
        overrides=SHORT_APPROACH,
    )  # fmt: skip
    assert r["outside"] == 0
    assert r["steps"] >= 12


def test_a_range_finder_corner_run_splits_bands_and_keeps_the_truth():
    """The full Fig. 5 approach with the range finder from the box corner, errors at
    their bounds: ranges empty bands, the live ones split (more than the four bands
    the set starts with, up to the cap), and the truth is never outside. The cap is
    32 live bands here (the default is 64): this run reaches either, and 64 only
    doubles its cost."""
    r = run_schedule(
        "kp_fig5_range", (-10e3, -100.0, 5301.3e3, 57.9e3), [80.0], [20.0, 90.0],
        overrides=["estimator.infoset.max_bands=32"],
    )  # fmt: skip
    assert r["outside"] == 0
    assert r["max_live_bands"] == 32


def _convex_polygon(rng, n, flat):
    pts = rng.normal(size=(n, 2)) * [1.0, flat]
    hull = shapely.convex_hull(shapely.multipoints(pts))
    return np.asarray(hull.exterior.coords)[:-1][::-1].copy()  # CCW, not closed


@settings(max_examples=200, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(3, 60),
    subdivide=st.integers(1, 40),
    flat=st.sampled_from([1.0, 1e-6, 1e-12]),
)
def test_segment_sum_is_the_convex_minkowski_sum_with_at_most_two_more_vertices(
    seed, n, subdivide, flat
):
    """Polygon plus segment against shapely's hull of ``p +- g``: the same area, at
    most ``m + 2`` vertices, winding once -- also when the edges along ``g`` are cut
    into many short pieces whose cross products with ``g`` are rounding (the case
    that once gave a zigzag winding twice)."""
    rng = np.random.default_rng(seed)
    poly = _convex_polygon(rng, n, flat)
    if len(poly) < 3:
        return
    g = rng.normal(size=2)
    if subdivide > 1:  # many collinear-to-rounding vertices on the edge most along g
        d = np.roll(poly, -1, axis=0) - poly
        j = int(np.argmin(np.abs(d[:, 0] * g[1] - d[:, 1] * g[0]) / np.hypot(*d.T)))
        s = np.linspace(0, 1, subdivide + 1)[1:-1, None]
        poly = np.insert(poly, j + 1, poly[j] + s * d[j], axis=0)
    m = len(poly)
    dst = np.empty((2 * m + 8, 2))
    k, _ = _nk._segment1(poly, m, g[0], g[1], dst, float(np.abs(poly).max()), False)
    out = dst[:k]
    assert k <= m + 2
    want = shapely.convex_hull(shapely.multipoints(np.vstack([poly + g, poly - g])))
    got = shapely.Polygon(out)
    assert got.area == pytest.approx(want.area, rel=1e-9, abs=1e-12 * want.length**2)
    w, _ = winding_and_turn(out)
    assert abs(w - 1.0) < 1e-9 or want.area < 1e-12 * want.length**2


def _moved_then_summed(poly, sheared, shear, dx, dz, g, want_scale):
    """The two passes the replay ran before :func:`_nk._moved_segment1`: the move
    (``x += shear y + dx``, then ``y += dz``, with the moved polygon's largest coordinate)
    and :func:`_nk._segment1`."""
    p = poly.copy()
    big = 0.0
    for j in range(len(p)):  # the replaced loop, statement by statement
        if sheared:
            p[j, 0] += shear * p[j, 1] + dx
        p[j, 1] += dz
        big = max(big, abs(p[j, 0]), abs(p[j, 1]))
    dst = np.full((2 * len(p) + 8, 2), np.nan)
    k, scale = _nk._segment1(p, len(p), g[0], g[1], dst, big, want_scale)
    return p, dst[:k], scale


@settings(max_examples=300, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 40),
    flat=st.sampled_from([1.0, 1e-9, 1e-15, 0.0]),
    subdivide=st.integers(1, 20),
    sheared=st.booleans(),
    g_kind=st.sampled_from(["any", "zero", "along_x", "along_y", "tiny"]),
)
def test_moved_segment_sum_is_the_move_then_the_sum_bit_for_bit(
    seed, n, flat, subdivide, sheared, g_kind
):
    """One pass (the replay's prediction and impulse) against the two it replaced, on
    points, segments, polygons flat along ``g`` or cut into many collinear-to-rounding
    vertices (the rare path), zero and tiny ``g``: the moved polygon, the sum and its
    scale are equal to the last bit (the node set's published results depend on it)."""
    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, 2)) * [1.0, flat] * 10.0 ** rng.integers(-3, 4)
    if n >= 3 and flat > 0.0:
        hull = _convex_polygon(rng, n, flat)
        pts = hull if len(hull) >= 3 else pts[:1]
    if subdivide > 1 and len(pts) >= 3:
        d = np.roll(pts, -1, axis=0) - pts
        s = np.linspace(0, 1, subdivide + 1)[1:-1, None]
        pts = np.insert(pts, 1, pts[0] + s * d[0], axis=0)
    g = {
        "any": rng.normal(size=2),
        "zero": np.zeros(2),
        "along_x": np.array([rng.normal(), 0.0]),
        "along_y": np.array([0.0, rng.normal()]),
        "tiny": rng.normal(size=2) * 1e-300,
    }[g_kind]
    shear, dx, dz = rng.normal(size=3) * [10.0, 1.0, 1.0]
    for want_scale in (False, True):
        p_want, out_want, scale_want = _moved_then_summed(
            pts, sheared, shear, dx, dz, g, want_scale
        )
        p = pts.copy()
        dst = np.full((2 * len(p) + 8, 2), np.nan)
        k, scale, big = _nk._moved_segment1(
            p, len(p), sheared, shear, dx, dz, g[0], g[1], dst, want_scale
        )
        assert p.tobytes() == p_want.tobytes()
        assert dst[:k].tobytes() == out_want.tobytes()
        assert scale == scale_want or (np.isnan(scale) and np.isnan(scale_want))
        assert big == max([0.0, *np.abs(p_want).ravel()])


@pytest.mark.parametrize("n", [1, 2, 5])
def test_moved_segment_sum_of_a_polygon_at_the_origin_is_flat_as_before(n):
    """A polygon collapsed onto the origin (zero scale, so a zero flatness tolerance:
    the boundary of the test ``|cross| > tol``) takes both ends of ``g`` at every vertex,
    in one pass as in two."""
    pts = np.zeros((n, 2))
    g = np.array([0.3, -0.2])
    p_want, out_want, _ = _moved_then_summed(pts, True, 2.0, 0.0, 0.0, g, True)
    p, dst = pts.copy(), np.full((2 * n + 8, 2), np.nan)
    k, _, _ = _nk._moved_segment1(p, n, True, 2.0, 0.0, 0.0, g[0], g[1], dst, True)
    assert k == 2 * n and dst[:k].tobytes() == out_want.tobytes()


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(20, 400), cap=st.integers(8, 64))
def test_outer_simplification_contains_the_polygon_within_the_cap(seed, n, cap):
    """The simplified polygon contains the input (shapely), has at most ``cap``
    vertices (when the input has more), stays convex and winds once; its first
    removal adds the least area of all single-edge removals (brute force)."""
    rng = np.random.default_rng(seed)
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    poly = np.column_stack([np.cos(ang), 0.3 * np.sin(ang)]) * rng.uniform(0.1, 10)
    poly = _convex_polygon(np.random.default_rng(0), 3, 1.0) if len(poly) < 3 else poly
    m = len(poly)
    p = poly.copy()
    k = _k.simplify_polygon(p, m, -1.0, cap)
    assert k <= max(cap, 3) or k == m
    got, orig = shapely.Polygon(p[:k]), shapely.Polygon(poly)
    assert got.buffer(1e-9 * np.abs(poly).max()).contains(orig)
    w, turn = winding_and_turn(p[:k])
    assert abs(w - 1.0) < 1e-9 and turn > -DENT_TOL
    if m > cap:  # the first removal is the least-area one
        one = poly.copy()
        k1 = _k.simplify_polygon(one, m, -1.0, m - 1)
        added = shapely.Polygon(one[:k1]).area - orig.area
        best = np.inf
        for i in range(m):
            a, b, c, d = poly[i - 1], poly[i], poly[(i + 1) % m], poly[(i + 2) % m]
            u, v = b - a, d - c
            den = u[0] * v[1] - u[1] * v[0]
            if den > 0:
                t = ((c - b)[0] * v[1] - (c - b)[1] * v[0]) / den
                if t >= 0:
                    best = min(best, shapely.Polygon([b, b + t * u, c]).area)
        assert added == pytest.approx(best, rel=1e-6, abs=1e-12 * orig.area)


_REPLAY = """
import json, sys
import numpy as np
from kalman_vs_infoset.estim.common import _kernels as _k
from kalman_vs_infoset.estim.intercept.nodeset import _kernels as _nk
calls = np.load(sys.argv[1], allow_pickle=False)
n = int(calls["n"])
for i in range(n):
    args = [calls[f"{i}_{j}"] for j in range(int(calls[f"{i}_nargs"]))]
    args = [a.item() if a.ndim == 0 else a for a in args]
    xy, off, t, lo, hi, ns = _nk.apply_ops(*args)
    assert np.array_equal(xy, calls[f"{i}_xy"]) and np.array_equal(off, calls[f"{i}_off"])
print(json.dumps({"replayed": n}))
"""


@_KP_FIG5_CORNER
def test_kernel_stays_within_its_buffers_under_numba_bounds_checking(tmp_path, kp_fig5_corner_run):
    """The largest ``apply_ops`` calls of the corner schedule (kp_fig5), recorded
    (``kp_fig5_corner_run``) and replayed in a fresh process compiled with
    ``NUMBA_BOUNDSCHECK=1`` (a write past a buffer raises IndexError there), give the
    same polygons."""
    calls = sorted(kp_fig5_corner_run[1], key=lambda c: -c[0])
    assert calls
    keep = calls[:6] + calls[len(calls) // 2 : len(calls) // 2 + 2]
    arrays = {"n": np.array(len(keep))}
    for i, (_, args, out) in enumerate(keep):
        arrays[f"{i}_nargs"] = np.array(len(args))
        arrays.update({f"{i}_{j}": np.asarray(a) for j, a in enumerate(args)})
        arrays[f"{i}_xy"], arrays[f"{i}_off"] = out[0], out[1]
    path = tmp_path / "calls.npz"
    np.savez(path, **arrays)
    env = {**os.environ, "NUMBA_BOUNDSCHECK": "1", "NUMBA_CACHE_DIR": str(tmp_path / "nb")}
    # without LLVM's optimisation passes: a quarter less compile time, and no check is
    # optimised away (numba emits the bounds checks before LLVM sees the code). This
    # compile cannot be done ahead: numba does not cache a bounds-checked kernel (it
    # "uses dynamic globals"), so the process compiles it every time
    env["NUMBA_OPT"] = "0"
    proc = subprocess.run(
        [sys.executable, "-c", _REPLAY, str(path)], env=env, cwd=ROOT,
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert json.loads(proc.stdout.strip().splitlines()[-1]) == {"replayed": len(keep)}


@pytest.mark.parametrize(
    ("bad", "said"),
    [
        ([[0, 0], [2, 0], [1, 0.5], [2, 2], [0, 2]], "reflex vertex"),
        ([[0, 0], [0, 1], [1, 1], [1, 0]], "winds -1.000 times"),
        ([[1, 0], [0, 1], [-1, 0], [0, -1]] * 2, "winds 2.000 times"),
    ],
    ids=["reflex", "clockwise", "twice"],
)
def test_the_convexity_check_of_the_schedules_is_not_vacuous(bad, said):
    """``assert_convex_once`` (the check after every operation above) passes convex
    slices and an empty one, and names a dented, a clockwise or a twice-wound slice
    wherever it sits in the batch (first, between, last)."""
    from types import SimpleNamespace

    from kalman_vs_infoset.estim.common.polygons import ConvexPolygons

    def belief(*polys):
        arrays = [np.asarray(p, dtype=float).reshape(-1, 2) for p in polys]
        off = np.r_[0, np.cumsum([len(a) for a in arrays])].astype(np.int64)
        # (the internal constructor: the public one refuses a non-convex polygon)
        return SimpleNamespace(polygons=ConvexPolygons._make(np.concatenate(arrays), off))

    square, triangle = [[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 0], [2, 0], [1, 1]]
    assert_convex_once(belief(square, [], triangle), "convex")  # passes: no AssertionError
    for at, polys in enumerate([(bad, square), (square, [], bad, triangle), (square, bad)]):
        node = [0, 2, 1][at]
        with pytest.raises(AssertionError, match=f"node {node} .*{said}"):
            assert_convex_once(belief(*polys), "case")
