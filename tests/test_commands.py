"""Thin commands with one flag vocabulary: ``--estimators`` (a list) everywhere an
estimator is chosen, ``--noise`` a list, the old spelling refused in one line; shared
option parsing in one module; the runner knowing no problem; typed attitude loops; a
slow single run showing its steps; refused commands leaving nothing behind."""

from __future__ import annotations

import argparse
import ast
import dataclasses
import json
from pathlib import Path

import pandas as pd
import pytest
from harness_texts import TINY_RW, one_line_error
from harness_texts import run_cli as run
from kalman_vs_infoset.experiments import executors, progress
from kalman_vs_infoset.experiments.cli import COMMANDS, build_parser

ROOT = Path(__file__).resolve().parents[1]
EXPERIMENTS = ROOT / "experiments"

#: the commands that choose estimators, with the arguments they need to parse
CHOOSERS = {
    "intercept": ["kp_fig3"],
    "compare": ["kp_fig3"],
    "sweep": ["kp_fig3", "--key", "model.nu_mps2", "--values", "[0.01]"],
    "adversaries": ["kp_fig3"],
    "fig5": [],
    "attitude": ["smallsat_rw"],
    "tightness": ["kp_fig5"],
    "attitude-tightness": ["smallsat_rw"],
}


def _files(path: Path) -> list[Path]:
    return sorted(p for p in Path(path).rglob("*"))


def _options(command: str) -> set[str]:
    parser = build_parser(command)
    sub = next(a for a in parser._actions if a.dest == "command").choices[command]
    return {s for a in sub._actions if a.help != "==SUPPRESS==" for s in a.option_strings}


# -- one flag vocabulary ------------------------------------------------------------
@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_estimators_are_chosen_by_one_list_flag_in_every_command(command):
    shown = {o for o in _options(command) if "estimator" in o}
    assert shown <= {"--estimators"}
    assert bool(shown) == (command in CHOOSERS)


@pytest.mark.parametrize("command", sorted(CHOOSERS))
def test_the_old_estimator_flag_is_refused_naming_the_new_one(command, tmp_path, capsys):
    out = tmp_path / "out"
    r = run(capsys, command, *CHOOSERS[command], "--estimator", "ukf", "--out", out)
    assert one_line_error(r), r.stderr
    assert "--estimator is now --estimators" in r.stderr and "--estimators ukf" in r.stderr
    assert not out.exists()


@pytest.mark.parametrize("command", sorted(CHOOSERS))
@pytest.mark.parametrize(
    ("value", "says"),
    [("", "empty list"), ("ukf,ukf", "ukf given twice"), ("kalman9", "unknown kalman9"),
     (",ukf", "an empty name")],  # an empty name was dropped silently
)  # fmt: skip
def test_empty_duplicate_and_unknown_estimator_lists_are_refused(
    command, value, says, tmp_path, capsys
):
    out = tmp_path / "out"
    r = run(capsys, command, *CHOOSERS[command], "--estimators", value, "--out", out)
    assert one_line_error(r), r.stderr
    assert "--estimators" in r.stderr and says in r.stderr
    assert not out.exists()


def test_tightness_studies_one_estimator_at_a_time(tmp_path, capsys):
    r = run(capsys, "tightness", "kp_fig5", "--estimators", "ukf,ekf", "--out", tmp_path / "o")
    assert one_line_error(r) and "at most 1" in r.stderr


@pytest.mark.parametrize("command", ["intercept", "compare", "sweep", "attitude"])
@pytest.mark.parametrize(
    ("value", "says"), [("", "empty list"), ("game,game", "given twice"), ("game,", "empty name")]
)
def test_noise_lists_are_refused_when_empty_or_repeated(command, value, says, tmp_path, capsys):
    out = tmp_path / "out"
    r = run(capsys, command, *CHOOSERS[command], "--noise", value, "--out", out)
    assert one_line_error(r) and "--noise" in r.stderr and says in r.stderr, r.stderr
    assert not out.exists()


