"""The attitude-control library refuses bad input with a ValueError (TypeError for a wrong
type) that names the argument, where it used to hang (an infinite integration step),
return a wrong result silently (a sign-flipped torque, NaN samples read as "settled", a
negative regime angle) or fail deep inside numpy/scipy with a message that names nothing
of the caller's (``Singular matrix``, ``zero norm quaternions``, ``ZeroDivisionError``).
Valid calls keep their results (values recorded before the checks were added)."""

import numpy as np
import pytest
from kalman_vs_infoset.guidance.attitude.energy import (
    EnergySavingConfig,
    EnergySavingController,
    EnergySavingState,
    given_system,
)
from kalman_vs_infoset.guidance.attitude.euler_turn import EulerTurnTracker
from kalman_vs_infoset.guidance.attitude.pd import (
    QuaternionPD,
    regime_boundaries,
    rest_to_rest_initial_state,
    settle_time,
)
from kalman_vs_infoset.guidance.attitude.plant import AttitudeState, RigidBody, propagate
from kalman_vs_infoset.guidance.attitude.wheels import ReactionWheels, simulate_closed_loop

BODY = RigidBody.diagonal([1.5, 1.5, 1.5])
REST = AttitudeState([0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])
TRACKER = {
    "error0_rotvec_rad": [0.1, 0.2, 0.3],
    "duration_s": 100.0,
    "accel_time_s": 20.0,
    "jerk_time_s": 5.0,
}
TRACKER_POINT = (7.0, [0.09, 0.19, 0.28], [0.001, -0.002, 0.003], [0.1, 0.0, 0.0])
RW_ARGS = {"k_q": 1.375, "k_w": 2.625, "inertia_kgm2": 1.5}
RW_LIMITS = {"torque_max_Nm": 0.0275, "momentum_max_Nms": 0.2}


# -- 1: plant.propagate --------------------------------------------------------------
@pytest.mark.parametrize("dt_s", [np.inf, np.nan, 0.0, -1.0])
def test_propagate_refuses_a_step_that_is_not_positive_and_finite(dt_s):
    # inf used to hang: solve_ivp stepped towards t = inf for ever
    with pytest.raises(ValueError, match="dt_s"):
        propagate(BODY, REST, [0.0, 0.0, 0.0], dt_s)


