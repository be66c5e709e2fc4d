"""Estimators behind one interface: the information set, EKF and UKF."""

from estim.base import Belief, Estimator, Extremes, PerfectEstimator, PointBelief, Status

__all__ = ["Belief", "Estimator", "Extremes", "PerfectEstimator", "PointBelief", "Status"]
