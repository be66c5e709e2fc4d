"""Options of the bootstrap particle filter of a channel."""

from __future__ import annotations

from typing import Annotated, Literal

from kalman_vs_infoset.estim.intercept.options import InterceptOptions
from pydantic import Field


class PfOptions(InterceptOptions):
    """Options of the particle filter
    (:class:`~kalman_vs_infoset.estim.intercept.pf.estimator.ParticleChannelEstimator`)."""

    n_particles: Annotated[int, Field(ge=10, le=1_000_000, description="particles")] = 2000
    seed: Annotated[
        int, Field(ge=0, le=2**63 - 1, description="root of the filter's random streams")
    ] = 0
    n_sigma: Annotated[
        float, Field(ge=0.5, le=10.0, description="contains: radius of the moments' ellipsoid")
    ] = 3.0
    resample_threshold: Annotated[
        float, Field(ge=0.0, le=1.0, description="resample when N_eff < this fraction of N")
    ] = 0.5
    resampler: Annotated[
        Literal["systematic", "stratified"], Field(description="resampling scheme")
    ] = "systematic"
    roughening: Annotated[
        float, Field(ge=0.0, le=10.0, description="Gordon et al.'s roughening constant K")
    ] = 0.2
    disturbance: Annotated[
        Literal["uniform", "gaussian"], Field(description="distribution of v (variance nu^2/3)")
    ] = "uniform"
    bearing_error: Annotated[
        Literal["uniform", "gaussian"],
        Field(description="likelihood: bounded (uniform) or normal of variance a^2/3"),
    ] = "uniform"

    def build(self, setting):
        from kalman_vs_infoset.estim.intercept.pf.estimator import ParticleChannelEstimator

        return ParticleChannelEstimator(
            setting.model, closing_speed_mps=setting.closing_speed_mps, **self.model_dump()
        )


#: the defaults (the estimator's dataclass fields take theirs from here)
DEFAULTS = PfOptions()
