"""docs/intercept.md: the numbers its prose derives (from a results file, the scenario
files, or one re-run engagement), and an inventory like the README's: every number of
its prose is read by a row of ``CHECKS``, by a test here (``DERIVED``), is an input
(``INPUTS``), or is named in ``OUTSIDE`` (a check made outside this package, quoted).
"""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest
from docs_checks import ADV5, CHECKS, INT
from docs_numbers import ROOT, agree_each, agrees, printed, results, study_variant
from test_docs_numbers import unlisted_numbers

#: the sentences whose numbers the tests below derive, by test
DERIVED = {
    "cover": r"covered together with the truth at (\d+) of the (\d+) steps \((\d+) %\)",
    "edge": r"its lower edge sits ~(\d+) km under the truth",
    "early": r"reaches eps about (\d+) s before closest approach",
    "reach": r"= ([\d.]+) s against ~(\d+) s\)",
    "guarantee": r"its guarantee holds under all three \((\d+) steps outside\)",
    "study": r"`docs/results/study/fig5-w2-1000-drift\.json`; the first (\d+) runs of each variant",
    "study_all": r"In none of the (\d+) engagements did the truth leave the set, and no set "
    r"emptied or diverged\. The (\d+)-run table's findings hold with (\w+) times the runs",
    "study_range": r"helps a little \(mean miss ([\d.]+) -> ([\d.]+) m, fuel ([\d.]+) -> "
    r"([\d.]+) m/s\), under the game it makes the miss worse \(([\d.]+) -> ([\d.]+) m\)\. "
    r"The (\d+)-run means were within ([\d.]+) m and ([\d.]+) m/s of these, the miss's "
    r"largest moves in the game rows \(([\d.]+) -> ([\d.]+) m with bearings only, "
    r"([\d.]+) -> ([\d.]+) m with the range finder\)",
    "paired_level": r"its\s+mean advantage's (\d+) % interval above zero in every row",
    "paired_bias": r"their intervals holding zero \(p ([\d.]+) and ([\d.]+)\)",
    "paired_game": r"the EKF spends ([\d.]+) m/s more than the set \(p ([\d.]+)\) and the UKF "
    r"about the\s+same \(p ([\d.]+)\)",
    "range_random": r"essential improvement\"\): ([\d.]+) m of miss and ([\d.]+) m/s of fuel "
    r"on average, both intervals below zero, with the miss smaller in only about half the runs",
    "range_game": r"Under the game it costs ([\d.]+) m of miss on average, more in (\d+) % of "
    r"the runs, for ([\d.]+) m/s less fuel",
    "study_max": r"as maxima do \(bearings-only random ([\d.]+) -> ([\d.]+) m\)",
    "study_fuel": r"Perfect-information fuel ([\d.]+) m/s over the (\d+) runs \(a lower bound of "
    r"the fuel; ([\d.]+)\s+m/s over the first (\d+)\)",
    "tenk": r"One variant was run to (\d+ \d+) runs, the bearing \+ range variant under random "
    r"errors \(`kvi intercept kp_fig5_range --runs (\d+) .* its first (\d+) runs\s+are this "
    r"table's; .*\): miss ([\d.]+) / ([\d.]+) / ([\d.]+) / ([\d.]+) m "
    r"\(mean / p50 / p90 / max\), fuel ([\d.]+) / ([\d.]+) / ([\d.]+) / ([\d.]+) m/s",
    "pointing_counts": r"\(`pointing_residual_over_bound_steps`, the premise of the guarantee "
    r"failed\); both read (\d+) in the published runs",
    "tenk_moves": r"From (\d+) runs to (\d+ \d+) the mean miss moved by ([\d.]+) m and the mean "
    r"fuel by ([\d.]+) m/s, the miss's p90 by ([\d.]+) m",
}

#: quoted checks made outside the package (no results file here can hold them)
OUTSIDE = (
    r"More than 20 further\s+readings of the rule, tried outside this package's commands "
    r"\(no results file holds them\),\s+drew at most about 300 m/s",
)

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


