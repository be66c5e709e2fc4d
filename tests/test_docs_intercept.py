"""docs/intercept.md: the numbers its prose derives (from a results file, the scenario
files, or one re-run engagement), and an inventory like the README's: every number of
its prose is read by a row of ``CHECKS``, by a test here (``DERIVED``), is an input
(``INPUTS``), or is named in ``OUTSIDE`` (a check made outside this package, quoted).
"""

from __future__ import annotations

import tomllib

import numpy as np
import pytest
from docs_checks import ADV5, CHECKS, INT
from docs_numbers import ROOT, agrees, printed, results
from test_docs_numbers import unlisted_numbers

#: the sentences whose numbers the tests below derive, by test
DERIVED = {
    "cover": r"covered together with the truth at (\d+) of the (\d+) steps \((\d+) %\)",
    "edge": r"its lower edge sits ~(\d+) km under the truth",
    "early": r"reaches eps about (\d+) s before closest approach",
    "reach": r"= ([\d.]+) s against ~(\d+) s\)",
    "guarantee": r"its guarantee holds under all three \((\d+) steps outside\)",
}

#: quoted checks made outside the package (no results file here can hold them)
OUTSIDE = (r"An outside check of more than 20 further readings drew at most about 300 m/s",)

#: the papers' and scenarios' inputs, run counts and seeds, section and figure numbers
INPUTS = (
    r"[Ss]eed 00\d",
    r"§\d(\.\d)?",
    r"Figs?\. \d+",
    r"seed \d+",
    r"our seed 3",
    r"\b\d+ runs( per (variant|row))?",
    r"\b50 truths",
    r"\(57\.9\.\.58\.1 km/s\)",
    r"57\.\.59 km/s",
    r"\b12 by default",
    r"\b3-sigma",
    r"Simon 2010",
    r"\b5 candidate errors per step, k = 2",
    r"\babout 2000 steps per row",
    r"seed's( game figure,)? 521\.7 m/s",
    r"\(of about 200\)",
    r"over the 10 +runs",  # "the 10 Fig. 5 runs" once the figure's name is out
    r"20 Hz",
    r"error bound 0\.005 deg, rate 0\.0005 deg/s",
    r"up to 1 mN m",
    r"to 1e-4 m over 100 s",
    r"eps = 5 km",
)


def _printed(key: str) -> tuple[str, ...]:
    return printed(INT, DERIVED[key])


def test_the_worst_point_is_covered_with_the_truth_seed_003_fig_3_game():
    """The seed's rule (§5) on the Fig. 3 game engagement (``kvi intercept kp_fig3
    --noise game``: seed 3, run 0): the steps where one admissible bearing interval
    holds both the truth's bearing and the set's worst point. Re-run here, with the
    published engagement's miss and fuel as the check that it is the same one."""
    from kalman_vs_infoset.experiments import noise
    from kalman_vs_infoset.experiments.runner import run_seed
    from kalman_vs_infoset.experiments.scenario import load_scenario
    from kalman_vs_infoset.experiments.sim.intercept import run_engagement

    covered: list[bool] = []
    real = noise.game_bearing

    def spy(alpha_true, bound_true, belief):
        worst = noise.worst_point(belief, belief.model)
        b_w = float(belief.model.bearing_bound(float(worst[2])))
        covered.append(abs(alpha_true - float(worst[0])) <= (bound_true + b_w) * (1 - 1e-9))
        return real(alpha_true, bound_true, belief)

    mp = pytest.MonkeyPatch()
    mp.setattr(noise, "game_bearing", spy)
    try:
        res = run_engagement(
            load_scenario("kp_fig3"), "infoset", "game", np.random.default_rng(run_seed(3, 0))
        )
    finally:
        mp.undo()
    published = results("docs/results/fig3/kp_fig3-infoset-game.json")
    assert agrees(f"{published['miss_m']['mean']:.6f}", res.miss_m)
    assert agrees(f"{published['fuel_mps']['mean']:.6f}", res.fuel_mps)
    hits, steps, percent = _printed("cover")
    assert int(hits) == sum(covered) and int(steps) == len(covered) == res.steps
    assert agrees(percent, 100.0 * sum(covered) / len(covered))


def test_the_constrained_filters_interval_reaches_eps_early():
    """The a-priori range interval of ``kp_fig5_kalman_constrained.toml``: its lower edge
    under the nominal truth, and when ``x_lo - e_hi t`` reaches eps against the nominal
    closest approach ``x0 / e``."""
    sc = tomllib.loads((ROOT / "data/scenarios/kp_fig5_kalman_constrained.toml").read_text())
    model, prior = sc["model"], sc["estimator"]
    x_lo, x_nom = prior["x_km"][0], model["nominal_range_km"]
    reach_s = (x_lo - model["eps_km"]) / prior["closing_speed_kmps"][1]
    approach_s = x_nom / model["closing_speed_kmps"]
    (edge,) = _printed("edge")
    (early,) = _printed("early")
    reach, approach = _printed("reach")
    assert agrees(edge, x_nom - x_lo) and agrees(reach, reach_s)
    assert agrees(approach, approach_s) and agrees(early, approach_s - reach_s)


def test_the_set_keeps_the_truth_under_every_adversary():
    (shown,) = _printed("guarantee")
    rows = [r for r in results(ADV5)["rows"] if r["estimator"] == "infoset"]
    assert {r["rule"] for r in rows} == {"game", "targeted", "lookahead"}
    assert all(r["truth_outside"] == int(shown) for r in rows)


@pytest.mark.parametrize("key", sorted(DERIVED))
def test_each_derived_sentence_is_on_the_page(key):
    assert _printed(key)


def test_every_number_of_the_intercept_page_is_checked():
    """A number in docs/intercept.md's prose is read by a row of ``CHECKS``, derived by
    a test here, an input, or a quoted outside check."""
    patterns = [c[1] for c in CHECKS if c[0] == INT] + list(DERIVED.values()) + list(OUTSIDE)
    assert unlisted_numbers(INT, patterns, INPUTS) == []
