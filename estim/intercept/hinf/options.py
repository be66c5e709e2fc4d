"""Options of the H-infinity filter of a channel: the Kalman filters' own, and its bound."""

from __future__ import annotations

from typing import Annotated, ClassVar, Literal

from kalman_vs_infoset.estim.intercept.gaussian.options import KalmanOptions
from pydantic import Field


class HinfOptions(KalmanOptions):
    """Options of the H-infinity filter
    (:class:`~kalman_vs_infoset.estim.intercept.hinf.estimator.HInfinityChannelEstimator`)."""

    legacy_keys: ClassVar[dict[str, str]] = {}  # the flat kalman_* keys meant the EKF/UKF

    theta: Annotated[
        float,
        Field(ge=0.0, lt=1.0, description="bound J < 1/theta, relative weight (0: the EKF)"),
    ] = 0.05
    weight: Annotated[
        Literal["state", "zem"],
        Field(description="estimate the whole state or the zero-effort miss alone"),
    ] = "state"

    def build(self, setting):
        from kalman_vs_infoset.estim.intercept.hinf.estimator import HInfinityChannelEstimator

        return HInfinityChannelEstimator(
            setting.model,
            theta=self.theta,
            weight=self.weight,
            n_sigma=self.n_sigma,
            range_constraint=self.range_constraint,
            closing_speed_mps=setting.closing_speed_mps,
            noise_inflation=self.noise_inflation,
        )


#: the defaults (the estimator's dataclass fields take theirs from here)
DEFAULTS = HinfOptions()
