"""Typed attitude scenarios (docs/models.md §2.5): the reaction-wheel, gyrodine and gyrostat
tables (:mod:`experiments.sim.attitude_rw_config`, :mod:`experiments.sim.attitude_cmg_config`,
:mod:`kalman_vs_infoset.experiments.sim.gyrostat_config`).

A bad value in any table, an unknown key in any table and a missing table are refused
with one line on stderr naming the file and the field (with what is allowed), exit
status 2, nothing written; ``--set`` overrides are validated the same way; the loops run
from typed configuration built in Python, without the command line's dicts.
"""

from __future__ import annotations

import inspect
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from kalman_vs_infoset.experiments import attitude_rw
from kalman_vs_infoset.experiments.cli import main
from kalman_vs_infoset.experiments.sim import (
    attitude_cmg_config,
    attitude_rw_config,
    gyrostat_config,
)
from kalman_vs_infoset.experiments.sim.attitude_rw import simulate_runs
from kalman_vs_infoset.experiments.sim.attitude_rw_config import (
    BodyTable,
    ManeuverTable,
    PdTable,
    RwScenario,
    SimulationTable,
)
from pydantic import BaseModel, ValidationError

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "data" / "scenarios"


def run(capsys, *args) -> tuple[int, str]:
    """``experiments.cli.main`` in this process: (exit status, stderr); an escaping
    exception fails the test (a traceback is what a user would see)."""
    code = main([str(a) for a in args])
    return code, capsys.readouterr().err


