"""Command line, scenario validation and the Monte Carlo harness (docs/models.md §3)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from harness_texts import RANGE_FINDER, cli_inproc, experiment
from harness_texts import SHORT as SHORT_ENGAGEMENT
from kalman_vs_infoset.experiments import intercept_runs, runner
from kalman_vs_infoset.experiments.intercept_runs import run_experiment
from kalman_vs_infoset.experiments.paired import paired_rows
from kalman_vs_infoset.experiments.results import read_metadata
from kalman_vs_infoset.experiments.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
FIG3 = ROOT / "data" / "scenarios" / "kp_fig3.toml"
SHORT = SHORT_ENGAGEMENT + RANGE_FINDER + experiment(runs=4)


def cli(*args, cwd=ROOT):
    """``kvi ARGS`` in a subprocess (the real entry point)."""
    return subprocess.run(
        [sys.executable, "-m", "kalman_vs_infoset", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
    )


@pytest.fixture
def short(tmp_path):
    p = tmp_path / "short.toml"
    p.write_text(SHORT)
    return p


@pytest.fixture(scope="module")
def four_runs(tmp_path_factory):
    """``run_experiment`` of ``SHORT``, infoset, random noise, 4 runs, seed 11, one
    worker: the reference of two tests, computed once (it was computed in each)."""
    d = tmp_path_factory.mktemp("four_runs")
    (d / "short.toml").write_text(SHORT)
    sc = load_scenario(d / "short.toml")
    return run_experiment(sc, "infoset", "random", 4, 11, d / "out", workers=1, progress=False)


def test_fig3_random_and_game_acceptance_seed003_fig3(tmp_path, capsys):
    """Fig. 3 with random noise misses by <= 10 m with 150..400 m/s of fuel;
    game noise costs more fuel; the truth never leaves the set, no empty set."""
    out = {}
    for noise in ("random", "game"):
        args = ("intercept", FIG3, "--noise", noise, "--json", "--out", tmp_path, "--no-progress")
        r = cli_inproc(capsys, *args)
        assert r.returncode == 0, r.stderr
        out[noise] = json.loads(r.stdout.strip().splitlines()[-1])
        assert out[noise]["truth_outside"] == 0
        assert out[noise]["empty_set"] == 0 and out[noise]["failures"] == 0
        assert out[noise]["diverged"] == 0
    assert out["random"]["miss_m"]["max"] <= 10.0
    assert 150.0 <= out["random"]["fuel_mps"]["max"] <= 400.0
    assert out["game"]["fuel_mps"]["mean"] > out["random"]["fuel_mps"]["mean"]


BAD = {
    "unknown top key": ("colour = 'red'\n", "unknown key 'colour'"),
    "unknown table key": ("[model]\nspeed = 3\n", "unknown key 'model.speed'"),
    "wrong type": ("[model]\ndt_s = 'fast'\n", "field 'model.dt_s' must be a number"),
    "out of range": ("[model]\nnu_mps2 = -1.0\n", "field 'model.nu_mps2' must be"),
    "bad choice": ("[experiment]\nnoise = 'pink'\n", "field 'experiment.noise' must be one of"),
    "bad interval": ("[estimator]\ny_km = [5.0, -5.0]\n", "field 'estimator.y_km'"),
    "truth outside box": ("[truth]\ny_km = [-20.0, 0.0]\n", "must lie inside"),
    "bad toml": ("[model\n", "invalid TOML"),
    "no split": (
        "[estimator.infoset]\nsplit_ratio = 1.0\n",
        "field 'estimator.infoset.split_ratio' must be",
    ),
    "bound shrinks as range closes": (
        "[model]\nbearing_bound_start_rad = 3e-4\nbearing_bound_end_rad = 2e-4\n",
        "'model.bearing_bound_start_rad' must be <=",
    ),
    "box past the bound's floor": (  # the line falls to its floor at 2020 km
        "[model]\nnominal_range_km = 2000.0\nbearing_bound_start_rad = 1e-5\n"
        "bearing_bound_end_rad = 1e-3\n",
        "where the bearing bound, linear in the range, falls to its floor",
    ),
    "margin not bool": (
        "[estimator.infoset]\nkinematic_margin = 1\n",
        "'estimator.infoset.kinematic_margin'",
    ),
    "option table": ("[estimator.ekf]\nn_sigma = 0.1\n", "field 'estimator.ekf.n_sigma' must be"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_scenario_input_exits_2_with_one_line(tmp_path, capsys, case):
    text, message = BAD[case]
    p = tmp_path / "bad.toml"
    p.write_text(text)
    r = cli_inproc(capsys, "intercept", p, "--json")
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and str(p) in lines[0]
    assert "Traceback" not in r.stderr and r.stdout == ""


@pytest.mark.parametrize(
    "args",
    [
        ["intercept", "missing.toml"],
        ["intercept", str(FIG3), "--estimators", "kalman9"],
        ["intercept", str(FIG3), "--runs", "0"],
        ["compare", str(FIG3), "--estimators", "infoset,foo"],
        ["intercept", str(FIG3), "--out", "/proc/no/such/folder"],
        ["attitude", str(ROOT / "data/scenarios/gyrostat_game.toml"), "--out", "/proc/no/such"],
        ["nonsense"],
        ["intercept", str(FIG3), "--set", "model.nu_mps2"],  # no value
        ["intercept", str(FIG3), "--set", "model.nu_mps2=fast"],  # not TOML
        ["intercept", str(FIG3), "--set", "model.nu_mps2=-1"],  # validated as the file
        ["compare", str(FIG3), "--set", "estimator.colour=1"],  # unknown key
        ["intercept", str(FIG3), "--set", "name=other"],  # the name is derived
    ],
)
def test_bad_command_line_exits_2_with_one_line(capsys, args):
    r = cli_inproc(capsys, *args)
    assert r.returncode == 2
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr


def test_a_folder_given_as_the_scenario_is_named_as_a_folder(tmp_path, capsys):
    """A folder where a scenario file is expected: one line that says so, not "no such
    file"."""
    folder = tmp_path / "runs.toml"
    folder.mkdir()
    r = cli_inproc(capsys, "intercept", folder, "--json")
    assert r.returncode == 2 and r.stderr.strip().endswith(
        f"{folder}: a folder, not a scenario file (a TOML file, or a bundled name)"
    )


