"""Attitude loops that diverge: a counted outcome of a finished run, not a failed run
with whatever error broke first (docs/results.md, ``diverged``).

A sampled-data loop whose gains are far too high for its inertia (a body of 1e-6 kg m^2
under the large-angle LQR, a gyrostat whose rotors leave 1e-8 kg m^2 of body inertia)
is unstable: its rates grow until the fixed-step RK4 no longer resolves them and then
overflow. Before, such runs failed with ``LinAlgError`` (the UKF's Cholesky) or
``ValueError: quat must be finite`` (scipy), after numpy's overflow warnings.
"""

import json
import warnings

import numpy as np
import pytest
from harness_texts import JOB_COLUMNS
from kalman_vs_infoset.experiments import attitude_cmg as attitude_cmg_loop
from kalman_vs_infoset.experiments import attitude_gyrostat, attitude_rw
from kalman_vs_infoset.experiments.cli import main
from kalman_vs_infoset.guidance.attitude.plant import (
    MAX_TURN_PER_STEP_RAD,
    LoopDiverged,
    RigidBody,
    unresolved,
)
from kalman_vs_infoset.guidance.attitude.wheels import rk4_step
from scipy.spatial.transform import Rotation

from kalman_vs_infoset import api

TINY_BODY = {"inertia_kgm2": [1e-6, 1e-6, 1e-6]}
#: the stable loop's check needs only a few seconds of its turn
SHORT = {"duration_s": 5.0}
#: rotors leaving 1e-8 kg m^2 of the body's own inertia about each axis
THIN_GYROSTAT = {"A_kgm2": [0.12000001, 0.10000001, 0.08000001]}
#: 1e-4 kg m^2 left: some runs of the seed-0 batch diverge, the others do not
THIN_EDGE = {"A_kgm2": [0.1201, 0.1001, 0.0801]}


