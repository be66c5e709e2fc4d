"""The UKF on the attitude error state."""

from kalman_vs_infoset.estim.attitude.ukf.options import UkfAttitudeOptions
from kalman_vs_infoset.estim.registry import declare

# the Kalman baseline of the attitude sets (Okabe & Ito 2008 bluish green, as the
# intercept UKF)
REGISTRATIONS = (
    declare("ukf", "attitude", UkfAttitudeOptions, doc="UKF on the error state", rank=1,
            roles=("baseline", "yardstick"), label="UKF", colour="#009E73"),
)  # fmt: skip
