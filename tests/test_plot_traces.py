"""``kvi plot`` on trace folders as commands leave them: runs traced by some estimators
only, traces of other scenarios of one seed side by side, and damaged trace files (one
line, exit status 2). The traces are written as ``--trace`` writes them, without the
figures the commands draw of them."""

from __future__ import annotations

import shutil
from pathlib import Path

import pandas as pd
import pytest
from harness_texts import SHORT, one_line_error
from harness_texts import run_cli as run
from kalman_vs_infoset.experiments.intercept_runs import results_path
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.traces import write_intercept_trace


def _trace(scenario: Path, out: Path, estimator: str, runs: list[int], *sets: str) -> None:
    """What ``kvi intercept SCENARIO --estimators E --trace RUNS --out OUT`` writes to
    ``_traces/`` (seed 1, random errors)."""
    sc = load_scenario(scenario, list(sets))
    write_intercept_trace(
        sc, estimator, "random", 1, runs, results_path(out, sc, estimator, "random", 1)
    )


def _figures(out: Path) -> set[str]:
    return {p.name for p in out.glob("*.png")}


def test_runs_traced_by_one_estimator_each_are_drawn_each_with_its_own(short, tmp_path, capsys):
    """Run 0 traced by the EKF, run 1 by the UKF (also what a compare leaves when a traced
    run failed for one estimator): each run's figure of the estimator that traced it, no
    overlay of one estimator (an IndexError before)."""
    res = tmp_path / "res"
    _trace(short, res, "ekf", [0])
    _trace(short, res, "ukf", [1])
    figs = tmp_path / "figs"
    r = run(capsys, "plot", res, "--no-animation", "--out", figs)
    assert r.returncode == 0, r.stderr
    assert _figures(figs) == {
        "short-ekf-random-s1-run0-processes.png",
        "short-ukf-random-s1-run1-processes.png",
    }


def test_traces_of_two_scenarios_of_one_seed_are_drawn_apart(short, tmp_path, capsys):
    """A scenario and its --set variant, same seed and run: a figure each, each from its
    own trace (they were drawn as one, under the first one's name, with both truths)."""
    res = tmp_path / "res"
    _trace(short, res, "ekf", [0])
    _trace(short, res, "ekf", [0], "guidance.max_impulse_mps=2")
    figs = tmp_path / "figs"
    r = run(capsys, "plot", res, "--no-animation", "--out", figs)
    assert r.returncode == 0, r.stderr
    names = {n for n in _figures(figs) if n.endswith("-processes.png")}
    assert names == {
        "short-ekf-random-s1-run0-processes.png",
        "short+guidance.max_impulse_mps=2-ekf-random-s1-run0-processes.png",
    }


@pytest.fixture(scope="module")
def node_set_trace(tmp_path_factory) -> Path:
    """A node-set trace with its sets file (written once for this module's tests)."""
    folder = tmp_path_factory.mktemp("traced")
    (folder / "short.toml").write_text(SHORT)
    _trace(folder / "short.toml", folder / "res", "infoset", [0])
    (path,) = (folder / "res").rglob("*-trace.parquet")
    return path


@pytest.fixture
def traced(node_set_trace, tmp_path) -> Path:
    """A copy of :func:`node_set_trace` and its sets file, this test's to damage."""
    for name in (node_set_trace.name, node_set_trace.name.replace("-trace", "-trace-sets")):
        shutil.copy2(node_set_trace.with_name(name), tmp_path / name)
    return tmp_path / node_set_trace.name


