"""The guidance layer's constructors refuse gains and parameters that are NaN or
infinite (each passed a ``> 0`` check: ``inf > 0`` holds, and ``nan <= 0`` is false,
so a NaN ``rho`` passed ``rho <= 0 or rho >= 1``), with one ``ValueError`` naming the
field; the limits documented as "inf for no limit" keep accepting inf."""

import numpy as np
import pytest
from kalman_vs_infoset.guidance.attitude.cmg import CmgCluster
from kalman_vs_infoset.guidance.attitude.energy import EnergySavingConfig
from kalman_vs_infoset.guidance.attitude.euler_turn import EulerAxisProfile, EulerTurnTracker
from kalman_vs_infoset.guidance.attitude.game import GameLaw
from kalman_vs_infoset.guidance.attitude.pd import QuaternionPD
from kalman_vs_infoset.guidance.attitude.plant import RigidBody
from kalman_vs_infoset.guidance.attitude.wheels import ReactionWheels
from kalman_vs_infoset.guidance.intercept.law import ImpulseLimits
from kalman_vs_infoset.guidance.intercept.truth import TwoBodyTruth

BODY = RigidBody(np.diag([10.0, 12.0, 14.0]))
GAME = {"a_star": [1.0, 1.0, 1.0], "rho": [0.5, 0.5, 0.5], "period_s": 0.1}
PROFILE = {"angle_rad": 1.0, "duration_s": 10.0, "accel_time_s": 2.0, "jerk_time_s": 0.5}
TRACKER = {
    "inertia_kgm2": np.diag([10.0, 12.0, 14.0]),
    "error0_rotvec_rad": np.array([0.1, 0.2, 0.3]),
    "duration_s": 10.0,
    "accel_time_s": 2.0,
    "jerk_time_s": 0.5,
}

CASES = [
    (GameLaw, GAME, "rho", [0.5, np.nan, 0.5], "rho"),
    (GameLaw, GAME, "period_s", np.inf, "period_s"),
    (QuaternionPD, {"body": BODY, "k_q": 1.0, "k_w": 1.0}, "k_q", np.inf, "k_q"),
    (QuaternionPD, {"body": BODY, "k_q": 1.0, "k_w": 1.0}, "k_w", np.inf, "k_w"),
    (EnergySavingConfig, {}, "dt_s", np.inf, "dt_s"),
    (EnergySavingConfig, {}, "f1_0", np.nan, "f1_0"),
    (EnergySavingConfig, {}, "f2_growth", np.inf, "f2_growth"),
    (EnergySavingConfig, {}, "control_var0_N2m2", np.inf, "control_var0_N2m2"),
    (EnergySavingConfig, {}, "u0_Nm", (0.0, np.nan, 0.0), "u0_Nm"),
    (EulerAxisProfile, PROFILE, "angle_rad", np.inf, "angle_rad"),
    (EulerAxisProfile, PROFILE, "duration_s", np.inf, "duration_s"),
    (EulerTurnTracker, TRACKER, "natural_freq_radps", np.inf, "natural_freq_radps"),
    (EulerTurnTracker, TRACKER, "error0_rotvec_rad", np.array([np.inf, 0, 0]), "error0"),
    (CmgCluster, {}, "rotor_momentum_Nms", np.inf, "rotor_momentum_Nms"),
    (CmgCluster, {}, "sr_damping", np.inf, "sr_damping"),
    (CmgCluster, {}, "pair_azimuths_deg", (0.0, np.nan, 240.0), "pair_azimuths_deg"),
    (TwoBodyTruth, {}, "mu_km3ps2", np.inf, "mu_km3ps2"),
    (TwoBodyTruth, {}, "sun_distance_km", np.nan, "sun_distance_km"),
]


@pytest.mark.parametrize(
    "cls, base, field, bad, named", CASES, ids=[f"{c[0].__name__}.{c[2]}" for c in CASES]
)
def test_a_parameter_that_is_not_finite_is_refused_naming_it(cls, base, field, bad, named):
    cls(**base)  # the valid base is accepted
    with pytest.raises(ValueError, match=named):
        cls(**{**base, field: bad})


def test_limits_documented_as_inf_for_none_still_accept_inf():
    assert ImpulseLimits(max_mps=np.inf, reserve_mps=np.inf).apply(3.0, 0.0) == 3.0
    wheels = ReactionWheels(torque_max_Nm=np.inf, momentum_max_Nms=np.inf)
    assert wheels.torque_max_Nm == np.inf
