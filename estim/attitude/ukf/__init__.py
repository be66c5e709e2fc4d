"""The UKF on the attitude error state."""

from kalman_vs_infoset.estim.attitude.ukf.options import UkfAttitudeOptions
from kalman_vs_infoset.estim.registry import declare

REGISTRATIONS = (
    declare("ukf", "attitude", UkfAttitudeOptions, doc="UKF on the error state", rank=1),
)
