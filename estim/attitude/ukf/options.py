"""Options of the attitude UKF on the multiplicative error state."""

from __future__ import annotations

from typing import Annotated

from kalman_vs_infoset.estim.options import EstimatorOptions
from pydantic import Field


class UkfAttitudeOptions(EstimatorOptions):
    """Options of the attitude UKF
    (:class:`~kalman_vs_infoset.estim.attitude.ukf.estimator.UkfAttitudeEstimator`)."""

    gate_prob: Annotated[
        float, Field(gt=0.0, lt=1.0, description="probability of the gate ellipsoid")
    ] = 0.997

    def build(self, setting):
        from kalman_vs_infoset.estim.attitude.ukf.estimator import UkfAttitudeEstimator

        return UkfAttitudeEstimator(setting, gate_prob=self.gate_prob)


#: the defaults (the estimator's dataclass fields take theirs from here)
DEFAULTS = UkfAttitudeOptions()
