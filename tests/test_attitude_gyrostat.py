"""Gyrostat game law (seed 004_75fdce96e51024ef.txt, docs/models.md §2.4).

Reference values come from the seed's equations re-derived independently here (momentum
balance of 1.1, the printed form of 2.1, Cauchy-Schwarz 2.3, the double-integrator time
2.8), from numpy/scipy (matrix inverse, solve_ivp) and from the seed's claims (turn
within tau, |u_i| <= alpha_i under every disturbance kind).
"""

from pathlib import Path

import numpy as np
import pytest
from kalman_vs_infoset.experiments.attitude_gyrostat import initial_quaternion, parse_scenario, run
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.scenario import load_toml
from kalman_vs_infoset.experiments.sim.gyrostat import LoopConfig, simulate_turn
from kalman_vs_infoset.guidance.attitude import plant
from kalman_vs_infoset.guidance.attitude.game import (
    GameLaw,
    beta_star,
    design_a_star,
    guaranteed_time_s,
    reachable_torque_bound_Nm,
    time_to_go_s,
)
from kalman_vs_infoset.guidance.attitude.gyrostat import (
    Gyrostat,
    aux_disturbance,
    eta_v_accel,
    eta_v_rate,
    g_inverse,
    g_matrix,
    linearising_torque,
    rhs,
    rk4_step,
)
from scipy.integrate import solve_ivp
from scipy.spatial.transform import Rotation

from kalman_vs_infoset.numerics.rotations import error_quaternion, quaternion_rate

SCENARIO = Path(__file__).resolve().parents[1] / "data" / "scenarios" / "gyrostat_game.toml"
GYRO = Gyrostat([120.0, 100.0, 80.0], [0.12, 0.10, 0.08])


def _random_states(rng, n=50):
    eta = rng.normal(size=(n, 4))
    eta /= np.linalg.norm(eta, axis=1, keepdims=True)
    eta[:, 3] = np.abs(eta[:, 3]) + 0.05  # keep away from eta4 = 0 (turns < 180 deg)
    eta /= np.linalg.norm(eta, axis=1, keepdims=True)
    x = rng.normal(scale=0.05, size=(n, 3))
    phidot = rng.normal(scale=30.0, size=(n, 3))
    return np.concatenate([eta, x, phidot], axis=1)


def test_plant_1_1_is_the_momentum_balance_dK_plus_x_cross_K_equals_v():
    """Seed (1.1) read as K' + x x K = v, K = A x + J phidot; J(phi'' + x') = u."""
    rng = np.random.default_rng(1)
    s = _random_states(rng)
    u, v = rng.normal(scale=0.1, size=(2, len(s), 3))
    d = rhs(s, GYRO, u, v)
    x, phidot, dx, dphi = s[:, 4:7], s[:, 7:10], d[:, 4:7], d[:, 7:10]
    k = GYRO.A_kgm2 * x + GYRO.rotor_J_kgm2 * phidot
    dk = GYRO.A_kgm2 * dx + GYRO.rotor_J_kgm2 * dphi
    np.testing.assert_allclose(dk + np.cross(x, k), v, atol=1e-12)
    np.testing.assert_allclose(GYRO.rotor_J_kgm2 * (dphi + dx), u, atol=1e-12)
    # kinematics (1.2) agree with the common plant's quaternion_rate (scalar last)
    for row in s[:5]:
        np.testing.assert_allclose(
            quaternion_rate(row[:4], row[4:7]), plant.quaternion_rate(row[:4], row[4:7])
        )


def test_fixed_step_rk4_matches_scipy_dop853_over_a_turn_segment():
    """The loop's RK4 at the scenario's 0.05 s step vs solve_ivp (rtol 1e-11), u, v held."""
    rng = np.random.default_rng(8)
    s0 = _random_states(rng, 1)[0]
    u, v = np.array([0.05, -0.03, 0.02]), np.array([0.004, 0.005, -0.003])
    s = s0[None, :].copy()
    for _ in range(200):  # 10 s
        s = rk4_step(GYRO, s, u[None], v[None], 0.05)
    ref = solve_ivp(
        lambda _t, y: rhs(y, GYRO, u, v), (0, 10), s0, method="DOP853", rtol=1e-11, atol=1e-13
    )
    np.testing.assert_allclose(s[0], ref.y[:, -1], rtol=1e-7, atol=1e-9)


def test_g_inverse_formula_equals_numpy_inverse():
    rng = np.random.default_rng(2)
    eta = _random_states(rng)[:, :4]
    np.testing.assert_allclose(g_inverse(eta), np.linalg.inv(g_matrix(eta)), rtol=1e-12)


