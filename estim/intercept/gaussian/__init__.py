"""The Kalman filters of a channel (EKF, UKF), each read as its n-sigma ellipsoid."""

from kalman_vs_infoset.estim.intercept.gaussian.options import (
    GATE_FIELDS,
    KalmanOptions,
    UkfOptions,
)
from kalman_vs_infoset.estim.registry import declare

# the Kalman baselines the reference set is compared with; the UKF is the yardstick of
# the step costs (colours: Okabe & Ito 2008, vermillion and bluish green)
REGISTRATIONS = (
    declare("ekf", "intercept", KalmanOptions, doc="EKF read as its n-sigma ellipsoid", rank=4,
            roles=("baseline",), label="EKF", colour="#D55E00", trace_fields=GATE_FIELDS),
    declare("ukf", "intercept", UkfOptions, doc="UKF read as its n-sigma ellipsoid", rank=5,
            roles=("baseline", "yardstick"), label="UKF", colour="#009E73",
            trace_fields=GATE_FIELDS),
)  # fmt: skip
