"""The Python front door (kalman_vs_infoset.api): its examples run, and it reproduces
the command line to the last digit (the same seeding function, the same rows)."""

import doctest
import importlib
import shutil
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from kalman_vs_infoset.experiments import results as results_module
from kalman_vs_infoset.experiments.cli import main
from kalman_vs_infoset.experiments.errors import InputError

import kalman_vs_infoset
from kalman_vs_infoset import api

#: columns that differ between two computations of the same run (timing)
TIMING = ["wall_s"]


@pytest.fixture(scope="module")
def fig3_tables(tmp_path_factory):
    """What ``run_experiment("kp_fig3", est, "random", runs=2, seed=3, out=...)`` writes
    for the EKF and the UKF, computed once for the tests of reading folders (each copies
    them where a command would have written them: they were computed nine times)."""
    out = tmp_path_factory.mktemp("fig3_tables")
    for est in ("ekf", "ukf"):
        api.run_experiment("kp_fig3", est, "random", runs=2, seed=3, out=out)
    return out


def _written(tables: Path, out: Path, estimators=("ekf", "ukf")) -> None:
    """``out`` as after ``run_experiment(..., out=out)`` of ``estimators`` (the table and
    its description in ``_meta``), from the copies in ``tables``."""
    (out / "_meta").mkdir(parents=True, exist_ok=True)
    for est in estimators:
        stem = f"kp_fig3-{est}-random-s3"
        shutil.copy2(tables / f"{stem}.parquet", out / f"{stem}.parquet")
        shutil.copy2(tables / "_meta" / f"{stem}.json", out / "_meta" / f"{stem}.json")


def test_the_package_root_re_exports_the_front_door_lazily():
    assert set(api.__all__) == set(kalman_vs_infoset._API)
    for name in api.__all__:
        assert getattr(kalman_vs_infoset, name) is getattr(api, name), name
    with pytest.raises(AttributeError):
        kalman_vs_infoset.no_such_name  # noqa: B018
    code = "import sys, kalman_vs_infoset; print('kalman_vs_infoset.api' in sys.modules)"
    import subprocess

    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.stdout.strip() == "False"  # importing the package does not load the API


def test_every_public_name_has_a_numpydoc_docstring():
    for name in api.__all__:
        obj = getattr(api, name)
        if callable(obj) and getattr(obj, "__module__", "").startswith("kalman_vs_infoset"):
            assert obj.__doc__ and obj.__doc__.strip(), name
    for name in ("load_scenario", "run_engagement", "run_experiment", "trace", "load_results",
                 "run_attitude"):  # fmt: skip
        doc = getattr(api, name).__doc__
        assert "Parameters\n    ----------" in doc and "Examples\n    --------" in doc, name


@pytest.mark.parametrize("module", ["kalman_vs_infoset.api", "kalman_vs_infoset.data",
                                    "kalman_vs_infoset.experiments.results"])  # fmt: skip
