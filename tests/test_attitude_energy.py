"""Energy-saving discrete control of Resurs-P (seed 000, docs/models.md §2.1) and the min-energy
bound.

The two full 300-s turns (energy law, Euler-axis baseline) are simulated once each
(module fixtures) and shared by the tests that check them.
"""

import dataclasses
import itertools

import numpy as np
import pytest
from kalman_vs_infoset.experiments.attitude_cmg_setup import setup_from_scenario
from kalman_vs_infoset.experiments.sim.attitude_cmg import lower_bound_energy_N2m2s, simulate_turn
from kalman_vs_infoset.guidance.attitude.energy import (
    EnergySavingConfig,
    EnergySavingController,
    EnergySavingState,
    given_system,
    resurs_p_inertia,
    skew,
)
from kalman_vs_infoset.guidance.attitude.euler_turn import EulerAxisProfile
from kalman_vs_infoset.guidance.attitude.min_energy import min_energy_turn
from numpy.typing import NDArray
from scipy.linalg import expm, null_space

J = resurs_p_inertia()
J_INV = np.linalg.inv(J)
X0 = np.r_[np.radians([110.0, 45.0, 45.0]), 0.0, 0.0, 0.0]
SEED_U0_NM = np.array([-5.4, -1.1, -2.4])
CONFIG = EnergySavingConfig()


#: the users of the two simulated turns (module fixtures, ~2 CPU-s each) run in one
#: xdist worker, which simulates each turn once
TURNS = pytest.mark.xdist_group("attitude_energy_turns")


@pytest.fixture(scope="module")
def energy_turn():
    setup = setup_from_scenario("test", {"horizon_s": 330.0})
    return setup, simulate_turn(setup, "energy")


@pytest.fixture(scope="module")
def euler_turn():
    setup = setup_from_scenario("test", {"horizon_s": 300.0})
    return setup, simulate_turn(setup, "euler")


def test_inertia_read_as_upper_triangle_with_thousands_separator():
    np.testing.assert_array_equal(np.diag(J), [22147, 10213, 24497])
    np.testing.assert_array_equal(J, J.T)
    assert resurs_p_inertia((1, -1, 1))[0, 2] == -321
    with pytest.raises(ValueError):
        resurs_p_inertia((1, 0, 1))
    with pytest.raises(ValueError):
        resurs_p_inertia("plus")


def test_inertia_default_is_the_standard_tensor_convention():
    """Seed section 4 prints the products without signs; the default reads them as the
    products of inertia I_jk of the standard tensor J_jk = -I_jk ("-" off the diagonal),
    "entries" as the tensor's entries; both stay positive definite."""
    np.testing.assert_array_equal(J, resurs_p_inertia("standard"))
    assert np.all(J[np.triu_indices(3, 1)] == [-144, -321, -752])
    assert np.all(resurs_p_inertia("entries")[np.triu_indices(3, 1)] == [144, 321, 752])
    for signs in itertools.product((1, -1), repeat=3):
        assert np.all(np.linalg.eigvalsh(resurs_p_inertia(signs)) > 0)


