"""Stochastic and robust filters as pure functions on immutable values: the H-infinity
filter (Simon 2006, ch. 11) and a bootstrap particle filter (Gordon et al. 1993)."""

from kalman_vs_infoset.estim.filters.hinf import (
    HInfinityEstimate,
    HInfinityModel,
    hinf_filter,
    hinf_step,
)
from kalman_vs_infoset.estim.filters.particle import (
    ParticleSet,
    bootstrap_step,
    stratified_resample,
    systematic_resample,
)

__all__ = [
    "HInfinityEstimate",
    "HInfinityModel",
    "ParticleSet",
    "bootstrap_step",
    "hinf_filter",
    "hinf_step",
    "stratified_resample",
    "systematic_resample",
]
