"""Impulsive guidance law of seed 003 section 5 (docs/models.md §1.5).

For the current belief (after the measurements) take the extremes of the miss
forecast ``Pi`` over it, ``Pi_min`` at range ``x*`` and ``Pi_max`` at ``x**``. An
impulse ``k`` (relative velocity) shifts ``omega`` by ``k/x`` and so ``Pi`` by
``k x / e``; the impulse that re-centres the forecast interval about zero is

    k = -(Pi_min + Pi_max) e / (x* + x**)

(the seed prints it without the minus sign; under its own lateral equation, where the
impulse enters ``omega`` as ``+k/x``, the printed sign would double the offset instead
of cancelling it, so we take the sign the derivation gives: docs/models.md §1.5).
Then ``|k| < mu1`` means no impulse, ``|k| > mu2`` is clipped, and the total fuel
``sum |k|`` over both channels never exceeds the reserve ``mu``.

The law only asks the belief for the extremes of a function over itself, so it
runs unchanged on an information set or on a Kalman filter's k-sigma ellipsoid.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from kalman_vs_infoset.estim.base import Belief, Extremes
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import ChannelModel


@dataclass(frozen=True)
class ImpulseLimits:
    """``mu1 <= |k| <= mu2`` for an issued impulse, total fuel ``<= mu`` (m/s)."""

    min_mps: float = 0.25
    max_mps: float = 7.5
    reserve_mps: float = 2000.0

    def __post_init__(self) -> None:
        if not 0 <= self.min_mps <= self.max_mps:
            raise ValueError("impulse limits need 0 <= min_mps <= max_mps")
        if not self.reserve_mps >= 0:
            raise ValueError("reserve_mps must be non-negative")

    def apply(self, k_mps: float, fuel_used_mps: float) -> float:
        """The impulse actually issued for a command ``k_mps`` given the fuel used."""
        k = float(np.clip(k_mps, -self.max_mps, self.max_mps))
        k = float(np.sign(k)) * min(abs(k), max(self.reserve_mps - fuel_used_mps, 0.0))
        return 0.0 if abs(k) < self.min_mps else k


@dataclass(frozen=True)
class ForecastCentringLaw:
    """The seed's law: re-centre the interval of forecast misses about zero."""

    model: ChannelModel
    limits: ImpulseLimits = ImpulseLimits()

    def forecast(self, belief: Belief) -> Extremes:
        """Extremes of ``Pi`` over the belief (with the states attaining them)."""
        return belief.extremes(MissForecast(self.model))

    def command_mps(self, belief: Belief) -> float:
        """Unlimited impulse ``k = -(Pi_min + Pi_max) e / (x* + x**)``; 0 if the belief
        is empty or its forecast interval is unbounded (no centre to move: a sound set
        may be unbounded where it cannot bound a cell, and an impulse computed from inf
        would be nan)."""
        return self._command(belief)[0]

    def _command(self, belief: Belief) -> tuple[float, bool]:
        """:meth:`command_mps` and whether the forecast was bounded (an empty belief
        asks for nothing: bounded)."""
        if belief.is_empty:
            return 0.0, True
        ext = self.forecast(belief)
        if not isinstance(ext, Extremes):  # a plug-in's own answer, never checked
            raise TypeError(
                f"{type(belief).__name__}.extremes returned a {type(ext).__name__}, "
                "not an estim.base.Extremes"
            )
        x_sum = float(ext.argmin[2] + ext.argmax[2])
        if np.isfinite(ext.min_value) and np.isfinite(ext.max_value) and np.isnan(x_sum):
            # finite bounds at states without a range: the estimator's fault, not a set
            # too wide to bound (which would count as unbounded and issue nothing)
            raise ValueError(
                f"{type(belief).__name__}.extremes bounds the miss forecast "
                f"({ext.min_value:g}, {ext.max_value:g}) at states without a range "
                f"(x = {ext.argmin[2]:g}, {ext.argmax[2]:g})"
            )
        k = -(ext.min_value + ext.max_value) * self.model.e / x_sum
        return (float(k), True) if np.isfinite(k) else (0.0, False)

    def impulse_mps(self, belief: Belief, fuel_used_mps: float) -> float:
        """The impulse issued: the command with the limits and the reserve applied."""
        return self.decide(belief, fuel_used_mps)[0]

    def decide(self, belief: Belief, fuel_used_mps: float) -> tuple[float, bool]:
        """:meth:`impulse_mps`, and whether the belief's forecast interval was bounded
        (False: no impulse, for want of a centre; the engagement counts such steps)."""
        k, bounded = self._command(belief)
        return self.limits.apply(k, fuel_used_mps), bounded
