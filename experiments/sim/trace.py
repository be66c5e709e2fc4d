"""Per-step records of a simulation, as plain dicts and arrays (the simulation layer).

A loop asked to record fills a :class:`Recorder`: one row (a dict of scalars) per step
and per channel or axis, and, for the intercept, the sections of a polygon set before
and after each step's measurements. The loops record only what they computed anyway,
plus questions asked of immutable beliefs, so a recorded run gives the same results as
an unrecorded one. Writing the records (Parquet) and drawing them is the harness's job
(:mod:`kalman_vs_infoset.experiments.traces`, :mod:`kalman_vs_infoset.experiments.trace_plots`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.base import Belief
from kalman_vs_infoset.estim.intercept.describe import describe_channel, section_vertices
from kalman_vs_infoset.estim.intercept.model import ChannelModel


@dataclass
class Recorder:
    """Rows of one run: ``rows`` (one dict per step and channel/axis) and ``sets``
    (vertex columns of the sets, one dict of arrays per step, phase and channel).

    ``sets_every`` records the sets after the measurements every that many steps (0:
    never); the first ``sets_first`` steps are recorded before the measurements too
    (the seed's Fig. 4 shows the set at ``t = 1 s`` before and after them).
    """

    sets_every: int = 10
    sets_first: int = 4
    rows: list[dict[str, Any]] = field(default_factory=list)
    sets: list[dict[str, Any]] = field(default_factory=list)

    def wants_sets(self, step: int) -> bool:
        if self.sets_every <= 0:
            return False
        return step < self.sets_first or step % self.sets_every == 0

    def wants_prior(self, step: int) -> bool:
        return self.sets_every > 0 and step < self.sets_first

    def add_sets(self, belief: Belief, model: ChannelModel, **keys: Any) -> None:
        """The sections of ``belief`` (if it is a polygon set) with ``keys`` as labels."""
        cols = section_vertices(belief, model)
        if cols is not None:
            self.sets.append({**keys, **cols})


def channel_row(
    belief: Belief,
    model: ChannelModel,
    truth: np.ndarray,
    range_true_m: float,
    alpha_meas_rad: float,
    range_meas_m: float,
) -> dict[str, Any]:
    """One channel's record after the step's measurements: truth, measurement and its
    error and bound, and what the belief says (:func:`estim.intercept.describe.describe_channel`).

    ``truth`` is the channel's true ``(alpha, omega, x)``; ``range_meas_m`` is NaN when
    no range was measured.
    """
    alpha, omega, x = (float(v) for v in truth)
    row: dict[str, Any] = {
        "alpha_true_rad": alpha,
        "omega_true_radps": omega,
        "x_true_m": x,
        "range_true_m": float(range_true_m),
        "zem_true_m": float(model.zero_effort_miss_m(omega, x)),
        "forecast_true_m": float(model.miss_forecast_m(np.asarray(truth, dtype=float))),
        "alpha_meas_rad": float(alpha_meas_rad),
        "alpha_err_rad": float(alpha_meas_rad) - alpha,
        "alpha_bound_rad": float(model.bearing_bound(range_true_m)),
        "range_meas_m": float(range_meas_m),
        "range_err_m": float(range_meas_m) - float(range_true_m),
    }
    row.update(describe_channel(belief, model))
    row["truth_inside"] = bool(not belief.is_empty and belief.contains(truth))
    return row
