"""Paired differences of ``kvi compare`` (:mod:`experiments.paired`), against independent
computations: Student's t interval from its formula (``scipy.stats.t`` quantiles), the
signed-rank test's exact p-value by enumerating every sign pattern, and the pairing
itself on hand-made tables."""

from __future__ import annotations

import itertools

import numpy as np
import pandas as pd
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.experiments.paired import (
    comparison,
    paired_markdown,
    paired_rows,
    paired_stats,
    reference_of,
    variants,
)
from scipy import stats


def test_mean_difference_interval_is_students_t_formula():
    """``mean +- t_{n-1, 0.975} s / sqrt(n)`` with ``s`` the sample standard deviation."""
    d = np.random.default_rng(11).normal(0.3, 2.0, size=23)
    out = paired_stats(d)
    half = stats.t.ppf(0.975, d.size - 1) * d.std(ddof=1) / np.sqrt(d.size)
    assert out["mean"] == pytest.approx(d.mean(), rel=1e-14)
    assert out["ci"] == pytest.approx([d.mean() - half, d.mean() + half], rel=1e-12)
    assert out["median"] == np.median(d)
    assert out["larger_share"] == np.count_nonzero(d > 0) / d.size


def _exact_signed_rank_p(d: np.ndarray) -> float:
    """Two-sided p of the signed-rank statistic by enumerating all 2^n sign patterns
    (distinct, nonzero |d|: ranks 1..n)."""
    ranks = stats.rankdata(np.abs(d))
    observed = ranks[d > 0].sum()
    sums = np.array([sum(r for r, s in zip(ranks, signs, strict=True) if s)
                     for signs in itertools.product((False, True), repeat=d.size)])  # fmt: skip
    low, high = np.mean(sums <= observed), np.mean(sums >= observed)
    return min(1.0, 2.0 * min(low, high))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_signed_rank_p_is_the_exact_enumeration(seed):
    rng = np.random.default_rng(seed)
    d = rng.permutation(np.arange(1, 11)) * rng.choice([-1.0, 1.0], size=10) + 0.5
    assert paired_stats(d)["wilcoxon_p"] == pytest.approx(_exact_signed_rank_p(d), rel=1e-12)


def _enumerated_p_with_ties(d: np.ndarray) -> float:
    """The same enumeration, conditional on ties and zeros: zeros dropped, tied
    magnitudes given their mean rank (Hollander, Wolfe & Chicken 2014, sec. 3.1)."""
    return _exact_signed_rank_p(d[d != 0])


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(-4, 4), min_size=1, max_size=13))
def test_signed_rank_p_with_zeros_and_ties_is_the_conditional_enumeration(values):
    """Small integer differences: many zeros and ties. scipy's default switched to the
    normal approximation for these (0.109 where the exact p is 0.25, 0.18 for 0.5)."""
    d = np.array(values, dtype=float) * 0.05
    got = paired_stats(d)["wilcoxon_p"]
    if not np.any(d):
        assert got is None
    else:
        assert got == pytest.approx(_enumerated_p_with_ties(d), rel=1e-12)


def test_signed_rank_p_of_the_reviewed_case():
    """17 zero differences and three negative ones: the exact two-sided p is 2/8."""
    d = np.array([0.0] * 17 + [-0.05, -0.10, -0.15])
    assert paired_stats(d)["wilcoxon_p"] == 0.25


def test_differences_rounded_apart_are_one_tie():
    """Equal steps on a control grid, subtracted: 0.02 arrives as 0.019999999999996 and
    0.020000000000003. They are one tied value (not two ranks), as the exact ones are."""
    grid = np.array([0.02, 0.02, -0.02, 0.04, 0.02, -0.04, 0.06])
    rounded = grid + np.array([-4e-15, 3e-15, 0.0, 2e-15, -1e-15, 0.0, 5e-15])
    assert paired_stats(rounded)["wilcoxon_p"] == paired_stats(grid)["wilcoxon_p"]
    assert paired_stats(grid)["wilcoxon_p"] == pytest.approx(_enumerated_p_with_ties(grid))


@pytest.mark.parametrize("n", [20, 50])
def test_signed_rank_p_without_ties_is_scipys_exact_distribution(n):
    d = np.random.default_rng(n).normal(0.4, 1.0, size=n)
    want = stats.wilcoxon(d, method="exact").pvalue
    assert paired_stats(d)["wilcoxon_p"] == pytest.approx(want, rel=1e-10)


