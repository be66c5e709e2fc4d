"""The attitude loops on the one runner (docs/models.md §3): results do not depend on the worker
count or the scheduler, and an interrupted run resumes to identical results."""

from __future__ import annotations

import contextlib
import io
import json
import shutil
from dataclasses import replace

import pandas as pd
import pytest
from harness_texts import TINY_RW as TINY
from kalman_vs_infoset.experiments import attitude_rw
from kalman_vs_infoset.experiments.cli import main

# a random initial attitude under a small disturbance torque
TINY_RW = TINY.replace("angle_deg = 10.0\n", "angle_deg = 10.0\nrandom_attitude = true\n") + (
    "[noise]\ndisturbance_Nm = 1e-4\n"
)

RUNS = 2 * attitude_rw.CHUNK + 3  # three chunks


@pytest.fixture
def scenario(tmp_path):
    p = tmp_path / "tiny_rw.toml"
    p.write_text(TINY_RW)
    return p


def _attitude(capsys, scenario, out, *extra) -> tuple[int, dict | None]:
    code = main(
        ["attitude", str(scenario), "--noise", "random", "--estimators", "box", "--runs",
         str(RUNS), "--seed", "3", "--out", str(out), "--json", "--no-progress", *extra]
    )  # fmt: skip
    text = capsys.readouterr().out.strip().splitlines()
    return code, json.loads(text[-1]) if code == 0 else None


@pytest.fixture(scope="module")
def one_worker(tmp_path_factory):
    """The ``--workers 1`` run of the tiny turn (``(out, result)``), the reference that
    four tests compared their own runs with: computed once for the module (identical
    each time: the same scenario, seed and runs)."""
    folder = tmp_path_factory.mktemp("one_worker")
    scenario = folder / "tiny_rw.toml"
    scenario.write_text(TINY_RW)
    out = folder / "out"
    with contextlib.redirect_stdout(io.StringIO()) as stdout:
        code = main(
            ["attitude", str(scenario), "--noise", "random", "--estimators", "box", "--runs",
             str(RUNS), "--seed", "3", "--out", str(out), "--json", "--no-progress",
             "--workers", "1"]
        )  # fmt: skip
    assert code == 0
    return out, json.loads(stdout.getvalue().strip().splitlines()[-1])


def _table(out) -> pd.DataFrame:
    (path,) = out.glob("*.parquet")
    assert path.name == "tiny_rw-pd-box-random-s3.parquet"
    df = pd.read_parquet(path).drop(columns=["wall_s"])
    return df.sort_values("run").reset_index(drop=True)


def _summary(result: dict) -> dict:
    # what the host's load and the process layout change (the CPU time is the runs'),
    # and the command line that made it (its --out and --workers differ)
    return {
        k: v
        for k, v in result.items()
        if k not in ("wall_s", "files", "cpu_s", "worker_peak_rss_mb", "command")
    }


def test_attitude_results_do_not_depend_on_the_worker_count(scenario, tmp_path, capsys, one_worker):
    one_out, one = one_worker
    c2, two = _attitude(capsys, scenario, tmp_path / "two", "--workers", "2")
    assert c2 == 0 and one["failures"] == 0
    pd.testing.assert_frame_equal(_table(one_out), _table(tmp_path / "two"))
    assert _summary(one) == _summary(two)
    assert sorted(_table(one_out)["run"]) == list(range(RUNS))


def test_interrupted_attitude_run_resumes_to_identical_results(
    scenario, tmp_path, capsys, monkeypatch, one_worker
):
    fresh_out, fresh = one_worker
    real, calls = attitude_rw.task, []

    def interrupted(*args, **kw):
        calls.append(1)
        if len(calls) == 2:  # Ctrl-C during the second chunk
            raise KeyboardInterrupt
        return real(*args, **kw)

    monkeypatch.setattr(attitude_rw, "LOOP", replace(attitude_rw.LOOP, task=interrupted))
    code, _ = _attitude(capsys, scenario, tmp_path / "resumed", "--workers", "1")
    assert code == 130
    assert len(_table(tmp_path / "resumed")) == attitude_rw.CHUNK  # the first chunk kept
    monkeypatch.setattr(attitude_rw, "LOOP", replace(attitude_rw.LOOP, task=real))
    code, resumed = _attitude(capsys, scenario, tmp_path / "resumed", "--workers", "1")
    assert code == 0
    pd.testing.assert_frame_equal(_table(fresh_out), _table(tmp_path / "resumed"))
    assert _summary(fresh) == _summary(resumed)


@pytest.mark.xdist_group("dask")
def test_attitude_on_a_dask_local_cluster_is_identical(
    scenario, tmp_path, capsys, dask_cluster, one_worker
):
    local_out, local = one_worker
    code, dask = _attitude(
        capsys, scenario, tmp_path / "dask", "--scheduler", dask_cluster.scheduler_address
    )
    assert code == 0
    pd.testing.assert_frame_equal(_table(local_out), _table(tmp_path / "dask"))
    assert _summary(local) == _summary(dask)
    # the cluster's workers are not the command's processes: their CPU time is not counted
    assert local["cpu_s"] > 0.0 and dask["cpu_s"] is None and dask["worker_peak_rss_mb"] is None