def test_linearising_torque_matches_the_printed_seed_2_1():
    """Seed (2.1) for u_1 as printed (cyclic 1 -> 2 -> 3), written out by hand."""
    rng = np.random.default_rng(3)
    s = _random_states(rng, 20)
    us = rng.normal(scale=1e-3, size=(20, 3))
    got = linearising_torque(GYRO, s[:, :4], s[:, 4:7], s[:, 7:10], us)
    a, j = GYRO.A_kgm2, GYRO.rotor_J_kgm2
    for r in range(20):
        n, x, p, w = s[r, :4], s[r, 4:7], s[r, 7:10], us[r]
        for i in range(3):
            i2, i3 = (i + 1) % 3, (i + 2) % 3
            bracket = (
                w[i] * (n[i] ** 2 + n[3] ** 2)
                + w[i2] * (n[i] * n[i2] + n[i3] * n[3])
                + w[i3] * (n[i] * n[i3] - n[i2] * n[3])
                + 0.25 * n[i] * (x @ x)
            )
            expected = (
                -2.0 * (a[i] - j[i]) / n[3] * bracket
                + (a[i2] * x[i2] + j[i2] * p[i2]) * x[i3]
                - (a[i3] * x[i3] + j[i3] * p[i3]) * x[i2]
            )
            assert got[r, i] == pytest.approx(expected, rel=1e-10, abs=1e-15)


def test_closed_loop_rhs_gives_eta_ddot_equal_u_star_plus_v_star():
    """Seed (2.2): with u of (2.1) the plant's exact eta_v'' equals u* + v*."""
    rng = np.random.default_rng(4)
    s = _random_states(rng, 200)
    us = rng.uniform(-1e-3, 1e-3, size=(200, 3))
    v = rng.uniform(-0.01, 0.01, size=(200, 3))
    u = linearising_torque(GYRO, s[:, :4], s[:, 4:7], s[:, 7:10], us)
    np.testing.assert_allclose(
        eta_v_accel(GYRO, s, u, v), us + aux_disturbance(GYRO, s[:, :4], v), rtol=0, atol=1e-15
    )


def test_linearisation_identity_along_a_trajectory_is_a_parabola():
    """Continuous closed loop (2.1) with constant u* and a disturbance v(t) chosen so that
    v* is constant: eta_v(t) must be eta_v0 + eta_v0' t + (u* + v*) t^2 / 2 (scipy DOP853)."""
    eta0 = Rotation.from_rotvec(np.radians(60.0) * np.array([1.0, 2.0, 3.0]) / 14**0.5).as_quat()
    s0 = np.concatenate([eta0, [0.01, -0.02, 0.015], [20.0, -10.0, 5.0]])
    us = np.array([2e-4, -1e-4, 1.5e-4])
    vs = np.array([-3e-5, 2e-5, 1e-5])

    def closed_loop(_t, s):
        eta = s[:4] / np.linalg.norm(s[:4])
        v = 2.0 * GYRO.body_moments_kgm2 * (g_inverse(eta) @ vs)  # v* = G D v / 2 = vs
        u = linearising_torque(GYRO, eta, s[4:7], s[7:10], us)
        return rhs(s, GYRO, u, v)

    t = np.linspace(0.0, 20.0, 41)
    sol = solve_ivp(closed_loop, (0, 20), s0, method="DOP853", t_eval=t, rtol=1e-12, atol=1e-14)
    assert sol.success
    d0 = eta_v_rate(s0[:4], s0[4:7])
    parabola = s0[:3] + np.outer(t, d0) + 0.5 * np.outer(t**2, us + vs)
    np.testing.assert_allclose(sol.y[:3].T, parabola, atol=1e-9)
    # the same from finite differences of the trajectory: eta'' = u* + v*
    fd = (sol.y[:3, 2:] - 2 * sol.y[:3, 1:-1] + sol.y[:3, :-2]) / (t[1] - t[0]) ** 2
    np.testing.assert_allclose(fd.T, np.broadcast_to(us + vs, fd.T.shape), atol=1e-8)


def test_beta_star_bounds_the_auxiliary_disturbance_seed_2_3():
    rng = np.random.default_rng(6)
    beta = np.array([0.01, 0.02, 0.005])
    eta = _random_states(rng, 2000)[:, :4]
    v = rng.choice([-1.0, 1.0], size=(2000, 3)) * beta
    vstar = aux_disturbance(GYRO, eta, v)
    bs = beta_star(GYRO, beta)
    assert np.abs(vstar).max() <= bs
    assert np.abs(vstar).max() > 0.8 * bs  # and it is not a vacuous bound


