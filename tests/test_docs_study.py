"""docs/performance.md's large study: the numbers derived from the measured runs
(``kvi fig5 --runs 50 --workers 1|2`` and on a local Dask scheduler, kept in
``docs/results/study/``) are the arithmetic the text says, and the Dask run drew the
same table as the local processes."""

from __future__ import annotations

import re

import numpy as np
from docs_numbers import (
    ROOT,
    agree_each,
    agrees,
    results,
    speed_base_cpu_s,
    speed_cpu_s,
    speed_rows,
    study_variant,
)

STUDY = "docs/results/study/fig5-"
TEXT = " ".join((ROOT / "docs/performance.md").read_text(encoding="utf-8").split())


def _words(n: int) -> str:
    return {3: "three", 10: "ten", 20: "twenty"}[n]


def _cpu(path: str) -> list[float]:
    return [v["cpu_s"] for v in results(path)["variants"]]


def test_the_1000_run_study_costs_what_the_text_says():
    """docs/performance.md's 1000 runs per variant (``kvi fig5 --runs 1000 --workers 2``):
    twenty times ``make run``'s runs; the total CPU time and wall time; the CPU time a
    run against the 50-run 2-worker column's, per variant (extremes, the variant of the
    largest) and over all four; the workers' peak memory against the 50 runs'; and
    10 000 runs a variant as ten times the study, in CPU-hours and in hours on the
    host's cores. Every run kept the truth and none failed."""
    big, small = results(STUDY + "w2-1000.json"), results(STUDY + "w2.json")
    n_big, n_small = big["runs"], small["runs"]
    found = _found(r"Measured at (\d+) runs per variant, (\w+) times `make run` \(`kvi fig5 "
                   r"--runs (\d+) --workers 2`")  # fmt: skip
    assert int(found.group(1)) == int(found.group(3)) == n_big
    assert found.group(2) == _words(n_big // results("docs/results/fig5.json")["runs"])
    found = _found(r"fig5-w2-1000\.json`\): (\d+) CPU-s for the four variants, ([\d.]+) minutes "
                   r"on the host's (\d+) cores")  # fmt: skip
    assert int(found.group(3)) == results("docs/results/bench.json")["machine"]["cpus"]
    assert agrees(found.group(1), sum(_cpu(STUDY + "w2-1000.json")))
    assert agrees(found.group(2), big["wall_s"] / 60.0)
    # a second run of the same command: the same runs, its own CPU and wall time
    again = results(STUDY + "w2-1000-paired.json")
    keys = ("variant", "noise", "runs", "seed", "miss_m", "fuel_mps", "truth_outside")
    assert [{k: v[k] for k in keys} for v in again["variants"]] == [
        {k: v[k] for k in keys} for v in big["variants"]
    ]
    found = _found(r"a second run of the same command right after it, whose runs are the same "
                   r"to the last digit, read (\d+) CPU-s and ([\d.]+) minutes: "
                   r"`fig5-w2-1000-paired\.json`")  # fmt: skip
    assert agrees(found.group(1), sum(_cpu(STUDY + "w2-1000-paired.json")))
    assert agrees(found.group(2), again["wall_s"] / 60.0)
    per_run = [b / n_big / (s / n_small) for b, s in
               zip(_cpu(STUDY + "w2-1000.json"), _cpu(STUDY + "w2.json"), strict=True)]  # fmt: skip
    found = _found(r"A run cost ([\d.]+) to ([\d.]+) times the CPU time of the 2-worker column's "
                   r"\(the most in the bearings-only game, ([\d.]+) over all four\)")  # fmt: skip
    assert agrees(found.group(1), min(per_run)) and agrees(found.group(2), max(per_run))
    most = big["variants"][per_run.index(max(per_run))]
    assert (most["variant"], most["noise"]) == ("bearing only", "game")
    overall = sum(_cpu(STUDY + "w2-1000.json")) / n_big / (sum(_cpu(STUDY + "w2.json")) / n_small)
    assert agrees(found.group(3), overall)
    found = _found(r"at a rate the (\d+)-run column underestimates by less than a fifth")
    assert int(found.group(1)) == n_small and 1.0 < min(per_run) and max(per_run) < 1.2
    peak = lambda d: max(v["worker_peak_rss_mb"] for v in d["variants"])  # noqa: E731
    found = _found(r"worker peaked at (\d+) MB, (\d+) % more than over (\d+) runs, for (\w+) "
                   r"times the runs")  # fmt: skip
    assert int(found.group(3)) == n_small and found.group(4) == "twenty" == _words(n_big // n_small)
    assert agrees(found.group(1), peak(big))
    assert agrees(found.group(2), 100.0 * (peak(big) / peak(small) - 1.0))
    found = _found(r"(\d+ \d+) runs per variant are (\w+) times this study: ([\d.]+) CPU-hours, "
                   r"([\d.]+) hours on this host's (\d+) cores")  # fmt: skip
    n_10k = int(found.group(1).replace(" ", ""))
    assert found.group(2) == _words(n_10k // n_big)
    cpu_h = n_10k / n_big * sum(_cpu(STUDY + "w2-1000.json")) / 3600
    cores = int(found.group(5))
    assert cores == results("docs/results/bench.json")["machine"]["cpus"]
    assert agrees(found.group(3), cpu_h) and agrees(found.group(4), cpu_h / cores)
    found = _found(r"The first (\d+) runs of each variant are the table's .* the statistics of "
                   r"all (\d+) runs")  # fmt: skip
    assert (int(found.group(1)), int(found.group(2))) == (n_small, n_big)
    for v in big["variants"]:
        assert v["runs"] == n_big
        assert (v["truth_outside"], v["empty_set"], v["diverged"], v["failures"]) == (0,) * 4


def test_the_10000_run_variant_costs_and_draws_what_the_text_says():
    """docs/performance.md's 10 000 runs of the bearing + range variant under random
    errors: CPU and wall time, the CPU time a run against the 1000-run study's of that
    variant, the workers' peak memory against it, the statistics beside the 1000- and
    50-run studies', the runs' prefixes equal to those studies' runs (the kept Parquet of
    the runs' miss and fuel), every run inside and none failed, and the progress lines
    its stderr received."""
    import pandas as pd

    base = "docs/results/study/kp_fig5_range-random-10000"
    big = results(base + ".json")
    n = big["runs"]

    small, mid = (study_variant(STUDY + f, big["scenario"], big["noise"])
                  for f in ("w2.json", "w2-1000.json"))  # fmt: skip
    found = _found(r"Measured at (\d+ \d+) runs for one variant, the cheapest \(bearing \+ "
                   r"range under random errors: `kvi intercept (\w+) --runs (\d+) --noise (\w+) "
                   r"--estimators (\w+) --workers 2 --json`")  # fmt: skip
    assert int(found.group(1).replace(" ", "")) == int(found.group(3)) == n == 10_000
    assert found.groups()[1:] == (big["scenario"], str(n), big["noise"], big["estimator"])
    assert mid["variant"] == "bearing + range"
    # the cheapest variant per run, in the 50-run study
    assert small["cpu_s"] == min(v["cpu_s"] for v in results(STUDY + "w2.json")["variants"])
    found = _found(
        r"kp_fig5_range-random-10000\.json`; a few minutes of other work ran beside "
        r"it\): (\d+) CPU-s, ([\d.]+) minutes on the host's (\d+) cores\. A run cost "
        r"([\d.]+) times the CPU time of the (\d+)-run study's runs of that variant, "
        r"and each worker peaked at (\d+) MB \((\d+) MB in the (\d+)-run study\)"
    )
    assert int(found.group(3)) == results("docs/results/bench.json")["machine"]["cpus"]
    assert int(found.group(5)) == int(found.group(8)) == mid["runs"]
    agree_each(found.group(1, 2, 4, 6, 7), [
        big["cpu_s"], big["wall_s"] / 60.0, big["cpu_s"] / n / (mid["cpu_s"] / mid["runs"]),
        big["worker_peak_rss_mb"], mid["worker_peak_rss_mb"],
    ])  # fmt: skip
    runs = pd.read_parquet(ROOT / (base + "-runs.parquet")).sort_values("run")
    assert runs["run"].tolist() == list(range(n))
    for ref in (small, mid):  # the first runs are the smaller studies' runs
        head = runs[runs["run"] < ref["runs"]]
        for col in ("miss_m", "fuel_mps"):
            assert head[col].mean() == ref[col]["mean"] and head[col].max() == ref[col]["max"]
    assert runs["miss_m"].mean() == big["miss_m"]["mean"]
    found = _found(r"Its first (\d+) and first (\d+) runs are the (\d+)- and (\d+)-run studies'")
    assert [int(g) for g in found.groups()] == [small["runs"], mid["runs"]] * 2
    found = _found(r"Over the 10 000 runs the mean miss is ([\d.]+) m and the mean fuel ([\d.]+) "
                   r"m/s \(1000 runs: ([\d.]+) m and ([\d.]+) m/s; 50 runs: ([\d.]+) m and "
                   r"([\d.]+) m/s\)")  # fmt: skip
    agree_each(found.groups(), [x for v in (big, mid, small)
                                for x in (v["miss_m"]["mean"], v["fuel_mps"]["mean"])])  # fmt: skip
    assert (big["truth_outside"], big["empty_set"], big["diverged"], big["failures"]) == (0,) * 4
    assert (runs["truth_outside"] == 0).all() and (runs["status"] == "ok").all()
    lines = (ROOT / (base + "-stderr.txt")).read_text().splitlines()
    progress = [line for line in lines if re.search(r"\d+/\d+ runs, ~\d+ s left$", line)]
    last = re.search(rf"{n}/{n} runs \(([\d.]+) s\)$", lines[-1])  # its own clock
    assert last and abs(float(last.group(1)) - big["wall_s"]) < 1.0
    from kalman_vs_infoset.experiments.progress import LOG_EVERY_S

    found = _found(r"the command wrote (\d+) progress lines with the time left, one every (\d+) s")
    assert int(found.group(1)) == len(progress) and float(found.group(2)) == LOG_EVERY_S


def test_the_study_against_5f9e157_on_one_host():
    """The previous study (``*_at_5f9e157``) drew the same bearings-only runs at less CPU
    on another host; run alternately on one host, the two codes cost the same there
    (the ratios' extremes, the same results in every pair), and the range-finder rows
    cost more, with other results (``band_trials="auto"``)."""
    old_w1, now_w1 = (results(f"{STUDY}w1{tag}.json")["variants"] for tag in ("_at_5f9e157", ""))
    found = _found(r"another host\) read ([\d.]+) and ([\d.]+) CPU-s for the bearings-only rows "
                   r"with one worker, for the same runs to the last digit")  # fmt: skip
    assert agrees(found.group(1), old_w1[0]["cpu_s"]) and agrees(found.group(2), old_w1[1]["cpu_s"])
    keys = ("variant", "noise", "runs", "seed", "miss_m", "fuel_mps", "truth_outside")
    for old, now in zip(old_w1[:2], now_w1[:2], strict=True):
        assert old["variant"] == "bearing only" and {k: old[k] for k in keys} == {
            k: now[k] for k in keys
        }
    side = results("docs/results/study/side_by_side_5f9e157.json")
    found = _found(r"\((\w+) pairs of `kvi fig5 --runs (\d+) --workers 1`, the code of 5f9e157 "
                   r"first")  # fmt: skip
    assert found.group(1) == _words(len(side["pairs"]))
    assert int(found.group(2)) == side["runs_per_variant"]
    ratios: dict[bool, list[float]] = {True: [], False: []}  # by "bearing only"
    for pair in side["pairs"]:
        for old, now in zip(pair["5f9e157"]["variants"], pair["now"]["variants"], strict=True):
            assert old["runs"] == now["runs"] == side["runs_per_variant"]
            bearing_only = old["variant"] == "bearing only"
            same = all(old[k] == now[k] for k in ("miss_m", "fuel_mps"))
            assert same == bearing_only, (old["variant"], old["noise"])
            ratios[bearing_only].append(now["cpu_s"] / old["cpu_s"])
    found = _found(r"this code's bearings-only rows cost ([\d.]+) to ([\d.]+) times the CPU time "
                   r"of 5f9e157's, with the same results\. Its range-finder rows cost ([\d.]+) to "
                   r"([\d.]+) times as much, and their results differ")  # fmt: skip
    values = (min(ratios[True]), max(ratios[True]), min(ratios[False]), max(ratios[False]))
    for printed, value in zip(found.groups(), values, strict=True):
        assert agrees(printed, value), (printed, value)


def test_the_dask_run_drew_the_same_table_as_local_processes():
    """The same seeds give the same runs wherever they run (the study's Dask claim)."""
    keys = ("variant", "noise", "runs", "miss_m", "fuel_mps", "truth_outside", "failures")
    runs = [results(f"{STUDY}{w}.json")["variants"] for w in ("w1", "w2", "dask")]
    first = [{k: v[k] for k in keys} for v in runs[0]]
    for other in runs[1:]:
        assert [{k: v[k] for k in keys} for v in other] == first
    assert all(v["cpu_s"] is None for v in runs[2])  # a cluster's workers: not counted
    found = _found(r"The (\d+)-run study on a local Dask scheduler")
    assert int(found.group(1)) == results(STUDY + "dask.json")["runs"]


def test_the_scaling_with_workers_is_what_the_files_measured():
    """docs/performance.md's scaling (``docs/results/study/scaling/``): one and two
    workers, local processes and a local Dask scheduler, two commands each; the wall
    clocks, their pooled ratios, the CPU time a run with two local workers against one,
    the variants' wall clock against half their CPU time, the command's own time after the
    runs; and all eight drew the same table."""
    scaling = "docs/results/study/scaling/"
    got = {(kind, w): [results(f"{scaling}{kind}-w{w}-{r}.json") for r in (1, 2)]
           for kind in ("local", "dask") for w in (1, 2)}  # fmt: skip
    keys = ("variant", "noise", "runs", "seed", "miss_m", "fuel_mps", "truth_outside", "failures")
    tables = [[{k: v[k] for k in keys} for v in d["variants"]] for ds in got.values() for d in ds]
    assert len(tables) == 8 and all(t == tables[0] for t in tables)
    runs = {d["runs"] for ds in got.values() for d in ds}
    found = _found(r"measured on the (\d+)-core host with (\d+) runs per variant")
    assert int(found.group(1)) == results("docs/results/bench.json")["machine"]["cpus"]
    assert runs == {int(found.group(2))}
    wall = {k: [d["wall_s"] for d in ds] for k, ds in got.items()}
    found = _found(r"took ([\d.]+) and ([\d.]+) s of wall clock with one worker and ([\d.]+) "
                   r"and ([\d.]+) s with two: ([\d.]+) times faster")  # fmt: skip
    agree_each(found.groups(), [*wall["local", 1], *wall["local", 2],
                                sum(wall["local", 1]) / sum(wall["local", 2])])  # fmt: skip
    found = _found(r"the same command took ([\d.]+) and ([\d.]+) s with one worker and ([\d.]+) "
                   r"and ([\d.]+) s with two: ([\d.]+) times faster, and ([\d.]+) times the local "
                   r"processes' wall clock with two workers")  # fmt: skip
    agree_each(found.groups(), [*wall["dask", 1], *wall["dask", 2],
                                sum(wall["dask", 1]) / sum(wall["dask", 2]),
                                sum(wall["dask", 2]) / sum(wall["local", 2])])  # fmt: skip
    cpu = {w: sum(v["cpu_s"] for d in got["local", w] for v in d["variants"]) for w in (1, 2)}
    variant_wall = sum(v["wall_s"] for d in got["local", 2] for v in d["variants"])
    rest = [d["wall_s"] - sum(v["wall_s"] for v in d["variants"]) for d in got["local", 2]]
    found = _found(r"a run cost ([\d.]+) times the CPU time with two workers that it cost with "
                   r"one; the variants' wall clock was ([\d.]+) times half their CPU time .*\("
                   r"the tables and the figure\) took ([\d.]+) s")  # fmt: skip
    agree_each(found.groups(), [cpu[2] / cpu[1], variant_wall / (cpu[2] / 2), np.mean(rest)])
    assert all(v["cpu_s"] is None for d in got["dask", 2] for v in d["variants"])


def _before_drift_rows() -> dict[str, dict]:
    """The published node-set runs of kp_fig5 per noise as they read before
    ``model.along_sight_drift`` became the default (``docs/results/drift/fig5-no_drift.json``,
    the ``make run`` of that release): the speed files were made then, and their
    commands reproduce them with ``--set model.along_sight_drift=false``."""
    path = "docs/results/drift/fig5-no_drift.json"
    return {n: study_variant(path, "kp_fig5", n) for n in ("random", "game")}


def test_the_speed_options_defaults_rows_are_the_published_runs():
    """docs/performance.md's table of the node set's speed options: its defaults' rows are
    the runs published before the drift became the default (the same seeds, the same
    numbers)."""
    keys = ("runs", "seed", "miss_m", "fuel_mps", "truth_outside", "empty_set", "failures")
    published = {n: {k: r[k] for k in keys} for n, r in _before_drift_rows().items()}
    for row in results("docs/results/speed/kp_fig5-default.json")["rows"]:
        assert {k: row[k] for k in keys} == published[row["noise"]], row["noise"]


def _found(pattern: str) -> re.Match:
    found = re.search(pattern, TEXT)
    assert found, f"the sentence was rewritten: re-point this test ({pattern})"
    return found


def test_the_speed_options_ratios_are_the_measured_cpu_times():
    """The speed options' savings and costs, in per cent and times, are the arithmetic of
    the results files: each option's CPU time against the mean of the defaults' two
    measurements (the first row and the two repeats), random then game."""
    first, repeat = speed_cpu_s("default"), speed_cpu_s("default-repeat")
    base = speed_base_cpu_s()

    def pct(name: str, noise: str) -> float:
        return 100.0 * (speed_cpu_s(name)[noise] / base[noise] - 1.0)

    saved = _found(r"piece splits \(a ratio of 4 instead of 2\) saved (\d+) % and (\d+) %")
    assert agrees(saved.group(1), -pct("node_split_ratio_4", "random"))
    assert agrees(saved.group(2), -pct("node_split_ratio_4", "game"))
    cap = _found(r"A vertex cap saves nothing \(\+(\d+) % and \+(\d+) % CPU time here\)")
    assert agrees(cap.group(1), pct("max_vertices_64", "random"))
    assert agrees(cap.group(2), pct("max_vertices_64", "game"))
    one = _found(r"one band was only ([\d.]+) times cheaper under random errors and "
                 r"([\d.]+) times under the game")  # fmt: skip
    n1 = speed_cpu_s("n_bands_1")
    assert agrees(one.group(1), base["random"] / n1["random"])
    assert agrees(one.group(2), base["game"] / n1["game"])
    rep = _found(r"CPU-s for random / game, (\d+) % and (\d+) % above the first rows")
    assert agrees(rep.group(1), 100.0 * (repeat["random"] / first["random"] - 1.0))
    assert agrees(rep.group(2), 100.0 * (repeat["game"] / first["game"] - 1.0))


def test_one_band_costs_little_under_random_errors_as_printed():
    """'(-0.02 m, +0.3 m/s)': one band's mean miss and fuel minus the defaults' (random)."""
    found = _found(r"it costs little under random errors \(([-+][\d.]+) m, ([-+][\d.]+) m/s\)")

    def means(name: str) -> tuple[float, float]:
        rows = results(f"docs/results/speed/kp_fig5-{name}.json")["rows"]
        (r,) = [r for r in rows if r["noise"] == "random"]
        return r["miss_m"]["mean"], r["fuel_mps"]["mean"]

    (m1, f1), (m0, f0) = means("n_bands_1"), means("default")
    assert agrees(found.group(1), m1 - m0)
    assert agrees(found.group(2), f1 - f0)


def _more_with_two_workers(tag: str = "") -> list[float]:
    """Per variant, per cent more CPU with two workers than with one (study files)."""
    w1, w2 = (results(f"{STUDY}{w}{tag}.json")["variants"] for w in ("w1", "w2"))
    return [100.0 * (b["cpu_s"] / a["cpu_s"] - 1.0) for a, b in zip(w1, w2, strict=True)]


def test_two_workers_cost_what_the_study_table_says_more_than_one():
    """'two workers cost from 4 % less to 8 % more CPU than one': the extremes over the
    four variants of the 2-worker column against the 1-worker one; the code before the
    pool's change, '7 % to 22 % more'; and the release before, '10 % less to 50 % more'."""
    found = _found(r"two workers cost from (\d+) % less to (\d+) % more CPU than one here")
    more = _more_with_two_workers()
    assert min(more) < 0 < max(more)
    assert agrees(found.group(1), -min(more)) and agrees(found.group(2), max(more))
    found = _found(r"and from (\d+) % less to (\d+) % more in the previous measurement")
    more = _more_with_two_workers("_at_5f9e157")
    assert min(more) < 0 < max(more)
    assert agrees(found.group(1), -min(more)) and agrees(found.group(2), max(more))
    found = _found(r"the pool's change they cost (\d+) % to (\d+) % more")
    more = _more_with_two_workers("_at_52398b6")
    assert 0 < min(more)
    assert agrees(found.group(1), min(more)) and agrees(found.group(2), max(more))
    before = _found(r"`fig5-w2_at_1f4367d.json`\) read (\d+) % less to (\d+) % more")
    more = _more_with_two_workers("_at_1f4367d")
    assert min(more) < 0 < max(more)
    assert agrees(before.group(1), -min(more)) and agrees(before.group(2), max(more))


def test_impulse_per_band_costs_what_the_text_says():
    """'cost 1.04 and 1.61 times less CPU time than the defaults here (random, game)':
    the defaults' mean CPU time over the mean of the per-band replay's two measurements."""
    found = _found(r"two measurements, alternated with the repeats\) cost ([\d.]+) and "
                   r"([\d.]+) times less CPU time than the defaults")  # fmt: skip
    base = speed_base_cpu_s()
    runs = [speed_cpu_s(n) for n in ("impulse_per_band", "impulse_per_band-repeat")]
    for noise, printed in zip(("random", "game"), found.groups(), strict=True):
        assert agrees(printed, base[noise] / (0.5 * (runs[0][noise] + runs[1][noise])))
    # the same game ratio where the 35e3739 comparison quotes it
    again = _found(r"own band \(docs/infoset\.md\), which costs ([\d.]+) times the per-band "
                   r"replay's CPU time in the bearings-only game runs")  # fmt: skip
    assert again.group(1) == found.group(2)
    # and the game's mean miss both ways (each file's two measurements: the same runs)
    miss = _found(r"the game's mean miss is ([\d.]+) m against the defaults' ([\d.]+) m")
    for printed, name in zip(miss.groups(), ("impulse_per_band", "default"), strict=True):
        for stem in (name, f"{name}-repeat"):
            assert agrees(printed, speed_rows(f"kp_fig5-{stem}")["game"]["miss_m"]["mean"])


def test_fewer_nodes_save_what_the_text_says():
    """'(`estimator.infoset.n_nodes=8`) saved 11 % and 11 % of the CPU time (random, game)':
    each option's CPU time against the mean of the defaults run before and after it on
    the same day, and the defaults drew the published runs."""
    first, repeat = speed_cpu_s("later-default"), speed_cpu_s("later-default-repeat")
    base = {n: 0.5 * (first[n] + repeat[n]) for n in ("random", "game")}
    for opt, name in (("n_nodes=8", "n_nodes_8"), ("min_live_nodes=4", "min_live_nodes_4")):
        found = _found(rf"`estimator\.infoset\.{re.escape(opt)}`\) saved (\d+) % and (\d+) %")
        got = speed_cpu_s(f"later-{name}")
        assert all(r["truth_outside"] == 0 for r in speed_rows(f"kp_fig5-later-{name}").values())
        for noise, printed in zip(("random", "game"), found.groups(), strict=True):
            assert agrees(printed, 100.0 * (1.0 - got[noise] / base[noise])), (opt, noise)
    keys = ("runs", "seed", "miss_m", "fuel_mps", "truth_outside", "empty_set", "failures")
    published = {n: {k: r[k] for k in keys} for n, r in _before_drift_rows().items()}
    for name in ("default", "default-repeat"):
        for row in speed_rows(f"kp_fig5-later-{name}").values():
            assert {k: row[k] for k in keys} == published[row["noise"]], (name, row["noise"])


def test_the_piece_split_floor_saves_what_the_text_says():
    """docs/performance.md's paragraph on ``min_split_tau_s``: every CPU time, per cent,
    miss and fuel it prints is the results files' (``kvi compare ... --set
    estimator.infoset.min_split_tau_s=1|0.5``, the defaults run before and after), and
    what it calls unchanged is: the same summaries."""
    first, repeat = speed_rows("kp_fig5-floor-default"), speed_rows("kp_fig5-floor-default-repeat")
    one, half = speed_rows("kp_fig5-min_split_tau_1"), speed_rows("kp_fig5-min_split_tau_0.5")
    base = {n: 0.5 * (first[n]["cpu_s"] + repeat[n]["cpu_s"]) for n in ("random", "game")}
    found = _found(
        r"the defaults cost ([\d.]+) and ([\d.]+) CPU-s random, ([\d.]+) and ([\d.]+) game; a "
        r"floor of one second \(two decision steps\) read ([\d.]+) and ([\d.]+), (\d+) % and "
        r"(\d+) % below the defaults' means, and half a second ([\d.]+) and ([\d.]+) \((\d+) % "
        r"and (\d+) %\)"
    )
    saved = {k: {n: 100.0 * (1.0 - r[n]["cpu_s"] / base[n]) for n in base}
             for k, r in (("one", one), ("half", half))}  # fmt: skip
    values = [first["random"]["cpu_s"], repeat["random"]["cpu_s"], first["game"]["cpu_s"],
              repeat["game"]["cpu_s"], one["random"]["cpu_s"], one["game"]["cpu_s"],
              saved["one"]["random"], saved["one"]["game"], half["random"]["cpu_s"],
              half["game"]["cpu_s"], saved["half"]["random"], saved["half"]["game"]]  # fmt: skip
    for printed, value in zip(found.groups(), values, strict=True):
        assert agrees(printed, value), (printed, value)
    # random errors: the same means; the game: the means printed
    found = _found(r"Under random errors the means are unchanged \(([\d.]+) m and ([\d.]+) m/s\)")
    for r in (first, repeat, one, half):
        assert agrees(found.group(1), r["random"]["miss_m"]["mean"])
        assert agrees(found.group(2), r["random"]["fuel_mps"]["mean"])
    found = _found(
        r"The game's mean miss read ([\d.]+) m with the floor of one second and ([\d.]+) m "
        r"with half a second, against the defaults' ([\d.]+) m \(fuel ([\d.]+) and ([\d.]+) "
        r"against ([\d.]+) m/s\)"
    )
    values = [one["game"]["miss_m"]["mean"], half["game"]["miss_m"]["mean"],
              first["game"]["miss_m"]["mean"], one["game"]["fuel_mps"]["mean"],
              half["game"]["fuel_mps"]["mean"], first["game"]["fuel_mps"]["mean"]]  # fmt: skip
    for printed, value in zip(found.groups(), values, strict=True):
        assert agrees(printed, value), (printed, value)
    # with the range finder and on Fig. 3: what the text calls the same is the same
    keys = ("miss_m", "fuel_mps", "truth_outside", "empty_set", "diverged", "failures")
    same = lambda a, b: all(a[n][k] == b[n][k] for n in ("random", "game") for k in keys)  # noqa: E731
    r0, r1 = speed_rows("kp_fig5_range-floor-default"), speed_rows("kp_fig5_range-min_split_tau_1")
    assert same(r0, r1)
    found = _found(
        r"\(kp_fig5_range: the same results, ([\d.]+) and ([\d.]+) CPU-s \(random, game\) with "
        r"the defaults, ([\d.]+) and ([\d.]+) with the floor"
    )
    values = [r[n]["cpu_s"] for r in (r0, r1) for n in ("random", "game")]
    for printed, value in zip(found.groups(), values, strict=True):
        assert agrees(printed, value), (printed, value)
    c0, c1 = speed_rows("kp_fig3-floor-default"), speed_rows("kp_fig3-min_split_tau_1")
    found = _found(
        r"on Fig\. 3 the means read the same ([\d.]+) m and ([\d.]+) m/s \(random\) and ([\d.]+) m "
        r"and ([\d.]+) m/s \(game\) both ways, and the floor saved (\d+) % and (\d+) %"
    )
    for r in (c0, c1):
        values = [r["random"]["miss_m"]["mean"], r["random"]["fuel_mps"]["mean"],
                  r["game"]["miss_m"]["mean"], r["game"]["fuel_mps"]["mean"]]  # fmt: skip
        for printed, value in zip(found.groups()[:4], values, strict=True):
            assert agrees(printed, value), (printed, value)
    for printed, n in zip(found.groups()[4:], ("random", "game"), strict=True):
        assert agrees(printed, 100.0 * (1.0 - c1[n]["cpu_s"] / c0[n]["cpu_s"])), n
    # every run of every file: the truth inside, nothing emptied, diverged or failed
    for name in ("kp_fig5-min_split_tau_1", "kp_fig5-min_split_tau_0.5",
                 "kp_fig5_range-min_split_tau_1", "kp_fig3-min_split_tau_1"):  # fmt: skip
        for r in speed_rows(name).values():
            assert (r["truth_outside"], r["empty_set"], r["diverged"], r["failures"]) == (0,) * 4
    # the defaults drew the published runs
    published = _before_drift_rows()
    for r in (first, repeat):
        assert all(r[n][k] == published[n][k] for n in ("random", "game") for k in keys)


def test_the_piece_split_floor_tightness_sentence_matches_its_files():
    """'the exact interval is inside the set in all 90 with the floor, 88 read the same
    widths as with the defaults, and the widest is 1.016 ... (the defaults: 1.016) and
    1.022 over all three (the same)': counted over the two folders of guided runs."""
    found = _found(
        r"the exact interval is inside the set in all (\d+) with the floor, (\d+) read the "
        r"same widths as with the defaults \(`seeds_601/`\), and the widest is ([\d.]+) times "
        r"the exact width with bearings only \(the defaults: ([\d.]+)\) and ([\d.]+) over all "
        r"three \(the same\)"
    )

    def runs(folder: str) -> dict[tuple, dict]:
        out = {}
        for path in sorted((ROOT / "docs/results/tightness" / folder).glob("*.json")):
            d = results(str(path.relative_to(ROOT)))
            out[(d["scenario"].split("+")[0], d["noise"], d["seed"])] = d
        return out

    floor, default = runs("split_floor"), runs("seeds_601")
    assert set(floor) == set(default) and int(found.group(1)) == len(floor)
    assert all(all(d["exact_inside"]) for d in floor.values())
    assert all(d["guided"] and not d["kinematic_margin"] for d in floor.values())
    same = sum(floor[k]["ratio"] == default[k]["ratio"] for k in floor)
    assert int(found.group(2)) == same
    widest = lambda rs, scs: max(d["max_ratio"] for k, d in rs.items() if k[0] in scs)  # noqa: E731
    bearings = ("kp_fig5", "kp_fig3")
    assert agrees(found.group(3), widest(floor, bearings))
    assert agrees(found.group(4), widest(default, bearings))
    everything = ("kp_fig5", "kp_fig3", "kp_fig5_range")
    assert agrees(found.group(5), widest(floor, everything))
    assert agrees(found.group(5), widest(default, everything))


def test_the_old_commits_cpu_time_on_the_two_hosts_of_the_35e3739_comparison():
    """'That host ran the old commit's command 1.22 times slower than the table's host
    did': the mean CPU time of commit 35e3739's runs in the two comparisons."""
    now, before = (results(f"docs/results/vs_35e3739{s}.json") for s in ("", "_at_f15e898"))
    found = _found(r"ran the old commit's command ([\d.]+) times slower than the table's host")
    old = [sum(r["cpu_s_35e3739"]) / len(r["cpu_s_35e3739"]) for r in (now, before)]
    assert agrees(found.group(1), old[0] / old[1])


def test_the_drift_s_10000_runs_cost_what_the_text_says():
    """docs/performance.md: the 10 000-run variant re-run with the along-sight drift (the
    default) read its CPU time against the previous default's, and no more (its first
    run, with nothing else running; the statistics file is a later re-run's)."""
    base = "docs/results/study/kp_fig5_range-random-10000"
    new, old = results(base + "-drift-first.json"), results(base + ".json")
    found = _found(r"read (\d+) CPU-s against the (\d+) below: one\s+reading each, no sign "
                   r"that the drift adds to the cost")  # fmt: skip
    agree_each(found.groups(), [new["cpu_s"], old["cpu_s"]])
    assert new["runs"] == old["runs"] and new["cpu_s"] <= old["cpu_s"]
