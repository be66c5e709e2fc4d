"""A bootstrap particle filter of one intercept guidance channel (Gordon et al. 1993).

State. Each particle is a physical row ``(Y, V, x, e)``: lateral offset (m) and velocity
(m/s) of the channel, range along the nominal axis (m) and the particle's own closing
speed (m/s), drawn once in the estimator's closing-speed interval ``[e_lo, e_hi]`` and
kept (the truth's closing speed is a constant the bearings reveal only slowly, not a
noise). Why physical rather than the EKF's ``(alpha, w, x)``: the auxiliary model of
models.md §1.3 is, in these coordinates, the double integrator
``Y'' = v, x' = -e`` (with ``alpha = Y/x``: ``alpha' = omega`` and
``omega' = 2 e omega/x + v/x``), so the one-step map is exact and linear for every
particle's own ``e`` (in ``w = omega x^2/e`` the nominal ``e`` is built into the
coordinate); the a-priori boxes are boxes in these coordinates, so the first cloud is
drawn from the prior itself (uniform), not from a moment-matched Gaussian; and the
bearing ``atan2(Y, x)`` is the truth's, which a particle filter needs no linearisation of.

One step (``Delta``, :meth:`ParticleChannelEstimator.predict`)::

    V <- V + k (+ u, u uniform in +-dk)             the impulse, at the step's start
    Y <- Y + V Delta + v Delta^2/2,  V <- V + v Delta,  x <- x - e Delta,  e <- e

with ``v`` drawn per particle and step uniform in ``[-nu, nu]`` (``disturbance =
"gaussian"``: normal with the same variance ``nu^2/3``). Before it, the cloud is
resampled when its effective sample size is under ``resample_threshold N`` (the
package's systematic or stratified resampler), then roughened: each coordinate is
jittered by a normal of standard deviation ``K E_j N^(-1/d)``, ``E_j`` the coordinate's
spread over the cloud, ``d = 4`` (Gordon et al.'s roughening against sample
impoverishment: the static ``x`` and ``e`` would otherwise collapse onto a few values;
``e`` is reflected into its interval); then particles that would pass under ``eps``
(``x < eps + e Delta``) get zero weight (the set's threshold, models.md §1.4; every
particle dropped: status ``TERMINAL``).

Likelihood (:meth:`ParticleChannelEstimator.update`): a bearing error uniform within
its bound, ``p(z | particle) = 1{|z - atan2(Y, x)| <= a(d)}`` up to a constant, with
``a`` taken at the particle's range ``d = hypot(Y, x)`` (the smallest its 3D range can
be, so the widest bound: a particle the sensor could have produced is never dropped).
A bounded likelihood: particles outside the strip get zero weight. When every particle
gets zero weight the measurement is rejected, the cloud is kept and the belief reports
``Status.CONTRADICTION`` (counted in ``contradictions``), as the information set does.
A range ``d_m`` keeps the particles with ``x`` in ``[d_m cos(phi)/(1 + b), d_m/(1 - b)]``
(``phi`` the measurement's off-axis bound), as the node set does.
``bearing_error = "gaussian"`` weighs by a normal of variance ``a^2/3`` instead (the
EKF's ``R``; the linear-Gaussian test uses it).

Randomness. The estimator holds a ``seed`` (an option, fixed by default, so runs are
reproducible); the belief counts its random operations (``draws``) and each draws from
``default_rng(SeedSequence(seed, spawn_key=(STREAM_KEY, draws)))``: the key's first
element is beyond every run index, so no draw repeats a run's own stream (run ``j``
draws its truth and errors from ``SeedSequence(seed, spawn_key=(j,))``: with the keys
``(draws,)``, a command run with ``--seed`` equal to the filter's seed gave draw ``j``
of the filter the stream of run ``j``). No generator is stored: the
same belief predicted twice gives the same cloud, which the adversaries that search over
the pursuer's updates rely on. Every run and channel starts from the same stream;
their clouds differ through their data.

References
----------
N. J. Gordon, D. J. Salmond & A. F. M. Smith, "Novel approach to nonlinear/non-Gaussian
Bayesian state estimation", IEE Proceedings F 140(2), 107-113, 1993 (the bootstrap
filter and roughening).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from kalman_vs_infoset.estim.base import Estimator, Status
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    Impulse,
    Range,
    check_step,
    impulse_parts,
)
from kalman_vs_infoset.estim.intercept.pf.belief import E, ParticleBelief, V, X, Y
from kalman_vs_infoset.estim.intercept.pf.filter import ParticleSet
from kalman_vs_infoset.estim.intercept.pf.options import DEFAULTS
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

#: relative margin of the bounded likelihoods (the generators' errors sit 1e-9 inside)
MARGIN = 1e-9
#: first element of the filter's spawn keys: above every run index (at most 10**6), so
#: the filter's streams are never a run's own (module docstring)
STREAM_KEY = 2**62 + 0x7066


@dataclass(frozen=True)
class ParticleChannelEstimator(Estimator[ParticleBelief, ChannelPrior]):
    """Bootstrap particle filter of one guidance channel (module docstring).

    Parameters
    ----------
    model : ChannelModel
        The channel's auxiliary model: ``nu``, the bearing bound, ``eps``.
    n_particles : int
        Particles of the cloud.
    seed : int
        Root of the filter's random streams.
    closing_speed_mps : (float, float) or None
        Interval the particles' closing speeds are drawn in (None: the nominal ``e``).
    n_sigma : float
        Radius of the moments' ellipsoid that ``contains`` tests.
    resample_threshold : float
        Resample when the effective sample size is under this fraction of N.
    resampler : {"systematic", "stratified"}
        The package's resampler (:mod:`kalman_vs_infoset.estim.intercept.pf.filter`).
    roughening : float
        Gordon et al.'s ``K`` (0: no roughening).
    disturbance, bearing_error : {"uniform", "gaussian"}
        Distribution of ``v`` and of the bearing error (the bounded one by default).
    """

    model: ChannelModel = field(default_factory=ChannelModel)
    n_particles: int = DEFAULTS.n_particles
    seed: int = DEFAULTS.seed
    closing_speed_mps: tuple[float, float] | None = None
    n_sigma: float = DEFAULTS.n_sigma
    resample_threshold: float = DEFAULTS.resample_threshold
    resampler: Literal["systematic", "stratified"] = DEFAULTS.resampler
    roughening: float = DEFAULTS.roughening
    disturbance: Literal["uniform", "gaussian"] = DEFAULTS.disturbance
    bearing_error: Literal["uniform", "gaussian"] = DEFAULTS.bearing_error

    def __post_init__(self) -> None:
        if self.n_particles < 2:
            raise ValueError("n_particles must be at least 2")
        if not 0.0 <= self.resample_threshold <= 1.0:
            raise ValueError("resample_threshold must lie in [0, 1]")
        if not 0.0 <= self.roughening < math.inf:
            raise ValueError("roughening must be a finite number >= 0")
        if self.disturbance not in ("uniform", "gaussian"):
            raise ValueError(f"unknown disturbance {self.disturbance!r}")
        if self.bearing_error not in ("uniform", "gaussian"):
            raise ValueError(f"unknown bearing_error {self.bearing_error!r}")
        if self.closing_speed_mps is not None:
            lo, hi = self.closing_speed_mps
            if not 0 < lo <= hi:
                raise ValueError("closing_speed_mps must be an interval 0 < lo <= hi")

    @property
    def speed_interval(self) -> tuple[float, float]:
        if self.closing_speed_mps is None:
            return self.model.e, self.model.e
        return self.closing_speed_mps

    def rng(self, belief: ParticleBelief | None) -> np.random.Generator:
        """The Generator of the belief's next random operation (module docstring)."""
        draws = 0 if belief is None else belief.draws
        return np.random.default_rng(
            np.random.SeedSequence(self.seed, spawn_key=(STREAM_KEY, draws))
        )

    # -- Estimator interface ---------------------------------------------------------
    def initial(self, prior: ChannelPrior) -> ParticleBelief:
        """``N`` particles uniform in the a-priori boxes and the closing-speed interval."""
        rng = self.rng(None)
        n = self.n_particles
        boxes = (prior.lateral_m, prior.lateral_vel_mps, prior.x_m, self.speed_interval)
        cols = [rng.uniform(lo, hi, n) if hi > lo else np.full(n, lo) for lo, hi in boxes]
        cloud = ParticleSet(np.column_stack(cols))
        return ParticleBelief(cloud, self.model, self.n_sigma, draws=1)

    def predict(
        self, belief: ParticleBelief, dt_s: float, control: float | Impulse | None = None
    ) -> ParticleBelief:
        """Resampling (with roughening), the threshold, the impulse, then the exact step."""
        check_step(dt_s)
        if belief.is_empty:
            return belief
        rng = self.rng(belief)
        cloud = belief.cloud
        resampled = cloud.resample_if_needed(rng, self.resample_threshold, self.resampler)
        if resampled is not cloud:
            cloud = self.roughen(resampled, rng)
        x_lo = self.model.eps_m + cloud.particles[:, E] * dt_s
        try:
            cloud = cloud.update_log(lambda p: np.where(p[:, X] >= x_lo, 0.0, -np.inf))
        except ValueError:  # every particle passes under eps
            return replace(belief, status=Status.TERMINAL, draws=belief.draws + 1)
        k, dk = (0.0, 0.0) if control is None else impulse_parts(control)
        nu = self.model.nu_mps2

        def move(p: FloatArray) -> FloatArray:
            out = p.copy()
            out[:, V] += k
            out[:, Y] += out[:, V] * dt_s
            out[:, X] -= out[:, E] * dt_s
            return out

        def noise(g: np.random.Generator, size: int) -> FloatArray:
            out = np.zeros((size, 4))
            if dk > 0.0:
                du = g.uniform(-dk, dk, size)
                out[:, Y] += du * dt_s
                out[:, V] += du
            if self.disturbance == "uniform":
                v = g.uniform(-nu, nu, size)
            else:
                v = g.normal(0.0, nu / math.sqrt(3.0), size)
            out[:, Y] += v * dt_s**2 / 2.0
            out[:, V] += v * dt_s
            return out

        moved = cloud.predict(move, noise, rng)
        return replace(belief, cloud=moved, draws=belief.draws + 1)

    def update(self, belief: ParticleBelief, measurement: Bearing | Range) -> ParticleBelief:
        """Reweight by the bounded likelihood of a bearing or a range (module docstring);
        every weight zero: the update is rejected and reported (``CONTRADICTION``)."""
        if belief.is_empty:
            return belief
        if isinstance(measurement, Bearing):
            loglik = self._bearing_loglik(float(measurement.alpha_rad))
        elif isinstance(measurement, Range):
            b, d = self.model.range_rel_bound, float(measurement.range_m)
            phi = measurement.off_axis_rad
            phi = self.model.max_off_axis_rad if phi is None else phi
            lo = d * math.cos(phi) / (1.0 + b) * (1.0 - MARGIN)
            hi = d / (1.0 - b) * (1.0 + MARGIN)

            def loglik(p: FloatArray) -> FloatArray:
                return np.where((p[:, X] >= lo) & (p[:, X] <= hi), 0.0, -np.inf)
        else:
            raise TypeError(f"unsupported measurement {type(measurement).__name__}")
        try:
            cloud = belief.cloud.update_log(loglik)
        except ValueError:
            return replace(
                belief, status=Status.CONTRADICTION, contradictions=belief.contradictions + 1
            )
        return replace(belief, cloud=cloud, status=Status.OK)

    # -- pieces ----------------------------------------------------------------------
    def _bearing_loglik(self, z: float):
        bound = self.model.bearing_bound

        def loglik(p: FloatArray) -> FloatArray:
            alpha = np.arctan2(p[:, Y], p[:, X])
            a = bound(np.hypot(p[:, Y], p[:, X]))
            if self.bearing_error == "gaussian":
                return -1.5 * (z - alpha) ** 2 / a**2
            return np.where(np.abs(z - alpha) <= a * (1.0 + MARGIN), 0.0, -np.inf)

        return loglik

    def roughen(self, cloud: ParticleSet, rng: np.random.Generator) -> ParticleSet:
        """Jitter by ``N(0, (K E_j N^(-1/d))^2)`` per coordinate (Gordon et al. 1993);
        closing speeds reflected into their interval."""
        if self.roughening == 0.0:
            return cloud
        p = cloud.particles
        n, d = p.shape
        spread = p.max(axis=0) - p.min(axis=0)
        sigma = self.roughening * spread * n ** (-1.0 / d)
        out = p + rng.normal(size=p.shape) * sigma
        lo, hi = self.speed_interval
        e = out[:, E]
        e = np.where(e < lo, 2.0 * lo - e, e)
        out[:, E] = np.clip(np.where(e > hi, 2.0 * hi - e, e), lo, hi)
        return ParticleSet(out, cloud.weights)
