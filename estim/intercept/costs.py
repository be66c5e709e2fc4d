"""Functions of the intercept channel's state that guidance asks a belief about.

A belief answers ``extremes(fn)`` for any vectorised function of rows
``(alpha_rad, omega_radps, x_m)``. The functions below are *objects* a belief can
recognise (by type) to take an exact or cheaper route than sampling: a Kalman
belief has a closed form for the miss forecast over its ellipsoid, a set made of
sections bounds them section by section. Any other callable still works through
the belief's generic route.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from kalman_vs_infoset.estim.intercept.model import ChannelModel
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True)
class MissForecast:
    """Seed 003 section 5: ``Pi = omega x^2/e + sign(omega) nu (x/e)^2 / 2`` (m)."""

    model: ChannelModel

    def __call__(self, points: ArrayLike) -> NDArray[np.float64]:
        return self.model.miss_forecast_m(points)


@dataclass(frozen=True)
class ZeroEffortMiss:
    """``w = omega x^2 / e`` (m, nominal ``e``): the miss of free motion of the
    auxiliary model, without the disturbance term of :class:`MissForecast`."""

    model: ChannelModel

    def __call__(self, points: ArrayLike) -> NDArray[np.float64]:
        p = np.asarray(points, dtype=float)
        return self.model.zero_effort_miss_m(p[..., 1], p[..., 2])
