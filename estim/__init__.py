"""Estimators behind one interface: the information set, EKF and UKF."""

from kalman_vs_infoset.estim.base import (
    Belief,
    Estimator,
    Extremes,
    PerfectEstimator,
    PointBelief,
    Status,
)

__all__ = ["Belief", "Estimator", "Extremes", "PerfectEstimator", "PointBelief", "Status"]
