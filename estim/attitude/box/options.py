"""Options of the guaranteed attitude box, which the set families intersect with."""

from __future__ import annotations

from typing import Annotated

from kalman_vs_infoset.estim.options import EstimatorOptions
from pydantic import Field


class BoxAttitudeOptions(EstimatorOptions):
    """Options of the guaranteed attitude box
    (:class:`~kalman_vs_infoset.estim.attitude.box.estimator.BoxAttitudeEstimator`)."""

    abs_inflation_rad: Annotated[
        float, Field(ge=0.0, le=1e-3, description="absolute inflation per step, rad and rad/s")
    ] = 1e-12

    def build(self, setting):
        from kalman_vs_infoset.estim.attitude.box.estimator import BoxAttitudeEstimator

        return BoxAttitudeEstimator(setting, abs_inflation_rad=self.abs_inflation_rad)


#: the defaults (the estimator's dataclass fields take theirs from here)
DEFAULTS = BoxAttitudeOptions()