def test_above_fifty_differences_the_p_value_is_the_normal_approximation():
    """Scipy's approximation with the tie correction (z from the tie-corrected
    variance, computed here by hand)."""
    rng = np.random.default_rng(5)
    d = np.round(rng.normal(0.2, 1.0, size=300), 1)  # ties and zeros
    nz = d[d != 0]
    r = stats.rankdata(np.abs(nz))
    t = r[nz > 0].sum()
    n = nz.size
    _, tie_counts = np.unique(np.abs(nz), return_counts=True)
    var = n * (n + 1) * (2 * n + 1) / 24 - (tie_counts**3 - tie_counts).sum() / 48
    z = (t - n * (n + 1) / 4) / np.sqrt(var)
    assert paired_stats(d)["wilcoxon_p"] == pytest.approx(2 * stats.norm.sf(abs(z)), rel=1e-9)


def test_undefined_statistics_are_none():
    assert paired_stats(np.array([]))["mean"] is None
    one = paired_stats(np.array([2.0]))
    assert one["mean"] == 2.0 and one["ci"] is None and one["wilcoxon_p"] is not None
    zeros = paired_stats(np.zeros(5))
    assert zeros["ci"] == [0.0, 0.0] and zeros["wilcoxon_p"] is None
    assert zeros["larger_share"] == 0.0


def _table(values: dict[str, list[float]], status=None, noise="random") -> pd.DataFrame:
    rows = []
    for est, miss in values.items():
        for j, m in enumerate(miss):
            ok = "ok" if status is None or (est, j) not in status else "failed"
            rows.append({"estimator": est, "noise": noise, "seed": 5, "run": j, "miss_m": m,
                         "fuel_mps": 10.0 * m, "status": ok})  # fmt: skip
    return pd.DataFrame(rows)


def test_runs_are_paired_by_index_not_by_order_and_failures_drop_out():
    """A shuffled table gives the same rows; a run failed by either estimator, or with a
    non-finite value, is left out of that pair."""
    table = _table({"infoset": [1.0, 2.0, 3.0, 4.0], "ekf": [2.0, 2.5, np.inf, 9.0]},
                   status={("infoset", 3)})  # fmt: skip
    (row,) = paired_rows(table, "infoset")
    assert (row["estimator"], row["noise"]) == ("ekf", "random")
    assert row["miss_m"]["runs"] == 2  # run 2: inf; run 3: the reference failed
    assert row["miss_m"]["mean"] == pytest.approx(np.mean([1.0, 0.5]))
    assert row["fuel_mps"]["mean"] == pytest.approx(np.mean([10.0, 5.0]))
    shuffled = table.sample(frac=1.0, random_state=3)
    assert paired_rows(shuffled, "infoset") == [row]


def test_without_the_reference_no_run_is_paired():
    (row,) = paired_rows(_table({"ekf": [1.0, 2.0]}), "infoset")
    assert row["miss_m"]["runs"] == 0 and row["miss_m"]["mean"] is None


def test_the_reference_is_the_registrys_when_compared_else_the_first():
    assert reference_of("intercept", ["ekf", "infoset"]) == "infoset"
    assert reference_of("intercept", ["ukf", "ekf"]) == "ukf"
    assert reference_of("attitude", ["ukf", "box"]) == "box"
    assert comparison(_table({"ekf": [1.0]}), ["ekf"], "intercept") is None
    table = _table({"ukf": [1.0, 2.0], "ekf": [2.0, 2.0]})
    out = comparison(table, ["ukf", "ekf"], "intercept")
    assert out is not None and out["reference"] == "ukf"
    assert out["rows"] == paired_rows(table, "ukf") and out["confidence"] == 0.95


def test_a_missing_metric_column_is_left_out():
    """An attitude loop without one of the problem's metrics (here, no final angle): the
    others are compared, and the table prints them only."""
    table = _table({"box": [1.0, 2.0], "ukf": [2.0, 4.0]}).rename(
        columns={"miss_m": "settle_time_s", "fuel_mps": "energy_N2m2s"}
    )
    out = comparison(table, ["box", "ukf"], "attitude")
    assert out is not None and out["metrics"] == ["settle_time_s", "energy_N2m2s"]
    text = paired_markdown(out, "attitude")
    assert "settle time - box" in text and "energy - box" in text and "final angle" not in text