# -- 2: EulerTurnTracker's inertia -----------------------------------------------------
@pytest.mark.parametrize(
    "inertia, what",
    [
        (-np.eye(3), "positive definite"),  # used to flip the torque's sign
        (np.zeros((3, 3)), "positive definite"),  # used to give no torque
        (np.full((3, 3), np.nan), "finite"),  # used to give NaN
        (np.eye(2), "shape"),  # used to fail in a matmul
        (np.array([[1.0, 0.5, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "symmetric"),
    ],
)
def test_euler_turn_tracker_refuses_an_inertia_that_is_not_spd(inertia, what):
    with pytest.raises(ValueError, match=f"inertia_kgm2 must .*{what}"):
        EulerTurnTracker(inertia, **TRACKER)


def test_euler_turn_tracker_keeps_a_valid_inertia_as_given():
    """The check keeps the inertia's values: the tracker holds the same matrix."""
    inertia = np.diag([10.0, 12.0, 14.0])
    tracker = EulerTurnTracker(inertia, **TRACKER)
    np.testing.assert_array_equal(tracker.inertia_kgm2, inertia)
    assert np.isfinite(tracker.torque(*TRACKER_POINT)).all()


# -- 3: settle_time --------------------------------------------------------------------
@pytest.mark.parametrize(
    "time_s, angle_deg, rate_degps, named",
    [
        ([0.0, 1.0, 2.0], [np.nan] * 3, [0.0] * 3, "angle_deg"),  # used to be "settled at 0"
        ([0.0, 1.0, 2.0], [0.0] * 3, [0.0, np.nan, 0.0], "rate_degps"),
        ([], [], [], "time_s"),  # used to raise IndexError
        ([0.0, 1.0, 2.0], [0.0], [0.0, 0.0, 0.0], "angle_deg"),  # used to return 0.0
        ([0.0, 1.0, 2.0], [0.0] * 3, [0.0, 0.0], "rate_degps"),
    ],
)
def test_settle_time_refuses_nan_empty_and_mismatched_samples(time_s, angle_deg, rate_degps, named):
    with pytest.raises(ValueError, match=named):
        settle_time(time_s, angle_deg, rate_degps)


def test_settle_time_is_unchanged_for_valid_samples():
    t = np.arange(6.0)
    assert settle_time(t, [1, 0, 0, 1, 0, 0], [0] * 6, 0.5, 0.5) == 4.0
    assert settle_time(t, [1, 0, 0, 0, 0, 1], [0] * 6, 0.5, 0.5) == np.inf
    assert settle_time(t, [np.inf] * 6, [0] * 6) == np.inf  # an infinite error: not settled


# -- 4: regime_boundaries --------------------------------------------------------------
@pytest.mark.parametrize(
    "field, bad",
    [
        ("k_q", 0.0),  # used to raise ZeroDivisionError
        ("inertia_kgm2", 0.0),
        ("torque_max_Nm", 0.0),
        ("k_q", -1.375),  # used to return a negative angle
        ("k_w", -2.625),
        ("momentum_max_Nms", np.nan),
        ("torque_max_Nm", np.inf),
    ],
)
def test_regime_boundaries_refuse_arguments_that_are_not_positive_and_finite(field, bad):
    with pytest.raises(ValueError, match=field):
        regime_boundaries(**{**RW_ARGS, **RW_LIMITS, field: bad})


def test_regime_boundaries_are_the_seed_s_formulas_for_valid_arguments():
    """eq. (14) and (23) of the reaction-wheel paper, written out here."""
    phi10, phi20 = regime_boundaries(**RW_ARGS, **RW_LIMITS)
    kq, kw, j = RW_ARGS["k_q"], RW_ARGS["k_w"], RW_ARGS["inertia_kgm2"]
    m, lm = RW_LIMITS["torque_max_Nm"], RW_LIMITS["momentum_max_Nms"]
    assert phi10 == pytest.approx(2 * np.arcsin(m / (kq * j)), rel=1e-14)
    assert phi20 == pytest.approx(
        lm**2 / (2 * j * m) + 2 * np.arcsin(kw * lm / (kq * j)), rel=1e-14
    )


# -- 5: EnergySavingConfig's variances ----------------------------------------------
def test_energy_config_refuses_variances_that_make_the_gain_singular():
    zero = (0.0,) * 6
    with pytest.raises(ValueError, match="state_var or meas_var"):
        EnergySavingConfig(state_var=zero, aux_var=zero, meas_var=zero)
    # one component zero in both is enough: S loses that direction
    one_zero = (0.0, 1.0, 1.0, 0.01, 0.01, 0.01)
    with pytest.raises(ValueError, match=r"state_var or meas_var.*\[0\]"):
        EnergySavingConfig(state_var=one_zero, meas_var=(0.0,) + (1e-8,) * 5)


@pytest.mark.parametrize(
    "variances",
    [
        {"state_var": (0.0,) * 6},  # the measurement variance alone keeps S regular
        {"meas_var": (0.0,) * 6, "aux_var": (0.0,) * 6},  # the state variance alone
        {"state_var": (1.0, 1.0, 1.0, 0.0, 0.0, 0.0), "meas_var": (0.0,) * 3 + (1e-10,) * 3},
    ],
)
def test_energy_controller_updates_with_the_variances_still_accepted(variances):
    cfg = EnergySavingConfig(**variances)
    a, b = given_system(np.diag([1.0 / 22147.0, 1.0 / 10213.0, 1.0 / 24497.0]), [0, 0, 0], 0.1)
    x0 = np.array([0.1, -0.2, 0.3, 0.0, 0.0, 0.0])
    state, diag = EnergySavingController(cfg).update(
        EnergySavingState.initial(cfg, x0), a, b, a @ x0
    )
    assert np.isfinite(state.u_Nm).all() and np.isfinite(diag.gain).all()


# -- 6: rest_to_rest_initial_state -----------------------------------------------------
@pytest.mark.parametrize(
    "axis, angle_deg, named",
    [
        ([0.0, 0.0, 0.0], 30.0, "axis"),  # used to be scipy's "zero norm quaternions"
        ([np.nan, 0.0, 1.0], 30.0, "axis"),
        ([0.0, 1.0], 30.0, "axis"),
        ([0.0, 0.0, 1.0], np.nan, "angle_deg"),
        ([0.0, 0.0, 1.0], np.inf, "angle_deg"),
    ],
)
def test_rest_to_rest_initial_state_refuses_a_bad_axis_or_angle(axis, angle_deg, named):
    with pytest.raises(ValueError, match=named):
        rest_to_rest_initial_state(axis, angle_deg)


def test_rest_to_rest_initial_state_is_unchanged_for_a_valid_turn():
    x0 = rest_to_rest_initial_state([0.0, 0.0, 2.0], 150.0)
    # a turn by 150 deg about z: (0, 0, sin 75 deg, cos 75 deg), at rest
    half = np.radians(75.0)
    expected = [0.0, 0.0, np.sin(half), np.cos(half)] + [0.0] * 6
    np.testing.assert_allclose(x0, expected, rtol=1e-15, atol=1e-15)


# -- 7: QuaternionPD's gains -----------------------------------------------------------
@pytest.mark.parametrize("field", ["k_q", "k_w"])
def test_quaternion_pd_names_a_gain_of_the_wrong_type(field):
    gains = {"k_q": 1.0, "k_w": 1.0, field: "1"}
    with pytest.raises(TypeError, match=f"{field} must be a positive finite number, got '1'"):
        QuaternionPD(BODY, **gains)


@pytest.mark.parametrize("field, bad", [("k_q", 0.0), ("k_w", -1.0), ("k_w", np.nan)])
def test_quaternion_pd_names_a_gain_that_is_not_positive(field, bad):
    with pytest.raises(ValueError, match=field):
        QuaternionPD(BODY, **{"k_q": 1.0, "k_w": 1.0, field: bad})


# -- 8: simulate_closed_loop -----------------------------------------------------------
def _loop(**overrides):
    law = QuaternionPD(BODY, 1.375, 2.625)
    args = {
        "body": BODY,
        "wheels": ReactionWheels(0.0275, 0.2),
        "control": lambda _t, x: law.torque(x),
        "x0": rest_to_rest_initial_state([0.0, 0.0, 1.0], 30.0),
        "duration_s": 1.0,
        "control_period_s": 0.1,
    }
    return simulate_closed_loop(**{**args, **overrides})


@pytest.mark.parametrize(
    "field, bad",
    [
        ("duration_s", np.inf),  # used to raise OverflowError
        ("control_period_s", np.inf),  # used to return time_s = [nan]
        ("duration_s", np.nan),
        ("control_period_s", 0.0),
        ("substeps", 0),
    ],
)
def test_simulate_closed_loop_refuses_bad_durations_and_substeps(field, bad):
    with pytest.raises(ValueError, match=field):
        _loop(**{field: bad})


def test_simulate_closed_loop_names_substeps_that_are_not_an_integer():
    # used to be range()'s "'float' object cannot be interpreted as an integer"
    with pytest.raises(TypeError, match="substeps must be an integer"):
        _loop(substeps=1.5)


def test_simulate_closed_loop_is_unchanged_for_valid_arguments():
    tr = _loop(substeps=np.int64(2))  # a numpy integer is an integer
    np.testing.assert_allclose(tr.time_s, np.arange(11) * 0.1)
    assert tr.x.shape == (11, 10) and np.isfinite(tr.x).all()
