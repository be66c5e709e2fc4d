"""An attitude estimator's own options in a scenario, ``[estimator_options.<name>]``
(``--set estimator_options.<name>.<field>=...``), validated by the options model its
registration declares and built into the estimator of every attitude loop: the
reaction-wheel loop, the gyrodine turn, the gyrostat game and the pointing loop of an
intercept scenario (``[attitude.estimator_options.<name>]``)."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest
from kalman_vs_infoset.estim.attitude.model import AttitudeModel
from kalman_vs_infoset.experiments import attitude_cmg_setup, attitude_gyrostat, attitude_rw
from kalman_vs_infoset.experiments.cli import main
from kalman_vs_infoset.experiments.scenario import parse_scenario
from kalman_vs_infoset.experiments.sim.estimator_loop import EstimatorLoop
from kalman_vs_infoset.experiments.sim.gyrostat_config import GyrostatSetup
from kalman_vs_infoset.experiments.sim.pointing import PointingLoop
from kalman_vs_infoset.experiments.sim.turn_setup import TurnSetup
from scipy.stats import chi2

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "data" / "scenarios"
GATE = {"ukf": {"gate_prob": 0.5}}


def _toml(name: str) -> dict:
    return tomllib.loads((SCENARIOS / f"{name}.toml").read_text())


def _gate(loop: EstimatorLoop) -> float:
    """The gate probability the loop's UKF was built with."""
    return float(loop.estimator.gate_prob)


def test_the_loop_builds_its_estimator_with_its_own_table_and_defaults_elsewhere():
    model = AttitudeModel(np.array([1.0, 2.0, 3.0]), 0.0, 1e-4, 1e-5)
    assert _gate(EstimatorLoop("ukf", model, GATE)) == 0.5
    assert _gate(EstimatorLoop("ukf", model)) == 0.997  # the model's default
    box = EstimatorLoop("box", model, {**GATE, "box": {"abs_inflation_rad": 1e-9}})
    assert box.estimator.abs_inflation_rad == 1e-9


def test_every_attitude_scenario_carries_its_tables_to_the_loop():
    """The typed tables reach what each loop builds its estimator from."""
    rw = attitude_rw.parse_scenario("s", {**_toml("smallsat_rw"), "estimator_options": GATE})
    assert rw.estimator_options == GATE
    cmg = attitude_cmg_setup.parse_scenario("s", {**_toml("resurs_p"), "estimator_options": GATE})
    assert TurnSetup.from_config(cmg).estimator_options == GATE
    gyro = {**_toml("gyrostat_game"), "estimator_options": GATE}
    setup = GyrostatSetup.from_config(attitude_gyrostat.parse_scenario("s", gyro), "random", "s")
    assert setup.cfg.estimator_options == GATE
    data = _toml("kp_fig3_attitude")
    data["attitude"] = {**data["attitude"], "estimator": "ukf", "estimator_options": GATE}
    loop = PointingLoop.from_config(parse_scenario(data).attitude, np.random.default_rng(0))
    assert _gate(loop.loop) == 0.5


def test_a_gate_option_changes_what_the_rw_loop_counts_outside(tmp_path, capsys):
    """``--set estimator_options.ukf.gate_prob`` reaches the runs: a gate at probability
    0.5 (radius sqrt(chi2.ppf(0.5, 6)) = 2.35 against 4.24) leaves the truth outside
    at steps where the default gate holds it (smallsat_rw, random noise: 0 against 42
    steps over the first 3 s)."""
    assert np.sqrt(chi2.ppf(0.5, 6)) < 0.6 * np.sqrt(chi2.ppf(0.997, 6))
    outside = []
    for extra in ([], ["--set", "estimator_options.ukf.gate_prob=0.5"]):
        argv = ["attitude", "smallsat_rw", "--noise", "random", "--runs", "1"]
        argv += ["--estimators", "ukf", "--set", "simulation.duration_s=3", "--json"]
        argv += ["--no-progress", "--out", str(tmp_path / str(len(extra))), *extra]
        assert main(argv) == 0
        outside.append(json.loads(capsys.readouterr().out.strip().splitlines()[-1]))
    assert outside[0]["truth_outside"] < outside[1]["truth_outside"]


#: a bad table and the line that names it
BAD = {
    "estimator_options.ukf.gate=0.5": "unknown key 'estimator_options.ukf.gate' "
    "(allowed: gate_prob)",
    "estimator_options.ukk.gate_prob=0.5": "table 'estimator_options.ukk': unknown attitude "
    "estimator 'ukk'",
    "estimator_options.ukf.gate_prob=2": "field 'estimator_options.ukf.gate_prob' must be a "
    "number in (0, 1) (got 2)",
    "estimator_options.ukf=3": "field 'estimator_options.ukf' must be a table (got 3)",
}


@pytest.mark.parametrize(("setting", "message"), BAD.items())
def test_a_bad_options_table_is_one_line_and_exit_2(setting, message, tmp_path, capsys):
    argv = ["attitude", "smallsat_rw", "--estimators", "ukf", "--set", setting]
    assert main([*argv, "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err, err
    assert not (tmp_path / "o").exists()


def test_a_bad_table_of_the_pointing_loop_names_its_place():
    data = _toml("kp_fig3_attitude")
    data["attitude"] = {
        **data["attitude"],
        "estimator_options": {"box": {"abs_inflation_rad": -1.0}},
    }
    with pytest.raises(Exception, match=r"attitude\.estimator_options\.box\.abs_inflation_rad"):
        parse_scenario(data)


def test_an_intercept_style_estimator_table_points_at_estimator_options(tmp_path, capsys):
    """``--set estimator.box.x=1`` (the intercept's form) read "field 'estimator' must be
    a string"; the line now names the table the options go in."""
    assert main(["attitude", "smallsat_rw", "--set", "estimator.box.abs_inflation_rad=1e-9",
                 "--out", str(tmp_path / "o")]) == 2  # fmt: skip
    err = capsys.readouterr().err
    assert "its options are the table [estimator_options.<name>]" in err
    data = _toml("kp_fig3_attitude")
    data["attitude"] = {**data["attitude"], "estimator": {"box": {}}}
    with pytest.raises(Exception, match=r"\[attitude\.estimator_options\.<name>\]"):
        parse_scenario(data)


def test_set_reaches_a_pointing_loop_option_field_by_field(tmp_path, capsys):
    """``--set attitude.estimator_options.box.abs_inflation_rad=...`` (four parts) was
    refused as not ``TABLE.KEY=VALUE``."""
    from kalman_vs_infoset.experiments.scenario import load_scenario

    key = "attitude.estimator_options.box.abs_inflation_rad"
    sc = load_scenario("kp_fig3_attitude", [f"{key}=1e-9"])
    assert sc.attitude.estimator_options == {"box": {"abs_inflation_rad": 1e-9}}
    assert main(["intercept", "kp_fig3_attitude", "--runs", "1", "--set",
                 f"{key[:-4]}=1e-9", "--out", str(tmp_path / "o")]) == 2  # fmt: skip
    err = capsys.readouterr().err  # named once, not as "field 'attitude' must be a table"
    assert "(with --set): unknown key 'attitude.estimator_options.box.abs_inflation'" in err, err
