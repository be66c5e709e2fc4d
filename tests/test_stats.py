"""The summary statistics (mean / p50 / p90 / max) every command prints, against numpy's
percentile for finite samples and against the rule's limit when samples are infinite
(runs that never settled enter the attitude summaries as ``inf``)."""

from fractions import Fraction

import numpy as np
import pandas as pd
import pytest
from hypothesis import example, given
from hypothesis import strategies as st
from kalman_vs_infoset.experiments.stats import percentile, summary_stats

finite = st.floats(-1e6, 1e6, allow_nan=False)
QS = st.sampled_from([0.0, 10.0, 50.0, 90.0, 100.0]) | st.floats(0.0, 100.0)


@given(st.lists(finite, min_size=1, max_size=30), QS)
def test_finite_samples_give_numpys_percentile_to_the_last_digit(xs, q):
    assert percentile(np.array(xs), q) == float(np.percentile(xs, q))


def _exact_rule(xs: list[float], q: float) -> Fraction:
    """The linear rule in exact rationals (samples and position), an independent
    reference for finite samples."""
    x = sorted(Fraction(v) for v in xs)
    h = Fraction(q) * (len(x) - 1) / 100
    lo = int(h)
    hi = min(lo + 1, len(x) - 1)
    return x[lo] + (h - lo) * (x[hi] - x[lo])


@given(st.lists(finite, min_size=0, max_size=20), st.integers(1, 10), QS)
# a position a hair past a finite sample (fuzz seed 1205051103): the rule reaches inf
@example(xs=[1.0], n_inf=1, q=2.2250738585072014e-308)
def test_infinite_samples_give_the_limit_of_a_growing_sample(xs, n_inf, q):
    """Replacing each ``inf`` by a huge ``M`` and letting ``M`` grow (the rule in exact
    rationals): the percentile either stays put (it does not reach the replaced
    samples) or grows without bound."""
    ours = percentile(np.array([*xs, *[np.inf] * n_inf]), q)
    big = [_exact_rule([*xs, *[m] * n_inf], q) for m in (1e200, 1e250)]
    if big[0] == big[1]:
        assert ours == pytest.approx(float(big[0]), rel=1e-12, abs=1e-300)
    else:
        assert ours == np.inf


def test_runs_that_never_settled_give_inf_statistics_not_nan():
    """A summary over settle times with unsettled runs (kept as ``inf``): all unsettled
    reads inf throughout; one unsettled of three leaves the median finite."""
    s = summary_stats([np.inf] * 3, finite_only=False)
    assert s == {"mean": np.inf, "p50": np.inf, "p90": np.inf, "max": np.inf}
    s = summary_stats([1.0, 2.0, np.inf], finite_only=False)
    assert s["p50"] == 2.0 and s["p90"] == np.inf and s["max"] == np.inf
    assert summary_stats([1.0, 2.0, np.inf])["p90"] == float(np.percentile([1.0, 2.0], 90))


def test_a_nan_sample_makes_every_statistic_nan_when_kept():
    """``finite_only=False`` keeps what is not finite: a NaN sample has no place in the
    order, so no statistic (p50 of ``[1, NaN, 3]`` read 3, NaN sorted last)."""
    import math

    from kalman_vs_infoset.experiments.stats import percentile, summary_stats

    values = np.array([1.0, np.nan, 3.0])
    assert all(math.isnan(v) for v in summary_stats(values, finite_only=False).values())
    assert math.isnan(percentile(values, 50.0)) and math.isnan(percentile(values, 0.0))
    assert summary_stats(values)["p50"] == 2.0  # finite_only (the default) drops it


def test_the_intercept_summary_keeps_a_value_that_is_not_finite():
    """The intercept summary dropped a finished run's NaN miss from its statistics (the
    mean over the others, "failures 0"); it now shows in them."""
    import math

    import pandas as pd
    from kalman_vs_infoset.experiments.intercept_runs import summarise
    from kalman_vs_infoset.experiments.scenario import load_scenario

    df = pd.DataFrame(
        {"status": "ok", "miss_m": [1.0, np.nan, 3.0], "fuel_mps": [1.0, 2.0, 3.0],
         "truth_outside": 0, "contradictions": 0, "diverged": False}
    )  # fmt: skip
    out = summarise(df, load_scenario("kp_fig3"), "ekf", "random", 3, 0.0)
    assert math.isnan(out["miss_m"]["mean"]) and out["fuel_mps"]["mean"] == 2.0