def test_the_text_summary_has_one_block_per_estimator_and_noise(scenario, tmp_path, capsys):
    """Without ``--json`` every estimator x noise gets its lines (settle, energy, final
    error, containment), then the estimators paired with the box, then the cost and the
    files; no raw record is printed."""
    args = ["attitude", str(scenario), "--noise", "random,game", "--estimators", "box,perfect",
            "--runs", "2", "--out", str(tmp_path / "o"), "--no-progress"]  # fmt: skip
    assert main(args) == 0
    text = capsys.readouterr().out
    blocks, paired = text.split("Paired by run, each estimator minus box", 1)
    heads = [line for line in blocks.splitlines() if not line.startswith(" ")]
    assert heads == [
        f"{scenario.stem}: pd on {e} / {n} noise, 2 runs, seed 0"
        for e in ("box", "perfect")
        for n in ("random", "game")
    ]
    # then the estimators paired with the box, a table row per estimator x noise
    table = [line for line in paired.splitlines() if line.startswith("| perfect |")]
    assert [row.split(" | ")[1] for row in table] == ["random", "game"]
    assert text.count("truth outside belief: ") == 4 and "CPU-s); files:" in text
    assert "{" not in text and "settle s" in text


def test_a_statistic_without_runs_prints_a_dash_and_never_settled_prints_inf():
    """``-`` when no run gave the statistic (NaN: every run failed; ``None``: after
    JSON), ``inf`` when a run that never settled enters it (it printed ``nan``)."""
    from kalman_vs_infoset.experiments.errors import stat_text

    assert stat_text(float("nan"), ".2f") == "-" and stat_text(None, ".2f") == "-"
    assert stat_text(float("inf"), ".2f") == "inf" and stat_text(12.345, ".2f") == "12.35"


@pytest.mark.parametrize(
    ("scenario", "overrides"),
    [
        ("smallsat_rw", {"simulation": {"duration_s": 2.0}}),  # the reaction-wheel loop
        ("resurs_p", {"duration_s": 20.0, "horizon_s": 20.0, "euler": {"accel_time_s": 5.0}}),
    ],
)
def test_the_rows_count_steps_in_integers(scenario, overrides, tmp_path, monkeypatch):
    """``truth_outside``, ``empty_steps`` and ``unbounded_steps`` are integer columns in
    every attitude loop's results, as in the intercept's (the reaction-wheel loop wrote
    them as floats: 0.0 steps)."""
    from kalman_vs_infoset import api

    monkeypatch.chdir(tmp_path)
    df = api.run_attitude(scenario, noise="random", runs=2, estimator="box", **overrides)
    for column in ("truth_outside", "empty_steps", "unbounded_steps"):
        assert pd.api.types.is_integer_dtype(df[column]), (column, df[column].dtype)


def test_the_attitude_cdf_says_its_scenario_and_the_runs_that_never_settled(tmp_path, monkeypatch):
    """The CDF figure's title was the files' stem ("...-perfect+ukf+box-random+game-s0");
    a settle-time panel whose runs never settled was empty without a word."""
    import pandas as pd
    from kalman_vs_infoset.experiments import attitude_est, plots

    figs = []
    monkeypatch.setattr(plots, "save", lambda fig, stem: figs.append(fig) or [])
    rows = [{"scenario": "tiny", "seed": 3, "controller": "pd", "estimator": e, "noise": "random",
             "settle_time_s": s, "energy_N2m2s": 1.0 + j, "final_angle_deg": 0.1 * (j + 1)}
            for e, s in (("box", float("inf")), ("ukf", 12.0)) for j in range(2)]  # fmt: skip
    attitude_est.write_figure(tmp_path, "tiny-pd-box+ukf-random-s3", pd.DataFrame(rows))
    (fig,) = figs
    assert fig._suptitle.get_text().startswith("tiny: 2 runs per curve, seed 3; curves:")
    texts = [t.get_text() for t in fig.axes[0].texts]
    assert "2 of 4 runs never settled:\ncurves end below 1" in texts
    # failed and diverged runs (NaN: no curve reaches them) are not "never settled":
    # two runs drawn, all settled, no note (it said "2 of 4 runs never settled")
    figs.clear()
    nan = float("nan")
    runs = ((nan, "failed", 0), (nan, "ok", 1), (12.0, "ok", 0), (13.0, "ok", 0))
    rows = [{**r, "settle_time_s": s, "status": st, "diverged": dv}
            for r, (s, st, dv) in zip(rows, runs, strict=True)]  # fmt: skip
    attitude_est.write_figure(tmp_path, "tiny-pd-box+ukf-random-s3", pd.DataFrame(rows))
    assert [t.get_text() for t in figs[0].axes[0].texts] == []
    rows[3]["settle_time_s"] = float("inf")
    figs.clear()
    attitude_est.write_figure(tmp_path, "tiny-pd-box+ukf-random-s3", pd.DataFrame(rows))
    texts = [t.get_text() for t in figs[0].axes[0].texts]
    assert texts == ["1 of 2 runs never settled:\ncurves end below 1"]


def test_an_edit_of_another_estimators_options_resumes_the_attitude_runs(
    scenario, tmp_path, capsys, one_worker
):
    """An attitude loop's estimator reads only its own ``[estimator_options.<name>]``
    table: the box's runs resume after a UKF table is added to the file (they were
    refused as "results of a different scenario"), the finished ones kept, and are
    refused after an edit of the box's own table."""
    out = tmp_path / "out"
    text = scenario.read_text()
    # the finished runs of this scenario: a copy of the module's run of it
    shutil.copytree(one_worker[0], out)
    before = _table(out)
    scenario.write_text(text + "[estimator_options.ukf]\ngate_prob = 0.99\n")
    code, _ = _attitude(capsys, scenario, out, "--workers", "1")
    assert code == 0
    pd.testing.assert_frame_equal(_table(out), before)
    scenario.write_text(text + "[estimator_options.box]\nabs_inflation_rad = 1e-6\n")
    args = ["attitude", str(scenario), "--noise", "random", "--estimators", "box", "--runs",
            str(RUNS), "--seed", "3", "--out", str(out), "--no-progress"]  # fmt: skip
    code = main(args)
    err = capsys.readouterr().err
    assert code == 2 and "different scenario (scenario.estimator_options.box" in err, err
