"""Gyrodine cluster (seed 000 eqs. 4.1-4.5), Euler-axis baseline profile, RK4 plant, scenario."""

import numpy as np
import pytest
from docs_numbers import ROOT
from kalman_vs_infoset.experiments.attitude_cmg import run, setup_from_scenario
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.scenario import load_toml
from kalman_vs_infoset.guidance.attitude.cmg import RESURS_P_BETA0_DEG, CmgCluster, rk4_step
from kalman_vs_infoset.guidance.attitude.energy import resurs_p_inertia
from kalman_vs_infoset.guidance.attitude.euler_turn import EulerAxisProfile
from kalman_vs_infoset.guidance.attitude.plant import AttitudeState, RigidBody, propagate
from scipy.integrate import cumulative_trapezoid
from scipy.linalg import pinv
from scipy.spatial.transform import Rotation

from kalman_vs_infoset.numerics.rotations import cross

CLUSTER = CmgCluster()
BETA0 = np.radians(RESURS_P_BETA0_DEG)


def test_torque_matrix_4_1_is_minus_numerical_derivative_of_gyro_momentum():
    """Seed (3.3) + (4.1): M = S(beta) beta' = -dK_G/dt, checked by central differences."""
    rng = np.random.default_rng(1)
    for beta in [BETA0, *rng.uniform(0, 2 * np.pi, (5, 6))]:
        eps = 1e-6
        num = np.column_stack(
            [
                -(CLUSTER.momentum_Nms(beta + eps * e) - CLUSTER.momentum_Nms(beta - eps * e))
                / (2 * eps)
                for e in np.eye(6)
            ]
        )
        np.testing.assert_allclose(CLUSTER.torque_matrix(beta), num, atol=1e-6)


def test_layout_three_collinear_pairs_on_a_30deg_cone_and_zero_initial_momentum():
    """Seed section 4: gimbal axes on a cone of half-angle 30 deg about body y, pairs
    collinear; with beta0 = 315, 225, ... deg no momentum (no disturbing torque at spin-up)."""
    g = CLUSTER.gimbal_axes
    np.testing.assert_allclose(np.degrees(np.arccos(g[:, 1])), 30.0, atol=1e-12)
    np.testing.assert_allclose(g[0::2], g[1::2], atol=1e-15)
    # first rotation about y by psi, second about the new z by alpha:
    # y_P = (-sin a cos psi, cos a, sin a sin psi)
    psi, a = np.radians([0.0, 120.0, 240.0]), np.radians(30.0)
    expected = np.column_stack(
        [-np.sin(a) * np.cos(psi), np.full(3, np.cos(a)), np.sin(a) * np.sin(psi)]
    )
    np.testing.assert_allclose(g[0::2], expected, atol=1e-12)
    np.testing.assert_allclose(CLUSTER.momentum_Nms(BETA0), 0.0, atol=1e-9)
    # every rotor momentum is perpendicular to its gimbal axis and has modulus H
    h = CLUSTER.gyro_momenta_Nms(BETA0)
    np.testing.assert_allclose(np.einsum("ij,ij->i", h, g), 0.0, atol=1e-9)
    np.testing.assert_allclose(np.linalg.norm(h, axis=1), 250.0)


def test_steering_4_5_equals_scipy_pseudo_inverse_and_reproduces_the_torque():
    rng = np.random.default_rng(2)
    for _ in range(5):
        beta = rng.uniform(0, 2 * np.pi, 6)
        torque = rng.normal(0, 10, 3)
        if CLUSTER.manipulability(beta) < 2 * CLUSTER.sr_threshold:
            continue
        rates, singular = CLUSTER.steering_rates(beta, torque)
        assert not singular
        np.testing.assert_allclose(rates, pinv(CLUSTER.torque_matrix(beta)) @ torque, rtol=1e-9)
        np.testing.assert_allclose(CLUSTER.torque_matrix(beta) @ rates, torque, atol=1e-9)


