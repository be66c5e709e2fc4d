"""LQR with the analytic Riccati solution (seed 002, docs/models.md §2.3), checked against scipy."""

import numpy as np
import pytest
from docs_numbers import ROOT
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim import PerfectEstimator, PointBelief
from kalman_vs_infoset.guidance.attitude.lqr import (
    LQRController,
    analytic_riccati,
    complete_weights,
    constraint_residual,
    linear_model,
    rate_gains,
    riccati_full,
)
from kalman_vs_infoset.guidance.attitude.pd import error_quaternion
from kalman_vs_infoset.guidance.attitude.plant import RigidBody, attitude_rhs
from scipy.integrate import solve_ivp
from scipy.linalg import solve_continuous_are
from scipy.spatial.transform import Rotation

pos = st.floats(0.01, 100.0)
vec3 = st.tuples(pos, pos, pos)
vec6 = st.tuples(pos, pos, pos, pos, pos, pos)


@settings(max_examples=60, deadline=None)
@given(j=vec3, q=vec6, r=vec3)
def test_analytic_riccati_equals_scipy_solve_continuous_are(j, q, r):
    a, b = linear_model(np.diag(j))
    ref = solve_continuous_are(a, b, np.diag(q), np.diag(r))
    got = analytic_riccati(j, q, r)
    assert got.shape == (6, 6)
    np.testing.assert_allclose(got, ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(ref)))


@settings(max_examples=20, deadline=None)
@given(j=vec3, q=vec6, r=vec3, seed=st.integers(0, 2**31))
def test_non_diagonal_inertia_P_and_law_equal_scipy(j, q, r, seed):
    """J = W J_diag W^T, Q and R diagonal in the basis W (seed, last slides)."""
    w = Rotation.random(rng=seed).as_matrix()
    jm = w @ np.diag(j) @ w.T
    t = np.kron(np.eye(2), w)
    a, b = linear_model(jm)
    rm = w @ np.diag(r) @ w.T
    ref = solve_continuous_are(a, b, t @ np.diag(q) @ t.T, rm)
    p = riccati_full(j, w, q, r)
    np.testing.assert_allclose(p, ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(ref)))
    law = LQRController(jm, q, r, enforce_constraint=False, axes=w)
    rng = np.random.default_rng(seed)
    x = np.concatenate([Rotation.random(rng=rng).as_quat(), rng.normal(size=3), np.zeros(3)])
    lam = error_quaternion(x[0:4], law.q_target, shortest=False)[:3]
    u_ref = -np.linalg.solve(rm, b.T @ ref) @ np.concatenate([x[4:7], lam])
    np.testing.assert_allclose(law.torque(x), u_ref, rtol=1e-7, atol=1e-9 * np.max(np.abs(u_ref)))


def test_gain_formulas_of_the_seed():
    """u = -diag(sqrt(y J + q/r)) w - diag(y) lam, y = sqrt(q_{i+3}/r_i)."""
    j, q, r = np.array([2.0, 3.0, 5.0]), np.array([1.0, 2, 3, 4, 5, 6]), np.array([0.5, 1, 2])
    a, b = linear_model(np.diag(j))
    k = np.linalg.solve(np.diag(r), b.T @ solve_continuous_are(a, b, np.diag(q), np.diag(r)))
    k_w, y = rate_gains(j, q, r)
    np.testing.assert_allclose(np.diag(k[:, :3]), k_w, rtol=1e-9)
    np.testing.assert_allclose(np.diag(k[:, 3:]), y, rtol=1e-9)


@settings(max_examples=50, deadline=None)
@given(j=vec3, q=vec6, r=vec3)
def test_completed_weights_satisfy_constraint_star(j, q, r):
    q2 = complete_weights(j, q, r)
    assert np.all(q2 > 0)
    assert np.sum(q2 != np.asarray(q)) <= 1
    _, y = rate_gains(j, q2, r)
    assert abs(constraint_residual(j, y)) <= 1e-9 * np.sum(np.abs(np.diff(j))) / np.min(y) + 1e-12