@pytest.mark.parametrize("command", ["tightness", "intercept", "bench"])
def test_an_unknown_option_is_named_with_its_command(capsys, command):
    """argparse said ``kvi: error: unrecognized arguments`` without the command."""
    scenario = [] if command == "bench" else [str(FIG3)]
    r = cli_inproc(capsys, command, *scenario, "--seedz", "1-0")
    assert r.returncode == 2
    assert r.stderr.strip() == f"kvi {command}: error: unrecognized arguments: --seedz 1-0"


def _table(df):
    cols = ["run", "miss_m", "fuel_mps", "truth_outside", "x0_km", "y0_km", "vy0_kmps"]
    return df[cols].sort_values("run").reset_index(drop=True)


def test_same_results_with_one_and_two_workers_and_same_seed(short, tmp_path, four_runs):
    """The same table with 1 or 2 workers and 1 or 3 runs a task (``chunk``)."""
    sc = load_scenario(short)
    a = four_runs  # workers=1, chunk 1
    b = run_experiment(sc, "infoset", "random", 4, 11, tmp_path / "b", workers=2, progress=False)
    c = run_experiment(
        sc, "infoset", "random", 4, 11, tmp_path / "c", workers=1, progress=False, chunk=3
    )
    pd.testing.assert_frame_equal(_table(a), _table(b))
    pd.testing.assert_frame_equal(_table(a), _table(c))
    assert (a["status"] == "ok").all() and a["truth_outside"].sum() == 0
    d = run_experiment(sc, "infoset", "random", 4, 12, tmp_path / "d", workers=1, progress=False)
    assert not np.allclose(a["y0_km"], d["y0_km"])  # another seed, another realisation


@pytest.mark.xdist_group("dask")
def test_same_results_on_a_dask_local_cluster(short, tmp_path, monkeypatch, dask_cluster):
    sc = load_scenario(short)
    address = dask_cluster.scheduler_address
    a = run_experiment(sc, "infoset", "game", 3, 11, tmp_path / "a", workers=1, progress=False)
    b = run_experiment(
        sc, "infoset", "game", 3, 11, tmp_path / "b", scheduler=address, progress=False
    )
    pd.testing.assert_frame_equal(_table(a), _table(b))
    # workers running other sources are refused before any run (one line, exit 2)
    fake = {**runner.code_identity(), "sources_sha256": "f" * 64}
    from kalman_vs_infoset.experiments import executors

    monkeypatch.setattr(executors, "code_identity", lambda: fake)  # this process only
    with pytest.raises(runner.InputError, match="runs other code"):
        run_experiment(
            sc, "infoset", "game", 3, 11, tmp_path / "c", scheduler=address, progress=False
        )
    assert not (tmp_path / "c").exists() or not list((tmp_path / "c").glob("*.parquet"))


def test_interrupted_experiment_resumes_without_redoing_or_losing_runs(
    short, tmp_path, monkeypatch, capsys, four_runs
):
    sc = load_scenario(short)
    calls = []
    real = intercept_runs.timed_engagement

    def flaky(sc_, est, noise, ss):
        if len(calls) == 2:
            raise KeyboardInterrupt  # Ctrl-C after two finished runs
        calls.append(ss.spawn_key)
        return real(sc_, est, noise, ss)

    monkeypatch.setattr(intercept_runs, "timed_engagement", flaky)
    with pytest.raises(KeyboardInterrupt):
        run_experiment(sc, "infoset", "random", 4, 11, tmp_path, workers=1, progress=False)
    path = intercept_runs.results_path(tmp_path, sc, "infoset", "random", 11)
    first = pd.read_parquet(path)
    assert sorted(first["run"]) == [0, 1]  # finished runs were written
    monkeypatch.setattr(intercept_runs, "timed_engagement", real)
    calls.clear()
    capsys.readouterr()
    done = run_experiment(sc, "infoset", "random", 4, 11, tmp_path, workers=1, progress=False)
    assert sorted(done["run"]) == [0, 1, 2, 3]
    # the resume says what it kept (one line), and again when nothing is left to run
    assert capsys.readouterr().err == (
        f"short infoset-random: 2 runs of 4 already in {path}: running the other 2\n"
    )
    run_experiment(sc, "infoset", "random", 4, 11, tmp_path, workers=1, progress=False)
    assert (
        capsys.readouterr().err == f"short infoset-random: all 4 runs already in {path}: none run\n"
    )
    # the first two rows are the stored ones (wall times unchanged: not recomputed)
    np.testing.assert_array_equal(done["wall_s"][:2], first.sort_values("run")["wall_s"])
    pd.testing.assert_frame_equal(_table(done), _table(four_runs))  # an uninterrupted run


_REAL_ENGAGEMENT = intercept_runs.timed_engagement


def _dies_on_run_3(sc_, est, noise, ss):
    """Module level so that worker processes can unpickle it."""
    import os

    if ss.spawn_key == (3,):
        os._exit(1)  # the worker process dies
    return _REAL_ENGAGEMENT(sc_, est, noise, ss)


