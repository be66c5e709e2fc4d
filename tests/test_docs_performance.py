"""docs/performance.md: an inventory like the README's. Every number of its prose is read
by a row of ``CHECKS``, by a sentence a test of ``test_docs_study.py`` or
``test_docs_tightness.py`` checks (``docs_numbers.searched_patterns``, read from those
tests' own source), by a test here (``DERIVED``), or is an input (``INPUTS``). Its tables
are ``test_docs_tables.py``'s.
"""

from __future__ import annotations

import math

import docs_bench_table
import numpy as np
import test_docs_study
import test_docs_tightness
from docs_checks import CHECKS, PERF
from docs_numbers import (
    ROOT,
    agree_each,
    agrees,
    band_widths_pct,
    printed,
    results,
    scenario_tables,
    searched_patterns,
)
from test_docs_numbers import unlisted_numbers

#: the sentences whose numbers the tests below derive, by test
DERIVED = {
    "exponent": r"that approach cost ([\d.]+) to ([\d.]+) ms and the exponent read ([\d.]+) to "
    r"(\d+\.\d+)",
    "memory": r"kept are runs with the cache filled, (\d+) to (\d+) MB a worker over all of them",
    "old": r"the old commit's runs read ([\d.]+) to ([\d.]+) CPU-s",
    "approach": r"an approach of about (\d+) steps instead of (\d+)\)",
    "width": r"Fig\. 5's interval is ([\d.]+) % wide",
    "bands": r"scale by its width, ([\d.]+) %, where four relax it by ([\d.]+) % each",
    "median": r"load average ([\d.]+) and ([\d.]+)\), read an exponent of ([\d.]+) and ([\d.]+) "
    r"\(([\d.]+) / ([\d.]+) / ([\d.]+) ms and ([\d.]+) / ([\d.]+) / ([\d.]+) ms\)\. One pass "
    r"moved by up to ([\d.]+) % from its approach's median, and the slope through one pass "
    r"of each approach read ([\d.]+) to ([\d.]+) over the six passes",
    "make_run": r"what `make run` runs after its install, took ([\d.]+) s\s+of wall clock",
    "make_run_now": r"took ([\d.]+) to ([\d.]+) s of wall clock\s+over (\d+) runs in two "
    r"series half an hour\s+apart, at ([\d.]+) to ([\d.]+) CPU-s for the same work "
    r"\(`docs/results/make_run_wall\.json`\):\s+under the target of 30 s in (\d+) of the "
    r"(\d+),",
    "make_run_row": r"\| `make run`, wall clock, 2 cores, nothing else running "
    r"\(`make_run_wall\.json`\) \| ([\d.]+) to ([\d.]+) s, (\d+) of (\d+) runs within \| "
    r"<= 30 s \(met on a quiet host only\) \|",
    "interleaved": r"\(`docs/results/bench_interleaved_1\.json` and `_2\.json`, load average "
    r"([\d.]+) and ([\d.]+), the second beside a test run\) read the whole approach at "
    r"([\d.]+) and ([\d.]+) UKF steps, the UKF's step there at (\d+) and (\d+) us",
    "glance": r"every one of them misses the engine's goals: the Fig\. 3 game engagement read "
    r"(\d+) to (\d+) UKF steps \(goal 60\), the random one (\d+) to (\d+) \(goal 40\), the "
    r"whole approach ([\d.]+) to ([\d.]+) UKF steps \(goal 0\.5\) and the cost exponent "
    r"([\d.]+) to ([\d.]+) \(goal 1\.2\)\. The costliest `--help` met its goal of 0\.5 "
    r"CPU-s in (\d+) of the (\d+) readings",
    "median_ratio": r"the whole approach read ([\d.]+) and ([\d.]+) UKF steps, because the "
    r"UKF's step there moved \((\d+) and (\d+) us\) and the set's did not \((\d+) and (\d+) "
    r"us\); the engagements read (\d+) / (\d+) and (\d+) / (\d+) UKF steps",
}