@pytest.mark.parametrize("damage", ["junk", "truncated"])
def test_a_damaged_sets_file_is_one_line(traced, tmp_path, capsys, damage):
    sets = traced.with_name(traced.name.replace("-trace", "-trace-sets"))
    data = sets.read_bytes()
    sets.write_bytes(b"not parquet" if damage == "junk" else data[: len(data) // 2])
    r = run(capsys, "plot", traced, "--no-animation", "--out", tmp_path / "figs")
    assert one_line_error(r) and sets.name in r.stderr, r.stderr
    assert not (tmp_path / "figs").exists()  # refused before the folder is made


@pytest.mark.parametrize(
    ("sets_file", "column", "value"),
    [(False, "t_s", float("nan")), (False, "t_s", float("inf")), (False, "scenario", None),
     (False, "estimator", None), (True, "alpha_rad", float("nan")), (True, "x_m", float("-inf")),
     (True, "phase", None)],
)  # fmt: skip
def test_a_damaged_value_is_one_line_before_any_figure_or_folder(
    traced, tmp_path, capsys, sets_file, column, value
):
    """A value the package never writes (an empty label, a time or a vertex that is not a
    finite number) drew figures up to a traceback (NaN axis limits of the 3-D set, a
    KeyError for an empty scenario), and the command made its ``--out`` before reading
    the traces, leaving an empty folder behind every refusal."""
    path = traced.with_name(traced.name.replace("-trace", "-trace-sets")) if sets_file else traced
    df = pd.read_parquet(path)
    df[column] = df[column].astype(object if value is None else float)
    df.loc[df.index[len(df) // 2], column] = value
    df.to_parquet(path)
    r = run(capsys, "plot", traced, "--no-animation", "--out", tmp_path / "figs")
    assert one_line_error(r) and path.name in r.stderr and repr(column) in r.stderr, r.stderr
    assert not (tmp_path / "figs").exists()


def test_an_attitude_trace_without_the_rows_it_draws_is_one_line(tmp_path, capsys):
    """The history figure draws axis 1's rows: a trace without them (a damaged ``axis``
    column) ended in a traceback of the log scale."""
    from harness_texts import small_attitude_trace

    df = small_attitude_trace()
    good, bad = tmp_path / "good-trace.parquet", tmp_path / "bad-trace.parquet"
    df.to_parquet(good)
    df.assign(axis=df["axis"] + 10).to_parquet(bad)
    assert run(capsys, "plot", good, "--out", tmp_path / "ok").returncode == 0
    r = run(capsys, "plot", bad, "--out", tmp_path / "figs")
    assert one_line_error(r) and "axis 1" in r.stderr, r.stderr
    assert not (tmp_path / "figs").exists()


@pytest.mark.parametrize("column", ["t_s", "scenario", "forecast_lo_m", "zem_true_m"])
def test_a_trace_without_a_column_its_figures_read_is_one_line(traced, tmp_path, capsys, column):
    pd.read_parquet(traced).drop(columns=column).to_parquet(traced)
    r = run(capsys, "plot", traced, "--no-animation", "--out", tmp_path / "figs")
    assert one_line_error(r) and repr(column) in r.stderr, r.stderr


def test_sets_without_a_column_their_figures_read_are_one_line(traced, tmp_path, capsys):
    sets = traced.with_name(traced.name.replace("-trace", "-trace-sets"))
    pd.read_parquet(sets).drop(columns="zem_m").to_parquet(sets)
    r = run(capsys, "plot", traced, "--no-animation", "--out", tmp_path / "figs")
    assert one_line_error(r) and "'zem_m'" in r.stderr, r.stderr
    assert _drawn(tmp_path / "figs") == []


def _drawn(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob("*") if p.is_file()) if folder.exists() else []


def test_a_trace_without_steps_is_one_line(traced, tmp_path, capsys):
    pd.read_parquet(traced).iloc[:0].to_parquet(traced)
    r = run(capsys, "plot", traced, "--no-animation", "--out", tmp_path / "figs")
    assert one_line_error(r) and "without steps" in r.stderr, r.stderr


def test_an_animation_stopped_mid_write_leaves_the_one_before_it(traced, tmp_path, monkeypatch):
    """The GIF is written whole or not at all, as every other figure: a write that fails
    half-way leaves the previous GIF and no temporary file beside it (pillow wrote the
    named file in place before)."""
    from kalman_vs_infoset.experiments import plots_sets
    from matplotlib import animation

    sets = pd.read_parquet(traced.with_name(traced.name.replace("-trace", "-trace-sets")))
    out = tmp_path / "figs"
    gif = out / "set.gif"
    plots_sets.animate(sets, 0, gif, max_frames=2)
    before = gif.read_bytes()
    assert before.startswith(b"GIF8")

    def half_then_fail(self):
        Path(self.outfile).write_bytes(b"GIF8")  # part of a file, then the write stops
        raise OSError("disk full")

    monkeypatch.setattr(animation.PillowWriter, "finish", half_then_fail)
    with pytest.raises(OSError, match="disk full"):
        plots_sets.animate(sets, 0, gif, max_frames=3)
    assert gif.read_bytes() == before
    assert [p.name for p in out.iterdir()] == ["set.gif"]


def test_each_scenario_is_marked_with_its_own_printed_numbers(short, tmp_path, monkeypatch):
    """The paper's marks were read from the first trace's results and drawn on every
    scenario's figures; a scenario's --set variant may carry another reference."""
    from kalman_vs_infoset.experiments import plots_traces

    res = tmp_path / "res"
    _trace(short, res, "ekf", [0])
    _trace(short, res, "ekf", [0], "reference.miss_random_m=7.0")
    monkeypatch.setattr(plots_traces, "_paper_from_json", lambda path: {"from": path.name})
    drawn = {}

    def figures(df, name, tag, out, paper):
        drawn[name] = paper
        return []

    monkeypatch.setattr(plots_traces, "_step_figures", figures)
    plots_traces.plot_files(sorted(res.rglob("*-trace.parquet")), out=tmp_path, animation=False)
    assert len(drawn) == 2
    for name, marks in drawn.items():
        assert marks["from"].startswith(name + "-ekf-random-s1")
