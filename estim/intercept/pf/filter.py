"""The bootstrap particle filter (Gordon, Salmond & Smith 1993) as an immutable particle set.

A :class:`ParticleSet` holds ``N`` particles ``x^i`` (rows) and normalised weights
``w^i``; it approximates a distribution by ``sum_i w^i delta(x - x^i)``. One filter step is

1. **predict** -- ``x^i <- f(x^i) + u^i``, ``u^i`` drawn from the process noise
   (the bootstrap proposal: the transition density itself);
2. **update** -- ``w^i <- w^i p(y | x^i) / sum_j w^j p(y | x^j)`` (done in log space);
3. **resample** when the effective sample size ``N_eff = 1 / sum_i (w^i)^2`` falls under
   ``threshold * N`` (Kong, Liu & Wong 1994): ``N`` indices drawn with probabilities
   ``w^i``, then uniform weights. Gordon et al. resample at every step (``threshold = 1``
   does that; an ``N_eff`` equal to ``N`` is not under it).

Estimates (:meth:`ParticleSet.mean`, :meth:`ParticleSet.covariance`) are weighted
moments; take them after the update and before resampling, which only adds noise.

Randomness comes only from the ``numpy.random.Generator`` passed to each call. The
resamplers are filterpy's (``filterpy.monte_carlo.systematic_resample`` and
``stratified_resample``), restated here to draw their uniforms from that generator:
filterpy's functions call ``numpy.random.random``, the global state. Given the same
uniforms the indices are identical (a test replaces filterpy's ``random`` to show it);
``np.searchsorted`` replaces filterpy's Python loop, and the last cumulative weight is
set to exactly 1 so that rounding cannot push an index past the end (filterpy's loop
then raises ``IndexError``).

References
----------
N. J. Gordon, D. J. Salmond & A. F. M. Smith, "Novel approach to nonlinear/non-Gaussian
Bayesian state estimation", IEE Proceedings F 140(2), 107-113, 1993.
A. Kong, J. S. Liu & W. H. Wong, "Sequential imputations and Bayesian missing data
problems", J. American Statistical Association 89(425), 278-288, 1994.
R. Douc, O. Cappe & E. Moulines, "Comparison of resampling schemes for particle
filtering", ISPA 2005 (systematic and stratified resampling).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "ParticleSet",
    "bootstrap_step",
    "stratified_resample",
    "systematic_resample",
]

FloatArray = NDArray[np.float64]
Transition = Callable[[FloatArray], FloatArray]
NoiseSampler = Callable[[np.random.Generator, int], FloatArray]
Likelihood = Callable[[FloatArray], FloatArray]
Resampler = Callable[[FloatArray, np.random.Generator], NDArray[np.intp]]


def _indices(weights: FloatArray, positions: FloatArray) -> NDArray[np.intp]:
    """For each position in [0, 1), the first ``j`` with ``cumsum(w)[j] > position``."""
    cumulative = np.cumsum(weights)
    cumulative[-1] = 1.0
    return np.minimum(np.searchsorted(cumulative, positions, side="right"), len(weights) - 1)


def systematic_resample(weights: ArrayLike, rng: np.random.Generator) -> NDArray[np.intp]:
    """Systematic resampling: one uniform ``u``, positions ``(u + i) / N``."""
    w = np.asarray(weights, dtype=float)
    return _indices(w, (rng.random() + np.arange(len(w))) / len(w))


def stratified_resample(weights: ArrayLike, rng: np.random.Generator) -> NDArray[np.intp]:
    """Stratified resampling: one uniform per stratum, positions ``(u_i + i) / N``."""
    w = np.asarray(weights, dtype=float)
    return _indices(w, (rng.random(len(w)) + np.arange(len(w))) / len(w))


_RESAMPLERS: dict[str, Resampler] = {
    "systematic": systematic_resample,
    "stratified": stratified_resample,
}


@dataclass(frozen=True, eq=False)
class ParticleSet:
    """Particles (shape (N, n)) and normalised weights (shape (N,)); immutable.

    ``weights`` default to uniform; given weights are normalised on construction.
    """

    particles: FloatArray
    # None (uniform) is replaced by the normalised weights in __post_init__: typed as held
    weights: FloatArray = None  # type: ignore[assignment]

    def __post_init__(self) -> None:
        x = np.array(self.particles, dtype=float)
        if x.ndim == 1:
            x = x[:, None]
        if x.ndim != 2 or len(x) == 0 or not np.all(np.isfinite(x)):
            raise ValueError("particles must be a finite (N, n) array with N >= 1")
        if self.weights is None:
            w = np.full(len(x), 1.0 / len(x))
        else:
            w = np.array(self.weights, dtype=float).reshape(-1)
            if w.size != len(x) or np.any(w < 0) or not np.all(np.isfinite(w)) or w.sum() <= 0:
                raise ValueError("weights must be N finite non-negative numbers, not all zero")
            w = w / w.sum()
        x.setflags(write=False)
        w.setflags(write=False)
        object.__setattr__(self, "particles", x)
        object.__setattr__(self, "weights", w)

    @classmethod
    def _make(cls, x: FloatArray, w: FloatArray) -> ParticleSet:
        obj = object.__new__(cls)
        x.setflags(write=False)
        w.setflags(write=False)
        object.__setattr__(obj, "particles", x)
        object.__setattr__(obj, "weights", w)
        return obj

    @property
    def n_particles(self) -> int:
        return len(self.particles)

    @property
    def dim(self) -> int:
        return self.particles.shape[1]

    def mean(self) -> FloatArray:
        """``sum_i w^i x^i``."""
        return self.weights @ self.particles

    def covariance(self) -> FloatArray:
        """``sum_i w^i (x^i - m)(x^i - m)^T`` (the weighted second central moment)."""
        d = self.particles - self.mean()
        return (d * self.weights[:, None]).T @ d

    def ess(self) -> float:
        """Effective sample size ``1 / sum_i (w^i)^2`` (between 1 and N)."""
        return float(1.0 / np.sum(self.weights**2))

    def predict(
        self, transition: Transition, sample_noise: NoiseSampler, rng: np.random.Generator
    ) -> ParticleSet:
        """``x^i <- transition(x)[i] + sample_noise(rng, N)[i]``; weights unchanged.

        ``transition`` maps the (N, n) array of particles to an (N, n) array (vectorised);
        ``sample_noise(rng, N)`` returns N process-noise draws, shape (N, n).
        """
        moved = np.asarray(transition(self.particles), dtype=float)
        noise = np.asarray(sample_noise(rng, self.n_particles), dtype=float)
        new = (moved + noise).reshape(self.particles.shape)
        return ParticleSet._make(new, self.weights.copy())

    def update(self, likelihood: Likelihood) -> ParticleSet:
        """Reweight by ``likelihood(particles)`` (N values ``p(y | x^i)`` >= 0)."""
        with np.errstate(divide="ignore"):
            return self.update_log(lambda x: np.log(np.asarray(likelihood(x), dtype=float)))

    def update_log(self, log_likelihood: Likelihood) -> ParticleSet:
        """Reweight by ``exp(log_likelihood(particles))``, normalised in log space.

        Raises ``ValueError`` when every particle has zero likelihood (the filter has
        lost the state; a set-membership filter would report an empty set).
        """
        ll = np.asarray(log_likelihood(self.particles), dtype=float).reshape(-1)
        if ll.size != self.n_particles or np.any(np.isnan(ll)) or np.any(ll == np.inf):
            raise ValueError("log-likelihood must give N values, none NaN or +inf")
        with np.errstate(divide="ignore"):
            logw = np.log(self.weights) + ll
        top = logw.max()
        if not np.isfinite(top):
            raise ValueError("every particle has zero likelihood")
        w = np.exp(logw - top)
        return ParticleSet._make(self.particles.copy(), w / w.sum())

    def resample(
        self,
        rng: np.random.Generator,
        method: Literal["systematic", "stratified"] | Resampler = "systematic",
    ) -> ParticleSet:
        """Draw N particles with probabilities ``w^i``; uniform weights after."""
        resampler = _RESAMPLERS[method] if isinstance(method, str) else method
        idx = np.asarray(resampler(self.weights, rng))
        x = self.particles[idx]
        return ParticleSet._make(x, np.full(len(x), 1.0 / len(x)))

    def resample_if_needed(
        self,
        rng: np.random.Generator,
        threshold: float = 0.5,
        method: Literal["systematic", "stratified"] | Resampler = "systematic",
    ) -> ParticleSet:
        """:meth:`resample` when ``ess() < threshold * N``, otherwise this set."""
        if not 0.0 <= threshold <= 1.0:
            raise ValueError("threshold must lie in [0, 1]")
        if self.ess() < threshold * self.n_particles * (1.0 - 1e-12):
            return self.resample(rng, method)
        return self


def bootstrap_step(
    ps: ParticleSet,
    rng: np.random.Generator,
    transition: Transition,
    sample_noise: NoiseSampler,
    likelihood: Likelihood,
    threshold: float = 0.5,
    method: Literal["systematic", "stratified"] | Resampler = "systematic",
) -> tuple[ParticleSet, ParticleSet]:
    """Predict, update and (if needed) resample. Returns ``(weighted, next)``: the
    updated set to read estimates from, and the set to carry to the next step."""
    weighted = ps.predict(transition, sample_noise, rng).update(likelihood)
    return weighted, weighted.resample_if_needed(rng, threshold, method)
