"""Options of the EKF and UKF of a channel, each read as its n-sigma ellipsoid."""

from __future__ import annotations

from typing import Annotated, ClassVar

from kalman_vs_infoset.estim.intercept.options import InterceptOptions
from pydantic import Field

#: what a filter's belief reports to a trace (:meth:`GaussianBelief.trace_fields
#: <kalman_vs_infoset.estim.intercept.gaussian.belief.GaussianBelief.trace_fields>`): here,
#: beside the options, so that the registry's scan imports no filter
GATE_FIELDS = ("n_sigma", "innovation_outliers")


class KalmanOptions(InterceptOptions):
    """Options of the Kalman filters of a channel
    (:class:`~kalman_vs_infoset.estim.intercept.gaussian.estimator.KalmanChannelEstimator`)."""

    #: the filter (``"ekf"`` or ``"ukf"``): one options class per registration
    kind: ClassVar[str] = "ekf"
    legacy_keys: ClassVar[dict[str, str]] = {
        "kalman_sigma": "n_sigma",
        "kalman_range_constraint": "range_constraint",
        "kalman_noise_inflation": "noise_inflation",
    }

    n_sigma: Annotated[
        float, Field(ge=0.5, le=10.0, description="radius of the ellipsoid, standard deviations")
    ] = 3.0
    range_constraint: Annotated[
        bool, Field(description="project the range estimate onto the a-priori interval")
    ] = False
    noise_inflation: Annotated[
        float, Field(ge=1.0, le=1e6, description="factor on every noise variance, R and Q")
    ] = 1.0

    def build(self, setting):
        from kalman_vs_infoset.estim.intercept.gaussian.estimator import KalmanChannelEstimator

        return KalmanChannelEstimator(
            setting.model,
            kind=self.kind,
            n_sigma=self.n_sigma,
            range_constraint=self.range_constraint,
            noise_inflation=self.noise_inflation,
            closing_speed_mps=setting.closing_speed_mps,
        )


class UkfOptions(KalmanOptions):
    """Options of the UKF of a channel (the EKF's)."""

    kind: ClassVar[str] = "ukf"


#: the defaults (the estimator's dataclass fields take theirs from here)
DEFAULTS = KalmanOptions()