def test_F_is_inverse_inertia_times_momentum_cross_matrix():
    """(3.5): dw/dt = -J^-1 (w x K) + J^-1 M  =>  F w = -J^-1 (w x K)."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        w, k = rng.normal(size=3), rng.normal(0, 100, 3)
        a, _ = given_system(J_INV, k, 0.1)
        f = (a[3:, 3:] - np.eye(3)) / 0.1  # recovering dt F from E + dt F costs ~4 digits
        np.testing.assert_allclose(f @ w, -J_INV @ np.cross(w, k), rtol=1e-9)
        np.testing.assert_allclose(skew(k) @ w, np.cross(k, w))


def test_discretisation_3_10_3_11_against_scipy_expm():
    """Zero-order hold of X' = R X + G M: exact for F = 0 (K = 0), first order in dt
    for A and second order for B otherwise (the seed keeps these terms)."""

    def exact(k, dt):
        r = np.zeros((9, 9))
        r[:3, 3:6] = np.eye(3)
        r[3:6, 3:6] = J_INV @ skew(k)
        r[3:6, 6:] = J_INV
        e = expm(r * dt)
        return e[:6, :6], e[:6, 6:]

    a, b = given_system(J_INV, np.zeros(3), 0.1)
    a_ex, b_ex = exact(np.zeros(3), 0.1)
    np.testing.assert_allclose(a, a_ex, atol=1e-14)
    np.testing.assert_allclose(b, b_ex, atol=1e-16)
    k = np.array([300.0, -200.0, 100.0])
    err_a = [np.abs(given_system(J_INV, k, dt)[0] - exact(k, dt)[0]).max() for dt in (0.1, 0.05)]
    err_b = [np.abs(given_system(J_INV, k, dt)[1] - exact(k, dt)[1]).max() for dt in (0.1, 0.05)]
    assert err_a[0] / err_a[1] == pytest.approx(4.0, rel=0.05)  # local error O(dt^2)
    assert err_b[0] / err_b[1] == pytest.approx(8.0, rel=0.05)  # local error O(dt^3)


def test_auxiliary_matrix_4_6():
    c = CONFIG.aux_matrix(1000)
    f1, f2 = 2.5e-5 * (1 + 5e-3 * 1000), 0.01 * (1 + 2.5e-4 * 1000)
    np.testing.assert_allclose(np.diag(c[3:, :3]), -f1)
    np.testing.assert_allclose(np.diag(c[3:, 3:]), 1 - f2)
    np.testing.assert_allclose(c[:3, 3:], 0.1 * np.eye(3))


def test_unforced_auxiliary_system_lyapunov_function_decreases_fig7():
    """Seed Fig. 7: theta_i = (C_i xi_i)^T (C_i xi_i) decreases along the unforced motion."""
    xi, theta = X0.copy(), []
    for i in range(3000):
        xi = CONFIG.aux_matrix(i) @ xi
        theta.append(xi @ xi)
    assert np.all(np.diff(theta) < 0)


def _k_u_22(p, a, b, c, d, k_x, k_xi, k_u, k_eps):
    """Seed eq. (2.2), written out independently of the controller."""
    m = p @ (b - d) + np.eye(3)
    return p @ a @ k_x @ a.T @ p.T + p @ c @ k_xi @ c.T @ p.T + m @ k_u @ m.T + p @ k_eps @ p.T


def test_gain_2_4_minimises_trace_of_2_2_and_gives_2_5():
    a, b = given_system(J_INV, np.array([10.0, -5.0, 3.0]), 0.1)
    law = EnergySavingController(CONFIG)
    rng = np.random.default_rng(4)
    state = EnergySavingState(7, X0.copy(), np.zeros(3), np.diag([2e6, 5e5, 1e6]))
    new, diag = law.update(state, a, b, X0 + 0.01)
    k_x, k_eps = np.diag(CONFIG.state_var), np.diag(CONFIG.meas_var)
    c, d = CONFIG.aux_matrix(7), -b
    args = (a, b, c, d, k_x, np.diag(CONFIG.aux_var), state.k_u, k_eps)
    best = np.trace(_k_u_22(diag.gain, *args))
    for _ in range(20):
        delta = rng.normal(size=(3, 6)) * np.abs(diag.gain).max() * 1e-3
        assert np.trace(_k_u_22(diag.gain + delta, *args)) > best
        assert np.trace(_k_u_22(diag.gain - delta, *args)) > best
    np.testing.assert_allclose(new.k_u, _k_u_22(diag.gain, *args), rtol=1e-9)
    assert diag.trace_increment == pytest.approx(np.trace(new.k_u) - np.trace(state.k_u))


def _u0_matching_auxiliary_first_step(j: NDArray[np.float64]) -> NDArray[np.float64]:
    """U0 with X_1 - xi_1 = A X0 - C_0 X0 + 2 B U0 = 0 in least squares (J, D = -B)."""
    a, b = given_system(np.linalg.inv(j), np.zeros(3), 0.1)
    return np.linalg.lstsq(2 * b, CONFIG.aux_matrix(0) @ X0 - a @ X0, rcond=None)[0]


def test_seed_u0_is_the_torque_matching_the_auxiliary_first_step():
    """Reading check (J, D = -B; seed section 5, Fig. 8): the torque that keeps X on xi
    over the first step is close to the seed's M_0 = (-5.4, -1.1, -2.4) N m under every
    reading of the products' signs (without the factor 2 of B - D it would be twice)."""
    for signs in itertools.product((1, -1), repeat=3):
        u0 = _u0_matching_auxiliary_first_step(resurs_p_inertia(signs))
        np.testing.assert_allclose(u0, SEED_U0_NM, atol=0.32)


