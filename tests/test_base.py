"""The estimator interface and the common attitude plant."""

import numpy as np
import pytest
from kalman_vs_infoset.estim import PerfectEstimator, PointBelief
from kalman_vs_infoset.guidance.attitude.plant import (
    AttitudeState,
    RigidBody,
    propagate,
    total_momentum_Nms,
)
from scipy.spatial.transform import Rotation


def test_point_belief_is_immutable_and_estimator_returns_new_values():
    belief = PointBelief(np.array([1.0, 2.0, 3.0]))
    with pytest.raises(ValueError):
        belief.state[0] = 5.0
    est = PerfectEstimator()
    new = est.update(belief, [4.0, 5.0, 6.0])
    assert new is not belief
    np.testing.assert_array_equal(belief.state, [1.0, 2.0, 3.0])
    ext = new.extremes(lambda p: p[:, 0] + p[:, 1])
    assert ext.min_value == ext.max_value == 9.0


def test_plant_conserves_total_momentum_and_matches_euler_torque_free_spin():
    """Torque-free: J w + h is constant in inertial axes; a pure spin about a
    principal axis stays a spin (analytic solution q(t) = rotation w t)."""
    body = RigidBody.diagonal([2.0, 3.0, 4.0])
    w0 = np.array([0.0, 0.0, 0.3])
    state = AttitudeState(Rotation.identity().as_quat(), w0, np.zeros(3))
    for _ in range(10):
        state = propagate(body, state, np.zeros(3), 0.5)
    expected = Rotation.from_rotvec(w0 * 5.0)
    assert (expected.inv() * state.rotation).magnitude() < 1e-8
    # momentum exchange with the actuator: body torque +M, actuator dh/dt = -M
    state = AttitudeState(Rotation.identity().as_quat(), [0.1, -0.2, 0.05], np.zeros(3))
    h_in0 = state.rotation.apply(total_momentum_Nms(body, state))
    state = propagate(body, state, [0.01, 0.02, -0.03], 2.0)
    h_in1 = state.rotation.apply(total_momentum_Nms(body, state))
    np.testing.assert_allclose(h_in1, h_in0, atol=1e-9)


@pytest.mark.parametrize("low, high", [(np.nan, 1.0), (0.0, np.nan), (np.nan, np.nan)])
def test_extremes_of_nan_say_the_belief_is_not_a_number(low, high):
    """A plug-in whose belief went NaN failed its run with "min_value nan exceeds
    max_value nan", which reads as the harness's fault; the error now says the belief
    is not a number."""
    from kalman_vs_infoset.estim.base import Extremes

    with pytest.raises(ValueError, match="are NaN: the belief is not a number"):
        Extremes(low, np.zeros(3), high, np.zeros(3))
    with pytest.raises(ValueError, match="exceeds max_value"):
        Extremes(2.0, np.zeros(3), 1.0, np.zeros(3))
