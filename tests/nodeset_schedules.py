"""Worst-case schedules for the node set in seed 003's auxiliary model (shared by tests).

A truth starts at a corner of the a-priori box and moves by the auxiliary model
(``x -= e dt``, ``Y'' = v``); bearing errors and the disturbance sit at their bounds
(``a`` a hair inside, ``nu``) and switch sign at given times. Each step runs what an
engagement asks of the set: update, ``contains(truth)``, the extremes of the
zero-effort miss, and the prediction; ``check`` sees every belief after every
operation.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from hypothesis import strategies as st
from kalman_vs_infoset.estim.intercept.costs import ZeroEffortMiss
from kalman_vs_infoset.estim.intercept.model import Bearing, Range
from kalman_vs_infoset.estim.intercept.nodeset.bands import live_bands
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.sim.channel import auxiliary_model_options
from kalman_vs_infoset.experiments.sim.intercept import build_estimator

ROOT = Path(__file__).resolve().parents[1]

#: hypothesis strategies of a schedule: which end of the box on each of ``(Y, V, x, e)``,
#: the switch times (s) of the bearing error and of the disturbance, and their first signs
BOX_CORNERS = st.tuples(*(st.booleans() for _ in range(4)))
SIGNS = st.tuples(st.sampled_from([-1.0, 1.0]), st.sampled_from([-1.0, 1.0]))


def switch_times(max_size: int, last_s: float = 16.0):
    """Sorted switch times in ``[0, last_s]`` s, at most ``max_size``."""
    return st.lists(st.floats(0.0, last_s), max_size=max_size).map(sorted)


def corner_state(corner, x_box, e_box) -> tuple[float, float, float, float]:
    """``(Y m, V m/s, x m, e m/s)`` of a corner of the box: ``Y`` +-10 km, ``V`` +-100
    m/s, ``x`` and ``e`` at the ends of ``x_box`` and ``e_box``."""
    return (10e3 if corner[0] else -10e3, 100.0 if corner[1] else -100.0,
            x_box[int(corner[2])], e_box[int(corner[3])])  # fmt: skip


def winding_and_turn(xy: np.ndarray) -> tuple[float, float]:
    """Winding number of a closed polygon (zero-length edges skipped) and its deepest
    reflex vertex: the least signed distance of a vertex outside the chord of its
    neighbours, over the polygon's coordinate scale (its diameter or its largest
    coordinate, whichever is larger: the rounding of the vertices is relative to the
    latter); negative: the vertex dents inwards."""
    d = np.roll(xy, -1, axis=0) - xy
    keep = np.hypot(d[:, 0], d[:, 1]) > 0
    d, q = d[keep], xy[keep]
    if len(d) < 3:
        return 1.0, 0.0
    ang = np.arctan2(d[:, 1], d[:, 0])
    turn = np.diff(np.append(ang, ang[0]))
    turn = (turn + np.pi) % (2 * np.pi) - np.pi
    prev, nxt = np.roll(q, 1, axis=0), np.roll(q, -1, axis=0)
    chord = nxt - prev
    length = np.hypot(chord[:, 0], chord[:, 1])
    off = (chord[:, 0] * (q - prev)[:, 1] - chord[:, 1] * (q - prev)[:, 0]) / np.where(
        length > 0, length, 1.0
    )
    scale = max(float(np.ptp(q, axis=0).max()), float(np.abs(q).max()))
    return float(turn.sum() / (2 * np.pi)), float((-off).min() / scale)


#: a vertex may dent inwards by this much of the polygon's coordinate scale (rounding
#: of the clips' intersection points; the strips' outward margin is 1e-9 relative)
DENT_TOL = 1e-12


def _cyclic_next(v: np.ndarray, first: np.ndarray, last: np.ndarray) -> np.ndarray:
    """``v`` at each vertex's successor within its polygon: ``v[polys.next_index()]``,
    by one shift and a write per polygon instead of a gather (the same values)."""
    out = np.empty_like(v)
    out[:-1] = v[1:]
    out[last] = v[first]
    return out


def _cyclic_prev(v: np.ndarray, first: np.ndarray, last: np.ndarray) -> np.ndarray:
    """``v`` at each vertex's predecessor within its polygon."""
    out = np.empty_like(v)
    out[1:] = v[:-1]
    out[first] = v[last]
    return out