def test_seed_u0_digits_favour_signs_plus_minus_plus_not_the_standard_reading():
    """What the text says about the lost signs (seed section 5, the printed M_0 of Fig. 8):
    M_2 and M_3 depend on the products' signs, M_1 hardly. Rounded to the printed digit,
    the first-step torque of the reading [+, -, +] gives M_2, M_3 = -1.1, -2.4 as printed;
    the standard reading (all "-") gives -0.9, -2.2. M_1 rounds to -5.3 in every reading
    (printed -5.4), so the evidence is indirect; the default stays the standard one."""
    u = {s: _u0_matching_auxiliary_first_step(resurs_p_inertia(s))
         for s in itertools.product((1, -1), repeat=3)}  # fmt: skip
    printed = {s for s, v in u.items() if np.all(np.round(v[1:], 1) == SEED_U0_NM[1:])}
    assert printed == {(1, -1, 1)}
    np.testing.assert_array_equal(np.round(u[-1, -1, -1], 1), [-5.3, -0.9, -2.2])
    assert all(np.round(v[0], 1) == -5.3 for v in u.values())


def test_min_energy_bound_equals_continuous_double_integrator_closed_form():
    """With K = 0 the model is three double integrators J phi'' = M; the continuous
    minimum of int M^T M dt over T is 12 |J phi0|^2 / T^3."""
    a, b = given_system(J_INV, np.zeros(3), 0.1)
    turn = min_energy_turn(a, b, X0, 3000, 0.1)
    closed = 12.0 * np.sum((J @ X0[:3]) ** 2) / 300.0**3
    assert turn.energy_N2m2s == pytest.approx(closed, rel=2e-3)
    np.testing.assert_allclose(turn.final_state, 0.0, atol=1e-9)


def test_min_energy_controls_beat_every_other_transfer():
    """Any other control sequence reaching X_N = 0 (min-energy + null-space of the
    reachability map) costs more."""
    dt, n = 0.1, 40
    a, b = given_system(J_INV, np.array([50.0, 0.0, -20.0]), dt)
    x0 = np.r_[0.01, -0.02, 0.005, 0.0, 0.0, 0.0]
    turn = min_energy_turn(a, b, x0, n, dt)
    reach = np.hstack([np.linalg.matrix_power(a, n - 1 - i) @ b for i in range(n)])
    basis = null_space(reach)
    rng = np.random.default_rng(5)
    for _ in range(10):
        u = turn.controls_Nm.ravel() + basis @ rng.normal(size=basis.shape[1]) * 10
        x = np.linalg.matrix_power(a, n) @ x0 + reach @ u
        np.testing.assert_allclose(x, 0.0, atol=1e-9)
        assert dt * u @ u > turn.energy_N2m2s


@TURNS
def test_energy_turn_trace_of_k_u_decreases_every_step_2_6(energy_turn):
    _, res = energy_turn
    assert np.all(np.diff(res.trace_k_u) < 0)
    assert np.all(res.trace_increment < 0)


@TURNS
def test_energy_turn_reaches_seed_accuracy_by_320s_and_stays(energy_turn):
    setup, res = energy_turn
    settle = res.settle_time_s()
    assert settle <= 320.0
    end = slice(int(round(settle / setup.dt_s)), None)
    assert np.all(res.angle_deg[end] <= 0.2) and np.all(res.rate_norm_degps[end] <= 0.02)


@pytest.mark.xfail(
    strict=True,
    reason="seed data as printed (f1_i, f2_i of eq. 4.6) bring the error under 0.2 deg "
    "only at ~313-316 s; at 300 s it is ~0.34 deg per axis, 0.39 deg in total",
)
@TURNS
def test_energy_turn_errors_within_seed_tolerance_at_300s(energy_turn):
    setup, res = energy_turn
    k = setup.n_turn_steps
    assert res.angle_deg[k] <= 0.2 and res.rate_norm_degps[k] <= 0.02