def run_json(capsys, *args) -> dict:
    """The ``--json`` result of a command that succeeds."""
    code = main([str(a) for a in args] + ["--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out.strip().splitlines()[-1])


def one_line_error(code: int, err: str) -> bool:
    lines = err.strip().splitlines()
    return code == 2 and len(lines) == 1 and "Traceback" not in err


def files_under(path: Path) -> list[Path]:
    return sorted(p for p in Path(path).rglob("*") if p.is_file())


# (scenario file, --controller or None, override, field named, what is allowed)
BAD_VALUES = [
    ("smallsat_rw", None, "body.inertia_kgm2=[1.5, 1.5]", "body.inertia_kgm2", "a list of 3"),
    ("smallsat_rw", None, "body.axes_rotvec_deg=[0.0, 0.0, 400.0]", "body.axes_rotvec_deg",
     "[-360, 360]"),
    ("smallsat_rw", None, "wheels.torque_max_Nm=0", "wheels.torque_max_Nm", "(0, inf)"),
    ("smallsat_rw", None, "wheels.momentum_max_Nms=-0.2", "wheels.momentum_max_Nms", "(0, inf)"),
    ("smallsat_rw", None, "maneuver.angle_deg=181", "maneuver.angle_deg", "[0, 180]"),
    ("smallsat_rw", None, "maneuver.axis=[0, 0, 0]", "maneuver.axis", "non-zero"),
    ("smallsat_rw", None, "maneuver.target_quaternion=[0.5, 0.0, 0.0, 0.5]",
     "maneuver.target_quaternion", "unit quaternion"),
    ("smallsat_rw", None, "maneuver.random_attitude=1", "maneuver.random_attitude",
     "true or false"),
    ("smallsat_rw", None, "simulation.substeps=0", "simulation.substeps", "an integer in [1, 100]"),
    ("smallsat_rw", None, 'simulation.duration_s="long"', "simulation.duration_s",
     "a number in [1, 100000]"),
    ("smallsat_rw", None, "simulation.duration_s=90000", "simulation.duration_s", "the limit is"),
    ("smallsat_rw", "pd", "pd.k_q=0", "pd.k_q", "(0, inf)"),
    ("smallsat_rw", "pd", 'pd.quaternion_term="double"', "pd.quaternion_term",
     "'vector', 'twice'"),
    ("smallsat_rw", "lqr", "lqr.r=[1.0, 0.0, 1.0]", "lqr.r", "(0, inf)"),
    ("smallsat_rw", "lqr", 'lqr.shortest="no"', "lqr.shortest", "true or false"),
    ("smallsat_rw", None, "noise.meas_rate_degps=11", "noise.meas_rate_degps", "[0, 10]"),
    ("smallsat_rw", None, "description=3", "description", "a string"),
    ("lqr_large_angle", None, "lqr.q=[0.2, 0.2, 0.2, 0.004, 0.004]", "lqr.q", "a list of 6"),
    ("resurs_p", None, "dt_s=2", "dt_s", "[0.001, 1]"),
    ("resurs_p", None, "horizon_s=100.0", "horizon_s", ">= duration_s"),
    ("resurs_p", None, "inertia_products_sign=[1, 0, 1]", "inertia_products_sign", "+1 or -1"),
    ("resurs_p", None, 'inertia_products_sign="plus"', "inertia_products_sign",
     "'standard', 'entries'"),
    ("resurs_p", None, "initial_error_deg=[180.0, 0.0, 0.0]", "initial_error_deg",
     "[-179, 179]"),
    ("resurs_p", "energy", 'controller="pd"', "controller", "'energy', 'euler'"),
    ("resurs_p", None, "energy.control_std0_Nm=0", "energy.control_std0_Nm", "(0, 1e+07]"),
    ("resurs_p", None, "energy.state_var=[1.0, 1.0, 1.0]", "energy.state_var", "a list of 6"),
    ("resurs_p", "euler", "euler.accel_time_s=200.0", "euler.accel_time_s", "duration_s/2"),
    ("resurs_p", "euler", "euler.damping=0", "euler.damping", "(0, 10]"),
    ("resurs_p", None, "cmg.cone_half_angle_deg=90", "cmg.cone_half_angle_deg", "(0, 90)"),
    ("resurs_p", None, "noise.game_disturbance_Nm=-1", "noise.game_disturbance_Nm", "[0, 1000]"),
    ("gyrostat_game", None, "gyrostat.rho=[0.4, 1.2, 0.4]", "gyrostat.rho", "(0, 1)"),
    ("gyrostat_game", None, "gyrostat.rotor_J_kgm2=[200.0, 0.1, 0.08]", "gyrostat", "J_i < A_i"),
    ("gyrostat_game", None, "manoeuvre.initial_angle_deg=180", "manoeuvre.initial_angle_deg",
     "[0, 180)"),
    ("gyrostat_game", None, 'simulation.switching="chatter"', "simulation.switching",
     "'discrete', 'sign'"),
    ("gyrostat_game", None, "simulation.control_period_s=1e-4", "simulation.control_period_s",
     "the limit is"),
]  # fmt: skip


def _attitude(capsys, scenario, out: Path, *extra):
    return run(capsys, "attitude", scenario, "--out", out, "--no-progress", *extra)


@pytest.mark.parametrize(
    ("name", "controller", "override", "field", "allowed"),
    BAD_VALUES,
    ids=[f"{c[0]}:{c[2].partition('=')[0]}" for c in BAD_VALUES],
)
def test_a_bad_value_in_any_attitude_table_is_one_line_naming_the_field(
    capsys, tmp_path, name, controller, override, field, allowed
):
    out = tmp_path / "out"
    extra = ["--controller", controller] if controller else []
    code, err = _attitude(capsys, SCENARIOS / f"{name}.toml", out, "--set", override, *extra)
    assert one_line_error(code, err), err
    assert f"{name}.toml" in err
    assert f"'{field}" in err and allowed in err, err
    assert not files_under(out)


TABLES = (
    [
        ("smallsat_rw", table)
        for table in ("body", "wheels", "maneuver", "simulation", "pd", "lqr", "noise")
    ]
    + [("resurs_p", table) for table in ("energy", "euler", "cmg", "noise")]
    + [("gyrostat_game", table) for table in ("gyrostat", "manoeuvre", "simulation")]
)


@pytest.mark.parametrize(("name", "table"), TABLES)
def test_an_unknown_key_in_any_attitude_table_is_refused(capsys, tmp_path, name, table):
    path = SCENARIOS / f"{name}.toml"
    code, err = _attitude(capsys, path, tmp_path / "out", "--set", f"{table}.bogus=1")
    assert one_line_error(code, err), err
    assert f"{name}.toml" in err and f"unknown key '{table}.bogus' (allowed: " in err


@pytest.mark.parametrize("name", ["smallsat_rw", "lqr_large_angle", "resurs_p", "gyrostat_game"])
def test_an_unknown_top_level_key_in_the_file_is_refused(capsys, tmp_path, name):
    p = tmp_path / f"{name}.toml"
    p.write_text("bogus = 1\n" + (SCENARIOS / f"{name}.toml").read_text(encoding="utf-8"))
    code, err = _attitude(capsys, p, tmp_path / "out")
    assert one_line_error(code, err), err
    assert str(p) in err and "(with --set)" not in err
    assert "unknown key 'bogus' (allowed: " in err
    assert not files_under(tmp_path / "out")


@pytest.mark.parametrize(
    ("name", "table", "controller"),
    [
        ("smallsat_rw", "body", None),
        ("smallsat_rw", "simulation", None),
        ("smallsat_rw", "pd", None),
        ("smallsat_rw", "lqr", "lqr"),
        ("gyrostat_game", "gyrostat", None),
        ("gyrostat_game", "manoeuvre", None),
    ],
)
def test_a_missing_table_is_named(capsys, tmp_path, name, table, controller):
    text = (SCENARIOS / f"{name}.toml").read_text(encoding="utf-8")
    head, _, rest = text.partition(f"[{table}]")
    rest = rest[rest.index("\n[") :] if "\n[" in rest else ""
    p = tmp_path / f"{name}.toml"
    p.write_text(head + rest)
    assert table not in tomllib.loads(head + rest)
    extra = ["--controller", controller] if controller else []
    code, err = _attitude(capsys, p, tmp_path / "out", *extra)
    assert one_line_error(code, err), err
    assert str(p) in err and f"missing table '[{table}]'" in err


def test_set_overrides_reach_the_typed_attitude_tables(capsys, tmp_path):
    """``--set`` is validated like the file and gives the run of the file with those values."""
    path = SCENARIOS / "smallsat_rw.toml"
    sets = {"simulation.duration_s": ("80.0", "3.0"), "pd.k_q": ("1.375", "1.2"),
            "simulation.control_period_s": ("0.01", "0.05")}  # fmt: skip
    text = path.read_text(encoding="utf-8")
    for key, (old, new) in sets.items():
        line = f"{key.split('.')[1]} = {old}"
        assert text.count(line) == 1
        text = text.replace(line, f"{key.split('.')[1]} = {new}")
    edited = tmp_path / "smallsat_rw.toml"
    edited.write_text(text, encoding="utf-8")
    args = ("--noise", "random", "--runs", "2", "--no-progress")
    overrides = [a for key, (_, new) in sets.items() for a in ("--set", f"{key}={new}")]
    by_set = run_json(capsys, "attitude", path, "--out", tmp_path / "a", *args, *overrides)
    by_file = run_json(capsys, "attitude", edited, "--out", tmp_path / "b", *args)
    assert by_set["scenario"] == "smallsat_rw" + "".join(  # in the order of the keys
        f"+{key}={new}" for key, (_, new) in sorted(sets.items())
    )
    for key in ("scenario", "wall_s", "files", "cpu_s", "worker_peak_rss_mb", "command"):
        del by_set[key], by_file[key]
    assert by_set == by_file


def test_every_attitude_table_field_is_declared_with_a_doc():
    """One declaration per field: a type, a default or required, and a one-line doc."""
    modules = (attitude_rw_config, attitude_cmg_config, gyrostat_config)
    tables = [
        obj
        for mod in modules
        for obj in vars(mod).values()
        if inspect.isclass(obj) and issubclass(obj, BaseModel) and obj.__module__ == mod.__name__
    ]
    assert len(tables) == 17  # 14 tables and the 3 scenarios
    for table in tables:
        assert table.model_config.get("extra") == "forbid", table
        for key, info in table.model_fields.items():
            assert info.description and "\n" not in info.description, (table, key)


def test_the_reaction_wheel_loop_runs_from_typed_configuration():
    """A notebook's call: tables built in Python, no dicts; the same rows as the command's
    task on the same scenario read from TOML."""
    config = RwScenario(
        body=BodyTable(inertia_kgm2=(1.5, 1.5, 1.5)),
        maneuver=ManeuverTable(angle_deg=10.0),
        simulation=SimulationTable(duration_s=5.0, control_period_s=0.05),
        pd=PdTable(k_q=1.375, k_w=2.625),
    )
    rngs = [np.random.default_rng(1), np.random.default_rng(2)]
    metrics = simulate_runs(config, "pd", "random", rngs, "box")
    assert metrics["settle_time_s"].shape == (2,)
    assert np.all(metrics["truth_outside"] == 0)
    toml = tomllib.loads(
        "[body]\ninertia_kgm2 = [1.5, 1.5, 1.5]\n[maneuver]\nangle_deg = 10.0\n"
        "[simulation]\nduration_s = 5.0\ncontrol_period_s = 0.05\n[pd]\nk_q = 1.375\nk_w = 2.625\n"
    )
    read = attitude_rw.prepare("t.toml", toml, "pd", "random")
    assert read == config
    again = simulate_runs(read, "pd", "random", [np.random.default_rng(1)], "box")
    assert again["energy_N2m2s"][0] == metrics["energy_N2m2s"][0]
    with pytest.raises(ValidationError, match="simulation.duration_s"):
        SimulationTable(duration_s=1e5, control_period_s=1e-4)
    with pytest.raises(ValueError, match=r"missing table '\[lqr\]'"):
        simulate_runs(config, "lqr", "none", rngs[:1])
