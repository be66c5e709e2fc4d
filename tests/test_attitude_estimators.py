"""Attitude estimators (docs/models.md §2.5): the box's guarantee, the UKF against filterpy, the
loops.

Independent references: scipy's ``Rotation`` for the quaternion maps, scipy's DOP853
(:func:`kalman_vs_infoset.guidance.attitude.plant.propagate`) for the truth, filterpy's
``UnscentedKalmanFilter`` for the batched UKF, the chi-square law for its NEES.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from docs_numbers import ROOT
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.attitude.box.estimator import BoxAttitudeEstimator
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
    draw_measurement,
)
from kalman_vs_infoset.estim.attitude.ukf.estimator import (
    UkfAttitudeBelief,
    UkfAttitudeEstimator,
    residual_x,
    state_add,
)
from kalman_vs_infoset.estim.base import Status
from kalman_vs_infoset.guidance.attitude.plant import AttitudeState, RigidBody, propagate
from scipy.spatial.transform import Rotation

from kalman_vs_infoset.numerics.rotations import cross, qexp, qlog, qmatrix, qmul


def test_quaternion_maps_equal_scipy():
    rng = np.random.default_rng(0)
    for scale in (1e-9, 1e-4, 1e-2, 1.0, 3.0):
        v = rng.normal(size=(200, 3)) * scale
        v = v[np.linalg.norm(v, axis=1) < np.pi - 1e-6]
        np.testing.assert_allclose(qexp(v), Rotation.from_rotvec(v).as_quat(), atol=1e-15)
        np.testing.assert_allclose(qlog(qexp(v)), v, atol=1e-13)
        np.testing.assert_allclose(
            qmatrix(qexp(v)), Rotation.from_rotvec(v).as_matrix(), atol=1e-14
        )
    p, q = Rotation.random(50, rng=1), Rotation.random(50, rng=2)
    np.testing.assert_allclose(
        np.abs(np.sum(qmul(p.as_quat(), q.as_quat()) * (p * q).as_quat(), axis=1)), 1.0, atol=1e-12
    )


@pytest.mark.parametrize(
    ("shape_a", "shape_b"),
    [((3,), (3,)), ((1, 3), (1, 3)), ((3,), (1, 3)), ((1, 1, 3), (3,)), ((4, 3), (3,)),
     ((3,), (2, 5, 3))],
)  # fmt: skip
def test_cross_equals_numpy_for_one_vector_and_for_batches(shape_a, shape_b):
    """``cross`` (a Python-float path for one vector each, arrays for batches) gives
    ``np.cross``'s shape and, where numpy's products are the same, its values."""
    rng = np.random.default_rng(3)
    for scale in (1e-9, 1.0, 1e7):
        a, b = rng.normal(size=shape_a) * scale, rng.normal(size=shape_b)
        got = cross(a, b)
        assert got.shape == np.cross(a, b).shape and got.dtype == np.float64
        np.testing.assert_allclose(got, np.cross(a, b), rtol=1e-12, atol=1e-300)
        a2, b2 = np.broadcast_arrays(a, b)  # the batch path on the same numbers: identical
        batch = cross(np.stack([a2, a2]), np.stack([b2, b2]))
        assert np.array_equal(got, batch[0])


def _measure_at(x: np.ndarray, model: AttitudeModel, signs: np.ndarray) -> AttitudeMeasurement:
    """Measurement with errors ``signs * bounds`` (signs in [-1, 1]: 1 = at the bound)."""
    n = signs[0:3] * model.meas_angle_bound_rad
    q = (Rotation.from_quat(x[0:4]) * Rotation.from_rotvec(n)).as_quat()
    return AttitudeMeasurement(q, x[4:7] + signs[3:6] * model.meas_rate_bound_radps)


@settings(
    max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(
    seed=st.integers(0, 2**31 - 1),
    rate_scale=st.sampled_from([0.0, 0.02, 0.2]),
    at_bounds=st.booleans(),
    dt_s=st.sampled_from([0.01, 0.1, 0.5]),
)
def test_box_never_loses_the_truth(seed, rate_scale, at_bounds, dt_s):
    """Truth by DOP853 with disturbances at the bound (bang-bang, random switches), errors
    at the bounds (or uniform inside), asymmetric non-diagonal inertia, actuator momentum:
    the truth is in the box at every step and no intersection is empty."""
    rng = np.random.default_rng(seed)
    w_rot = Rotation.random(rng=rng).as_matrix()
    inertia = w_rot @ np.diag(rng.uniform(1.0, 30.0, 3)) @ w_rot.T
    body = RigidBody(inertia)
    model = AttitudeModel(
        inertia, rng.uniform(0.0, 0.05, 3), rng.uniform(1e-5, 1e-3, 3), rng.uniform(1e-6, 1e-4, 3)
    )
    est = BoxAttitudeEstimator(model)
    state = AttitudeState(
        Rotation.random(rng=rng).as_quat(), rng.uniform(-1, 1, 3) * rate_scale, rng.normal(size=3)
    )

    def signs() -> np.ndarray:
        return rng.choice([-1.0, 1.0], 6) if at_bounds else rng.uniform(-1, 1, 6)

    belief = est.initial(AttitudePrior(_measure_at(state.as_vector(), model, signs())))
    assert belief.contains(state.as_vector()[None, 0:7])
    for _ in range(25):
        torque = rng.uniform(-0.5, 0.5, 3)
        d = rng.choice([-1.0, 1.0], 3) * model.disturbance_bound_Nm
        known = AttitudeControl.held(torque, state.h_Nms, dt_s)
        state = propagate(body, state, torque, dt_s, d)
        belief = est.update(
            est.predict(belief, dt_s, known), _measure_at(state.as_vector(), model, signs())
        )
        assert belief.status == Status.OK  # admissible data: no contradiction
        assert belief.contains(state.as_vector()[None, 0:7])
        angle = (Rotation.from_quat(belief.centre()[0, 0:4]).inv() * state.rotation).magnitude()
        assert angle <= belief.attitude_bound_rad()[0] + 1e-12
    assert int(belief.n_empty[0]) == 0


def _rw_loop(est, model, runs=10, steps=300, dt=0.05, d_const=True, seed=3):
    """A small batched loop (truth by RK4 of the same plant); returns per-step inside flags."""
    from kalman_vs_infoset.guidance.attitude.wheels import rk4_step

    rng = np.random.default_rng(seed)
    body = RigidBody(model.inertia_kgm2)
    x = np.zeros((runs, 10))
    x[:, 0:4] = Rotation.random(runs, rng=rng).as_quat()
    x[:, 4:7] = rng.uniform(-0.05, 0.05, (runs, 3))
    d = rng.uniform(-1, 1, (runs, 3)) * model.disturbance_bound_Nm if d_const else 0.0
    belief = est.initial(AttitudePrior(draw_measurement(x, model, rng)))
    flags, beliefs, nees = [], [], []
    for k in range(steps):
        u = 0.02 * np.sin(0.05 * k + np.arange(3)) * np.ones((runs, 3))
        known = AttitudeControl.held(u, x[:, 7:10], dt)
        x = rk4_step(body, x, u, dt, d)
        belief = est.update(est.predict(belief, dt, known), draw_measurement(x, model, rng))
        flags.append(belief.inside(x[:, 0:7]))
        beliefs.append(belief)
        if hasattr(belief, "mahalanobis"):
            nees.append(belief.mahalanobis(x[:, 0:7]) ** 2)
    return np.array(flags), beliefs, np.array(nees)


MODEL = AttitudeModel(np.diag([1.0, 1.5, 2.0]), 1e-4, np.radians(0.01), np.radians(0.001))


def test_box_is_tighter_than_one_measurement_and_immutable():
    est = BoxAttitudeEstimator(MODEL)
    flags, beliefs, _ = _rw_loop(est, MODEL, runs=5, steps=200)
    assert flags.all()
    last = beliefs[-1]
    assert np.all(last.e_r < MODEL.meas_angle_bound_rad)  # data fused over time
    assert np.all(last.w_r <= MODEL.meas_rate_bound_radps + 1e-15)
    before = beliefs[-2].e_r.copy()
    est.predict(beliefs[-2], 0.05)
    np.testing.assert_array_equal(beliefs[-2].e_r, before)
    with pytest.raises(ValueError):
        beliefs[-2].e_r[0, 0] = 1.0


def test_box_inadmissible_measurement_is_a_reported_empty_status():
    est = BoxAttitudeEstimator(MODEL)
    x = np.array([[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]])
    belief = est.initial(AttitudePrior(AttitudeMeasurement(x[:, 0:4], x[:, 4:7])))
    far = Rotation.from_rotvec([20 * MODEL.meas_angle_bound_rad[0], 0, 0]).as_quat()
    new = est.update(
        est.predict(belief, 0.01, AttitudeControl.zero(1)), AttitudeMeasurement(far, x[:, 4:7])
    )
    # reported, and restarted from the data: a set that holds states (finite centre)
    assert new.status == Status.CONTRADICTION and int(new.n_empty[0]) == 1
    assert not new.is_empty and np.all(np.isfinite(new.centre()))
    assert new.contains(np.concatenate([far, x[0, 4:7]])[None])
    ok = est.update(
        est.predict(new, 0.01, AttitudeControl.zero(1)),
        AttitudeMeasurement(far, x[:, 4:7]),
    )
    assert ok.status == Status.OK and int(ok.n_empty[0]) == 1


def _random_ukf_belief(rng, runs=1):
    """A belief and the known inputs of its next step."""
    a = rng.normal(size=(9, 9))
    cov = a @ a.T * 1e-8 + np.eye(9) * 1e-10
    mean = np.concatenate([np.zeros(3), rng.normal(size=3) * 0.05, rng.normal(size=3) * 1e-4])
    ctrl = AttitudeControl.held(rng.normal(size=(runs, 3)) * 0.01, rng.normal(size=(runs, 3)), 0.1)
    belief = UkfAttitudeBelief(
        Rotation.random(runs, rng=rng).as_quat(),
        np.tile(mean, (runs, 1)),
        np.broadcast_to(cov, (runs, 9, 9)),
    )
    return belief, ctrl


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_batched_ukf_equals_filterpy(seed):
    rng = np.random.default_rng(seed)
    inertia = np.diag(rng.uniform(1, 5, 3))
    model = AttitudeModel(inertia, 1e-3, 1e-4, 1e-5)
    est = UkfAttitudeEstimator(model)
    belief, ctrl = _random_ukf_belief(rng)
    a, b = est.predict(belief, 0.1, ctrl), est.predict_filterpy(belief, 0.1, ctrl)
    np.testing.assert_allclose(a.q_ref, b.q_ref, atol=1e-14)
    np.testing.assert_allclose(a.mean, b.mean, atol=1e-14)
    np.testing.assert_allclose(a.cov, b.cov, rtol=1e-9, atol=1e-20)
    q_true = qmul(a.q_ref, qexp(rng.normal(size=(1, 3)) * 1e-4))
    meas = AttitudeMeasurement(q_true, a.mean[:, 3:6] + 1e-5)
    ua, ub = est.update(a, meas), est.update_filterpy(a, meas)
    np.testing.assert_allclose(ua.q_ref, ub.q_ref, atol=1e-14)
    np.testing.assert_allclose(ua.mean, ub.mean, atol=1e-14)
    np.testing.assert_allclose(ua.cov, ub.cov, rtol=1e-9, atol=1e-20)
    assert not np.allclose(ua.cov, a.cov)  # the update did something


@settings(max_examples=30, deadline=None, derandomize=True)
@given(
    a=st.lists(st.floats(-1.0, 1.0), min_size=9, max_size=9),
    b=st.lists(st.floats(-1.0, 1.0), min_size=9, max_size=9),
)
def test_ukf_manifold_hooks_are_inverse(a, b):
    """state_add(b, residual_x(a, b)) = a: the error state lives on SO(3) x R^6."""
    a, b = np.array(a), np.array(b)
    back = state_add(b, residual_x(a, b))
    ra, rb = Rotation.from_rotvec(a[0:3]), Rotation.from_rotvec(back[0:3])
    assert (ra.inv() * rb).magnitude() < 1e-9
    np.testing.assert_allclose(back[3:], a[3:], atol=1e-12)


def test_ukf_is_consistent_without_unmodelled_effects():
    """No disturbance: the mean NEES of (a, w) is near its chi-square(6) mean, 6."""
    model = AttitudeModel(np.diag([1.0, 1.5, 2.0]), 0.0, np.radians(0.01), np.radians(0.001))
    est = UkfAttitudeEstimator(model)
    flags, _, nees = _rw_loop(est, model, runs=10, steps=150, d_const=False, seed=5)
    mean_nees = nees[20:].mean()
    # 1300 (run, step) samples, correlated in time: a wide but failing band
    assert 6.0 / 2 < mean_nees < 6.0 * 1.5
    assert flags[20:].mean() > 0.97  # 99.7 % gate


def test_attitude_command_estimators_paired_and_counted(tmp_path):
    """Short smallsat runs through the CLI: three estimators on the same realisations,
    Parquet + CDF figures written, the box never loses the truth, and the others paired
    with it run by run."""
    from kalman_vs_infoset.experiments.cli import main

    scen = tmp_path / "short.toml"
    text = (
        open(ROOT / "data/scenarios/smallsat_rw.toml")
        .read()
        .replace("duration_s = 80.0", "duration_s = 1.0")
    )
    scen.write_text(text)
    out = tmp_path / "out"
    args = ["attitude", str(scen), "--noise", "random", "--runs", "3", "--seed", "4",
            "--estimators", "perfect,ukf,box", "--out", str(out), "--json"]  # fmt: skip
    res = _run_cli(main, args)
    assert res["failures"] == 0 and res["estimator"] == "perfect"
    rows = {r["estimator"]: r for r in res["rows"]}
    assert set(rows) == {"perfect", "ukf", "box"}
    assert rows["box"]["truth_outside"] == 0 and rows["box"]["empty_steps"] == 0
    assert rows["perfect"]["truth_outside"] == 3 * 100  # a noisy point never contains the truth
    for f in res["files"]:
        assert (tmp_path / f).exists() or __import__("pathlib").Path(f).exists()
    import pandas as pd

    tables = [p for p in res["files"] if p.endswith(".parquet")]
    df = pd.concat([pd.read_parquet(p) for p in tables])  # one per estimator, seed-named
    assert len(tables) == 3 and all(p.endswith("-s4.parquet") for p in tables)
    assert len(df) == 9 and set(df["estimator"]) == {"perfect", "ukf", "box"}
    # paired run by run against the box (the attitude registry's reference), from the tables
    from kalman_vs_infoset.experiments.paired import paired_rows

    assert res["paired"]["reference"] == "box"
    assert res["paired"]["metrics"] == ["settle_time_s", "energy_N2m2s", "final_angle_deg"]
    assert res["paired"]["rows"] == paired_rows(df, "box", res["paired"]["metrics"])
    assert [(r["estimator"], r["noise"]) for r in res["paired"]["rows"]] == [
        ("perfect", "random"), ("ukf", "random"),
    ]  # fmt: skip
    again = _run_cli(main, args)
    assert again["rows"][2]["energy_N2m2s"] == rows["box"]["energy_N2m2s"]


def _run_cli(main, args):
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = main(args)
    assert code in (0, None)
    return json.loads(buf.getvalue().strip().splitlines()[-1])


def test_ukf_runs_the_gyrostat_turn_with_error_free_measurements(tmp_path):
    """Noise "none" gives the gyrostat loop's estimators measurement bounds of 1e-12:
    ``R ~ 1e-24`` left the updated covariance indefinite to rounding and every run
    failed (``LinAlgError: Matrix is not positive definite``); the filter floors its
    bounds at ``MEAS_FLOOR`` (1e-8), so the turn runs and settles."""
    from kalman_vs_infoset.experiments.cli import main

    args = ["attitude", "gyrostat_game", "--noise", "none", "--runs", "1",
            "--estimators", "ukf", "--set", "manoeuvre.initial_angle_deg=5",
            "--set", "simulation.control_period_s=0.2",
            "--workers", "1", "--no-progress", "--out", str(tmp_path), "--json"]  # fmt: skip
    res = _run_cli(main, args)
    assert res["failures"] == 0 and res["estimator"] == "ukf"
    assert np.isfinite(res["settle_time_s"]["mean"])
