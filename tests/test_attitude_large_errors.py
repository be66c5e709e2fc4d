"""Attitude boxes beyond the BCH enclosure's radius (|a| + |b| <= 1/2 rad): the
measurement and the re-centring fall back, per run, to the ball bound
``|log(exp(a) exp(b))| <= min(|a| + |b|, pi)``, so a large measurement error bound gives
a large box instead of an error; predictions whose set is the whole space are reported
per run as ``unbounded_steps``."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.attitude.box.estimator import (
    BCH_MAX,
    BoxAttitudeEstimator,
    bch,
    bch_or_ball,
)
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
)
from kalman_vs_infoset.experiments.sim.estimator_loop import EstimatorLoop
from kalman_vs_infoset.guidance.attitude.plant import AttitudeState, RigidBody, propagate
from scipy.spatial.transform import Rotation

from kalman_vs_infoset.numerics.rotations import qexp, qlog, qmul


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    size_rad=st.sampled_from([0.05, 0.2, 0.6, 1.5, 3.0]),
    runs=st.integers(1, 6),
)
def test_the_enclosure_holds_log_of_the_product_at_any_size(seed, size_rad, runs):
    """Brute force: points of both boxes (corners and random), the rotation vector of
    the product (scipy's ``Rotation``, independent of the package's maps) lies in the
    returned box; runs within the BCH radius get exactly ``bch``'s box."""
    rng = np.random.default_rng(seed)
    ca, cb = rng.uniform(-1, 1, (runs, 3)) * size_rad, rng.uniform(-1, 1, (runs, 3)) * size_rad
    ra, rb = rng.uniform(0, 0.5, (runs, 3)) * size_rad, rng.uniform(0, 0.5, (runs, 3)) * size_rad
    c, r = bch_or_ball(ca, ra, cb, rb)
    signs = rng.uniform(-1, 1, (64, 2, 3))
    signs[:8, :, :] = np.sign(signs[:8, :, :])  # corners among them
    for i in range(runs):
        a = ca[i] + signs[:, 0] * ra[i]
        b = cb[i] + signs[:, 1] * rb[i]
        e = (Rotation.from_rotvec(a) * Rotation.from_rotvec(b)).as_rotvec()
        assert np.all(np.abs(e - c[i]) <= r[i] + 1e-12 * (1 + np.abs(e)))
        na = np.linalg.norm(np.abs(ca[i]) + ra[i])
        nb = np.linalg.norm(np.abs(cb[i]) + rb[i])
        if na + nb <= BCH_MAX:  # the strict enclosure, to the last bit
            c1, r1 = bch(ca[i : i + 1], ra[i : i + 1], cb[i : i + 1], rb[i : i + 1])
            assert np.array_equal(c1[0], c[i]) and np.array_equal(r1[0], r[i])


def _measure(x, model, rng):
    n = rng.uniform(-1, 1, 3) * model.meas_angle_bound_rad
    q = (Rotation.from_quat(x[0:4]) * Rotation.from_rotvec(n)).as_quat()
    w = x[4:7] + rng.uniform(-1, 1, 3) * model.meas_rate_bound_radps
    return AttitudeMeasurement(q, w)


def test_a_measurement_bound_beyond_the_bch_radius_keeps_the_truth():
    """17 deg a axis (the bound of ``noise.meas_angle_deg = 10``, uniform errors): the
    initial box and every update used to raise ``FloatingPointError``; now the truth
    is in the box at every step, and whole-space predictions are counted."""
    rng = np.random.default_rng(7)
    inertia = np.diag([2.0, 3.0, 4.0])
    model = AttitudeModel(inertia, 1e-3, np.radians(17.3), np.radians(17.3))
    est = BoxAttitudeEstimator(model)
    body = RigidBody(inertia)
    state = AttitudeState(Rotation.random(rng=rng).as_quat(), rng.uniform(-0.05, 0.05, 3),
                          np.zeros(3))  # fmt: skip
    belief = est.initial(AttitudePrior(_measure(state.as_vector(), model, rng)))
    assert belief.contains(state.as_vector()[None, 0:7])
    dt = 0.1
    for _ in range(30):
        state = propagate(body, state, np.zeros(3), dt, rng.uniform(-1e-3, 1e-3, 3))
        belief = est.predict(belief, dt, AttitudeControl.held(np.zeros(3), state.h_Nms, dt))
        belief = est.update(belief, _measure(state.as_vector(), model, rng))
        assert belief.contains(state.as_vector()[None, 0:7])
    assert np.all(np.isfinite(belief.e_r))  # the update restarts from the measurement
    # boxes this large are beyond the prediction's enclosure: every step's prediction
    # was the whole space, and it is counted (not hidden in "truth inside")
    assert belief.n_unbounded.tolist() == [30]
    assert EstimatorLoop.unbounded_steps(belief).tolist() == [30]