def test_unresolved_is_a_rate_past_one_radian_a_step_or_a_state_not_finite():
    dt = 0.1
    w = np.array([[0.0, 0.0, 9.99], [0.0, 10.01, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    x = np.zeros((4, 10))
    x[:, 3] = 1.0
    x[:, 4:7] = w
    x[2, 8] = np.nan  # a wheel momentum that is not finite
    assert unresolved(w, x, dt).tolist() == [False, True, True, False]
    big = np.array([1e308, 1e308, 1e308])  # its norm overflows: unresolved, no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert unresolved(big, np.zeros(3), dt)


def test_one_radian_a_step_is_still_resolved_to_a_thousandth_torque_free_spin():
    """The bound's reading: a torque-free spin about a principal axis turns at a constant
    rate (Euler's equations, an exact solution), and one RK4 step of |w| dt = 1 rad
    reproduces the turn to better than 1e-3 rad (the quaternion's Taylor remainder,
    2 (1/2)^5 / 5! = 5.2e-4): the bound marks the runaway of an unstable loop, not a
    stable loop's lost accuracy."""
    body = RigidBody.diagonal([2.0, 3.0, 4.0])
    dt = 0.05
    w = np.array([0.0, MAX_TURN_PER_STEP_RAD / dt, 0.0])
    x = np.concatenate([[0.0, 0.0, 0.0, 1.0], w, np.zeros(3)])
    x1 = rk4_step(body, x, np.zeros(3), dt)
    turned = Rotation.from_quat(x1[0:4]) * Rotation.from_rotvec(w * dt).inv()
    assert turned.magnitude() < 1e-3
    np.testing.assert_allclose(x1[4:7], w, rtol=1e-12)


def test_a_batch_raises_and_each_run_alone_ends_diverged():
    from kalman_vs_infoset.experiments.attitude_rw import parse_scenario
    from kalman_vs_infoset.experiments.scenario import read
    from kalman_vs_infoset.experiments.sim.attitude_rw import simulate_runs

    raw, source = read("lqr_large_angle", ["body.inertia_kgm2=[1e-6, 1e-6, 1e-6]"])
    config = parse_scenario(source, raw)
    rngs = [np.random.default_rng(s) for s in (1, 2)]
    with pytest.raises(LoopDiverged, match="diverged at t = .* runs \\[0, 1\\] of a batch of 2"):
        simulate_runs(config, "lqr", "random", rngs, "box")
    record: dict = {}
    row = simulate_runs(config, "lqr", "random", rngs[:1], "box", record)
    assert row["diverged"].tolist() == [1]
    t = row["diverged_time_s"][0]
    assert 0 < t < config.simulation.duration_s
    for key in ("settle_time_s", "energy_N2m2s", "final_angle_deg", "lyapunov_max_increase"):
        assert np.isnan(row[key][0]), key
    # the record ends at the last resolved instant, before the loop diverged
    assert np.all(np.isfinite(record["states"])) and record["time_s"][-1] < t
    assert len(record["estimate"]) == len(record["time_s"])


@pytest.mark.parametrize("estimator", ["box", "ukf", "perfect"])
def test_unstable_lqr_runs_finish_as_diverged_not_failed(estimator):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning reaches the user
        df = api.run_attitude(
            "lqr_large_angle", noise="random", estimator=estimator, runs=3, body=TINY_BODY
        )
    assert (df["status"] == "ok").all() and df["diverged"].tolist() == [1, 1, 1]
    assert np.isfinite(df["diverged_time_s"]).all()
    assert df["settle_time_s"].isna().all() and df["final_angle_deg"].isna().all()


def test_a_stable_loop_reports_no_divergence():
    df = api.run_attitude("lqr_large_angle", noise="random", estimator="box", runs=2,
                          simulation=SHORT)  # fmt: skip
    assert df["diverged"].tolist() == [0, 0]
    assert np.isinf(df["diverged_time_s"]).all() and df["final_angle_deg"].notna().all()
    assert set(df.columns) - JOB_COLUMNS == set(attitude_rw.LOOP.columns("lqr"))


def test_a_gyrostat_batch_splits_into_diverged_and_finished_runs():
    """Seed 0's first nine runs on the edge: a batch where some runs diverge is simulated
    run by run, the others finish with their values, and the summary counts both."""
    df = api.run_attitude("gyrostat_game", noise="random", estimator="box", runs=9,
                          gyrostat=THIN_EDGE)  # fmt: skip
    assert (df["status"] == "ok").all()
    gone = df["diverged"] == 1
    assert 0 < gone.sum() < len(df)
    assert df.loc[gone, "final_angle_deg"].isna().all()
    assert set(df.columns) - JOB_COLUMNS == set(attitude_gyrostat.LOOP.columns("game"))
    assert df.loc[~gone, "final_angle_deg"].notna().all()
    assert np.isinf(df.loc[~gone, "diverged_time_s"]).all()
    # a run of the batch simulated alone is the same run (its own generator)
    alone = api.run_attitude("gyrostat_game", noise="random", estimator="box", runs=1,
                             gyrostat=THIN_EDGE)  # fmt: skip
    assert alone.iloc[0].drop("wall_s").equals(df.iloc[0].drop("wall_s"))


def test_the_command_counts_diverged_runs_in_one_line_and_exits_0(tmp_path, capsys):
    argv = ["attitude", "gyrostat_game", "--noise", "random", "--estimators", "ukf",
            "--runs", "3", "--workers", "1", "--no-progress", "--out", str(tmp_path),
            "--set", f"gyrostat.A_kgm2={THIN_GYROSTAT['A_kgm2']}"]  # fmt: skip
    assert main(argv) == 0
    out, err = capsys.readouterr()
    assert "diverged: 3 runs" in out and "failed" not in err and "warning" not in err
    assert main([*argv, "--json"]) == 0  # the finished runs, read back
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["diverged"] == 3 and result["failures"] == 0
    assert result["final_angle_deg"]["mean"] is None  # no run to measure


def test_a_gyrodine_turn_that_diverges_ends_there(monkeypatch):
    """The Resurs-P turn has fixed inertia and bounded gyrodine torques: a divergence is
    forced by a plant step that overflows at the sixth step (i = 5, t = 0.6 s)."""
    from kalman_vs_infoset.experiments.attitude_cmg_setup import setup_from_scenario
    from kalman_vs_infoset.experiments.scenario import read
    from kalman_vs_infoset.experiments.sim import attitude_cmg

    real, calls = attitude_cmg.rk4_step, []

    def step(*args):
        calls.append(1)
        x = real(*args)
        return x * np.inf if len(calls) == 6 else x

    monkeypatch.setattr(attitude_cmg, "rk4_step", step)
    setup = setup_from_scenario("resurs_p", read("resurs_p")[0])
    record: dict = {}
    res = attitude_cmg.simulate_turn(setup, "energy", None, "box", "none", record)
    assert res.diverged_time_s == pytest.approx(6 * setup.dt_s)
    assert np.isfinite(res.error_rotvec_deg[:6]).all() and np.isnan(res.error_rotvec_deg[6:]).all()
    assert len(record["estimate"]) == 6
    calls.clear()
    row = attitude_cmg.one_run(setup, "energy", "none", 0, "box")
    assert row["diverged"] == 1 and row["diverged_time_s"] == pytest.approx(6 * setup.dt_s)
    assert np.isnan(row["energy_N2m2s"]) and np.isnan(row["settle_time_s"])
    assert np.isfinite(row["mean_knowledge_bound_deg"])
    # a diverged run's row has the columns every run's row has
    assert set(row) == set(attitude_cmg_loop.LOOP.columns("energy"))


def test_a_cdf_label_names_the_diverged_runs():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import pandas as pd
    from kalman_vs_infoset.experiments import plots

    rows = pd.DataFrame({"status": ["ok"] * 4, "settle_time_s": [1.0, 2.0, np.nan, np.nan],
                         "diverged": [0, 0, 1, 0]})  # fmt: skip
    fig, ax = plt.subplots()
    plots.curve(ax, "box", rows, "settle_time_s")
    (label,) = [line.get_label() for line in ax.get_lines()]
    plt.close(fig)
    assert label == "box (n=2, 1 diverged, 1 without a value)"


def test_a_ukf_that_diverges_while_the_loop_does_not_says_so():
    """A stiff but bounded gyrostat (1e-4 kg m^2 of body inertia left): the truth stays
    resolved, the UKF's covariance does not. A failed run, the estimator's, and its
    error says which (numpy's own words named neither the filter nor the cause)."""
    df = api.run_attitude("gyrostat_game", noise="random", estimator="ukf", runs=1,
                          gyrostat=THIN_EDGE)  # fmt: skip
    (error,) = df["error"]
    assert df["status"].tolist() == ["failed"]
    assert error == "LinAlgError: the UKF diverged: its covariance is no longer positive definite"


def test_a_diverged_gyrostat_run_ends_at_its_last_resolved_state_without_a_warning():
    """Its closing values were taken from the state that overflowed (numpy's overflow
    warning reached the user; found by a sweep of tiny inertias x estimators x noises)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        df = api.run_attitude("gyrostat_game", noise="none", estimator="ukf", runs=1,
                              gyrostat={"A_kgm2": [0.12000012, 0.1000001, 0.08000008]})  # fmt: skip
    assert df["status"].tolist() == ["ok"] and df["diverged"].tolist() == [1]


@pytest.mark.parametrize(
    ("command", "scenario", "key"),
    [("attitude", "smallsat_rw", "body.inertia_kgm2"),
     ("attitude", "gyrostat_game", "gyrostat.rotor_J_kgm2"),
     ("attitude", "gyrostat_game", "gyrostat.A_kgm2"),
     ("intercept", "kp_fig3_attitude", "attitude.inertia_kgm2")],
)  # fmt: skip
def test_an_inertia_past_1e12_is_refused_in_one_line(command, scenario, key, tmp_path, capsys):
    """1e300 kg m^2 was admitted: the UKF's disturbance variance (J times its floor,
    squared) overflowed, numpy warned and an eigenvalue solve failed the runs. Inertias
    are bounded by ``MAX_INERTIA_KGM2`` (1e12; the ISS is about 1e8)."""
    from kalman_vs_infoset.experiments.sim.fields import MAX_INERTIA_KGM2

    value = [MAX_INERTIA_KGM2 * 10, 2.0, 3.0]
    argv = [command, scenario, "--runs", "1", "--out", str(tmp_path), "--set", f"{key}={value}"]
    assert main(argv) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert f"field '{key}' must be a number in (0, 1e+12]" in line
