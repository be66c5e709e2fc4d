"""States of the node set in a sliver narrower than the spacing of the nodes around them.

From the corner of the a-priori box at the fastest closing speed (seed 003's auxiliary
model, a short approach, bearing errors at ``+a`` that flip to ``-a`` at the last step),
the last bearing leaves the lowest closing-speed band a sliver of states between its
nodes. Nothing may drop it: the refinement's re-grid of a piece down to one live node,
and the search of a piece that a bearing emptied, whose grid can miss the states the
piece held before the bearing. (``make fuzz`` found the first: the truth was outside
the set at the last step.)
"""

from __future__ import annotations

import numpy as np
import pytest
from kalman_vs_infoset.estim.intercept.model import Bearing
from kalman_vs_infoset.estim.intercept.nodeset import _kernels as _nk
from kalman_vs_infoset.estim.intercept.nodeset.bounds import OpLog
from kalman_vs_infoset.estim.intercept.nodeset.refine import _merge
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.sim.channel import auxiliary_model_options
from kalman_vs_infoset.experiments.sim.intercept import build_estimator
from nodeset_schedules import ROOT, run_schedule

SHORT_APPROACH = ["estimator.x_km=[801.3, 951.3]", "truth.x_km=[801.3, 951.3]", "model.dt_s=1.0"]


@pytest.fixture(scope="module")
def last_step():
    """The estimator, the set before the last bearing, that bearing's measured angle and
    the truth ``(alpha, omega, x)`` then, its ``u = 1/e``."""
    sc = auxiliary_model_options(
        load_scenario(ROOT / "data/scenarios/kp_fig5.toml", SHORT_APPROACH), False
    )
    model, dt = sc.channel_model(), sc.model.dt_s
    est, belief = build_estimator("infoset", sc, model, "lateral")
    y, v, x, e = 10e3, 100.0, 951.3e3, 58.1e3  # the corner; errors +a, then -a at 16 s
    t = 0.0
    while x - e * dt > model.eps_m:
        a = float(model.bearing_bound(x)) * (1 - 1e-9)
        belief = est.predict(est.update(belief, Bearing(y / x + a)), dt, 0.0)
        y, v, x = y + v * dt + 0.5 * model.nu_mps2 * dt**2, v + model.nu_mps2 * dt, x - e * dt
        t += dt
    alpha_m = y / x - float(model.bearing_bound(x)) * (1 - 1e-9)
    truth = np.array([y / x, (v * x + e * y) / x**2, x])
    return est, belief, alpha_m, truth, 1.0 / e


def test_the_last_bearing_keeps_the_sliver_that_holds_the_truth(last_step):
    est, before, alpha_m, truth, _ = last_step
    assert before.contains(truth)
    after = est.update(before, Bearing(alpha_m))
    assert not after.is_empty and after.contains(truth)


def test_a_search_grid_that_misses_the_states_is_searched_again(last_step):
    """A grid whose nodes all miss the states the piece held before the bearing says
    nothing about the states after it: the search must still find them (it adds the
    labels known to hold states), not report the piece empty."""
    est, before, alpha_m, truth, u = last_step
    p = int(np.flatnonzero((before.u_lo <= u) & (u <= before.u_hi))[0])
    held = before.label_s[before.live & (before.piece == p)]
    s = est._record(before, OpLog.one(_nk.BEARING, len(before.u_lo), alpha_m))
    assert not (s.live & (s.piece == p)).any()  # the bearing emptied every node
    # a bracket around the piece's states whose grid steps over all of them
    lo, hi = est._bracket(before, p)
    step = 4.0 * (hi - lo)
    grid_lo = lo - 0.37 * step
    grid = np.linspace(grid_lo, grid_lo + (est.n_nodes - 1) * step, est.n_nodes)
    assert not ((grid > lo) & (grid < hi)).any()
    found = est._search(s, p, float(grid[0]), float(grid[-1]), held)
    assert (found.live & (found.piece == p)).any()
    assert found.contains(truth)


def test_a_node_within_rounding_of_a_live_node_is_not_added(last_step):
    """Two live nodes of a piece a few ulps apart are one slice up to rounding; a secant
    through them extrapolates rounding (a band split once left such a pair, and the
    truth left the end cell beside it). A new node that close is not added; one a
    little farther is, and one without states is."""
    _, s, _, _, _ = last_step
    i = int(np.flatnonzero(s.live)[0])
    one = s.polygons.select(np.array([i]))
    keep = np.ones(s.polygons.n, dtype=bool)
    p, lab = s.piece[i : i + 1], s.label_s[i]
    twin = _merge(s, keep, p, np.array([lab + 4 * np.spacing(lab)]), one)
    assert twin.polygons.n == s.polygons.n
    apart = _merge(s, keep, p, np.array([lab * (1 + 1e-11)]), one)
    assert apart.polygons.n == s.polygons.n + 1
    empty = s.polygons.select(np.flatnonzero(~s.live)[:1])
    assert _merge(s, keep, p, np.array([lab + 4 * np.spacing(lab)]), empty).polygons.n == (
        s.polygons.n + 1
    )


def test_the_strip_proof_never_skips_a_search_that_finds_states(monkeypatch):
    """A piece whose nodes a bearing all emptied is searched for states between them,
    unless the bounds between nodes prove that the strip misses it at every time to go
    (``_strip_misses``). Forced to search every time, over corner schedules of a short
    approach (every corner of the box, errors at the bounds flipping late): every
    search the proof would have skipped finds nothing, and searches that find states
    occur (the proof is not vacuous, nor is the check)."""
    from kalman_vs_infoset.estim.intercept.nodeset import refine

    pairs: list[tuple[bool, bool]] = []
    verdict: list[bool] = []
    strip, search = refine.NodeRefinement._strip_misses, refine.NodeRefinement._search

    def forced(self, before, p, alpha_m):
        verdict.append(strip(self, before, p, alpha_m))
        return False

    def searched(self, s, p, lo, hi, held):
        out = search(self, s, p, lo, hi, held)
        if verdict:  # (a search from the top, not one of its own levels)
            found = out is not s and bool((out.live & (out.piece == p)).any())
            pairs.append((verdict.pop(), found))
        return out

    monkeypatch.setattr(refine.NodeRefinement, "_strip_misses", forced)
    monkeypatch.setattr(refine.NodeRefinement, "_search", searched)
    # corners whose searches the proof skips (64, 111) and that find states (12, 5)
    corners = ((10e3, 100.0, 951.3e3, 57.9e3), (-10e3, -100.0, 801.3e3, 58.1e3),
               (10e3, -100.0, 951.3e3, 58.1e3), (-10e3, 100.0, 951.3e3, 58.1e3))  # fmt: skip
    for corner in corners:
        run_schedule("kp_fig5", corner, [16.0], [], 1.0, -1.0, overrides=SHORT_APPROACH)
    assert not any(skip and found for skip, found in pairs)
    assert sum(skip for skip, _ in pairs) >= 10
    assert sum(found for _, found in pairs) >= 10