def test_a_run_with_an_unbounded_set_enters_the_knowledge_bound_statistics():
    """An attitude run whose set was the whole space on a step has an infinite mean
    knowledge bound: it makes p90 and max infinite (it was left out: mean 0.6, max 0.7
    over three runs, one unbounded); a NaN (no value) is left out."""
    from kalman_vs_infoset.experiments.stats import estimator_counts

    table = pd.DataFrame({"truth_outside": [0] * 4, "empty_steps": [0] * 4,
                          "unbounded_steps": [0, 0, 40, 0],
                          "mean_knowledge_bound_deg": [0.5, 0.7, np.inf, np.nan]})  # fmt: skip
    out = estimator_counts(table)
    assert out["unbounded_steps"] == 40
    stats = out["mean_knowledge_bound_deg"]
    assert stats["mean"] == np.inf and stats["max"] == np.inf and stats["p90"] == np.inf
    assert stats["p50"] == 0.7  # the middle of 0.5, 0.7, inf
    finite = estimator_counts(table.iloc[[0, 1]])["mean_knowledge_bound_deg"]
    assert finite["mean"] == 0.6 and finite["max"] == 0.7


def test_the_intercept_table_says_dash_where_no_run_gave_a_value():
    """Every run failed: the intercept table printed "nan / nan / nan / nan" where the
    attitude tables print "-"; values keep their formats, ``inf`` stays ``inf``."""
    from kalman_vs_infoset.experiments.report import summary_markdown

    none = summary_stats([])
    row = {"estimator": "ekf", "runs": 2, "miss_m": none, "fuel_mps": none,
           "truth_outside": 0, "empty_set": 0, "diverged": 0, "failures": 2}  # fmt: skip
    line = summary_markdown([row], ["estimator"]).splitlines()[2]
    assert line == "| ekf | 2 | - / - / - / - | - / - / - / - | 0 | 0 | 0 | 2 |"
    row["miss_m"], row["fuel_mps"] = summary_stats([1.0, 2.0, np.inf], finite_only=False), {
        "mean": 150.04, "p50": 150.0, "p90": 150.0, "max": 151.0}  # fmt: skip
    line = summary_markdown([row], ["estimator"]).splitlines()[2]
    assert "| inf / 2.00 / inf / inf | 150.0 / 150.0 / 150.0 / 151.0 |" in line


def test_the_intercept_summary_and_the_adversaries_table_say_dash_for_no_value(monkeypatch):
    """Every run failed: the text summary of ``kvi intercept`` and the adversaries table
    printed ``nan``; they print "-" as the other tables do (values keep their format)."""
    from kalman_vs_infoset.experiments import cmd_adversaries, cmd_intercept

    none = summary_stats([])
    row = {"scenario": "s", "estimator": "ekf", "noise": "game", "runs": 2, "seed": 1,
           "miss_m": none, "fuel_mps": summary_stats([150.04, 151.0]), "truth_outside": 0,
           "empty_set": 0, "diverged": 0, "failures": 2}  # fmt: skip
    lines = cmd_intercept._summary(row)
    assert lines[1] == "  miss  m   mean -  p50 -  p90 -  max -"
    assert lines[2] == "  fuel m/s  mean 150.5  p50 150.5  p90 150.9  max 151.0"
    table = cmd_adversaries.table_markdown(
        {"seed_fuel_game_mps": None, "lookahead_steps": 1, "lookahead_candidates": 3,
         "candidates": 3, "rows": [{**row, "rule": "game", "runs_at_seed_fuel": np.nan}]}
    )  # fmt: skip
    assert "| ekf | game | 2 | 150.5 / 150.5 / 150.9 | - / - / - | n/a | 0 | 2 |" in table
