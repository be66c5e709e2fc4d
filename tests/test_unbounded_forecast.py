"""A belief whose forecast-miss interval is unbounded gets no impulse (no centre to
move); the intercept engagement now counts such channel steps (``unbounded_steps``),
as the attitude loops count theirs, where before the run read "ok" and said nothing."""

from __future__ import annotations

import dataclasses

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.base import Extremes
from kalman_vs_infoset.guidance.intercept.law import ForecastCentringLaw
from toy_estimators import ToyBelief, ToyEstimator, ToyOptions

from kalman_vs_infoset import api


@dataclasses.dataclass(frozen=True, eq=False)
class BlindBelief(ToyBelief):
    """The toy box, but it bounds no function: every extreme is infinite."""

    def extremes(self, fn) -> Extremes:
        pts = self.corners()
        return Extremes(-np.inf, pts[0], np.inf, pts[-1])


class BlindEstimator(ToyEstimator):
    def _box(self, pts, **changes):
        return BlindBelief(pts.min(axis=0), pts.max(axis=0), **changes)


def test_the_law_says_when_it_had_no_bounded_forecast():
    model = api.load_scenario("kp_fig3").channel_model()
    law = ForecastCentringLaw(model)
    lo, hi = np.array([-1e-3, -1e-6, 5e6]), np.array([1e-3, 1e-6, 6e6])
    assert law.decide(BlindBelief(lo, hi), 0.0) == (0.0, False)
    k, bounded = law.decide(ToyBelief(lo + 2e-3, hi + 2e-3), 0.0)
    assert bounded and k == law.impulse_mps(ToyBelief(lo + 2e-3, hi + 2e-3), 0.0)


def test_an_engagement_counts_the_steps_without_a_bounded_forecast():
    registry.register("toy_blind", "intercept", ToyOptions, lambda o, s: BlindEstimator(s.model))
    try:
        row = api.run_engagement("kp_fig3", "toy_blind", "random", run=0).as_row()
        ekf = api.run_engagement("kp_fig3", "ekf", "random", run=0).as_row()
    finally:
        registry.unregister("intercept", "toy_blind")
    assert row["unbounded_steps"] > 0 and row["n_impulses"] == 0 and row["fuel_mps"] == 0.0
    assert ekf["unbounded_steps"] == 0