@settings(
    max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True
)
@given(
    j=st.tuples(*[st.floats(1.0, 4.0)] * 3),
    q_w=st.floats(0.1, 1.0),
    q_l=st.tuples(*[st.floats(0.04, 1.0)] * 3),
    seed=st.integers(0, 2**31),
)
def test_constrained_lqr_converges_globally_and_V_decreases(j, q_w, q_l, seed):
    """With (*) the nonlinear closed loop J w' + w x J w = u converges from a random
    attitude (any angle) and random rates up to 0.3 rad/s, and the seed's Lyapunov
    function V is non-increasing (continuous law, solve_ivp DOP853)."""
    rng = np.random.default_rng(seed)
    w_axes = Rotation.random(rng=rng).as_matrix()
    jm = w_axes @ np.diag(j) @ w_axes.T
    law = LQRController(jm, (q_w,) * 3 + tuple(q_l), (1.0, 1.0, 1.0), axes=w_axes)
    assert abs(law.constraint) < 1e-9
    body = RigidBody(jm)
    est = PerfectEstimator()
    x0 = np.concatenate(
        [Rotation.random(rng=rng).as_quat(), rng.uniform(-0.3, 0.3, 3), np.zeros(3)]
    )

    def rhs(_t, x):
        belief = est.update(PointBelief(x0), x)  # the law reads a belief, not the truth
        return attitude_rhs(x, body, law.from_belief(belief), np.zeros(3))

    horizon = 25.0 / law.closed_loop_decay_rate()
    sol = solve_ivp(
        rhs, (0, horizon), x0, method="DOP853", rtol=1e-10, atol=1e-12, dense_output=True
    )
    xs = sol.sol(np.linspace(0, horizon, 2000)).T
    xs[:, 0:4] /= np.linalg.norm(xs[:, 0:4], axis=1, keepdims=True)
    v = law.lyapunov(xs)
    assert np.max(np.diff(v)) <= 1e-8 * v[0]
    lam = error_quaternion(xs[-1, 0:4], law.q_target, shortest=False)
    assert lam[3] == pytest.approx(1.0, abs=1e-6)  # lam -> 0, lam0 -> +1
    assert np.linalg.norm(xs[-1, 4:7]) < 1e-4
    assert v[-1] < 1e-4 * v[0]


def test_attitude_command_lqr_scenario_json(capsys, tmp_path):
    """docs/models.md §3.1 attitude contract on data/scenarios/lqr_large_angle.toml."""
    import json

    from kalman_vs_infoset.experiments.cli import main

    args = ["attitude", str(ROOT / "data/scenarios/lqr_large_angle.toml"), "--runs", "2", "--json"]
    assert main([*args, "--out", str(tmp_path)]) == 0
    out = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    for key in ("settle_time_s", "energy_N2m2s", "final_angle_deg", "final_rate_degps"):
        assert set(out[key]) == {"mean", "p50", "p90", "max"}
    assert out["controller"] == "lqr" and out["failures"] == 0
    assert out["settle_time_s"]["max"] < 300.0
    assert abs(out["constraint_residual"]) < 1e-12
    assert out["max_torque_Nm"] <= 0.1 + 1e-12
    # the runs' CPU time, as the intercept commands report it (docs/models.md §3.1)
    assert out["cpu_s"] > 0.0 and out["worker_peak_rss_mb"] >= 0.0


def test_attitude_dispatcher_reports_unavailable_and_bad_input(monkeypatch, capsys):
    from kalman_vs_infoset.experiments import attitude_loops
    from kalman_vs_infoset.experiments.cli import main
    from kalman_vs_infoset.experiments.errors import InputError

    monkeypatch.setitem(
        attitude_loops.LOOPS, "game", "kalman_vs_infoset.experiments.no_such_module_xyz"
    )
    with pytest.raises(InputError, match="controller game is not available"):
        attitude_loops.loop_of("game")
    assert (
        main(["attitude", str(ROOT / "data/scenarios/lqr_large_angle.toml"), "--controller", "zzz"])
        == 2
    )
    with pytest.raises(SystemExit) as refused:  # the noises are parsed before any work
        main(["attitude", str(ROOT / "data/scenarios/lqr_large_angle.toml"), "--noise", "loud"])
    assert refused.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and "zzz" in err[0] and "loud" in err[1]


@pytest.mark.parametrize("q_target", [(0, 0, 0, 2), (np.nan, 0, 0, 1), (0, 0, 1)])
def test_lqr_refuses_a_target_that_is_not_a_unit_quaternion(q_target):
    """As QuaternionPD does: (0, 0, 0, 2) doubled the attitude torque and made the
    Lyapunov function negative; a NaN target gave NaN torques."""
    with pytest.raises(ValueError, match="unit quaternion"):
        LQRController(np.diag([1.0, 2.0, 3.0]), (1.0,) * 6, (1.0,) * 3, q_target=q_target)