def test_guaranteed_time_2_8_is_the_worst_case_of_the_scalar_game():
    """Scalar game eta'' = u* + v*, rest at eta0: the discrete law against v* = -rho a*
    sign(u*) (the worst admissible) arrives at tau (2.8) to within two samples; without
    disturbance it arrives earlier; time_to_go agrees with (2.8) at rest."""
    a, rho, h, e0 = 2e-4, 0.4, 0.01, 0.3
    law = GameLaw(np.full(3, a), np.full(3, rho), h)
    tau = guaranteed_time_s([e0, 0, 0], law.a_star, law.rho)
    assert tau == pytest.approx(2 * np.sqrt(e0 / ((1 - rho) * a)))
    assert time_to_go_s(np.array([e0]), np.array([0.0]), law.decel[:1])[0] == pytest.approx(tau)

    def arrival(adversary: bool) -> float:
        y, dy = np.array([e0, 0, 0]), np.zeros(3)
        for k in range(int(2 * tau / h)):
            u = law.u_star(y, dy)
            w = u - rho * a * np.sign(u) if adversary else u
            y, dy = y + dy * h + 0.5 * w * h * h, dy + w * h
            if abs(y[0]) < 1e-5 and abs(dy[0]) < 1e-5:  # 0.001 deg, 0.002 deg/s
                return (k + 1) * h
        return np.inf

    worst = arrival(True)
    assert tau - 0.5 <= worst <= tau  # tau is met and is tight
    assert arrival(False) < tau - 5.0


def test_a_star_iteration_is_maximal_and_respects_limits():
    eta0 = initial_quaternion(parse_scenario("s", load_toml(SCENARIO)).manoeuvre)[:3]
    alpha, beta, rho = np.array([0.25, 0.2, 0.15]), np.full(3, 0.005), np.full(3, 0.4)
    d = design_a_star(GYRO, eta0, alpha, beta, rho)
    assert np.all(d.torque_bound_Nm <= alpha)
    assert np.all(d.beta_star <= rho * d.a_star * (1 + 1e-12))
    assert np.max(d.torque_bound_Nm / alpha) > 0.999  # no reserve left
    bigger = reachable_torque_bound_Nm(GYRO, eta0, 1.01 * d.a_star, rho, beta)
    assert np.any(bigger > alpha)
    assert d.tau_s == pytest.approx(guaranteed_time_s(eta0, d.a_star, rho))
    with pytest.raises(ValueError, match="disturbance bound too large"):
        design_a_star(GYRO, eta0, alpha, 10 * alpha, rho)


@pytest.fixture(scope="module")
def scenario():
    return load_toml(SCENARIO)


@pytest.mark.parametrize(
    ("noise", "disturbance"),
    [("none", "auto"), ("random", "auto"), ("none", "constant"), ("game", "auto")],
)
def test_turn_completes_within_tau_and_torques_within_alpha(scenario, noise, disturbance):
    """Every disturbance kind, including the adversarial one."""
    sc = {**scenario, "simulation": {**scenario["simulation"], "disturbance": disturbance}}
    res = run(str(SCENARIO), sc, "game", noise, runs=3 if disturbance == "constant" else 2, seed=7)
    assert res["failures"] == 0 and res["unsettled_runs"] == 0 == res["not_settled"]
    assert res["settle_time_s"]["max"] <= res["guaranteed_time_s"]
    assert res["late_runs"] == 0
    assert res["max_torque_ratio"] <= 1.0
    assert res["final_angle_deg"]["max"] <= sc["simulation"]["settle_angle_deg"]


def test_disturbances_are_admissible_and_the_adversary_delays(scenario):
    config = parse_scenario("s", scenario)
    g = config.gyrostat
    beta, rho = np.array(g.beta_Nm), np.array(g.rho)
    q0 = initial_quaternion(config.manoeuvre)
    eta0 = error_quaternion(q0, np.array([0, 0, 0, 1.0]))[:3]
    d = design_a_star(GYRO, eta0, g.alpha_Nm, beta, rho)
    law = GameLaw(d.a_star, rho, 0.1)
    cfg = LoopConfig(period_s=0.1, horizon_s=1.2 * d.tau_s)
    settle = {}
    for kind in ("none", "random", "adversarial"):
        r = simulate_turn(
            GYRO, law, q0, [0, 0, 0, 1], beta, kind, [np.random.default_rng(3)], cfg, record=True
        )
        assert np.all(np.abs(r.disturbance_Nm) <= beta)
        settle[kind] = r.settle_time_s[0]
    assert settle["none"] < settle["adversarial"] <= d.tau_s
    assert settle["random"] < settle["adversarial"]


def test_scenario_validation_names_the_field(scenario):
    bad = {**scenario, "gyrostat": {**scenario["gyrostat"], "rho": [0.4, 1.2, 0.4]}}
    with pytest.raises(InputError, match="gyrostat.rho"):
        run("f.toml", bad, "game", "none", 1, 0)
    with pytest.raises(InputError, match="unknown key 'extra'"):
        run("f.toml", {**scenario, "extra": 1}, "game", "none", 1, 0)
    with pytest.raises(InputError, match="controller"):
        run("f.toml", scenario, "pd", "none", 1, 0)