def test_singular_configuration_is_detected_and_sr_inverse_stays_bounded():
    """All torque columns perpendicular to body x (tan beta = -z_P.x / x_P.x): S S^T is
    singular; the pseudo-inverse would blow up, the SR inverse obeys
    ||beta'|| <= |M| / (2 sqrt(lam))."""
    u = np.array([1.0, 0.0, 0.0])
    beta = np.arctan2(-(CLUSTER.z_axes @ u), CLUSTER.x_axes @ u)
    s = CLUSTER.torque_matrix(beta)
    np.testing.assert_allclose(u @ s, 0.0, atol=1e-9)
    assert CLUSTER.manipulability(beta) < 1e-9
    torque = np.array([5.0, 1.0, -1.0])
    rates, singular = CLUSTER.steering_rates(beta, torque)
    assert singular
    lam = CLUSTER.sr_damping * CLUSTER.rotor_momentum_Nms**2
    assert np.all(np.isfinite(rates))
    assert np.linalg.norm(rates) <= np.linalg.norm(torque) / (2 * np.sqrt(lam)) * (1 + 1e-9)
    # the components it can produce (perpendicular to u) are still mostly delivered
    produced = s @ rates
    assert abs(produced[0]) < 1e-9
    assert np.linalg.norm(produced[1:] - torque[1:]) < 0.1 * np.linalg.norm(torque[1:])


def _sr_steering_as_written(cluster: CmgCluster, beta, torque):
    """Seed eq. (4.5) with the SR inverse as written: ``S^T (S S^T + lam I)^-1 M``, lam =
    d H^2 (1 - m / m_sr)^2 below the threshold, m = sqrt(det(S S^T)) / H^3."""
    s = cluster.torque_matrix(beta)
    h = cluster.rotor_momentum_Nms
    m = np.sqrt(max(np.linalg.det(s @ s.T), 0.0)) / h**3
    lam = cluster.sr_damping * h**2 * (1 - m / cluster.sr_threshold) ** 2
    lam = lam if m < cluster.sr_threshold else 0.0
    return s.T @ np.linalg.solve(s @ s.T + lam * np.eye(3), torque), m


