"""The Kalman filters of a channel (EKF, UKF), each read as its n-sigma ellipsoid."""

from kalman_vs_infoset.estim.intercept.gaussian.options import KalmanOptions, UkfOptions
from kalman_vs_infoset.estim.registry import declare

REGISTRATIONS = (
    declare("ekf", "intercept", KalmanOptions, doc="EKF read as its n-sigma ellipsoid", rank=4),
    declare("ukf", "intercept", UkfOptions, doc="UKF read as its n-sigma ellipsoid", rank=5),
)