#: the benchmark's and the studies' settings, the options' values, seeds and sections
INPUTS = (
    r"§\d(\.\d)?",
    r"Figs?\. \d+",
    r"median of 3 repetitions",
    r"with 1 (and|/) 2\s+workers",
    r"\b0\.5 target",
    r'"5x" target',
    r"commit 35e3739",
    r"target 5: not met",
    r"\(58 km/s exactly\); at 10 km/s",
    r"known only to\s+within 1 %",
    r"rounding of 1 AU",
    r"0\.125-s steps",
    r"runs on 2 workers",
    r"50 runs a noise",
    r"57\.9\.\.58\.1 km/s",
    r"passes 1\.03 times",
    r"with 8 nodes a piece instead of 12",
    r"at 4 live nodes instead of 5",
    r"\b0 by default",
    r"seeds 601-610",
    r"3-sigma",
    r"10 000 runs per variant",
    r"50 runs per variant",
    r"pairs of 50-run",
    r"host's 2 CPUs",
    r"--workers [12]`",
    r"100-step approach",
    r"100 / 200 / 400-step approaches",
    r"The whole command with 2 workers",
    r"the target of 30 s",
)


def test_every_number_of_the_performance_page_is_checked():
    """A number in docs/performance.md's prose is read by a row of ``CHECKS``, searched
    by a test of the study or tightness checks, or an input."""
    patterns = [c[1] for c in CHECKS if c[0] == PERF]
    patterns += searched_patterns(test_docs_study) + searched_patterns(test_docs_tightness)
    patterns += list(DERIVED.values())
    assert unlisted_numbers(PERF, patterns, INPUTS) == []


def _read(key: str) -> tuple[str, ...]:
    return printed(PERF, DERIVED[key])


def test_the_exponents_spread_is_the_table_hosts_readings():
    """The 100-step approach's cost and the cost exponent over the bench readings kept
    from the table's host (``kvi bench --json``); the workers' peak memory over every
    kept reading."""
    table_host = ("bench", "bench_tail", "bench_at_39ec9cf", "bench_at_1f4367d")
    runs = [results(f"docs/results/{name}.json") for name in table_host]
    ms = [r["cost_ms"][0] for r in runs]
    exponent = [r["cost_exponent"] for r in runs]
    assert all(r["cost_steps"][0] == 100 for r in runs)
    agree_each(_read("exponent"), (min(ms), max(ms), min(exponent), max(exponent)))
    peaks = [
        mb
        for path in sorted((ROOT / "docs/results").glob("bench*.json"))
        for mb in results(str(path.relative_to(ROOT)))["worker_peak_rss_mb"].values()
    ]
    lo, hi = _read("memory")
    assert agrees(lo, min(peaks)) and agrees(hi, max(peaks))


def test_the_old_commits_runs_spread_over_the_three_comparisons_of_that_day():
    """'the old commit's runs read 56.5 to 69.6 CPU-s': commit 35e3739's runs in the
    three comparisons the paragraph quotes."""
    old = [
        cpu
        for tag in ("e8e92a3", "6ca6544", "8790e49")
        for cpu in results(f"docs/results/vs_35e3739_at_{tag}.json")["cpu_s_35e3739"]
    ]
    lo, hi = _read("old")
    assert agrees(lo, min(old)) and agrees(hi, max(old))


def test_the_slow_encounters_approach_is_its_steps_to_the_blind_range():
    """The steps until the range falls to eps, ``ceil((x0 - eps) / (e dt))``, of Fig. 3's
    engagement at 10 km/s and at its own 58 km/s."""
    sc = scenario_tables("kp_fig3")
    x0, eps, dt = sc["truth"]["x_km"][0], sc["model"]["eps_km"], sc["model"]["dt_s"]
    slow, fast = _read("approach")
    assert int(slow) == math.ceil((x0 - eps) / (10.0 * dt))
    assert int(fast) == math.ceil((x0 - eps) / (sc["model"]["closing_speed_kmps"] * dt))


def test_the_closing_speed_bands_relative_widths():
    """Fig. 5's closing-speed interval (57.9..58.1 km/s), ``e_hi / e_lo - 1``, and the
    widest of four bands cut as the node set cuts them: equal pieces of ``u = 1/e``."""
    e_lo, e_hi = scenario_tables("kp_fig5")["estimator"]["closing_speed_kmps"]
    (width,) = _read("width")
    one, four = _read("bands")
    assert agrees(width, 100.0 * (e_hi / e_lo - 1.0)) and one == width
    assert agrees(one, band_widths_pct("kp_fig5", 1)[0])
    assert agrees(four, max(band_widths_pct("kp_fig5", 4)))