@pytest.mark.parametrize("h_Nms", [250.0, 1e-3, 1e4])
def test_steering_equals_the_sr_inverse_as_written_singular_or_not(h_Nms):
    """The steering works with S / H (scale-free); at rotor momenta where the formula as
    written neither under- nor overflows it gives the same rates, near singular states
    too (beta drawn towards the singular one of the test above)."""
    cluster = CmgCluster(rotor_momentum_Nms=h_Nms)
    rng = np.random.default_rng(7)
    u = np.array([1.0, 0.0, 0.0])
    singular_beta = np.arctan2(-(cluster.z_axes @ u), cluster.x_axes @ u)
    seen = set()
    for spread in (3.0, 0.3, 0.03, 0.003, 0.0):
        beta = singular_beta + rng.normal(0.0, spread, 6)
        torque = rng.normal(0.0, 10.0, 3)
        rates, singular = cluster.steering_rates(beta, torque)
        expected, m = _sr_steering_as_written(cluster, beta, torque)
        assert singular == (m < cluster.sr_threshold)
        np.testing.assert_allclose(cluster.manipulability(beta), m, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(rates, expected, rtol=1e-7, atol=1e-12 / h_Nms)
        seen.add(singular)
    assert seen == {True, False}


def test_steering_of_a_rotor_of_1e_300_Nms_scales_instead_of_dividing_by_zero():
    """A rotor momentum the scenario admits (any positive value) once raised
    ZeroDivisionError in the steering: H^3 underflowed to 0 (random ``--set`` overrides
    found it). The rates scale as 1 / H, the manipulability not at all."""
    tiny = CmgCluster(rotor_momentum_Nms=1e-300)
    unit = CmgCluster(rotor_momentum_Nms=1.0)
    torque = np.array([1e-300, -2e-300, 5e-301])
    for beta in (BETA0, BETA0 + 0.4):
        rates, singular = tiny.steering_rates(beta, torque)
        unit_rates, unit_singular = unit.steering_rates(beta, torque * 1e300)
        assert singular == unit_singular
        np.testing.assert_allclose(rates, unit_rates, rtol=1e-12)
        assert tiny.manipulability(beta) == unit.manipulability(beta)


def test_cluster_step_delivers_the_requested_torque_as_momentum_exchange():
    beta, torque, dt = BETA0.copy(), np.array([-5.4, -1.1, -2.4]), 0.1
    h_before = CLUSTER.momentum_Nms(beta)
    beta_next, delivered, singular = CLUSTER.step(beta, torque, dt)
    assert not singular
    np.testing.assert_allclose(CLUSTER.momentum_Nms(beta_next), h_before - delivered * dt)
    np.testing.assert_allclose(delivered, torque, rtol=1e-6)


def test_rk4_plant_matches_common_plant_propagate():
    """The fixed-step RK4 used for the 3000-step turns vs plant.propagate (DOP853)."""
    body = RigidBody(resurs_p_inertia())
    state = AttitudeState(
        Rotation.from_rotvec([1.0, 0.5, -0.3]).as_quat(), [0.01, -0.02, 0.005], [30.0, -10, 5]
    )
    torque, ext = np.array([3.0, -1.0, 2.0]), np.array([0.1, 0.0, -0.2])
    x = state.as_vector()
    a, b = np.random.default_rng(0).normal(size=(2, 5, 3))
    np.testing.assert_allclose(cross(a, b), np.cross(a, b), rtol=1e-13)
    for _ in range(20):
        x = rk4_step(body, x, torque, 0.1, ext)
        state = propagate(body, state, torque, 0.1, ext)
    np.testing.assert_allclose(x, state.as_vector(), atol=1e-9)


def test_euler_profile_phases_and_boundary_conditions():
    """Seed intro: accelerate (rising, constant, falling acceleration), coast, decelerate;
    rest to rest, total angle theta0; rate and angle are integrals of the acceleration."""
    theta0, t_turn, ta, tj = 2.2, 300.0, 30.0, 10.0
    p = EulerAxisProfile(theta0, t_turn, ta, tj)
    t = np.linspace(0, t_turn, 30001)
    a = p.accel(t)
    amax = a.max()
    np.testing.assert_allclose(a[(t > 0) & (t < tj)] / amax, t[(t > 0) & (t < tj)] / tj, atol=1e-9)
    np.testing.assert_allclose(a[(t > tj) & (t < ta - tj)], amax)
    assert np.all(a[(t > ta) & (t < t_turn - ta)] == 0)
    np.testing.assert_allclose(a, -a[::-1], atol=1e-12)
    np.testing.assert_allclose(cumulative_trapezoid(a, t, initial=0), p.rate(t), atol=1e-9)
    np.testing.assert_allclose(cumulative_trapezoid(p.rate(t), t, initial=0), p.angle(t), atol=1e-7)
    assert p.angle(t_turn) == pytest.approx(theta0)
    assert p.rate(0.0) == 0.0 and abs(p.rate(t_turn)) < 1e-15
    # a_max from rest-to-rest kinematics: theta0 = w_max (T - ta), w_max = a_max (ta - tj)
    assert amax == pytest.approx(theta0 / ((t_turn - ta) * (ta - tj)))


def test_scenario_file_loads_and_bad_input_is_one_line_input_error():
    path = str(ROOT / "data/scenarios/resurs_p.toml")
    scenario = load_toml(path)
    assert scenario["controller"] == "energy"
    setup = setup_from_scenario(path, scenario)
    assert setup.n_turn_steps == 3000
    np.testing.assert_allclose(np.degrees(setup.initial_error_rad), [110, 45, 45])
    for bad, field in [
        ({"bogus": 1}, "bogus"),
        ({"dt_s": -1.0}, "dt_s"),
        ({"energy": {"u0_Nm": [1, 2]}}, "energy.u0_Nm"),
        ({"euler": {"accel_time_s": 200.0}}, "euler.accel_time_s"),
        ({"inertia_products_sign": [1, 0, 1]}, "inertia_products_sign"),
    ]:
        with pytest.raises(InputError, match=field.replace(".", r"\.")) as exc:
            setup_from_scenario(path, {**scenario, **bad})
        assert "\n" not in str(exc.value)
    no_game = {**scenario, "noise": {**scenario["noise"], "game_disturbance_Nm": 0.0}}
    with pytest.raises(InputError, match="not defined"):
        run(path, no_game, "energy", "game", 1, 0)


def test_run_random_noise_is_seeded_and_paired():
    """Short turns (20 s): the same root seed gives the same result; runs differ."""
    scenario = {"duration_s": 20.0, "horizon_s": 20.0}
    a = run("short", scenario, "energy", "random", 2, 7)
    b = run("short", scenario, "energy", "random", 2, 7)
    assert a["failures"] == 0
    assert a["energy_N2m2s"] == b["energy_N2m2s"]
    assert a["energy_N2m2s"]["max"] > a["energy_N2m2s"]["p50"] * (1 - 1e-3)
    assert a["energy_N2m2s"]["max"] != pytest.approx(a["energy_N2m2s"]["mean"], rel=1e-12)
    for key in ("settle_time_s", "final_angle_deg", "final_rate_degps", "lower_bound_energy_N2m2s"):
        assert key in a


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_propagate_refuses_a_torque_that_is_not_finite(bad):
    """A NaN torque made DOP853's step control loop for ever (minutes, no error)."""
    body = RigidBody.diagonal([1.0, 2.0, 3.0])
    state = AttitudeState([0.0, 0.0, 0.0, 1.0], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="finite"):
        propagate(body, state, [bad, 0.0, 0.0], 0.1)
    with pytest.raises(ValueError, match="finite"):
        propagate(body, state, [0.0, 0.0, 0.0], 0.1, [0.0, bad, 0.0])


def test_a_control_std_that_squares_to_zero_is_refused_in_one_line(tmp_path, capsys):
    """``energy.control_std0_Nm`` = 1e-300 is within the field's bounds, but the law's
    variance, its square, underflows to 0: the law's own check then raised out of the
    command with a traceback (random command lines found it). Refused in one line now,
    naming the field."""
    from harness_texts import one_line_error, run_cli

    r = run_cli(capsys, "attitude", "resurs_p", "--runs", "1", "--out", tmp_path / "out",
                "--set", "energy.control_std0_Nm=1e-300")  # fmt: skip
    assert one_line_error(r), r.stderr
    assert "'energy.control_std0_Nm'" in r.stderr and not (tmp_path / "out").exists()


def test_the_gyrodine_loop_s_library_checks_come_back_as_one_line(monkeypatch):
    """Any check of the library objects the turn is built from reads as an ``InputError``
    naming the file, as the reaction-wheel and gyrostat loops report theirs."""
    from kalman_vs_infoset.experiments import attitude_cmg_setup

    def refuse(config):
        raise ValueError("sr_damping must be positive")

    monkeypatch.setattr(attitude_cmg_setup.TurnSetup, "from_config", refuse)
    scenario = load_toml(ROOT / "data/scenarios/resurs_p.toml")
    with pytest.raises(InputError, match=r"^resurs_p.toml: sr_damping must be positive$"):
        setup_from_scenario("resurs_p.toml", scenario)


@pytest.mark.parametrize("controller", ["energy", "euler"])
def test_a_turn_cut_after_some_steps_is_the_whole_turn_s_prefix(controller):
    """``simulate_turn(..., steps=k)`` (what ``kvi attitude-tightness`` runs) is a longer
    run's first ``k`` steps to the last bit (the loop is causal), NaN after them; its
    record's truth is the gyrodines' RK4 of the delivered torque and disturbance, and
    each measurement is within the estimators' bounds of the truth it measured."""
    from kalman_vs_infoset.experiments.sim.attitude_cmg import estimator_model, simulate_turn

    from kalman_vs_infoset.numerics.rotations import qinv, qlog, qmul

    setup = setup_from_scenario("resurs_p", load_toml(ROOT / "data/scenarios/resurs_p.toml"))
    k, runs = 40, {}
    for steps in (k, 3 * k):  # (the whole turn: 3000 steps, 3 CPU-s with the box)
        rec: dict = {}
        rng = np.random.default_rng(7)
        runs[steps] = (simulate_turn(setup, controller, rng, "box", "game", rec, steps=steps), rec)
    (cut, rec), (whole, _) = runs[k], runs[3 * k]
    np.testing.assert_array_equal(cut.error_rotvec_deg[: k + 1], whole.error_rotvec_deg[: k + 1])
    np.testing.assert_array_equal(cut.torque_Nm[:k], whole.torque_Nm[:k])
    assert np.isnan(cut.torque_Nm[k:]).all() and np.isnan(cut.rate_degps[k + 1 :]).all()
    assert rec["states"].shape == (k + 1, 10) and len(rec["hull"]) == k + 1
    for j in range(k):
        step = rk4_step(setup.body, rec["states"][j], rec["torque_Nm"][j], setup.dt_s,
                        rec["disturbance_Nm"][j])  # fmt: skip
        np.testing.assert_array_equal(step, rec["states"][j + 1])
    model = estimator_model(setup, "game")
    err = qlog(qmul(qinv(rec["states"][:, 0:4]), rec["meas_quat"]))
    assert np.all(np.abs(err) <= model.meas_angle_bound_rad * (1 + 1e-9))
    rate_err = np.abs(rec["meas_rate_radps"] - rec["states"][:, 4:7])
    assert np.all(rate_err <= model.meas_rate_bound_radps * (1 + 1e-9))
    assert np.all(np.abs(rec["disturbance_Nm"]) <= model.disturbance_bound_Nm * (1 + 1e-12))