def test_whole_space_predictions_are_counted_per_run():
    """A step far too long for the rates: the prediction is the whole space (the truth
    inside, trivially), counted in ``n_unbounded`` for every run of the batch."""
    model = AttitudeModel(np.diag([1.0, 2.0, 3.0]), 0.0, 1e-3, 1e-3)
    est = BoxAttitudeEstimator(model)
    q = np.tile(qexp(np.array([0.1, 0.0, 0.0])), (2, 1))
    meas = AttitudeMeasurement(q, np.tile([5.0, -4.0, 3.0], (2, 1)))
    belief = est.initial(AttitudePrior(meas))
    assert belief.n_unbounded.tolist() == [0, 0]
    out = est.predict(belief, 50.0, AttitudeControl.zero(2))
    assert out.n_unbounded.tolist() == [1, 1]
    assert EstimatorLoop.unbounded_steps(out).tolist() == [1, 1]
    assert not np.any(np.isfinite(out.e_r))
    assert np.allclose(qlog(qmul(q, qexp(np.zeros((2, 3))))), qlog(q))


def test_attitude_command_at_the_largest_measurement_error_reports_not_fails(tmp_path, capsys):
    """``noise.meas_angle_deg = 10`` is inside its declared range: the set estimators'
    runs used to fail (``FloatingPointError`` from the BCH enclosure); now they run,
    the truth is never outside, and the whole-space steps are in the summary."""
    import json

    from harness_texts import run_cli as run

    r = run(capsys, "attitude", "smallsat_rw", "--estimators", "box", "--noise", "random",
            "--runs", 1, "--seed", 31337, "--workers", 1, "--no-progress", "--json",
            "--set", "noise.meas_angle_deg=10", "--set", "simulation.control_period_s=0.5",
            "--set", "simulation.duration_s=20", "--out", tmp_path)  # fmt: skip
    assert r.returncode == 0, r.stderr
    row = json.loads(r.stdout.strip().splitlines()[-1])
    assert row["failures"] == 0 and row["truth_outside"] == 0
    assert row["unbounded_steps"] > 0


def _batch_with_a_runaway(runs: int = 3, runaway: int = 1):
    """Measurements of ``runs`` runs at rest but for run ``runaway``, which spins at
    50 rad/s: a 1-s step cannot be enclosed for it (six halvings fail)."""
    rng = np.random.default_rng(5)
    q = Rotation.random(runs, rng=rng).as_quat()
    w = rng.uniform(-0.01, 0.01, (runs, 3))
    w[runaway] = [50.0, -40.0, 30.0]
    return AttitudeMeasurement(q, w)


@pytest.mark.parametrize("family", ["box", "zonotope", "ellipsoid"])
def test_a_run_that_cannot_be_enclosed_leaves_the_others_as_if_alone(family):
    """Batched runs are independent: the runaway run's prediction is the whole space
    (counted for it alone) and every other run's set is, to the last bit, what it is
    when predicted on its own; the next update restarts the runaway from its
    measurement."""
    from kalman_vs_infoset.estim.attitude.sets.ellipsoid import EllipsoidAttitudeEstimator
    from kalman_vs_infoset.estim.attitude.sets.zonotope import ZonotopeAttitudeEstimator

    model = AttitudeModel(np.diag([1.0, 2.0, 3.0]), 1e-3, 1e-3, 1e-3)
    est = {"box": BoxAttitudeEstimator, "zonotope": ZonotopeAttitudeEstimator,
           "ellipsoid": EllipsoidAttitudeEstimator}[family](model)  # fmt: skip
    meas = _batch_with_a_runaway()
    batch = est.predict(est.initial(AttitudePrior(meas)), 1.0, AttitudeControl.zero(3))
    assert batch.n_unbounded.tolist() == [0, 1, 0]
    for i in (0, 2):
        one = AttitudeMeasurement(meas.quat[i : i + 1], meas.rate_radps[i : i + 1])
        alone = est.predict(est.initial(AttitudePrior(one)), 1.0, AttitudeControl.zero(1))
        assert np.array_equal(batch.centre()[i], alone.centre()[0])
        assert np.array_equal(batch.attitude_bound_rad()[i], alone.attitude_bound_rad()[0])
    assert batch.inside(np.concatenate([meas.quat, meas.rate_radps], -1))[1]  # whole space
    after = est.update(batch, meas)
    assert np.all(np.isfinite(after.attitude_bound_rad()))