def test_the_markdown_prints_every_row_and_dashes_for_missing():
    rows = paired_rows(_table({"infoset": [1.0, 2.0], "ekf": [1.5], "ukf": [3.0, 1.0]}), "infoset")
    text = paired_markdown(
        {"reference": "infoset", "confidence": 0.95, "metrics": ["miss_m", "fuel_mps"],
         "rows": rows}
    )  # fmt: skip
    lines = text.strip().splitlines()
    assert len(lines) == 2 + 2 and "95 % CI" in lines[0]
    assert "| ekf | random | 1 | 0.50 [-] / 0.50 |" in text  # one pair: no interval


def test_the_markdown_prints_a_dash_for_a_nan_statistic_as_the_summaries_do():
    """A statistic that is NaN (no run gave it; e.g. a comparison read back from a JSON
    written by another tool) prints as ``-``, as ``errors.stat_text`` prints it in the
    summaries, not as ``nan``."""
    nan = float("nan")
    stats = {"runs": 3, "mean": nan, "ci": [nan, 1.0], "median": 0.5, "larger_share": nan,
             "wilcoxon_p": nan}  # fmt: skip
    row = {"estimator": "ekf", "noise": "random", "miss_m": stats}
    text = paired_markdown(
        {"reference": "infoset", "confidence": 0.95, "metrics": ["miss_m"], "rows": [row]}
    )
    assert "nan" not in text.lower()
    assert "| ekf | random | 3 | - [-, 1.00] / 0.50 | - | - |" in text


@settings(max_examples=40, deadline=None)
# (up to 8 pairs: with ties, scipy's signed-rank test enumerates 2^n sign patterns)
@given(st.lists(st.tuples(st.floats(0, 100), st.floats(0, 100)), min_size=2, max_size=8))
# found by `make fuzz` (seed 1796543303): a subnormal difference made the tie tolerance
# underflow to 0 and the signed-rank count raise
@example(pairs=[(0.0, 0.0), (0.0, 5e-324)])
def test_swapping_the_roles_negates_the_differences(pairs):
    """Estimator against reference, and back: mean, interval and median negate, the
    larger shares are those of the opposite sign, the two-sided p is the same."""
    a, b = (list(x) for x in zip(*pairs, strict=True))
    (ab,) = paired_rows(_table({"infoset": b, "ekf": a}), "infoset")
    (ba,) = paired_rows(_table({"infoset": b, "ekf": a}), "ekf")
    x, y = ab["miss_m"], ba["miss_m"]
    assert x["mean"] == pytest.approx(-y["mean"], abs=1e-9)
    assert x["median"] == pytest.approx(-y["median"], abs=1e-9)
    # (no interval either way when the pairs repeat one engagement: all equal)
    assert (x["ci"] is None) == (y["ci"] is None) == (len(set(pairs)) == 1)
    if x["ci"] is not None:
        assert x["ci"] == pytest.approx([-y["ci"][1], -y["ci"][0]], abs=1e-9)
    d = np.subtract(a, b)
    assert x["larger_share"] == np.mean(d > 0) and y["larger_share"] == np.mean(d < 0)
    assert (x["wilcoxon_p"] is None) == (y["wilcoxon_p"] is None)
    if x["wilcoxon_p"] is not None:
        assert x["wilcoxon_p"] == pytest.approx(y["wilcoxon_p"], rel=1e-9)


def test_fig5_variants_are_paired_per_estimator():
    """``kvi fig5``: the range finder's variant minus bearings only, per estimator and
    noise, matched by run (here the UKF's runs differ from the set's)."""
    one = _table({"infoset": [1.0, 2.0, 3.0], "ukf": [5.0, 5.0, 5.0]}).assign(variant="b")
    two = _table({"infoset": [2.0, 2.0, 5.0], "ukf": [4.0, 6.0, 5.0]}).assign(variant="r")
    out = variants(pd.concat([two, one]), "b")
    assert out["reference"] == "b" and out["by"] == "variant"
    rows = {r["estimator"]: r for r in out["rows"]}
    assert rows["infoset"]["variant"] == "r" and rows["infoset"]["noise"] == "random"
    assert rows["infoset"]["miss_m"]["mean"] == pytest.approx(1.0)  # (1 + 0 + 2) / 3
    assert rows["ukf"]["miss_m"]["mean"] == pytest.approx(0.0)
    assert rows["ukf"]["miss_m"]["larger_share"] == pytest.approx(1 / 3)
    text = paired_markdown(out)
    assert text.splitlines()[0].startswith("| variant | noise | estimator | paired runs |")


