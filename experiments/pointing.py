"""Coupling of an attitude loop to the intercept: the end-to-end scenario (SPEC 2.5).

The spacecraft's longitudinal axis is held by an attitude loop
(:class:`experiments.pointing_loop.PointingLoop`: plant, controller, estimator,
noise). Its pointing error enters the intercept twice:

* bearings are measured in body axes, so the true pointing error biases them; the
  guidance corrects them with the attitude estimator's estimate, and what is left
  (at most the estimator's knowledge bound ``kb``) is added to the bearing error
  bound the intercept estimators use;
* impulses are fired along body axes, so the commanded impulse is rotated by the
  residual (true vs estimated) pointing error: each channel's impulse is known only
  to ``+-kb |dv|``, which the estimators are told (:class:`estim.model.Impulse`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from estim.model import BearingBound, ChannelModel, Impulse

AXIS = {"lateral": 1, "vertical": 2}


class PointingCoupling:
    """Per-run adapter between a pointing loop and the engagement loop."""

    def __init__(self, loop: Any):
        self.loop = loop
        self.kb_rad = float(loop.knowledge_bound_rad)
        self.max_residual_rad = 0.0
        self.max_bound_rad = self.kb_rad

    def widen(self, model: ChannelModel) -> ChannelModel:
        """The intercept model with the bearing bound widened by the knowledge bound."""
        b = model.bearing_bound
        widened = BearingBound(b.start_rad + self.kb_rad, b.end_rad + self.kb_rad, b.ref_range_m)
        return replace(model, bearing_bound=widened)

    def bearing_errors(self, r_guidance: np.ndarray, channels: Sequence[str]) -> list[float]:
        """Bearing error (rad) per channel left after correcting the body-axis
        measurement with the estimated pointing error."""
        r_body = self.loop.true_error.inv().apply(r_guidance)
        r_corr = self.loop.estimated_error.apply(r_body)
        residual = (self.loop.estimated_error * self.loop.true_error.inv()).magnitude()
        self.max_residual_rad = max(self.max_residual_rad, float(residual))
        self.max_bound_rad = max(self.max_bound_rad, float(self.loop.knowledge_bound_rad))
        return [
            float(
                np.arctan2(r_corr[AXIS[c]], r_corr[0])
                - np.arctan2(r_guidance[AXIS[c]], r_guidance[0])
            )
            for c in channels
        ]

    def impulse(self, dv_cmd_mps: np.ndarray, channels: Sequence[str]):
        """Actual impulse (guidance axes) for a commanded one, and the commands as
        :class:`Impulse` values with their uncertainty ``kb |dv|``."""
        rot = self.loop.true_error * self.loop.estimated_error.inv()
        actual = rot.apply(dv_cmd_mps)
        dk = self.kb_rad * float(np.linalg.norm(dv_cmd_mps))
        return actual, [Impulse(float(dv_cmd_mps[AXIS[c]]), dk) for c in channels]

    def step(self, dt_s: float) -> None:
        self.loop.step(dt_s)

    def summary(self) -> dict[str, float]:
        out = {
            f"attitude_{k}": float(v)
            for k, v in self.loop.summary().items()
            if isinstance(v, int | float | np.number)
        }
        out["pointing_residual_max_deg"] = float(np.degrees(self.max_residual_rad))
        out["pointing_knowledge_bound_deg"] = float(np.degrees(self.kb_rad))
        out["pointing_bound_max_deg"] = float(np.degrees(self.max_bound_rad))
        return out
