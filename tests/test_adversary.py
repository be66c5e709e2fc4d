"""White-box adversaries (experiments.adversary): admissible errors chosen by the stated
rule (checked by brute force over the candidates), the look-ahead at depth one is the
greedy rule, the engagement shows the pursuer only to generators that want it, the
information set keeps the truth against them, and the adversary-strength command on a
tiny case."""

import json

import numpy as np
import pytest
from harness_texts import ONE_CHANNEL
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.gaussian.estimator import KalmanChannelEstimator
from kalman_vs_infoset.estim.intercept.model import Bearing, ChannelModel, ChannelPrior
from kalman_vs_infoset.experiments.adversary import (
    LookaheadNoise,
    PursuerView,
    TargetedNoise,
    WhiteBoxNoise,
    candidate_errors,
    misdirection,
)
from kalman_vs_infoset.experiments.cli import main
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.sim.intercept import Engagement, run_engagement
from kalman_vs_infoset.guidance.intercept.law import ForecastCentringLaw

MODEL = ChannelModel()
PRIOR = ChannelPrior((-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3))

SHORT = (
    ONE_CHANNEL
    + """[reference]
fuel_game_mps = 100.0
miss_game_m = 9.5
"""
)


@pytest.fixture
def tiny(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(SHORT)
    return p


def _pursuer(n_steps=20):
    """An EKF belief a few steps into an approach, its truth row and the view."""
    est = KalmanChannelEstimator(MODEL, kind="ekf")
    rng = np.random.default_rng(3)
    truth = MODEL.from_cartesian(-4e3, 15.0, 5801.3e3, -MODEL.e)
    b = est.initial(PRIOR)
    for _ in range(n_steps):
        a = MODEL.bearing_bound(truth[2])
        b = est.predict(est.update(b, Bearing(truth[0] + rng.uniform(-a, a))), 0.5)
        truth = MODEL.step(truth, 0.5)
    view = PursuerView((est,), (b,), ForecastCentringLaw(MODEL), 0.0)
    return est, b, truth, view


def test_targeted_bearing_is_admissible_and_maximises_the_stated_misdirection():
    est, b, truth, view = _pursuer()
    noise = TargetedNoise(MODEL, candidates=9)
    noise.observe_pursuer(view)
    d = float(truth[2])
    (alpha,) = noise.bearings([truth], d)
    bound = float(MODEL.bearing_bound(d))
    assert abs(alpha - truth[0]) < bound
    # brute force: |centre of [Pi_min, Pi_max] after the update - Pi(truth)| per candidate
    fc = MissForecast(MODEL)
    scores = []
    for err in np.linspace(-bound, bound, 9) * (1 - 1e-9):
        ext = est.update(b, Bearing(truth[0] + err)).extremes(fc)
        scores.append(abs(0.5 * (ext.min_value + ext.max_value) - fc(truth[None, :])[0]))
    assert alpha == pytest.approx(truth[0] + candidate_errors(bound, 9)[np.argmax(scores)])
    assert max(scores) > min(scores) + 1.0  # the choice matters (metres of miss)
    assert misdirection(est.update(b, Bearing(alpha)), truth, fc) == pytest.approx(max(scores))


def test_lookahead_of_depth_one_is_the_greedy_rule():
    _, _, truth, view = _pursuer()
    greedy, deep1 = TargetedNoise(MODEL, 7), LookaheadNoise(MODEL, 0.5, steps=1, candidates=7)
    for noise in (greedy, deep1):
        noise.observe_pursuer(view)
    d = float(truth[2])
    assert greedy.bearings([truth], d) == deep1.bearings([truth], d)
    deep2 = LookaheadNoise(MODEL, 0.5, steps=2, candidates=3)
    deep2.observe_pursuer(view)
    (a2,) = deep2.bearings([truth], d)
    assert abs(a2 - truth[0]) < MODEL.bearing_bound(d)
    assert np.isclose(a2 - truth[0], candidate_errors(MODEL.bearing_bound(d), 3), rtol=1e-9).any()


def test_lookahead_objectives_by_brute_force_at_depth_one():
    """fuel: the largest commanded impulse |k| after the update; width: the widest
    forecast interval; both over the same admissible candidates."""
    est, b, truth, view = _pursuer()
    d = float(truth[2])
    errs = candidate_errors(MODEL.bearing_bound(d), 5)
    updated = [est.update(b, Bearing(truth[0] + e)) for e in errs]
    fc, law = MissForecast(MODEL), view.law
    expect = {
        "fuel": np.argmax([abs(law.command_mps(u)) for u in updated]),
        "width": np.argmax([u.extremes(fc).max_value - u.extremes(fc).min_value for u in updated]),
    }
    for objective, j in expect.items():
        noise = LookaheadNoise(MODEL, 0.5, steps=1, candidates=5, objective=objective)
        noise.observe_pursuer(view)
        assert noise.bearings([truth], d) == [pytest.approx(truth[0] + errs[j])]
    with pytest.raises(ValueError, match="objective"):
        LookaheadNoise(MODEL, 0.5, objective="chaos")


def test_a_white_box_generator_must_be_shown_the_pursuer():
    with pytest.raises(RuntimeError, match="observe_pursuer"):
        TargetedNoise(MODEL).bearings([np.array([0.0, 0.0, 1e6])], 1e6)


def test_the_engagement_shows_the_pursuer_to_white_box_generators_only(tiny, monkeypatch):
    sc = load_scenario(tiny)
    seen = []
    monkeypatch.setattr(WhiteBoxNoise, "observe_pursuer", lambda self, v: seen.append(v))
    eng = Engagement(sc, "ekf", "random", np.random.default_rng(1))
    assert not isinstance(eng.noise, WhiteBoxNoise)
    while eng.step():
        pass
    assert seen == []
    eng = Engagement(sc, "ekf", "targeted", np.random.default_rng(1))
    monkeypatch.setattr(eng.noise, "bearings", lambda truth, d: [t[0] for t in truth])
    before = eng.beliefs
    eng.step()
    assert len(seen) == 1 and seen[0].beliefs == tuple(before)
    assert seen[0].estimators == tuple(eng.estimators) and seen[0].law is eng.law


@pytest.mark.parametrize("noise", ["targeted", "lookahead"])
def test_the_information_set_keeps_the_truth_against_white_box_noise(tiny, noise):
    """Every candidate is consistent with the truth: a sound set never loses it (five
    greedy candidates: the bounds, zero and the half-bounds)."""
    sc = load_scenario(tiny, ["adversary.lookahead_candidates=3", "adversary.candidates=5"])
    r = run_engagement(sc, "infoset", noise, np.random.default_rng(2))
    assert r.truth_outside == 0 and r.contradictions == 0 and r.checked_steps > 20
    assert dict(r.extras)["adversary_skipped"] == 0  # no branch raised


def test_node_set_updates_on_the_lookahead_branches_do_not_raise(tiny, monkeypatch):
    """Regression: on a branch of the look-ahead (update, impulse, predict, update) the
    node set's update raised IndexError in its refinement, whose loop over the pieces
    went on with stale indices after a nested search dropped empty pieces (fixed: pieces
    are renumbered only after every piece was visited)."""
    monkeypatch.setattr(WhiteBoxNoise, "try_update", lambda self, e, b, m: e.update(b, m))
    sc = load_scenario(tiny, ["adversary.lookahead_candidates=3"])
    run_engagement(sc, "infoset", "lookahead", np.random.default_rng(2))


def test_node_set_accepts_an_admissible_range_at_the_edge_of_its_interval(tiny):
    """Regression: with the range finder on, the greedy adversary issues ranges at the
    edge of their admissible interval (the true x 0.1 m inside it); the node set's update
    emptied the truth's piece and reported a contradiction (4 times in this run), as no
    search looked for the states left between the nodes after a range (fixed: such a
    piece is re-gridded where its old bracket meets the new limits)."""
    sc = load_scenario(tiny, ["range_finder.enabled=true"])
    r = run_engagement(sc, "infoset", "targeted", np.random.default_rng(2))
    assert r.truth_outside == 0
    assert r.contradictions == 0


def test_adversary_table_bounds_the_search(tiny):
    from kalman_vs_infoset.experiments.errors import InputError

    with pytest.raises(InputError, match="leaves"):
        load_scenario(tiny, ["adversary.lookahead_steps=5", "adversary.lookahead_candidates=5"])


def test_adversaries_command_on_a_tiny_case(tiny, tmp_path, capsys, monkeypatch):
    from kalman_vs_infoset.experiments import plots

    marks, real = [], plots.cdf_figure

    def spy(table, by, title, given, *a, **k):
        marks.extend(lab for pairs in given.values() for _, lab in pairs)
        return real(table, by, title, given, *a, **k)

    monkeypatch.setattr(plots, "cdf_figure", spy)
    args = ["adversaries", tiny, "--runs", "1", "--estimators", "ekf", "--lookahead", "1"]
    args += ["--out", tmp_path, "--no-progress", "--workers", "1", "--json"]
    code = main([str(a) for a in args])
    # the paper's number is marked as the paper's ("seed, game" read as a random seed)
    assert marks and set(marks) == {"paper Fig. 3 (one engagement), game errors"}
    out = capsys.readouterr()
    assert code == 0, out.err
    res = json.loads(out.out.strip().splitlines()[-1])
    assert [r["rule"] for r in res["rows"]] == ["game", "targeted", "lookahead"]
    assert res["lookahead_steps"] == 1 and res["seed_fuel_game_mps"] == 100.0
    for r in res["rows"]:
        assert r["failures"] == 0 and r["runs"] == 1
        assert set(r["fuel_mps"]) >= {"mean", "p50", "p90"} and r["fuel_mps"]["mean"] > 0
        assert r["runs_at_seed_fuel"] in (0.0, 1.0)
    assert res["scenario"].endswith("+adversary.lookahead_steps=1")
    md = next(f for f in res["files"] if f.endswith(".md"))
    assert "| ekf | lookahead | 1 |" in open(md).read()


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        # the field's check, said of the option given (it said "kp_fig5 (with --set)")
        (["--lookahead", "100"], "--lookahead 100: must be an integer in [1, 6] (got 100)"),
        # two ways to set one depth (it said "--set ... given twice")
        (["--lookahead", "1", "--set", "adversary.lookahead_steps=3"],
         "--lookahead and --set adversary.lookahead_steps both set the depth"),
    ],
)  # fmt: skip
def test_adversaries_says_which_option_is_wrong(tmp_path, capsys, extra, message):
    from harness_texts import one_line_error
    from harness_texts import run_cli as run

    r = run(capsys, "adversaries", "kp_fig5", "--runs", "1", "--out", tmp_path / "a", *extra)
    assert one_line_error(r) and message in r.stderr, r.stderr
    assert not (tmp_path / "a").exists()