def _linear_turn_error_deg(config: EnergySavingConfig, n_steps: int) -> NDArray[np.float64]:
    """Principal error angle (deg) of the linear loop (3.9) + law, perfect measurements.

    The total momentum is zero (gyrodines start balanced), so F = 0 and A_i, B_i are
    constant: the double integrator the seed linearises to.
    """
    a, b = given_system(J_INV, np.zeros(3), config.dt_s)
    ctl = EnergySavingController(config)
    x = X0.copy()
    state = EnergySavingState.initial(config, x)
    out = np.empty(n_steps + 1)
    out[0] = np.linalg.norm(x[:3])
    for i in range(n_steps):
        x = a @ x + b @ state.u_Nm
        state, _ = ctl.update(state, a, b, x)
        out[i + 1] = np.linalg.norm(x[:3])
    return np.degrees(out)


@pytest.fixture(scope="module")
def printed_error_deg() -> NDArray[np.float64]:
    """The linear loop's error under the printed data over 330 s, the reference of the
    tests below: computed once for the module (each case computed it again)."""
    out = _linear_turn_error_deg(CONFIG, 3300)
    out.flags.writeable = False
    return out


@pytest.mark.parametrize(
    ("which", "factor"),
    [
        *[(w, f) for w in ("state_var", "control_var0_N2m2", "meas_var") for f in (1e-2, 1e2)],
        ("degrees", (np.pi / 180.0) ** 2),
    ],
)
def test_seed_000_accuracy_at_300s_is_set_by_printed_f1_f2_not_by_covariances(
    which, factor, printed_error_deg
):
    """Why the xfail above is the seed's data, not our tuning (seed section 4, eq. 4.6).

    The law makes X follow the auxiliary system; where X is at 300 s is fixed by C_i
    (f1_i, f2_i) and D_i = -B_i. Scaling K_X and K_xi, K_U0 or K_eps by 1e-2 or 1e2, or
    reading the state in degrees (K_X, K_xi, K_eps divided by (180/pi)^2), moves the
    300-s error by under 2 %: it stays ~0.39 deg, twice the seed's 0.2 deg, and 0.2 deg
    is first reached after 310 s in every case.
    """
    base = printed_error_deg
    if which == "degrees":
        cfg = dataclasses.replace(
            CONFIG,
            state_var=tuple(np.multiply(CONFIG.state_var, factor)),
            aux_var=tuple(np.multiply(CONFIG.aux_var, factor)),
            meas_var=tuple(np.multiply(CONFIG.meas_var, factor)),
        )
    elif which == "state_var":
        cfg = dataclasses.replace(
            CONFIG,
            state_var=tuple(np.multiply(CONFIG.state_var, factor)),
            aux_var=tuple(np.multiply(CONFIG.aux_var, factor)),
        )
    elif which == "meas_var":
        cfg = dataclasses.replace(CONFIG, meas_var=tuple(np.multiply(CONFIG.meas_var, factor)))
    else:
        cfg = dataclasses.replace(CONFIG, control_var0_N2m2=CONFIG.control_var0_N2m2 * factor)
    err = _linear_turn_error_deg(cfg, 3300)
    assert err[3000] == pytest.approx(base[3000], rel=0.02)
    assert err[3000] > 0.35
    first_within = np.flatnonzero(err <= 0.2)[0] * CONFIG.dt_s
    assert first_within > 310.0


def test_seed_000_300s_point_needs_f1_six_percent_above_the_print(printed_error_deg):
    """What the seed's 300-s accuracy would take (our computation, not the seed's):
    f1_0 = 2.65e-5 instead of the printed 2.5e-5 (growth unchanged) brings the linear
    loop within 0.2 deg and 0.02 deg/s at 300 s (the full gyrodine simulation's error
    and index Z are in docs/attitude.md, from ``paper_figures.json``'s
    ``resurs/f1_raised``)."""
    printed = printed_error_deg[3000]  # (its first 3000 steps: the same loop)
    cfg = dataclasses.replace(CONFIG, f1_0=2.65e-5)
    moved = _linear_turn_error_deg(cfg, 3000)[3000]
    assert printed > 0.35 and moved <= 0.2