def test_intercept_runs_each_estimator_and_noise_of_its_lists_on_the_same_truths(
    short, tmp_path, capsys
):
    out = tmp_path / "out"
    r = run(capsys, "intercept", short, "--runs", 1, "--workers", 1, "--no-progress", "--json",
            "--estimators", "ekf,ukf", "--noise", "random,game", "--out", out)  # fmt: skip
    assert r.returncode == 0, r.stderr
    rows = json.loads(r.stdout.splitlines()[-1])["rows"]
    assert [(x["estimator"], x["noise"]) for x in rows] == [
        ("ekf", "random"), ("ekf", "game"), ("ukf", "random"), ("ukf", "game")
    ]  # fmt: skip
    tables = sorted(out.glob("*.parquet"))
    assert len(tables) == 4
    cols = ["x0_km", "y0_km", "z0_km", "vx0_kmps", "vy0_kmps", "vz0_kmps"]
    truths = {tuple(pd.read_parquet(t)[cols].iloc[0]) for t in tables}
    assert len(truths) == 1  # paired: the same truth whatever the estimator and noise
    # one estimator and one noise: the flat summary, as before
    r = run(capsys, "intercept", short, "--runs", 1, "--workers", 1, "--no-progress",
            "--estimators", "ekf", "--noise", "game", "--out", out, "--json")  # fmt: skip
    one = json.loads(r.stdout.splitlines()[-1])
    assert one["estimator"] == "ekf" and one["noise"] == "game" and "rows" not in one
    assert one["miss_m"] == rows[1]["miss_m"]  # the stored run, not a new one


def test_attitude_runs_each_noise_and_names_its_figures_by_all_of_them(tiny_rw, tmp_path, capsys):
    out = tmp_path / "out"
    r = run(capsys, "attitude", tiny_rw, "--runs", 2, "--workers", 1, "--no-progress",
            "--estimators", "box", "--noise", "none,random", "--out", out, "--json")  # fmt: skip
    assert r.returncode == 0, r.stderr
    res = json.loads(r.stdout.splitlines()[-1])
    assert [(x["estimator"], x["noise"]) for x in res["rows"]] == [
        ("box", "none"), ("box", "random")
    ]  # fmt: skip
    assert (out / "tiny_rw-pd-box-none+random-s0-cdf.png").exists()
    assert len(list(out.glob("tiny_rw-pd-box-*-s0.parquet"))) == 2


def test_a_bad_scenario_estimator_of_an_attitude_scenario_is_one_line(tmp_path, capsys):
    p = tmp_path / "bad.toml"
    p.write_text('estimator = "kalman9"\n' + TINY_RW)
    out = tmp_path / "out"
    r = run(capsys, "attitude", p, "--out", out)
    assert one_line_error(r) and "field 'estimator'" in r.stderr and "kalman9" in r.stderr
    assert not out.exists()


# -- nothing left behind -------------------------------------------------------------
@pytest.mark.parametrize(
    "args",
    [
        ["intercept", "{short}", "--set", "model.dt_s=-1"],
        ["intercept", "{short}", "--trace", "7", "--runs", "2"],
        ["compare", "{short}", "--set", 'experiment.estimator="foo"'],
        ["attitude", "{tiny_rw}", "--controller", "energy"],
        ["attitude", "{tiny_rw}", "--set", "wheels.torque_max_Nm=-1"],
        ["intercept", "{short}", "--scheduler", "tcp://127.0.0.1:1", "--runs", "1"],
    ],
)
def test_a_refused_command_leaves_no_folder_and_no_file(
    args, short, tiny_rw, tmp_path, capsys, monkeypatch
):
    # nothing listens on port 1: the refusal is the same after 1 s as after 10 s
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 1.0)
    out = tmp_path / "new" / "deeper"
    words = [a.format(short=short, tiny_rw=tiny_rw) for a in args]
    r = run(capsys, *words, "--no-progress", "--out", out)
    assert r.returncode in (1, 2) and "Traceback" not in r.stderr, r.stderr
    assert r.stderr.strip().splitlines()[-1].startswith("kvi "), r.stderr
    assert _files(tmp_path / "new") == [] and not (tmp_path / "new").exists()


def test_fig5_names_its_files_by_the_estimators_and_seed_when_not_the_seeds():
    from argparse import Namespace

    from kalman_vs_infoset.experiments.cmd_fig5 import _stem

    assert _stem(Namespace(estimators=["infoset"], seed=None, overrides=[])) == "fig5"
    assert _stem(Namespace(estimators=["ekf", "ukf"], seed=None, overrides=[])) == "fig5-ekf+ukf"
    assert _stem(Namespace(estimators=["infoset"], seed=4, overrides=[])) == "fig5-s4"
    floor = ["estimator.infoset.min_split_tau_s=1"]
    assert _stem(Namespace(estimators=["infoset"], seed=None, overrides=floor)) == (
        "fig5+estimator.infoset.min_split_tau_s=1"
    )


