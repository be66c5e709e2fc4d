"""The seed's game adversary (experiments.noise.GameNoise) on the node set.

Seed 003 section 5: from the pursuer's set before the measurement, the point of the
largest |forecast miss| is found; the measurement's interval contains the truth and
that point, with the widest intersection with the set (here: bearing overlap) as the
tie-break; when the point cannot be covered the interval is put as close to it as
possible. The worst point is recomputed here by brute force from the node polygons
themselves (every vertex of every live slice at both ends of its piece's closing
speed), independently of ``Belief.attained``; and sharing the pursuer's set instead of
keeping a copy changes no result, to the last digit.
"""

import numpy as np
import pytest
from harness_texts import ONE_CHANNEL
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import Bearing
from kalman_vs_infoset.experiments.noise import GameNoise
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.sim.intercept import Engagement, build_noise

TINY = ONE_CHANNEL

RANGE = """
[range_finder]
enabled = true
rel_bound = 0.05
first_s = 1.0
period_s = 2.0
"""


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(TINY)
    return p


@pytest.fixture
def tiny_range(tmp_path):
    p = tmp_path / "tiny_range.toml"
    p.write_text(TINY + RANGE)
    return p


def _brute_worst(belief, model):
    """The largest |Pi| over every vertex of every live slice within the hard limits,
    at both ends of its piece's ``u = 1/e``: ``x = tau / u``, ``w = zs / (u e)^2``."""
    fc = MissForecast(model)
    best, arg = -1.0, None
    off = belief.polygons.offsets
    for j in range(len(belief.label_s)):
        p = belief.piece[j]
        if off[j + 1] == off[j] or not (
            belief.hard_lo_s[p] * (1 - 1e-9)
            <= belief.label_s[j]
            <= belief.hard_hi_s[p] * (1 + 1e-9)
        ):
            continue
        tau = belief.label_s[j] - belief.t_s
        for a, zs in belief.polygons.xy[off[j] : off[j + 1]]:
            for u in (belief.u_lo[p], belief.u_hi[p]):
                x = tau / u
                w = zs / (u * model.e) ** 2
                row = np.array([a * belief.alpha_scale_rad, w * model.e / x**2, x])
                val = abs(float(fc(row[None, :])[0]))
                if val > best:
                    best, arg = val, row
    return best, arg


def _overlap(a_m, half, lo, hi):
    return max(0.0, min(a_m + half, hi) - max(a_m - half, lo))


def test_the_game_interval_holds_the_worst_vertex_whenever_it_can(tiny):
    """Seed 003 section 5, step by step on a node-set engagement: the issued bearing's
    interval contains the truth always, the set's worst vertex whenever both fit in
    one interval (then the pursuer keeps that vertex), the largest bearing overlap with
    the set among such intervals, and otherwise lies as close to the vertex as the
    truth allows."""
    sc = load_scenario(tiny)
    eng = Engagement(sc, "infoset", "game", np.random.default_rng(7))
    assert isinstance(eng.noise, GameNoise) and eng.noise.shared
    model, sensor = eng.model, eng.sensor
    issued = eng.noise.bearings
    counts = {"covered": 0, "not coverable": 0}

    def spy(truth, range_m):
        before = eng.beliefs[0]
        alphas = issued(truth, range_m)
        a_t, a_m = float(truth[0][0]), alphas[0]
        b_t = float(sensor.bearing_bound(range_m))
        assert abs(a_m - a_t) <= b_t  # (a): admissible
        if before.is_empty:
            return alphas
        val, _ = _brute_worst(before, model)
        att_val, worst = before.attained(MissForecast(model)).largest_abs()
        # the witness is a worst vertex (ties, e.g. the symmetric prior, may differ)
        assert abs(att_val) == pytest.approx(val, rel=1e-12) and before.contains(worst)
        a_w, b_w = float(worst[0]), float(model.bearing_bound(worst[2]))
        if abs(a_w - a_t) < (b_t + b_w) * (1 - 1e-6):  # coverable, with room for rounding
            counts["covered"] += 1
            assert abs(a_m - a_w) <= b_w  # (b): the worst vertex is inside the interval
            after = eng.estimators[0].update(before, Bearing(a_m))
            assert after.contains(worst)  # ... and survives the pursuer's update
            lo, hi = max(a_t - b_t, a_w - b_w), min(a_t + b_t, a_w + b_w)
            a_lo, a_hi = before.alpha_range_rad()
            best = max(_overlap(c, b_t, a_lo, a_hi) for c in np.linspace(lo, hi, 201))
            assert _overlap(a_m, b_t, a_lo, a_hi) >= best * (1 - 1e-9)  # (c)
        elif abs(a_w - a_t) > (b_t + b_w) * (1 + 1e-6):
            counts["not coverable"] += 1
            # as close as possible: at the bound, on the vertex's side
            assert abs(a_m - a_t) == pytest.approx(b_t, rel=1e-6)
            assert np.sign(a_m - a_t) == np.sign(a_w - a_t)
        return alphas

    eng.noise.bearings = spy
    while eng.step():
        pass
    res = eng.finish()
    assert res.truth_outside == 0
    assert counts["covered"] >= 5 and counts["not coverable"] >= 5, counts  # both rules ran


@pytest.mark.parametrize("scenario", ["tiny", "tiny_range"])
def test_sharing_the_pursuers_set_changes_no_result(scenario, request):
    """One set per engagement: the adversary reading the pursuer's node set gives the
    same engagement as one keeping its own copy, to the last digit (with and without
    range measurements, whose values the adversary also chooses)."""
    sc = load_scenario(request.getfixturevalue(scenario))
    rows = []
    for share in (True, False):
        eng = Engagement(sc, "infoset", "game", np.random.default_rng(5), share_adversary_set=share)
        assert eng.noise.shared is share
        while eng.step():
            pass
        rows.append(eng.finish().as_row())
    assert rows[0] == rows[1]
    assert rows[0]["n_impulses"] > 0


def test_the_adversary_keeps_its_own_set_against_another_estimator(tiny):
    """Against an EKF, or when the pursuer's bearings carry errors the adversary does
    not issue (pointing: ``sensor`` is not the pursuer's model), the adversary keeps
    its own information set and is never shown the pursuer's belief."""
    sc = load_scenario(tiny)
    eng = Engagement(sc, "ekf", "game", np.random.default_rng(5))
    assert not eng.noise.shared and len(eng.noise.sets) == 1
    own = eng.noise.sets[0]
    eng.step()
    assert eng.noise.sets[0] is not own and eng.noise.sets[0] is not eng.beliefs[0]
    model = sc.channel_model()
    sensor = sc.channel_model()  # the sensor's own model, not the pursuer's object
    noise = build_noise("game", sc, model, ["lateral"], np.random.default_rng(1), sensor,
                        pursuer="infoset")  # fmt: skip
    assert not noise.shared
    noise = build_noise("game", sc, model, ["lateral"], np.random.default_rng(1), None, "infoset")
    assert noise.shared
    with pytest.raises(RuntimeError, match="observe_pursuer"):
        noise.bearings([np.array([0.0, 0.0, 1e6])], 1e6)