def test_an_impulse_limit_error_names_the_scenario_fields(tmp_path, capsys):
    """Not the package's module path ('kalman_vs_infoset.guidance.min_impulse_mps')."""
    from harness_texts import one_line_error
    from harness_texts import run_cli as run

    r = run(capsys, "intercept", "kp_fig3", "--set", "guidance.min_impulse_mps=10", "--runs",
            "1", "--out", tmp_path / "g")  # fmt: skip
    assert one_line_error(r), r.stderr
    assert "field 'guidance.min_impulse_mps' must be <= 'guidance.max_impulse_mps'" in r.stderr


def test_the_adversaries_header_names_only_the_papers_numbers_it_has(monkeypatch):
    """A scenario without a ``[reference]`` table printed "the paper's game: fuel None
    m/s, miss None m"; each number is said when the scenario has it."""
    from kalman_vs_infoset.experiments import cmd_adversaries as ca

    monkeypatch.setattr(ca, "table_markdown", lambda result: "")
    base = {"scenario": "tiny", "runs": 2, "seed": 1, "files": []}
    first = lambda fuel, miss: ca.render(  # noqa: E731
        {**base, "seed_fuel_game_mps": fuel, "seed_miss_game_m": miss}
    ).splitlines()[0]
    assert first(None, None) == "tiny: adversary strength, 2 runs, seed 1"
    assert first(521.7, None).endswith("seed 1 (the paper's game: fuel 521.7 m/s)")
    assert first(521.7, 9.5).endswith("(the paper's game: fuel 521.7 m/s, miss 9.5 m)")