def test_the_1000_run_fig5_study_against_the_50_run_table():
    """docs/intercept.md's Fig. 5 at 1000 runs per variant (``kvi fig5 --runs 1000``)
    against the 50-run table (``docs/results/fig5.json``): the runs and engagements
    counted, no truth outside, the range finder's effect both ways, how far the 50-run
    means were (the largest gaps, and that the game rows have the largest miss gaps),
    the maximum's growth and the perfect-information fuel."""
    big = results("docs/results/study/fig5-w2-1000-drift.json")
    small = results("docs/results/fig5.json")
    rows = {(v["variant"], v["noise"]): v for v in big["variants"]}
    table = {(v["variant"], v["noise"]): v for v in small["variants"]}
    assert rows.keys() == table.keys()
    (first,) = _printed("study")
    assert int(first) == small["runs"] and big["runs"] > small["runs"]
    engagements, n_table, times = _printed("study_all")
    assert int(engagements) == sum(v["runs"] for v in big["variants"])
    assert int(n_table) == small["runs"]
    assert times == {20: "twenty"}[big["runs"] // small["runs"]]
    assert all(v["truth_outside"] == v["empty_set"] == v["diverged"] == 0 for v in rows.values())
    mean = lambda r, k: r[k]["mean"]  # noqa: E731
    bo, br = ("bearing only", "random"), ("bearing + range", "random")
    bg, rg = ("bearing only", "game"), ("bearing + range", "game")
    miss_gap = {k: abs(mean(rows[k], "miss_m") - mean(table[k], "miss_m")) for k in rows}
    fuel_gap = {k: abs(mean(rows[k], "fuel_mps") - mean(table[k], "fuel_mps")) for k in rows}
    values = [
        mean(rows[bo], "miss_m"), mean(rows[br], "miss_m"), mean(rows[bo], "fuel_mps"),
        mean(rows[br], "fuel_mps"), mean(rows[bg], "miss_m"), mean(rows[rg], "miss_m"),
        small["runs"], max(miss_gap.values()), max(fuel_gap.values()),
        mean(table[bg], "miss_m"), mean(rows[bg], "miss_m"), mean(table[rg], "miss_m"),
        mean(rows[rg], "miss_m"),
    ]  # fmt: skip
    for shown, value in zip(_printed("study_range"), values, strict=True):
        assert agrees(shown, value), (shown, value)
    assert mean(rows[br], "miss_m") < mean(rows[bo], "miss_m")  # helps a little
    assert mean(rows[rg], "miss_m") > mean(rows[bg], "miss_m")  # worse under the game
    assert sorted(miss_gap, key=miss_gap.get)[-2:] in ([bg, rg], [rg, bg])
    before, after = _printed("study_max")
    assert agrees(before, table[bo]["miss_m"]["max"]) and agrees(after, rows[bo]["miss_m"]["max"])
    assert all(rows[k]["miss_m"]["max"] >= table[k]["miss_m"]["max"] for k in rows)
    fuel, n, fuel_50, n_50 = _printed("study_fuel")
    assert agrees(fuel, big["fuel_perfect_info_mps"]) and int(n) == big["runs"]
    assert agrees(fuel_50, small["fuel_perfect_info_mps"]) and int(n_50) == small["runs"]


def test_the_10000_run_variant_against_the_1000_run_table():
    """docs/intercept.md's 10 000 runs of the bearing + range variant under random
    errors: its statistics, that its first runs are the 1000-run table's (the same
    seeds; the kept run table, docs/performance.md's test, checks them run by run), no
    truth outside, and how far the 1000-run numbers were."""
    import pandas as pd

    big = results("docs/results/study/kp_fig5_range-random-10000-drift.json")
    mid = study_variant("docs/results/study/fig5-w2-1000-drift.json", "kp_fig5_range", "random")
    assert mid["variant"] == "bearing + range"
    # its first runs are the table's, run by run (the kept run table's miss and fuel)
    runs = pd.read_parquet(
        ROOT / "docs/results/study/kp_fig5_range-random-10000-drift-runs.parquet"
    )
    runs = runs.sort_values("run")
    assert runs["run"].tolist() == list(range(big["runs"]))
    head = runs[runs["run"] < mid["runs"]]
    for col in ("miss_m", "fuel_mps"):
        assert head[col].mean() == mid[col]["mean"] and head[col].max() == mid[col]["max"]
    assert runs["miss_m"].mean() == big["miss_m"]["mean"] and (runs["truth_outside"] == 0).all()
    assert (big["scenario"], big["noise"], big["estimator"]) == ("kp_fig5_range", "random",
                                                                 "infoset")  # fmt: skip
    n, n_cmd, first, *stats = _printed("tenk")
    assert int(n.replace(" ", "")) == int(n_cmd) == big["runs"] and int(first) == mid["runs"]
    keys = ("mean", "p50", "p90", "max")
    for shown, value in zip(stats, [big[m][k] for m in ("miss_m", "fuel_mps") for k in keys],
                            strict=True):  # fmt: skip
        assert agrees(shown, value), (shown, value)
    assert (big["truth_outside"], big["empty_set"], big["diverged"], big["failures"]) == (0,) * 4
    n_mid, n_big, miss, fuel, p90 = _printed("tenk_moves")
    assert int(n_mid) == mid["runs"] and int(n_big.replace(" ", "")) == big["runs"]
    agree_each((miss, fuel, p90), [abs(big["miss_m"]["mean"] - mid["miss_m"]["mean"]),
                                   abs(big["fuel_mps"]["mean"] - mid["fuel_mps"]["mean"]),
                                   abs(big["miss_m"]["p90"] - mid["miss_m"]["p90"])])  # fmt: skip


def test_the_range_finders_paired_effect_at_1000_runs():
    """docs/intercept.md's reading of ``kvi fig5 --runs 1000``'s paired variants (a second
    run of the command, its runs the first's to the last digit): under random errors
    the range finder saves miss and fuel (intervals below zero, the miss smaller in
    about half the runs); under the game it adds miss in most runs and saves a little
    fuel."""
    # the study before the drift became the default: a second run drew the same runs
    first = results("docs/results/study/fig5-w2-1000.json")
    again = results("docs/results/study/fig5-w2-1000-paired.json")
    keys = ("variant", "noise", "runs", "seed", "miss_m", "fuel_mps", "truth_outside")
    assert [{k: v[k] for k in keys} for v in again["variants"]] == [
        {k: v[k] for k in keys} for v in first["variants"]
    ]
    paired = results("docs/results/study/fig5-w2-1000-drift.json")["paired"]
    assert (paired["reference"], paired["by"]) == ("bearing only", "variant")
    rows = {r["noise"]: r for r in paired["rows"]}
    assert all(r["variant"] == "bearing + range" and r["estimator"] == "infoset"
               for r in rows.values())  # fmt: skip
    rnd, game = rows["random"], rows["game"]
    miss, fuel = _printed("range_random")
    assert agrees(miss, -rnd["miss_m"]["mean"]) and agrees(fuel, -rnd["fuel_mps"]["mean"])
    assert rnd["miss_m"]["ci"][1] < 0.0 and rnd["fuel_mps"]["ci"][1] < 0.0
    # "smaller in only about half": the share of runs with a larger miss is 0.4 to 0.6
    assert 0.4 < rnd["miss_m"]["larger_share"] < 0.6
    more, share, less = _printed("range_game")
    assert agrees(more, game["miss_m"]["mean"]) and game["miss_m"]["ci"][0] > 0.0
    assert agrees(share, 100.0 * game["miss_m"]["larger_share"])
    assert agrees(less, -game["fuel_mps"]["mean"]) and game["fuel_mps"]["ci"][1] < 0.0


def test_the_paired_comparison_reads_as_its_file():
    """docs/intercept.md's reading of the paired Kalman-filter rows (``paired`` of
    ``kvi compare kp_fig5``): the set misses less in most runs of every row, each
    interval of the mean miss difference above zero; under random errors the filters
    spend more fuel in every run; the bias's fuel intervals hold zero (their p-values);
    the game's fuel difference of the EKF (and its p) and the UKF's interval holding
    zero (its p)."""
    data = results("docs/results/compare_kp_fig5.json")
    assert data["paired"]["reference"] == "infoset"
    rows = {(r["estimator"], r["noise"]): r for r in data["paired"]["rows"]}
    assert set(rows) == {(e, n) for e in ("ekf", "ukf") for n in ("random", "bias", "game")}
    (level,) = _printed("paired_level")
    assert int(level) / 100 == data["paired"]["confidence"]
    for r in rows.values():
        assert r["miss_m"]["larger_share"] > 0.5 and r["miss_m"]["ci"][0] > 0.0
        assert r["miss_m"]["runs"] == r["fuel_mps"]["runs"] == data["runs"]
    assert all(rows[(e, "random")]["fuel_mps"]["larger_share"] == 1.0 for e in ("ekf", "ukf"))
    holds_zero = lambda r: r["fuel_mps"]["ci"][0] < 0.0 < r["fuel_mps"]["ci"][1]  # noqa: E731
    p_ekf, p_ukf = _printed("paired_bias")
    for e, p in (("ekf", p_ekf), ("ukf", p_ukf)):
        assert holds_zero(rows[(e, "bias")]) and agrees(
            p, rows[(e, "bias")]["fuel_mps"]["wilcoxon_p"]
        )
    more, p_more, p_same = _printed("paired_game")
    ekf, ukf = rows[("ekf", "game")]["fuel_mps"], rows[("ukf", "game")]["fuel_mps"]
    assert agrees(more, ekf["mean"]) and ekf["ci"][0] > 0.0 and agrees(p_more, ekf["wilcoxon_p"])
    assert holds_zero(rows[("ukf", "game")]) and agrees(p_same, ukf["wilcoxon_p"])


@pytest.mark.parametrize("key", sorted(DERIVED))
def test_each_derived_sentence_is_on_the_page(key):
    assert _printed(key)


def test_every_number_of_the_intercept_page_is_checked():
    """A number in docs/intercept.md's prose is read by a row of ``CHECKS``, derived by
    a test here, an input, or a quoted outside check."""
    patterns = [c[1] for c in CHECKS if c[0] == INT] + list(DERIVED.values()) + list(OUTSIDE)
    assert unlisted_numbers(INT, patterns, INPUTS) == []


def test_the_end_to_end_runs_took_a_bound_that_held():
    """'both read 0 in the published runs': the end-to-end run tables
    (docs/results/e2e/) count no bearing at which the attitude loop's bound or the true
    pointing residual exceeded the bound the sets took."""
    (printed_count,) = _printed("pointing_counts")
    for noise in ("random", "game"):
        (row,) = results(f"docs/results/e2e/kp_fig3_attitude-infoset-{noise}-s3.parquet")
        assert row["pointing_bound_exceeded_steps"] == int(printed_count)
        assert row["pointing_residual_over_bound_steps"] == int(printed_count)
        assert row["pointing_residual_max_deg"] <= row["pointing_knowledge_bound_deg"]


def test_a_filter_without_the_range_box_loses_the_range_as_the_page_says():
    """'the EKF's range estimate in the second run swings over megametres and turns
    negative with status `ok`, its belief falls under the blind range, guidance stops and
    the miss is kilometres': the page's own command, its second run traced."""
    from kalman_vs_infoset.experiments.scenario import load_scenario

    from kalman_vs_infoset.api import trace

    flat = " ".join((ROOT / INT).read_text(encoding="utf-8").split())
    command = re.search(
        r"`(kvi intercept kp_fig5 --estimators ekf --runs 2 --trace 1 [^`]*)`", flat
    )
    assert command, "the example's command is gone (re-point this test)"
    sets = [s.strip("'") for s in re.findall(r"--set ('[^']*')", command.group(1))]
    steps, _ = trace(load_scenario("kp_fig5", sets), "ekf", "random", runs=[1], sets_every=10**6)
    negative = steps[steps["x_est_m"] < 0]
    assert len(negative) and (negative["status"] == "ok").any()
    assert steps["x_est_m"].max() - steps["x_true_m"].max() > 1e6  # megametres off
    assert steps["miss_m"].iloc[0] > 1000.0 and steps["step"].max() < 0.5 * 199