def test_the_table_of_every_bench_reading_is_built_from_the_files():
    """The page prints the table that ``docs_bench_table.table()`` builds from every
    ``docs/results/bench*.json`` (a reading kept and not listed, or a cell changed,
    fails), and the ranges under it are the readings' least and largest."""
    text = (ROOT / PERF).read_text(encoding="utf-8")
    assert docs_bench_table.table() in text
    r = docs_bench_table.ranges()
    readings = [row for _, row in docs_bench_table.readings()]
    met = sum(row["help_cpu_s_max"] <= 0.5 for row in readings)
    shown = [*r["game"], *r["random"], *r["whole"], *r["exponent"], met, len(readings)]
    agree_each(_read("glance"), shown)


def test_the_median_exponent_is_its_two_bench_runs():
    """The two bench runs with the median cost exponent: each approach's cost the
    median of its passes, the exponent numpy's slope through them, the largest move of
    one pass from its median, and the slope through pass k of each approach (numpy's
    polyfit, computed here); the whole approach and the engagements in UKF steps."""

    runs = [results(f"docs/results/bench_median_exponent_{i}.json") for i in (1, 2)]
    got = _read("median")
    shown = [r["machine"]["load_average"] for r in runs] + [r["cost_exponent"] for r in runs]
    shown += [*runs[0]["cost_ms"], *runs[1]["cost_ms"]]
    one_pass, moved = [], 0.0
    for r in runs:
        passes = np.array(r["cost_ms_passes"])  # approach x pass
        median = np.median(passes, axis=1)
        assert np.allclose(median, r["cost_ms"])
        log_steps = np.log(r["cost_steps"])
        assert math.isclose(r["cost_exponent"], np.polyfit(log_steps, np.log(median), 1)[0])
        moved = max(moved, float(np.max(np.abs(passes / median[:, None] - 1.0))) * 100)
        one_pass += [np.polyfit(log_steps, np.log(passes[:, k]), 1)[0] for k in range(3)]
    assert len(one_pass) == 6
    agree_each(got, [*shown, moved, min(one_pass), max(one_pass)])
    ratio = _read("median_ratio")
    shown = [r["whole_approach_ratio"] for r in runs]
    shown += [r["whole_approach_step_us"]["ukf"] for r in runs]
    shown += [r["whole_approach_step_us"]["infoset"] for r in runs]
    shown += [r[k] for r in runs for k in
              ("engagement_in_ukf_steps", "engagement_random_in_ukf_steps")]  # fmt: skip
    agree_each(ratio, shown)


def test_the_interleaved_bench_runs_are_their_files():
    """The two bench runs with the estimators' passes taken in turn: load, the whole
    approach in UKF steps and the UKF's step there."""
    runs = [results(f"docs/results/bench_interleaved_{i}.json") for i in (1, 2)]
    shown = [r["machine"]["load_average"] for r in runs]
    shown += [r["whole_approach_ratio"] for r in runs]
    shown += [r["whole_approach_step_us"]["ukf"] for r in runs]
    agree_each(_read("interleaved"), shown)


def test_the_make_run_wall_clock_is_the_study_file():
    """`make run`'s command (``kvi fig5``, 50 runs per variant, 2 workers): its wall
    clock as the study's results file records it."""
    (wall,) = _read("make_run")
    assert agrees(wall, results("docs/results/study/fig5-w2.json")["wall_s"])


def test_make_run_today_is_its_timing_file():
    """`make run` timed in two series (``docs/results/make_run_wall.json``: wall clock and
    the children's CPU time of each run): the page's numbers, in its prose and in the
    goals' table, are the file's, the count within 30 s included."""
    timed = results("docs/results/make_run_wall.json")
    runs = [r for series in timed["series"] for r in series["runs"]]
    walls, cpus = [r["wall_s"] for r in runs], [r["cpu_s"] for r in runs]
    within = sum(w <= 30.0 for w in walls)
    assert timed["command"] == "rm -rf results/fig5 && make run" and timed["cpus"] == 2
    shown = [min(walls), max(walls), len(runs), min(cpus), max(cpus), within, len(runs)]
    agree_each(_read("make_run_now"), shown)
    agree_each(_read("make_run_row"), [min(walls), max(walls), within, len(runs)])
