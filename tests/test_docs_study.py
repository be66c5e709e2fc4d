"""docs/performance.md's large study: the numbers derived from the measured runs
(``kvi fig5 --runs 50 --workers 1|2`` and on a local Dask scheduler, kept in
``docs/results/study/``) are the arithmetic the text says, and the Dask run drew the
same table as the local processes."""

from __future__ import annotations

import re

from docs_numbers import ROOT, agrees, results

STUDY = "docs/results/study/fig5-"
TEXT = " ".join((ROOT / "docs/performance.md").read_text(encoding="utf-8").split())


def test_ten_thousand_runs_per_variant_are_200_times_the_measured_50():
    """10 000 runs per variant = 200 x the 2-worker column's CPU time, in CPU-hours and
    in hours on the host's 2 cores."""
    found = re.search(r"200 times the column: ([\d.]+) CPU-hours, ([\d.]+) hours on this "
                      r"host's (\d+) cores", TEXT)  # fmt: skip
    assert found, "the sentence was rewritten: re-point this test"
    cpu_h = 200 * sum(v["cpu_s"] for v in results(STUDY + "w2.json")["variants"]) / 3600
    cores = int(found.group(3))
    assert cores == results("docs/results/bench.json")["machine"]["cpus"]
    assert agrees(found.group(1), cpu_h)
    assert agrees(found.group(2), cpu_h / cores)


def test_the_dask_run_drew_the_same_table_as_local_processes():
    """The same seeds give the same runs wherever they run (the study's Dask claim)."""
    keys = ("variant", "noise", "runs", "miss_m", "fuel_mps", "truth_outside", "failures")
    runs = [results(f"{STUDY}{w}.json")["variants"] for w in ("w1", "w2", "dask")]
    first = [{k: v[k] for k in keys} for v in runs[0]]
    for other in runs[1:]:
        assert [{k: v[k] for k in keys} for v in other] == first
    assert all(v["cpu_s"] is None for v in runs[2])  # a cluster's workers: not counted


def test_the_speed_options_defaults_rows_are_the_published_runs():
    """docs/performance.md's table of the node set's speed options: its defaults' rows are
    the runs of the published comparison (the same seeds, the same numbers)."""
    keys = ("runs", "seed", "miss_m", "fuel_mps", "truth_outside", "empty_set", "failures")
    published = {
        r["noise"]: {k: r[k] for k in keys}
        for r in results("docs/results/compare_kp_fig5.json")["rows"]
        if r["estimator"] == "infoset"
    }
    for row in results("docs/results/speed/kp_fig5-default.json")["rows"]:
        assert {k: row[k] for k in keys} == published[row["noise"]], row["noise"]