def test_fig5_takes_overrides_for_both_variants_in_files_of_their_own(tmp_path, capsys):
    """``kvi fig5 --set KEY=VALUE``: both variants run with it, their run tables and the
    figure's files carry it in their names (the seed's files are not replaced), and a
    key or value the scenario refuses is one line and exit status 2, before any run."""
    out = tmp_path / "out"
    r = run(capsys, "fig5", "--runs", 1, "--workers", 1, "--no-progress", "--out", out,
            "--set", "estimator.infoset.min_split_tau_s=1", "--json")  # fmt: skip
    assert r.returncode == 0, r.stderr
    stem = "fig5+estimator.infoset.min_split_tau_s=1"
    assert (out / f"{stem}_runs.csv").is_file() and not (out / "fig5_runs.csv").exists()
    table = pd.read_csv(out / f"{stem}_runs.csv")
    assert sorted(set(table["scenario"])) == [
        "kp_fig5+estimator.infoset.min_split_tau_s=1",
        "kp_fig5_range+estimator.infoset.min_split_tau_s=1",
    ]
    # the range finder against bearings only, run by run, from the same table
    from kalman_vs_infoset.experiments.paired import variants

    result = json.loads(r.stdout.strip().splitlines()[-1])
    table = pd.read_parquet(out / f"{stem}_runs.parquet")
    assert result["paired"] == variants(table, "bearing only")
    assert [(x["variant"], x["noise"]) for x in result["paired"]["rows"]] == [
        ("bearing + range", "random"), ("bearing + range", "game"),
    ]  # fmt: skip
    bad = tmp_path / "bad"
    r = run(capsys, "fig5", "--runs", 1, "--out", bad, "--set",
            "estimator.infoset.min_split_tau_s=-1")  # fmt: skip
    assert r.returncode == 2 and one_line_error(r), r.stderr
    assert "min_split_tau_s" in r.stderr and not bad.exists()


# -- thin commands --------------------------------------------------------------------
def _imports(path: Path) -> list[tuple[str, list[str]]]:
    """(module, names) of every import of a source file, at any depth."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module:
            found.append((node.module, [a.name for a in node.names]))
        elif isinstance(node, ast.Import):
            found += [(a.name, []) for a in node.names]
    return found


def test_commands_are_not_built_on_other_commands():
    """A command imports the harness (options, intercept runs, attitude loops), never
    another command's module; drawing traces is the one shared ``cmd_plot`` use."""
    for path in sorted(EXPERIMENTS.glob("cmd_*.py")):
        for module, names in _imports(path):
            others = [n for n in [module.rsplit(".", 1)[-1], *names] if n.startswith("cmd_")]
            assert not others, f"{path.name} imports {module} {names}"


def test_no_module_imports_another_ones_private_names():
    for path in sorted(EXPERIMENTS.rglob("*.py")):
        for module, names in _imports(path):
            if module.startswith("kalman_vs_infoset.experiments"):
                private = [n for n in names if n.startswith("_") and n != "__future__"]
                assert not private, f"{path.name} imports {private} from {module}"


def test_the_runner_knows_no_problem():
    modules = [m for m, _ in _imports(EXPERIMENTS / "runner.py")]
    assert not [m for m in modules if ".sim" in m or "intercept" in m or "attitude" in m]
    from kalman_vs_infoset.experiments.runner import run_seed

    assert run_seed.__code__.co_argcount == 2  # seed and run: the count never mattered


def test_every_controller_has_a_typed_loop_and_one_table_names_them():
    from kalman_vs_infoset.experiments import attitude_loops

    for controller in attitude_loops.LOOPS:
        loop = attitude_loops.loop_of(controller)
        assert isinstance(loop, attitude_loops.AttitudeLoop) and controller in loop.controllers
        with pytest.raises(dataclasses.FrozenInstanceError):
            loop.chunk = 3  # type: ignore[misc]
    source = (EXPERIMENTS / "attitude_traces.py").read_text()
    assert (
        "TRACERS" not in source and "DISPATCH" not in (EXPERIMENTS / "cmd_attitude.py").read_text()
    )


def test_an_attitude_request_is_typed_and_frozen(tiny_rw):
    from kalman_vs_infoset.experiments.cmd_attitude import request

    parser = build_parser("attitude")
    args = parser.parse_args(["attitude", str(tiny_rw), "--noise", "random"])
    req = request(args)
    assert (req.controller, req.estimators, req.noises) == ("pd", ("box",), ("random",))
    with pytest.raises(dataclasses.FrozenInstanceError):
        req.runs = 5  # type: ignore[misc]
    with pytest.raises(TypeError):
        req.scenario["name"] = "other"  # type: ignore[index]