@TURNS
def test_energy_turn_gyro_momentum_returns_to_zero(energy_turn):
    """Seed Fig. 9: K_G returns to zero. The total momentum J w + K_G is conserved (zero),
    so |K_G| at rest-within-tolerance is bounded by |J| * 0.02 deg/s."""
    setup, res = energy_turn
    h = res.gyro_momentum_Nms
    w = np.radians(res.rate_degps)
    np.testing.assert_allclose(w @ J.T + h, 0.0, atol=1e-6)
    settle = int(round(res.settle_time_s() / setup.dt_s))
    bound = np.linalg.norm(J, 2) * np.radians(0.02)
    assert np.all(np.linalg.norm(h[settle:], axis=1) <= bound)
    assert np.linalg.norm(h[-1]) < 0.01 * np.linalg.norm(h, axis=1).max()
    assert res.singular_steps == 0


@TURNS
def test_energy_index_near_seed_2150_and_above_lower_bound(energy_turn):
    setup, res = energy_turn
    z = res.energy_N2m2s()
    assert z == pytest.approx(2150.0, rel=0.10)
    assert z > lower_bound_energy_N2m2s(setup)


@TURNS
def test_euler_baseline_tracks_profile_and_costs_3x_the_energy_law(euler_turn, energy_turn):
    setup, res = euler_turn
    k = setup.n_turn_steps
    assert res.angle_deg[k] <= 0.2 and res.rate_norm_degps[k] <= 0.02
    # index of the ideal profile: M = J e s''(t) (total momentum zero: no gyroscopic term)
    theta0 = np.linalg.norm(setup.initial_error_rad)
    axis = setup.initial_error_rad / theta0
    eu = setup.euler
    prof = EulerAxisProfile(theta0, setup.duration_s, eu.accel_time_s, eu.jerk_time_s)
    t = np.linspace(0, setup.duration_s, 300001)
    ideal = np.sum((J @ axis) ** 2) * np.trapezoid(prof.accel(t) ** 2, t)
    z = res.energy_N2m2s()
    assert z == pytest.approx(ideal, rel=0.03)
    # CALIBRATION, not a reproduction: the seed gives no phase durations; the default
    # accel_time_s was chosen so that Z lands near the seed's 11200 (section 5, Fig. 5)
    assert z == pytest.approx(11200.0, rel=0.02)
    assert z >= 3.0 * energy_turn[1].energy_N2m2s()


def test_seed_u0_removes_the_initial_torque_oscillation():
    """Seed Fig. 8 vs Fig. 2: with U0 = (-5.4, -1.1, -2.4) N m the swing of the torques in
    the first 30 s almost disappears (excess total variation < 10 % of the U0 = 0 case)."""
    setup = setup_from_scenario("test", {"duration_s": 30.0, "horizon_s": 30.0})
    zero = simulate_turn(setup, "energy").initial_oscillation_Nm()
    seeded_setup = dataclasses.replace(
        setup, energy=dataclasses.replace(setup.energy, u0_Nm=tuple(SEED_U0_NM))
    )
    seeded = simulate_turn(seeded_setup, "energy").initial_oscillation_Nm()
    assert seeded < 0.1 * zero


@TURNS
def test_a_turn_that_never_settles_reads_inf_and_is_counted(energy_turn):
    """docs/results.md: ``settle_time_s`` is inf for a run that never settles, and the
    gyrodine loop's summary counts such runs (``not_settled``) and keeps them in its
    statistics, as the other attitude loops do (it read NaN and dropped them: a mean
    over the settled runs alone, and "not settled: 0 runs" printed)."""
    import pandas as pd
    from kalman_vs_infoset.experiments import attitude_cmg

    setup, res = energy_turn
    never = dataclasses.replace(res, angle_tol_deg=0.0)  # the error never reaches 0 deg
    assert never.settle_time_s() == np.inf
    settled = res.settle_time_s()
    assert np.isfinite(settled)
    ok = pd.DataFrame({"settle_time_s": [never.settle_time_s(), settled, settled]})
    out = attitude_cmg.summarise(setup, "energy", "game", "box", 3, 0, ok, 0)
    assert out["not_settled"] == 1
    assert out["settle_time_s"]["max"] == np.inf and out["settle_time_s"]["p50"] == settled