def test_the_paired_summaries_do_not_refuse_a_resume():
    """paired.py, stats.py and the figures summarise stored runs: presentation, outside
    the code hash that decides whether stored runs are resumed; and no code that
    computes a run's row (the estimators, guidance, the simulations) imports them."""
    import re

    from kalman_vs_infoset.experiments import provenance

    for name in ("paired.py", "stats.py", "figstyle.py", "plots_intercept.py"):
        assert any(provenance.ROOT.joinpath("experiments", name).match(p)
                   for p in provenance.PRESENTATION), name  # fmt: skip
    shown = re.compile(r"experiments(?:\.| import )(?:stats|paired|report|figstyle|plots)\b")
    for folder in ("estim", "guidance", "experiments/sim"):
        for f in provenance.ROOT.joinpath(folder).rglob("*.py"):
            assert not shown.search(f.read_text()), f


@pytest.mark.parametrize("tiny", [5e-324, 1e-310, 2.2e-308])
def test_signed_rank_p_of_subnormal_differences_is_that_of_larger_ones(tiny):
    """Differences at the smallest scales rank as larger ones do: the p-value of
    (tiny, -tiny, 2 tiny) equals that of (1, -1, 2), counted by hand (Hollander, Wolfe
    & Chicken sec. 3.1: ranks 1.5, 1.5, 3; T+ = 4.5 of 6, its mean 3; the 8 sign
    patterns give T+ in {0, 1.5, 1.5, 3, 3, 4.5, 4.5, 6}, of which 6 lie 1.5 or more
    from the mean: p = 0.75)."""
    assert paired_stats(np.array([1.0, -1.0, 2.0]))["wilcoxon_p"] == pytest.approx(0.75)
    d = np.array([tiny, -tiny, 2 * tiny])
    assert paired_stats(d)["wilcoxon_p"] == pytest.approx(0.75)


def test_runs_that_repeat_one_engagement_are_one_pair_not_n():
    """A fixed truth under a deterministic adversary repeats one engagement in every run
    (``kvi compare kp_fig3 --noise game``): four identical pairs printed a zero-width
    interval and p = 0.12 (fifty: p = 2e-15) as if they were independent. They are one
    observation: no interval, a test of one pair, and the table says so; runs that
    differ in any metric or on either side stay independent pairs."""
    same = _table({"infoset": [2.0] * 4, "ekf": [5.0] * 4})
    (row,) = paired_rows(same, "infoset")
    for m in ("miss_m", "fuel_mps"):
        assert row[m]["runs"] == 4 and row[m]["distinct_runs"] == 1
        assert row[m]["ci"] is None and row[m]["wilcoxon_p"] == 1.0
    assert row["miss_m"]["mean"] == 3.0 and row["miss_m"]["larger_share"] == 1.0
    paired = {"reference": "infoset", "confidence": 0.95, "metrics": ["miss_m", "fuel_mps"],
              "rows": [row]}  # fmt: skip
    assert "| ekf | random | 4 (one engagement) |" in paired_markdown(paired)
    # the reference's runs differ: four independent pairs
    (row,) = paired_rows(_table({"infoset": [2.0, 2.0, 2.0, 2.5], "ekf": [5.0] * 4}), "infoset")
    assert row["miss_m"]["distinct_runs"] == 4 and row["miss_m"]["ci"] is not None
    # the same misses, another fuel in one run: independent too
    differ = same.copy()
    differ.loc[(differ["estimator"] == "ekf") & (differ["run"] == 3), "fuel_mps"] = 51.0
    (row,) = paired_rows(differ, "infoset")
    assert row["miss_m"]["distinct_runs"] == 4 and row["miss_m"]["wilcoxon_p"] < 1.0