def test_the_docstring_examples_run(module):
    mod = importlib.import_module(module)
    res = doctest.testmod(mod, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert res.attempted >= 2 and res.failed == 0


def test_run_engagement_reproduces_cli_run_0_of_kp_fig3_to_the_last_digit(tmp_path, capsys):
    """``kvi intercept kp_fig3`` run 0 (root seed: the scenario's) and
    ``run_engagement(load_scenario("kp_fig3"), run=0)``: every column of the row is equal
    (floats bit for bit)."""
    assert main(["intercept", "kp_fig3", "--out", str(tmp_path), "--no-progress"]) == 0
    capsys.readouterr()
    cli = api.load_results(tmp_path)
    assert list(cli["run"]) == [0] and (cli["status"] == "ok").all()
    row = api.run_engagement(api.load_scenario("kp_fig3"), run=0).as_row()
    for key, value in row.items():
        assert cli[key].iloc[0] == value or (np.isnan(value) and np.isnan(cli[key].iloc[0])), key
    # and a later run: run j is SeedSequence(seed, spawn_key=(j,)), not default_rng(seed)
    other = api.run_engagement("kp_fig3", "ukf", "random", run=1, seed=7)
    df = api.run_experiment("kp_fig3", "ukf", "random", runs=2, seed=7)
    assert df["miss_m"].iloc[1] == other.miss_m and df["fuel_mps"].iloc[1] == other.fuel_mps
    assert df["miss_m"].iloc[0] != other.miss_m


def test_run_attitude_reproduces_the_command_s_rows_and_writes_nothing(tmp_path, capsys,
                                                                      monkeypatch):  # fmt: skip
    """``kvi attitude smallsat_rw --noise random --estimators ukf --runs 3 --seed 4`` (the
    first 5 s of the turn) and ``run_attitude`` with the same arguments: every column of every row
    equal (floats bit for bit), and ``run_attitude`` writes no file; a bad estimator is
    a ValueError naming the registered ones, a bad noise the command's one-line error."""
    argv = ["attitude", "smallsat_rw", "--noise", "random", "--estimators", "ukf", "--runs",
            "3", "--seed", "4", "--set", "simulation.duration_s=5.0", "--no-progress"]  # fmt: skip
    assert main([*argv, "--out", str(tmp_path / "cli")]) == 0
    capsys.readouterr()
    cli = api.load_results(tmp_path / "cli")
    monkeypatch.chdir(tmp_path)
    df = api.run_attitude("smallsat_rw", noise="random", estimator="ukf", runs=3, seed=4,
                          simulation={"duration_s": 5.0})  # fmt: skip
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cli"]
    assert list(df["run"]) == list(cli["run"]) == [0, 1, 2]
    assert set(df.columns) == set(cli.columns)  # the job's columns too (they were missing)
    for key in df.columns.drop("wall_s"):
        assert df[key].tolist() == cli[key].tolist(), key
    with pytest.raises(ValueError, match="unknown attitude estimator 'ukk'"):
        api.run_attitude("smallsat_rw", estimator="ukk")
    with pytest.raises(ValueError, match="noise must be one of none, random, game, got 'loud'"):
        api.run_attitude("smallsat_rw", noise="loud")
    with pytest.raises(InputError, match=r"\(with keyword overrides\)"):
        api.run_attitude("smallsat_rw", simulation={"duration_s": -1.0})
    # a scenario listing two estimators: both run, as the command runs them, each row
    # naming its own (only the first ran before)
    two = tmp_path / "two.toml"
    source = (Path(__file__).resolve().parents[1] / "data/scenarios/smallsat_rw.toml").read_text()
    two.write_text('estimator = "ukf,box"\n' + source)
    df = api.run_attitude(two, noise="random", runs=2, simulation={"duration_s": 5.0})
    assert df[["estimator", "run"]].values.tolist() == [["ukf", 0], ["ukf", 1], ["box", 0],
                                                          ["box", 1]]  # fmt: skip


def test_in_memory_run_experiment_equals_the_files_and_writes_nothing(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sc = api.load_scenario("kp_fig3", truth={"y_km": [-9.0, -7.0]})
    mem = api.run_experiment(sc, "ekf", "game", runs=3, seed=5)
    assert list(tmp_path.iterdir()) == []
    disk = api.run_experiment(sc, "ekf", "game", runs=3, seed=5, out=tmp_path / "out")
    pd.testing.assert_frame_equal(mem.drop(columns=TIMING), disk.drop(columns=TIMING))
    assert mem["y0_km"].nunique() == 3  # three different truths


def test_a_results_folder_reads_in_one_call_with_its_scenario(tmp_path, fig3_tables):
    """``pd.read_parquet(folder)`` and ``load_results(folder)`` give every run of every
    table of an intercept folder (traces and descriptions are in ``_`` folders); the
    metadata holds the resolved scenario and the code identity."""
    out = tmp_path / "out"
    _written(fig3_tables, out)  # run_experiment of the EKF and the UKF, runs=2, seed=3
    assert main(["intercept", "kp_fig3", "--estimators", "ekf", "--seed", "3", "--runs", "2",
                 "--out", str(out), "--trace", "0", "--no-progress"]) == 0  # fmt: skip
    assert (out / "_traces").is_dir() and (out / "_meta").is_dir()
    both = pd.read_parquet(out)
    assert len(both) == 4 and sorted(set(both["estimator"])) == ["ekf", "ukf"]
    loaded = api.load_results(out)
    assert len(loaded) == 4 and set(loaded.attrs["metadata"]) == {
        "kp_fig3-ekf-random-s3.parquet",
        "kp_fig3-ukf-random-s3.parquet",
    }
    meta = api.read_metadata(out / "kp_fig3-ekf-random-s3.parquet")
    assert meta["scenario"] == api.load_scenario("kp_fig3").model_dump(mode="json")
    assert meta["estimator"] == "ekf" and meta["seed"] == 3
    assert meta["code"]["version"] == kalman_vs_infoset.__version__
    assert len(meta["code"]["sources_sha256"]) == 64


def test_load_results_reads_each_run_once_beside_or_above_a_combined_table(tmp_path, fig3_tables):
    """A command's combined table (``report.write_tables``: compare and fig5 above their
    ``runs/``, adversaries beside its runs' tables) holds the runs' rows again:
    ``load_results`` of the folder reads the runs' own tables, each run once (it read an
    adversaries folder twice over); the combined table given alone is still read."""
    from kalman_vs_infoset.experiments.report import write_tables

    beside, above = tmp_path / "beside", tmp_path / "above"
    for folder in (beside, above / "runs"):  # the EKF's and UKF's runs=2, seed=3
        _written(fig3_tables, folder)
    combined = pd.concat([pd.read_parquet(p) for p in sorted(beside.glob("*.parquet"))])
    write_tables(combined, beside / "kp_fig3-adversaries")
    write_tables(combined, above / "kp_fig3-compare")
    for folder in (beside, above):
        loaded = api.load_results(folder)
        assert len(loaded) == 4 and sorted(loaded.attrs["metadata"]) == [
            "kp_fig3-ekf-random-s3.parquet",
            "kp_fig3-ukf-random-s3.parquet",
        ], folder
        assert sorted(zip(loaded["estimator"], loaded["run"], strict=True)) == sorted(
            zip(combined["estimator"], combined["run"], strict=True)
        )
    assert len(api.load_results(above / "kp_fig3-compare.parquet")) == 4


def test_results_of_an_earlier_release_resume(tmp_path):
    """A table with its description beside it (the earlier layout) is resumed, and its
    description moves to ``_meta/``."""
    sc = api.load_scenario("kp_fig3")
    api.run_experiment(sc, "ekf", "random", runs=1, out=tmp_path)
    table = tmp_path / "kp_fig3-ekf-random-s3.parquet"
    side = results_module.sidecar_path(table)
    side.rename(table.with_suffix(".json"))
    df = api.run_experiment(sc, "ekf", "random", runs=2, out=tmp_path)
    assert list(df["run"]) == [0, 1] and side.exists()


def test_bad_input_through_the_api_is_one_clear_error(tmp_path):
    with pytest.raises(InputError, match="kvi scenarios"):
        api.load_scenario("kp_fig33")
    with pytest.raises(InputError, match="model.nu_mps2") as bad:
        api.load_scenario("kp_fig3", model={"nu_mps2": -1.0})
    # the message names the overrides as the caller gave them, not the command's --set
    assert "(with keyword overrides)" in str(bad.value) and "--set" not in str(bad.value)
    with pytest.raises(InputError, match="no such results folder"):
        api.load_results("/nonexistent/folder")
    with pytest.raises(InputError, match="no results tables"):  # it read an empty table
        api.load_results(tmp_path)
    with pytest.raises(ValueError):
        api.run_engagement("kp_fig3", run=-1)
    # workers=0 ran on every CPU (0 read as "unset"); the command line refuses it
    for workers in (0, -2):
        with pytest.raises(ValueError, match="workers must be at least 1"):
            api.run_experiment("kp_fig3", "ekf", "random", runs=1, workers=workers)
    with pytest.raises(TypeError, match="workers must be an integer"):
        api.run_experiment("kp_fig3", "ekf", "random", runs=1, workers=1.5)


def test_wrong_kinds_of_arguments_are_named(tmp_path, monkeypatch):
    """Arguments of the wrong kind are named (before: "unhashable type: 'list'", an
    AttributeError 'submit', the results written to the working directory for
    ``out=''``, and every step twice for a run traced twice)."""
    with pytest.raises(TypeError, match="estimator must be one name"):
        api.run_engagement("kp_fig3", ["ekf"])
    with pytest.raises(TypeError, match="noise must be one name"):
        api.run_experiment("kp_fig3", "ekf", ("random",), runs=1)
    with pytest.raises(TypeError, match="executor must be a concurrent.futures.Executor"):
        api.run_experiment("kp_fig3", "ekf", "random", runs=1, executor=5)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ValueError, match="out must name a folder"):
        api.run_experiment("kp_fig3", "ekf", "random", runs=1, out="")
    assert list(tmp_path.iterdir()) == []
    with pytest.raises(ValueError, match="runs must be distinct"):
        api.trace("kp_fig3", "ekf", "random", runs=[0, 0])
    with pytest.raises(TypeError, match="runs must be a sequence of run indices"):
        api.trace("kp_fig3", "ekf", "random", runs=5)  # 'int' object is not iterable
    with pytest.raises(TypeError, match="estimator must be one name"):
        api.run_attitude("smallsat_rw", estimator=["box", "ukf"])


def test_run_attitude_changes_the_noise_table_through_tables(tmp_path, capsys, monkeypatch):
    """``noise=`` names the noise, so the ``[noise]`` table (the measurement errors) was
    out of reach of the keyword overrides; ``tables={"noise": {...}}`` reaches it, and
    gives the rows of ``--set noise.meas_angle_deg=0.05``, bit for bit."""
    argv = ["attitude", "smallsat_rw", "--noise", "random", "--estimators", "box", "--runs",
            "2", "--set", "simulation.duration_s=3.0", "--set", "noise.meas_angle_deg=0.05",
            "--no-progress", "--out", str(tmp_path / "cli")]  # fmt: skip
    assert main(argv) == 0
    capsys.readouterr()
    cli = api.load_results(tmp_path / "cli")
    monkeypatch.chdir(tmp_path)
    df = api.run_attitude("smallsat_rw", noise="random", estimator="box", runs=2,
                          simulation={"duration_s": 3.0},
                          tables={"noise": {"meas_angle_deg": 0.05}})  # fmt: skip
    for key in df.columns.drop("wall_s"):
        assert df[key].tolist() == cli[key].tolist(), key
    plain = api.run_attitude("smallsat_rw", noise="random", estimator="box", runs=2,
                             simulation={"duration_s": 3.0})  # fmt: skip
    assert (df["mean_knowledge_bound_deg"] > 5 * plain["mean_knowledge_bound_deg"]).all()


def test_load_results_reads_the_runs_of_every_command_that_wrote_to_one_folder(
    tmp_path, fig3_tables
):
    """``intercept`` and ``compare`` default to one folder: the first's table at its top,
    the second's in ``runs/`` beside its combined table. Every run of both is read (the
    top's tables hid ``runs/``), and a table of one name in both places (one job, run
    ``j`` seeded alike) gives each run once."""
    from kalman_vs_infoset.experiments.report import write_tables

    out = tmp_path / "results"
    api.run_experiment("kp_fig3", "ekf", "game", runs=2, seed=3, out=out)
    _written(fig3_tables, out / "runs")  # the EKF's and UKF's runs=2, seed=3
    api.run_experiment("kp_fig3", "ekf", "game", runs=3, seed=3, out=out / "runs")
    below = pd.concat([pd.read_parquet(p) for p in sorted((out / "runs").glob("*.parquet"))])
    write_tables(below, out / "kp_fig3-compare")
    loaded = api.load_results(out)
    keys = sorted(zip(loaded["estimator"], loaded["noise"], loaded["run"], strict=True))
    assert keys == sorted(
        [("ekf", "game", j) for j in range(3)]
        + [(e, "random", j) for e in ("ekf", "ukf") for j in range(2)]
    )
    assert sorted(loaded.attrs["metadata"]) == [
        "kp_fig3-ekf-game-s3.parquet",
        "kp_fig3-ekf-random-s3.parquet",
        "kp_fig3-ukf-random-s3.parquet",
    ]


def test_load_results_keeps_apart_tables_of_one_name_and_another_scenario(tmp_path, fig3_tables):
    """A table of one name at the top and in ``runs/`` is one job only when it describes
    the same scenario: edited between the two commands (here ``nu``), both tables' runs
    are read, each with its description (they were merged by name, the second's runs
    under the first's description)."""
    out = tmp_path / "results"
    sc = api.load_scenario("kp_fig3")
    edited = sc.model_copy(update={"model": sc.model.model_copy(update={"nu_mps2": 0.004})})
    _written(fig3_tables, out, ["ekf"])  # run_experiment(sc, "ekf", "random", 2, seed=3)
    api.run_experiment(edited, "ekf", "random", runs=2, seed=3, out=out / "runs")
    loaded = api.load_results(out)
    assert len(loaded) == 4
    assert sorted(loaded.attrs["metadata"]) == [
        "kp_fig3-ekf-random-s3.parquet",
        "runs/kp_fig3-ekf-random-s3.parquet",
    ]
    nus = {m["scenario"]["model"]["nu_mps2"] for m in loaded.attrs["metadata"].values()}
    assert nus == {sc.model.nu_mps2, 0.004}