def assert_convex_once(belief, where: str) -> None:
    """Every stored slice is convex (up to rounding: no vertex dents inwards by more
    than ``DENT_TOL`` of its coordinate scale) and winds once (all slices at once:
    vertices with their neighbours, per-polygon sums). The neighbours are shifted
    copies of the coordinate columns (the values a gather by the polygons' next and
    previous indices gives, at a third less CPU time: this check ran after every
    operation of a corner schedule and took most of its time)."""
    polys = belief.polygons
    xy, own = polys.xy, polys.owner()
    if len(xy) == 0:
        return
    live = polys.counts > 0
    first, last = polys.offsets[:-1][live], polys.offsets[1:][live] - 1
    x, y = np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1])
    xn, yn = _cyclic_next(x, first, last), _cyclic_next(y, first, last)
    dx, dy = xn - x, yn - y
    zero = (dx == 0) & (dy == 0)  # a zero-length edge (hypot(dx, dy) == 0)
    if zero.any() or (polys.counts[live] < 3).any():  # rare: one by one
        for i in range(polys.n):
            p = polys.polygon(i)
            if len(p) >= 3:
                w, dent = winding_and_turn(p)
                assert abs(w - 1.0) < 1e-9, f"{where}: node {i} winds {w:.3f} times"
                assert dent > -DENT_TOL, f"{where}: node {i} has a reflex vertex ({dent:.3g})"
        return
    ang = np.arctan2(dy, dx)
    turn = (_cyclic_next(ang, first, last) - ang + np.pi) % (2 * np.pi) - np.pi
    winding = np.bincount(own, weights=turn, minlength=polys.n) / (2 * np.pi)
    bad = np.flatnonzero(live & (np.abs(winding - 1.0) > 1e-9))
    assert not len(bad), f"{where}: node {bad[0]} winds {winding[bad[0]]:.3f} times"
    xp, yp = _cyclic_prev(x, first, last), _cyclic_prev(y, first, last)
    cx, cy = xn - xp, yn - yp
    off = (cx * (y - yp) - cy * (x - xp)) / np.hypot(cx, cy)
    lo, hi = np.minimum.reduceat(xy, first), np.maximum.reduceat(xy, first)
    scale = np.zeros(polys.n)
    scale[live] = np.maximum((hi - lo).max(axis=1), np.maximum(-lo, hi).max(axis=1))
    dent = -off / scale[own]
    assert dent.min() > -DENT_TOL, f"{where}: node {own[dent.argmin()]} has a reflex vertex"


def run_schedule(
    scenario: str,
    corner: Sequence[float],
    error_switch_s: Sequence[float],
    disturbance_switch_s: Sequence[float],
    error_sign: float = -1.0,
    disturbance_sign: float = -1.0,
    overrides: Sequence[str] = (),
    check: Callable = assert_convex_once,
) -> dict:
    """Run the node set of ``scenario`` (kinematic margin off, as ``tightness``
    builds it) from ``corner = (Y m, V m/s, x m, e m/s)`` to the threshold.

    The bearing error starts at ``error_sign * a`` and flips at each time of
    ``error_switch_s``; the disturbance likewise. Returns the step count, the steps
    with the truth outside, the largest slice and the belief's status."""
    sc = auxiliary_model_options(
        load_scenario(ROOT / f"data/scenarios/{scenario}.toml", list(overrides)), False
    )
    model, dt = sc.channel_model(), sc.model.dt_s
    est, belief = build_estimator("infoset", sc, model, "lateral")
    y, v, x, e = (float(c) for c in corner)
    steps = outside = max_vertices = bands = 0
    while x > model.eps_m:
        t = steps * dt
        a = float(model.bearing_bound(x)) * (1 - 1e-9)
        err = error_sign * (-1) ** np.searchsorted(error_switch_s, t, side="right") * a
        belief = est.update(belief, Bearing(y / x + err))
        if belief.is_empty:
            break
        check(belief, f"update at {t:g} s")
        if sc.range_finder.due(t):  # one channel: the range is x; its error follows a's sign
            b = model.range_rel_bound * (1 - 1e-9)
            belief = est.update(belief, Range(x * (1 + np.sign(err) * b), off_axis_rad=0.0))
            check(belief, f"range update at {t:g} s")
            bands = max(bands, len(live_bands(belief)))
        outside += not belief.contains(np.array([y / x, (v * x + e * y) / x**2, x]))
        belief.extremes(ZeroEffortMiss(model))
        sign = disturbance_sign * (-1) ** np.searchsorted(disturbance_switch_s, t, side="right")
        belief = est.predict(belief, dt, 0.0)
        if not belief.is_empty:
            check(belief, f"prediction at {t:g} s")
            max_vertices = max(max_vertices, int(belief.polygons.counts.max()))
        acc = sign * model.nu_mps2
        y, v, x = y + v * dt + 0.5 * acc * dt**2, v + acc * dt, x - e * dt
        steps += 1
    return {
        "steps": steps,
        "outside": outside,
        "max_vertices": max_vertices,
        "status": str(belief.status),
        "n_simplified": belief.n_simplified,
        "max_live_bands": bands,
    }