def test_killed_worker_loses_no_finished_run_and_resume_completes(short, tmp_path, monkeypatch):
    """A worker process killed mid-run (os._exit): finished runs are saved, the lost
    ones are missing (not failed), and rerunning completes exactly those. When the
    kernel's out-of-memory killer ended a process meanwhile (its counter rose, faked
    here), the message says so."""
    from kalman_vs_infoset.experiments import executors

    sc = load_scenario(short)
    real = intercept_runs.timed_engagement
    monkeypatch.setattr(intercept_runs, "timed_engagement", _dies_on_run_3)
    counts = iter(range(100))
    monkeypatch.setattr(executors, "oom_kills", lambda: next(counts))
    with pytest.raises(runner.WorkerLost, match=r"lost to a dead worker \(the system's out-of"):
        run_experiment(sc, "infoset", "random", 4, 11, tmp_path, workers=2, progress=False)
    path = intercept_runs.results_path(tmp_path, sc, "infoset", "random", 11)
    saved = pd.read_parquet(path) if path.exists() else pd.DataFrame({"run": []})
    assert 3 not in set(saved["run"]) and (saved.get("status", pd.Series()) == "ok").all()
    monkeypatch.setattr(intercept_runs, "timed_engagement", real)
    done = run_experiment(sc, "infoset", "random", 4, 11, tmp_path, workers=1, progress=False)
    assert sorted(done["run"]) == [0, 1, 2, 3] and (done["status"] == "ok").all()


def test_oom_kill_counter_is_read_from_vmstat(tmp_path):
    from kalman_vs_infoset.experiments.executors import oom_kills

    vmstat = tmp_path / "vmstat"
    vmstat.write_text("pgfault 12\noom_kill 3\n")
    assert oom_kills(str(vmstat)) == 3
    vmstat.write_text("pgfault 12\n")  # an older kernel: no counter
    assert oom_kills(str(vmstat)) is None
    assert oom_kills(str(tmp_path / "missing")) is None


def test_run_seed_is_the_spawned_child():
    """run j's seed is SeedSequence(seed).spawn(runs)[j] (docs/models.md §3)."""
    children = np.random.SeedSequence(7).spawn(5)
    for j in range(5):
        a = np.random.default_rng(runner.run_seed(7, j)).random(4)
        np.testing.assert_array_equal(a, np.random.default_rng(children[j]).random(4))


def test_a_failing_run_is_recorded_and_does_not_stop_the_others(short, tmp_path, monkeypatch):
    sc = load_scenario(short)
    real = intercept_runs.timed_engagement

    def sometimes(sc_, est, noise, ss):
        if ss.spawn_key == (1,):
            return {"status": "failed", "error": "RuntimeError: boom", "wall_s": 0.0}
        return real(sc_, est, noise, ss)

    monkeypatch.setattr(intercept_runs, "timed_engagement", sometimes)
    df = run_experiment(sc, "infoset", "random", 3, 11, tmp_path, workers=1, progress=False)
    assert list(df["status"]) == ["ok", "failed", "ok"]
    assert "boom" in df.loc[1, "error"]


def test_engagement_errors_are_caught_per_run(short):
    """timed_engagement records an exception inside a run as a failed row."""
    sc = load_scenario(short)
    broken = sc.model_copy(update={"model": sc.model.model_copy(update={"dt_s": float("nan")})})
    row = intercept_runs.timed_engagement(broken, "infoset", "random", runner.run_seed(1, 0))
    assert row["status"] == "failed" and row["error"]


def test_results_are_written_atomically_with_the_resolved_scenario(short, tmp_path):
    sc = load_scenario(short)
    run_experiment(sc, "infoset", "random", 2, 11, tmp_path, workers=1, progress=False)
    path = intercept_runs.results_path(tmp_path, sc, "infoset", "random", 11)
    meta = json.loads((tmp_path / "_meta" / f"{path.stem}.json").read_text())
    assert meta["scenario"]["name"] == "short" and meta["seed"] == 11
    assert read_metadata(path) == meta  # the table carries its description too
    assert not list(tmp_path.glob("*.tmp"))


def test_real_entry_point_reports_bad_input_in_one_line():
    r = cli("intercept", "missing.toml", "--json")
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "missing.toml" in r.stderr


def test_compare_pairs_estimators_on_the_same_realisations(short, tmp_path, capsys):
    """compare returns one row per estimator x noise, zero failures, zero
    containment violations for the set estimators, writes Parquet and PNG; run j has the
    same truth for every estimator; the same seed twice gives the same table."""
    names = ("infoset", "ekf", "ukf", "box")
    args = ("compare", short, "--runs", "2", "--json", "--workers", "1", "--no-progress")
    args += ("--estimators", ",".join(names))
    r = cli_inproc(capsys, *args, "--out", tmp_path / "a")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout.strip().splitlines()[-1])
    assert len(out["rows"]) == 2 * len(names)
    assert {(x["estimator"], x["noise"]) for x in out["rows"]} == {
        (e, n) for e in names for n in ("random", "game")
    }
    assert all(x["failures"] == 0 for x in out["rows"])
    # each row's CPU time and the workers' peak memory (docs/models.md, the JSON objects)
    assert all(x["cpu_s"] > 0 and x["worker_peak_rss_mb"] >= 0 for x in out["rows"])
    sets = ("infoset", "ellipsoid", "zonotope", "box")
    assert all(x["truth_outside"] == 0 for x in out["rows"] if x["estimator"] in sets)
    assert any(f.endswith(".parquet") for f in out["files"])
    assert any(f.endswith(".png") for f in out["files"])
    table = pd.read_parquet(next(f for f in out["files"] if f.endswith(".parquet")))
    truth = table.groupby("run")[["x0_km", "y0_km", "vy0_kmps", "vx0_kmps"]].nunique()
    assert (truth == 1).all().all()  # every estimator and noise saw the same truth in run j
    # the paired differences against the information set, from the same table
    assert out["paired"]["reference"] == "infoset"
    assert out["paired"]["rows"] == paired_rows(table, "infoset")
    assert {(x["estimator"], x["noise"]) for x in out["paired"]["rows"]} == {
        (e, n) for e in names[1:] for n in ("random", "game")
    }
    summary = (tmp_path / "a" / "short-compare-infoset+ekf+ukf+box.md").read_text()
    assert "Paired by run, each estimator minus infoset" in summary
    r2 = cli_inproc(capsys, *args, "--out", tmp_path / "b")
    table2 = pd.read_parquet(Path(tmp_path / "b") / "short-compare-infoset+ekf+ukf+box.parquet")
    cols = ["estimator", "noise", "run", "miss_m", "fuel_mps", "truth_outside"]
    pd.testing.assert_frame_equal(table[cols], table2[cols])
    assert r2.returncode == 0


