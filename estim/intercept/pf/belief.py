"""The belief of the intercept channel's particle filter: a weighted cloud.

Particles are physical rows ``(Y_m, V_mps, x_m, e_mps)``: the channel's lateral offset
and velocity, the range along the nominal axis and the particle's own closing speed
(:mod:`kalman_vs_infoset.estim.intercept.pf.estimator` says why). A particle leaves the belief as a
row ``(alpha, omega, x)`` of the auxiliary model (models.md §1.3) by the exact map
:meth:`kalman_vs_infoset.estim.intercept.model.ChannelModel.from_cartesian` with ``Vx = -e``:
``alpha = atan2(Y, x)``, ``omega = (x V + Y e)/(x^2 + Y^2)``.

How it answers the questions of :class:`kalman_vs_infoset.estim.base.Belief`:

* ``extremes(fn)``: min and max of ``fn`` over the particles of positive weight (the
  cloud's support, not a set around it: an inner estimate of the extremes over the
  support of the posterior);
* ``centre()`` and ``contains(state)``: through the cloud's weighted moments in the
  EKF's coordinates ``(alpha, w, x)``, ``w = omega x^2/e``: the centre is the weighted
  mean, ``contains`` the test of the n-sigma ellipsoid of the weighted mean and
  covariance (a :class:`estim.intercept.gaussian.belief.GaussianBelief` of those moments answers
  both), so a particle filter's containment is counted on the same footing as a
  Kalman filter's.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from kalman_vs_infoset.estim.base import Belief, Extremes, StateFunction, Status, state_values
from kalman_vs_infoset.estim.intercept.gaussian.belief import GaussianBelief
from kalman_vs_infoset.estim.intercept.model import ChannelModel, channel_state
from kalman_vs_infoset.estim.intercept.pf.filter import ParticleSet
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.arrays import readonly

FloatArray = NDArray[np.float64]

#: columns of a particle
Y, V, X, E = 0, 1, 2, 3


def particle_rows(particles: ArrayLike, model: ChannelModel) -> FloatArray:
    """Rows ``(alpha, omega, x)`` of physical particles ``(Y, V, x, e)`` (exact)."""
    p = np.asarray(particles, dtype=float)
    return model.from_cartesian(p[:, Y], p[:, V], p[:, X], -p[:, E])


@dataclass(frozen=True, eq=False)
class ParticleBelief(Belief):
    """An immutable weighted cloud of one channel (module docstring).

    Parameters
    ----------
    cloud : ParticleSet
        Particles ``(Y_m, V_mps, x_m, e_mps)`` and normalised weights.
    model : ChannelModel
        The channel's model (nominal ``e`` of ``w``, for the rows).
    n_sigma : float
        Radius of the moments' ellipsoid that ``contains`` tests.
    status : Status
        ``OK``; ``CONTRADICTION`` when the last update gave every particle zero weight
        (the update was rejected and the cloud kept); ``TERMINAL`` once every particle
        has passed under ``eps`` (empty).
    contradictions : int
        Updates rejected so far.
    draws : int
        Random operations so far: the next one draws from the Generator of
        ``SeedSequence(seed, spawn_key=(STREAM_KEY, draws))`` (beliefs stay values: the same
        belief predicted twice gives the same cloud).
    """

    cloud: ParticleSet
    model: ChannelModel
    n_sigma: float = 3.0
    status: Status = Status.OK
    contradictions: int = 0
    draws: int = 0

    def __post_init__(self) -> None:
        if self.cloud.dim != 4:
            raise ValueError("particles must be rows (Y_m, V_mps, x_m, e_mps)")
        if not self.n_sigma > 0:
            raise ValueError("n_sigma must be positive")

    @property
    def is_empty(self) -> bool:
        return self.status is Status.TERMINAL

    @property
    def particles(self) -> FloatArray:
        return self.cloud.particles

    @property
    def weights(self) -> FloatArray:
        return self.cloud.weights

    @cached_property
    def rows(self) -> FloatArray:
        """``(alpha, omega, x)`` of every particle (read-only, as the belief: a write
        into the cached rows changed its extremes)."""
        return readonly(particle_rows(self.cloud.particles, self.model), copy=False)

    @cached_property
    def moments(self) -> GaussianBelief:
        """The weighted mean and covariance of the rows in ``(alpha, w, x)``, as the
        n-sigma ellipsoid of a :class:`GaussianBelief`."""
        e = self.model.e
        q = self.rows.copy()
        q[:, 1] = q[:, 1] * q[:, 2] ** 2 / e
        w = self.cloud.weights
        mean = w @ q
        d = q - mean
        cov = (d * w[:, None]).T @ d
        return GaussianBelief(mean, cov, self.n_sigma, "zem", e)

    def trace_fields(self) -> dict[str, float]:
        """The gate (``n_sigma``) of the moments' ellipsoid."""
        return {"n_sigma": float(self.n_sigma)}

    def centre(self) -> FloatArray:
        """The weighted mean of ``(alpha, w, x)`` as a row ``(alpha, omega, x)``."""
        return self.moments.centre()

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the particles of positive weight."""
        if self.is_empty:
            raise ValueError(f"extremes of an empty particle belief (status {self.status})")
        rows = self.rows[self.cloud.weights > 0.0]
        vals = state_values(fn, rows)  # (a TypeError for a bad function, as elsewhere)
        i, j = int(np.argmin(vals)), int(np.argmax(vals))
        return Extremes(float(vals[i]), rows[i].copy(), float(vals[j]), rows[j].copy())

    def contains(self, state: ArrayLike) -> bool:
        """Whether ``state`` lies in the n-sigma ellipsoid of the weighted moments."""
        channel_state(state)  # (3,), or one line
        if self.is_empty:
            return False
        return self.moments.contains(state)