# -- a slow single run shows progress ------------------------------------------------
def test_a_slow_single_run_shows_its_steps_in_a_log(short, tmp_path, capsys, monkeypatch):
    """stderr is not a terminal here: log lines, one per step once the run is slow."""
    monkeypatch.setattr(progress, "SLOW_RUN_S", 0.0)
    monkeypatch.setattr(progress, "LOG_EVERY_S", 0.0)
    r = run(capsys, "intercept", short, "--runs", 1, "--workers", 1, "--out", tmp_path / "o")
    assert r.returncode == 0, r.stderr
    steps = [line for line in r.stderr.splitlines() if "steps (at most)" in line]
    assert steps and steps[0].startswith("kvi: short infoset-random run 0: ")
    done = [int(line.split(": ")[-1].split("/")[0]) for line in steps]
    assert done == sorted(done) and done[-1] > 10  # the run's steps, as they went


def test_a_fast_run_or_no_progress_shows_no_steps(short, tmp_path, capsys, monkeypatch):
    r = run(capsys, "intercept", short, "--runs", 1, "--workers", 1, "--out", tmp_path / "a")
    assert r.returncode == 0 and "steps (at most)" not in r.stderr  # faster than SLOW_RUN_S
    monkeypatch.setattr(progress, "SLOW_RUN_S", 0.0)
    monkeypatch.setattr(progress, "LOG_EVERY_S", 0.0)
    r = run(capsys, "intercept", short, "--runs", 1, "--workers", 1, "--no-progress",
            "--out", tmp_path / "b")  # fmt: skip
    assert r.returncode == 0 and "steps (at most)" not in r.stderr


def test_step_progress_is_silent_outside_the_runner():
    with progress.step_progress(10, "x", after_s=0.0, every_s=0.0) as shown:
        assert shown(3) is None  # no bar, no line: not inside steps_shown


def test_on_a_terminal_a_slow_run_draws_a_bar_of_its_steps(monkeypatch, capsys):
    monkeypatch.setattr(progress, "_isatty", lambda: True)
    with progress.steps_shown(), progress.step_progress(50, "slow run", after_s=0.0) as shown:
        for k in range(1, 51):
            shown(k)
    err = capsys.readouterr().err
    assert "slow run:" in err and "/50 [" in err and "step" in err


def test_a_count_of_one_run_reads_singular_in_the_summaries(monkeypatch):
    """'1 run, seed 3' and 'empty set: 1 run', not '1 runs' (and plural otherwise)."""
    from kalman_vs_infoset.experiments import cmd_adversaries, cmd_intercept
    from kalman_vs_infoset.experiments.errors import runs_text

    assert [runs_text(n) for n in (0, 1, 2)] == ["0 runs", "1 run", "2 runs"]
    stats = dict.fromkeys(("mean", "p50", "p90", "max"), 1.0)
    row = {"scenario": "kp_fig3", "estimator": "infoset", "noise": "game", "runs": 1,
           "seed": 3, "miss_m": stats, "fuel_mps": stats, "truth_outside": 0,
           "empty_set": 1, "diverged": 0, "failures": 0}  # fmt: skip
    text = "\n".join(cmd_intercept._summary(row))
    assert "1 run, seed 3" in text and "empty set: 1 run;" in text and "diverged: 0 runs" in text
    adv = {"scenario": "kp_fig3", "runs": 1, "seed": 3, "seed_fuel_game_mps": 521.7,
           "seed_miss_game_m": 9.5, "files": []}  # fmt: skip
    monkeypatch.setattr(cmd_adversaries, "table_markdown", lambda result: "")
    assert "adversary strength, 1 run, seed 3" in cmd_adversaries.render(adv)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_option_with_a_default_says_it_in_its_help(command):
    """``kvi COMMAND --help`` states the default of every option that has one (an
    empty repeatable ``--set`` has none to state)."""
    parser = build_parser(command)
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    silent = [
        a.option_strings
        for a in sub.choices[command]._actions
        if a.help not in (None, argparse.SUPPRESS)
        and not isinstance(a, argparse._HelpAction)
        and a.default not in (None, False, [])
        and "default" not in a.help
    ]
    assert silent == []


def test_the_summary_says_when_a_set_issued_no_impulse_for_an_unbounded_forecast(tmp_path, capsys):
    """A sound set too wide to bound the miss forecast issues no impulse (counted in
    ``unbounded_steps``); the printed summary said nothing of it. It says so when it
    happened, and the line is absent otherwise."""
    from harness_texts import SHORT
    from kalman_vs_infoset.experiments import cmd_intercept
    from kalman_vs_infoset.experiments.cli import main

    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT)
    argv = ["intercept", str(scenario), "--runs", "1", "--workers", "1", "--json",
            "--no-progress", "--out", str(tmp_path / "out")]  # fmt: skip
    assert main(argv) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["unbounded_steps"] == 0
    assert "bounded forecast" not in cmd_intercept.render(result)
    said = cmd_intercept.render({**result, "unbounded_steps": 7})
    assert "  no impulse for want of a bounded forecast: 7 channel steps" in said.splitlines()