def test_end_to_end_with_an_attitude_loop(tmp_path):
    """docs/models.md §2.5 end-to-end: the pointing loop biases bearings and rotates impulses;
    the run completes, the truth stays in the set (the bearing bound is widened by
    the attitude estimator's guaranteed knowledge bound, which the residual never
    exceeds) and the attitude summary is reported."""
    att = (ROOT / "data" / "scenarios" / "kp_fig3_attitude.toml").read_text()
    table = att[att.index("[attitude]") :]
    p = tmp_path / "short_att.toml"
    p.write_text(SHORT.replace('name = "short"', 'name = "short_att"') + "\n" + table)
    sc = load_scenario(p)
    for noise in ("random", "game"):
        df = run_experiment(sc, "infoset", noise, 2, 11, tmp_path, workers=1, progress=False)
        assert (df["status"] == "ok").all(), df.get("error")
        assert df["truth_outside"].sum() == 0
        assert (df["pointing_residual_max_deg"] <= df["pointing_knowledge_bound_deg"]).all()
        assert (df["pointing_residual_over_bound_steps"] == 0).all()
        assert (df["pointing_bound_exceeded_steps"] == 0).all()  # the box's bound held
        assert (df["attitude_max_pointing_error_deg"] > 0).all()


def test_attitude_table_is_validated_at_load(tmp_path, capsys):
    p = tmp_path / "bad_att.toml"
    p.write_text(SHORT + "\n[attitude]\ncontroller = 'bangbang'\n")
    r = cli_inproc(capsys, "intercept", p)
    assert r.returncode == 2 and "attitude.controller" in r.stderr


def test_resume_refuses_results_of_another_scenario_or_other_code(short, tmp_path, capsys):
    """Resuming must not mix runs: the JSON beside the results records the scenario and
    the code identity (version, SHA-256 of the sources, git commit); a mismatch in
    either is one line and exit 2, and the stored runs are left untouched."""
    from kalman_vs_infoset.experiments.provenance import code_identity

    sc = load_scenario(short)
    run_experiment(sc, "infoset", "random", 2, 11, tmp_path, workers=1, progress=False)
    path = intercept_runs.results_path(tmp_path, sc, "infoset", "random", 11)
    meta_path = tmp_path / "_meta" / f"{path.stem}.json"
    meta = json.loads(meta_path.read_text())
    assert meta["code"] == json.loads(json.dumps(code_identity()))
    assert len(meta["code"]["sources_sha256"]) == 64
    stored = path.read_bytes()
    cases = {
        "other code": {**meta, "code": {**meta["code"], "sources_sha256": "0" * 64}},
        "code that recorded no identity": {k: v for k, v in meta.items() if k != "code"},
        "different scenario": {**meta, "scenario": {**meta["scenario"], "name": "other"}},
    }
    for message, changed in cases.items():
        meta_path.write_text(json.dumps(changed))
        with pytest.raises(runner.InputError, match=message):
            run_experiment(sc, "infoset", "random", 4, 11, tmp_path, workers=1, progress=False)
        assert path.read_bytes() == stored
    r = cli_inproc(capsys, "intercept", short, "--runs", "4", "--out", tmp_path, "--no-progress")
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1
    assert "different scenario" in r.stderr and "Traceback" not in r.stderr
    meta_path.write_text(json.dumps(meta))  # the same code and scenario: it resumes
    done = run_experiment(sc, "infoset", "random", 4, 11, tmp_path, workers=1, progress=False)
    assert sorted(done["run"]) == [0, 1, 2, 3]


def test_rerun_other_code_replaces_only_the_runs_of_other_code(short, tmp_path, capsys):
    """``--rerun-other-code`` (what ``make run`` passes, so that it works after an
    update): a table another version of the code wrote is run again and replaced,
    with the rows a fresh run gives and this code's identity beside it; the refusal
    without the flag names it; a table of another scenario is still refused; and the
    runs of this code are resumed, not run again."""
    from kalman_vs_infoset.experiments.provenance import code_identity

    sc = load_scenario(short)
    out = tmp_path / "out"
    args = ("intercept", short, "--runs", "2", "--out", out, "--no-progress", "--workers", "1")
    assert cli_inproc(capsys, *args).returncode == 0
    path = intercept_runs.results_path(out, sc, "infoset", "random", 11)
    meta_path = out / "_meta" / f"{path.stem}.json"
    meta = json.loads(meta_path.read_text())
    fresh = _table(pd.read_parquet(path))
    stale = pd.read_parquet(path)
    stale["miss_m"] = -1.0  # what the other code "measured"
    stale.to_parquet(path)
    meta_path.write_text(json.dumps({**meta, "code": {**meta["code"], "sources_sha256": "0" * 64}}))
    r = cli_inproc(capsys, *args)
    assert r.returncode == 2 and "--rerun-other-code" in r.stderr
    r = cli_inproc(capsys, *args, "--rerun-other-code")
    assert r.returncode == 0, r.stderr
    assert "written by other code: its runs are run again" in r.stderr
    pd.testing.assert_frame_equal(_table(pd.read_parquet(path)), fresh)
    assert json.loads(meta_path.read_text())["code"] == json.loads(json.dumps(code_identity()))
    stored = path.read_bytes()  # this code's runs: resumed (nothing run, nothing written)
    r = cli_inproc(capsys, *args, "--rerun-other-code")
    assert r.returncode == 0 and "run again" not in r.stderr and path.read_bytes() == stored
    other = {**meta, "scenario": {**meta["scenario"], "name": "other"}}
    meta_path.write_text(json.dumps(other))
    r = cli_inproc(capsys, *args, "--rerun-other-code")
    assert r.returncode == 2 and "different scenario" in r.stderr and path.read_bytes() == stored


@pytest.mark.parametrize("damage", ["deleted", "truncated"])
def test_a_lost_description_is_read_from_the_table_itself(short, tmp_path, damage):
    """The ``_meta`` JSON deleted or damaged: the resume was refused ("delete the
    file"), losing the runs, while the table carries the same description in its own
    metadata. It is checked against that, resumes, and the JSON is written again; a
    table of another scenario is still refused through it."""
    sc = load_scenario(short)
    run_experiment(sc, "infoset", "random", 2, 11, tmp_path, workers=1, progress=False)
    path = intercept_runs.results_path(tmp_path, sc, "infoset", "random", 11)
    meta_path = tmp_path / "_meta" / f"{path.stem}.json"
    meta = meta_path.read_text()
    if damage == "deleted":
        meta_path.unlink()
    else:
        meta_path.write_text(meta[: len(meta) // 2])
    done = run_experiment(sc, "infoset", "random", 3, 11, tmp_path, workers=1, progress=False)
    assert sorted(done["run"]) == [0, 1, 2]
    assert json.loads(meta_path.read_text()) == json.loads(meta)
    meta_path.unlink()
    other = sc.model_copy(update={"model": sc.model.model_copy(update={"dt_s": 0.25})})
    with pytest.raises(runner.InputError, match="different scenario"):
        run_experiment(other, "infoset", "random", 4, 11, tmp_path, workers=1, progress=False)


def test_a_study_extended_through_the_file_resumes(short, tmp_path, capsys):
    """``[experiment] runs = 4`` edited to 5 (and the description edited) resumes as
    ``--runs 5`` does: the four runs are kept, one is made. It was refused as "results
    of a different scenario (scenario.experiment.runs: 4 in the file, 5 now)", and the
    fix offered, deleting the file, lost the finished runs. A change of what a run
    gives (here the model) is still refused."""
    out = tmp_path / "out"
    text = short.read_text()
    assert "runs = 4" in text
    args = ("intercept", short, "--out", out, "--no-progress", "--json", "--workers", "1")
    assert cli_inproc(capsys, *args).returncode == 0
    short.write_text('description = "now longer"\n' + text.replace("runs = 4", "runs = 5"))
    r = cli_inproc(capsys, *args)
    assert r.returncode == 0, r.stderr
    assert "4 runs of 5 already in" in r.stderr
    assert json.loads(r.stdout.splitlines()[-1])["runs"] == 5
    short.write_text(text.replace("nominal_range_km = 1000.0", "nominal_range_km = 999.0"))
    r = cli_inproc(capsys, *args)
    assert r.returncode == 2 and "different scenario" in r.stderr


def test_an_edit_of_options_a_job_never_reads_resumes_it(short, tmp_path, capsys):
    """A table of runs depends on its estimator's own options and, under game errors, on
    the information set's, which the adversary reasons with: an edit of another
    estimator's table (here the UKF's, added to the file: neither the set nor the EKF
    reads it) was refused as "results of a different scenario
    (scenario.estimator.options.ukf...)"; it resumes, the runs kept as they were, and so
    does a table that writes an estimator's defaults. An edit of a table a job reads is
    still refused: the EKF's own, and the set's for the EKF under game errors (while the
    EKF under random errors resumes)."""
    out = tmp_path / "out"
    text = short.read_text()
    args = ("intercept", short, "--estimators", "infoset,ekf", "--noise", "random,game",
            "--workers", 1, "--out", out, "--no-progress")  # fmt: skip
    assert cli_inproc(capsys, *args, "--runs", "2").returncode == 0
    before = {p.name: _table(pd.read_parquet(p)) for p in sorted(out.glob("*.parquet"))}
    assert len(before) == 4
    short.write_text(text + "[estimator.ukf]\nn_sigma = 4.0\n")
    r = cli_inproc(capsys, *args, "--runs", "3")
    assert r.returncode == 0, r.stderr
    assert r.stderr.count("2 runs of 3 already in") == 4, r.stderr
    for name, old in before.items():
        new = _table(pd.read_parquet(out / name))
        pd.testing.assert_frame_equal(new[new["run"] < 2].reset_index(drop=True), old)
    short.write_text(text + "[estimator.ekf]\nn_sigma = 3.0\n")  # its default: the same runs
    r = cli_inproc(capsys, *args, "--runs", "3")
    assert r.returncode == 0 and r.stderr.count("all 3 runs already in") == 4, r.stderr
    short.write_text(text + "[estimator.ekf]\nn_sigma = 4.0\n")
    r = cli_inproc(capsys, *args, "--runs", "3")
    assert r.returncode == 2, r.stderr
    assert "(scenario.estimator.options.ekf.n_sigma: 3.0 in the file, 4.0 now)" in r.stderr
    ekf = ("intercept", short, "--estimators", "ekf", "--noise", "random,game", "--workers",
           1, "--out", tmp_path / "ekf", "--no-progress")  # fmt: skip
    short.write_text(text)
    assert cli_inproc(capsys, *ekf, "--runs", "2").returncode == 0
    short.write_text(text.replace("n_sections = 9", "n_sections = 9\nn_nodes = 10"))
    r = cli_inproc(capsys, *ekf, "--runs", "3")
    assert r.returncode == 2, r.stderr
    assert "ekf-random: 2 runs of 3 already in" in r.stderr, r.stderr
    assert "ekf-game-s11.parquet: results of a different scenario" in r.stderr, r.stderr
    assert "scenario.estimator.options.infoset.n_nodes" in r.stderr, r.stderr


def test_set_override_equals_the_edited_file_and_keeps_its_own_results(short, tmp_path, capsys):
    """``--set range_finder.enabled=false`` resolves to the same scenario as the file
    with that line edited (the name aside, which gets a ``+key=value`` suffix), gives
    the same runs, and writes its own result files beside the original's."""
    edited = tmp_path / "edited.toml"
    edited.write_text(SHORT.replace("enabled = true", "enabled = false"))
    over = load_scenario(short, ["range_finder.enabled=false"])
    assert over.name == "short+range_finder.enabled=false"
    a, b = over.model_dump(), load_scenario(edited).model_dump()
    del a["name"], b["name"]
    assert a == b
    out = tmp_path / "out"
    for extra in ([], ["--set", "range_finder.enabled=false"]):
        r = cli_inproc(capsys, "intercept", short, "--out", out, "--no-progress", "--workers",
                       "1", *extra)  # fmt: skip
        assert r.returncode == 0, r.stderr
    mine = intercept_runs.results_path(out, over, "infoset", "random", 11)
    orig = intercept_runs.results_path(out, load_scenario(short), "infoset", "random", 11)
    assert mine != orig and mine.exists() and orig.exists()
    ref = run_experiment(load_scenario(edited), "infoset", "random", 4, 11, tmp_path / "e", 1,
                         progress=False)  # fmt: skip
    pd.testing.assert_frame_equal(_table(pd.read_parquet(mine)), _table(ref))


def test_sweep_is_compare_per_value_on_the_same_truths(short, tmp_path, capsys):
    """``sweep`` runs every value as a ``--set`` override: its rows equal ``intercept``
    with that override (same seed, same truths), it pairs each value with the first run
    by run, and it writes the table and the figure. Names with dots (the key) keep
    their file extensions."""
    out = tmp_path / "sw"
    r = cli_inproc(
        capsys, "sweep", short, "--key", "model.nu_mps2", "--values", "[0.002, 0.02]",
        "--estimators", "infoset,ekf", "--noise", "random", "--runs", "2", "--out", out,
        "--no-progress", "--json", "--workers", "1",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout.strip().splitlines()[-1])
    assert res["key"] == "model.nu_mps2" and res["values"] == [0.002, 0.02]
    assert [(row["value"], row["estimator"]) for row in res["rows"]] == [
        ("0.002", "infoset"), ("0.002", "ekf"), ("0.02", "infoset"), ("0.02", "ekf"),
    ]  # fmt: skip
    for ext in ("csv", "md", "png", "svg"):
        assert (out / f"short-sweep-model.nu_mps2.{ext}").is_file()
    # each value minus the first, run by run: with every run paired, the mean difference
    # is the difference of the two rows' means
    assert res["paired"]["reference"] == "0.002" and res["paired"]["by"] == "value"
    pairs = {(p["value"], p["estimator"]): p for p in res["paired"]["rows"]}
    assert set(pairs) == {("0.02", "infoset"), ("0.02", "ekf")}
    for k, est in enumerate(("infoset", "ekf")):
        for m in ("miss_m", "fuel_mps"):
            got = pairs[("0.02", est)][m]
            assert got["runs"] == 2
            want = res["rows"][2 + k][m]["mean"] - res["rows"][k][m]["mean"]
            assert got["mean"] == pytest.approx(want, rel=1e-12, abs=1e-12)
    assert "each value minus 0.002" in (out / "short-sweep-model.nu_mps2.md").read_text()
    r2 = cli_inproc(
        capsys, "intercept", short, "--set", "model.nu_mps2=0.02", "--estimators", "ekf",
        "--noise", "random", "--runs", "2", "--out", tmp_path / "one", "--no-progress", "--json",
        "--workers", "1",
    )  # fmt: skip
    one = json.loads(r2.stdout.strip().splitlines()[-1])
    assert one["miss_m"] == res["rows"][3]["miss_m"]
    assert one["fuel_mps"] == res["rows"][3]["fuel_mps"]
    assert res["rows"][0]["miss_m"] != res["rows"][2]["miss_m"]  # nu changes the set


def test_sweep_figure_names_the_swept_field_with_its_unit():
    """The x axis reads the key and its field's doc with the unit (it read "in the
    scenario's unit"); keys given the same value share one doc; an undeclared key
    (a plug-in's) reads as itself."""
    import pandas as pd
    from kalman_vs_infoset.experiments import plots
    from kalman_vs_infoset.experiments.cmd_sweep import _xlabel

    assert _xlabel(["model.nu_mps2"]) == "model.nu_mps2\ndisturbance bound nu, m/s^2"
    both = _xlabel(["estimator.ekf.noise_inflation", "estimator.ukf.noise_inflation"])
    assert both.count("\n") == 1 and both.endswith("noise variance, R and Q")
    assert _xlabel(["estimator.plugin.knob"]) == "estimator.plugin.knob"
    table = pd.DataFrame(
        {"value": ["0.002", "0.02"], "estimator": "ekf", "noise": "random",
         "miss_m_mean": [1.0, 2.0], "fuel_mps_mean": [3.0, 4.0]}
    )  # fmt: skip
    fig = plots.sweep_figure(table, "model.nu_mps2", "t", _xlabel(["model.nu_mps2"]))
    assert [ax.get_xlabel() for ax in fig.axes[:2]] == [_xlabel(["model.nu_mps2"])] * 2


def test_sweep_takes_an_estimator_option_as_set_does(short, tmp_path, capsys):
    """A nested key (``estimator.infoset.n_nodes``, the keys ``--set`` takes) is swept:
    one row per value, and the option reaches the estimator (the two rows differ)."""
    r = cli_inproc(
        capsys, "sweep", short, "--key", "estimator.infoset.n_nodes", "--values", "[6, 16]",
        "--estimators", "infoset", "--noise", "random", "--runs", "1", "--out", tmp_path,
        "--no-progress", "--json",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout.strip().splitlines()[-1])["rows"]
    assert [row["value"] for row in rows] == ["6", "16"]
    assert rows[0]["miss_m"] != rows[1]["miss_m"]


@pytest.mark.parametrize(
    "args,message",
    [
        (["--key", "nu_mps2", "--values", "[1]"], "expected TABLE.KEY"),
        (["--key", "estimator.infoset.n.nodes", "--values", "[1]"], "expected TABLE.KEY"),
        (["--key", "estimator.infoset.n_nodez", "--values", "[8]"], "n_nodez"),
        (["--key", "model.nu_mps2", "--values", "[]"], "non-empty TOML array"),
        (["--key", "model.nu_mps2", "--values", "0.1"], "non-empty TOML array"),
        (["--key", "model.nu_mps2", "--values", "[0.1, -1]"], "field 'model.nu_mps2' must be"),
        # fields no value changes (the runs are --runs/--seed's): taken and ignored before
        (["--key", "experiment.seed", "--values", "[1, 2]"], "same paired runs"),
        (["--key", "model.nu_mps2,experiment.runs", "--values", "[1]"], "same paired runs"),
        (["--key", "reference.miss_random_m", "--values", "[1]"], "no run reads"),
    ],
)
def test_sweep_bad_input_exits_2_before_any_run(short, tmp_path, capsys, args, message):
    r = cli_inproc(capsys, "sweep", short, "--out", tmp_path / "x", "--no-progress", *args)
    assert r.returncode == 2 and message in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert not (tmp_path / "x" / "runs").exists()  # every value checked first


def test_compare_files_keep_their_extensions_when_the_name_has_dots(short, tmp_path, capsys):
    """A ``--set`` suffix puts dots into the scenario name; output files must still be
    ``<name>-compare.parquet`` etc., not truncated at the first dot."""
    r = cli_inproc(
        capsys, "compare", short, "--set", "model.nu_mps2=0.01", "--estimators", "infoset",
        "--noise", "random", "--runs", "1", "--out", tmp_path, "--no-progress",
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    stem = "short+model.nu_mps2=0.01-compare-infoset-random"
    for name in (f"{stem}.parquet", f"{stem}.csv", f"{stem}.md", f"{stem}-cdf.png"):
        assert (tmp_path / name).is_file(), name


def test_compare_summaries_of_other_choices_keep_their_own_files(short, tmp_path, capsys):
    """A compare of other estimators, noises or seed in the same ``--out`` replaced the
    first one's summary (``<scenario>-compare.*``): the choices that are not the
    defaults are in the name, as in fig5's (the defaults keep the plain name)."""
    from kalman_vs_infoset.estim import registry
    from kalman_vs_infoset.experiments.cli import build_parser
    from kalman_vs_infoset.experiments.cmd_compare import summary_stem

    def stem(*args):
        return summary_stem(build_parser("compare").parse_args(["compare", "x", *args]), "sc")

    assert stem() == "sc-compare"
    assert stem("--estimators", ",".join(registry.names("intercept"))) == "sc-compare"
    assert stem("--noise", "random,game", "--seed", "7") == "sc-compare-s7"
    assert stem("--estimators", "ukf,infoset", "--noise", "bias") == "sc-compare-ukf+infoset-bias"
    common = ["--runs", "1", "--workers", "1", "--no-progress", "--out", tmp_path]
    for extra in (["--estimators", "infoset"], ["--estimators", "infoset", "--seed", "9"]):
        r = cli_inproc(capsys, "compare", short, "--noise", "random", *extra, *common)
        assert r.returncode == 0, r.stderr
    mds = sorted(p.name for p in tmp_path.glob("*.md"))
    assert mds == ["short-compare-infoset-random-s9.md", "short-compare-infoset-random.md"]


def test_code_identity_follows_the_sources_that_decide_a_run(tmp_path, monkeypatch):
    """The hash changes with an estimator's source (even uncommitted) and not with a
    presentation module (plots, tables, command line)."""
    import shutil

    from kalman_vs_infoset.experiments import provenance

    for pkg in provenance.PACKAGES:
        shutil.copytree(ROOT / pkg, tmp_path / pkg, ignore=shutil.ignore_patterns("__pycache__"))
    identity = provenance.code_identity.__wrapped__  # uncached
    real = identity()["sources_sha256"]
    monkeypatch.setattr(provenance, "ROOT", tmp_path)
    h0 = identity()["sources_sha256"]
    assert h0 == real  # the copy hashes as the package does
    with (tmp_path / "experiments" / "plots.py").open("a") as fh:
        fh.write("\n# a new figure\n")
    with (tmp_path / "experiments" / "cmd_compare.py").open("a") as fh:
        fh.write("\n# a new option\n")
    assert identity()["sources_sha256"] == h0
    with (tmp_path / "estim" / "infoset.py").open("a") as fh:
        fh.write("\n# an edit\n")
    assert identity()["sources_sha256"] != h0


def test_the_examples_of_kvi_help_parse():
    """Every example line of ``kvi --help`` is a command line the parser accepts (so the
    examples cannot go stale), and the page lists every command."""
    from kalman_vs_infoset.experiments import cli

    examples = [line.strip().split("  ")[0].split()[1:] for line in cli.EPILOG.splitlines()[1:]]
    runnable = [argv for argv in examples if argv and argv[0] in cli.COMMANDS]
    assert len(runnable) >= 4
    for argv in runnable:
        args = cli.build_parser(argv[0]).parse_args(argv)
        assert args.command == argv[0]
    text = cli.build_parser().format_help()
    assert all(name in text for name in cli.COMMANDS) and "examples:" in text


def test_the_python_api_reruns_other_code_s_table_when_asked(short, tmp_path):
    """``run_experiment(..., out=...)`` refused a table other code wrote, naming the
    command line's ``--rerun-other-code``, which it did not take: it takes
    ``rerun_other_code=True``, and the refusal names both."""
    from kalman_vs_infoset.experiments.errors import InputError

    from kalman_vs_infoset import api

    sc = load_scenario(short)
    out = tmp_path / "out"
    fresh = api.run_experiment(short, "infoset", "random", runs=2, out=out)
    path = intercept_runs.results_path(out, sc, "infoset", "random", 11)
    meta_path = out / "_meta" / f"{path.stem}.json"
    meta = json.loads(meta_path.read_text())
    meta_path.write_text(json.dumps({**meta, "code": {**meta["code"], "sources_sha256": "0" * 64}}))
    with pytest.raises(InputError, match=r"--rerun-other-code \(Python: rerun_other_code=True\)"):
        api.run_experiment(short, "infoset", "random", runs=2, out=out)
    again = api.run_experiment(short, "infoset", "random", runs=2, out=out, rerun_other_code=True)
    pd.testing.assert_frame_equal(_table(again), _table(fresh))


def test_a_json_summary_names_its_command_and_code_and_remakes_itself(
    tmp_path, capsys, monkeypatch
):
    """A ``--json`` summary kept as a results file says what made it: the command line
    and the package's code (version, sources' SHA-256, commit). Results files said so
    only in the prose around them (and one search's draws changed under its published
    numbers). ``kvi reproduce`` runs the named command again and finds the same numbers
    (exit 0); an edited number is found moved (exit 1, the value named); a summary
    without a command is listed as such; a file that is no summary is bad input."""
    import shlex

    from kalman_vs_infoset.experiments.cli import main
    from kalman_vs_infoset.experiments.provenance import code_identity

    argv = ["tightness", "kp_fig3", "--noise", "bias", "--seed", "3", "--times", "10",
            "--json", "--out", str(tmp_path / "first")]  # fmt: skip
    assert main(argv) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    summary = json.loads(line)
    assert summary["command"] == shlex.join(["kvi", *argv])
    assert summary["code"] == dict(code_identity())
    kept = tmp_path / "kept.json"
    kept.write_text(line + "\n")
    assert main(["reproduce", str(kept), "--json"]) == 0
    (row,) = json.loads(capsys.readouterr().out.strip().splitlines()[-1])["checked"]
    assert (row["verdict"], row["details"], row["same_code"]) == ("same", [], True)
    summary["ratio"][0] *= 1.001
    kept.write_text(json.dumps(summary) + "\n")
    assert main(["reproduce", str(kept)]) == 1
    out = capsys.readouterr().out
    assert out.startswith("moved") and "/ratio/0: " in out
    summary["ratio"][0] /= 1.001
    del summary["n_lp"]  # a field the file's code did not write yet: no number moved
    kept.write_text(json.dumps(summary) + "\n")
    assert main(["reproduce", str(kept)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("same") and "/n_lp: new" in out
    del summary["command"]
    kept.write_text(json.dumps(summary) + "\n")
    assert main(["reproduce", str(kept)]) == 0
    assert capsys.readouterr().out.startswith("no command")
    # an edited command with an unclosed quote: a failed check, said in its row (raised)
    kept.write_text(json.dumps({"ratio": [1.0], "command": "kvi tightness 'kp_fig3"}))
    assert main(["reproduce", str(kept)]) == 1
    assert capsys.readouterr().out.startswith("failed")
    # a benchmark's summary is timings: said so, not run for a minute to read "moved"
    kept.write_text(json.dumps({"step_us": {"ukf": 500.0}, "command": "kvi bench --json"}))
    assert main(["reproduce", str(kept)]) == 0
    assert capsys.readouterr().out.startswith("timings")
    kept.write_text("not json\n")
    assert main(["reproduce", str(kept)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"kvi reproduce: error: {kept}: not a --json summary (JSONDecodeError)"]
    # a scenario file named relative to the folder and no --out (the first run wrote
    # into results/ here): the rerun reads the file from the current folder and writes
    # into a scratch folder, not over the first run's files
    from kalman_vs_infoset import data as bundled

    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.toml").write_text(bundled.scenario_file("kp_fig3").read_text())
    argv = ["tightness", "mine.toml", "--noise", "bias", "--seed", "3", "--times", "10",
            "--json"]  # fmt: skip
    assert main(argv) == 0
    kept.write_text(capsys.readouterr().out.strip().splitlines()[-1] + "\n")
    written = [(p, p.stat().st_mtime_ns) for p in sorted((tmp_path / "results").rglob("*"))]
    assert written
    assert main(["reproduce", str(kept)]) == 0
    assert capsys.readouterr().out.startswith("same")
    assert [(p, p.stat().st_mtime_ns) for p in sorted((tmp_path / "results").rglob("*"))] == (
        written
    )
