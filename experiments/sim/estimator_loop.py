"""An attitude estimator run over a batch of runs, as every attitude loop uses it (docs/models.md
§2.5).

Per control step: ``predict`` over the period with the known inputs held over it
(delivered torque, momentum interval), then ``update`` with the new measurement; the
controller reads ``centre()`` = ``(q, w)`` per run; the loops count the (run, step)
pairs where the truth is not in the belief (for ``perfect`` that is every noisy step: a
point is not a set). Any estimator registered for the problem ``"attitude"``
(:mod:`kalman_vs_infoset.estim.registry`) runs here.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeBelief,
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
)
from kalman_vs_infoset.estim.base import Estimator

#: noise of the attitude loops: none (exact measurements, no disturbance), random, game
NOISES = ("none", "random", "game")


@dataclass(frozen=True)
class EstimatorLoop:
    """One registered attitude estimator run over a batch of runs (``name`` None: the
    one whose registration declares the role ``exact``, the measurement read as the
    state, as the seeds' loops assume), built with its table of ``options`` (its
    registered model's defaults for the fields not given)."""

    name: str | None
    model: AttitudeModel
    #: the scenario's ``[estimator_options.<name>]`` tables (None: every estimator's
    #: defaults); the loop's estimator takes its own table
    options: Mapping[str, Mapping[str, Any]] | None = None
    estimator: Estimator = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if self.name is None:
            object.__setattr__(self, "name", registry.first_with_role("attitude", "exact").name)
        try:
            reg = registry.get("attitude", str(self.name))
        except KeyError as exc:
            raise ValueError(exc.args[0]) from None
        table = (self.options or {}).get(str(self.name))
        object.__setattr__(self, "estimator", reg.build(dict(table or {}), self.model))

    def start(self, meas: AttitudeMeasurement) -> AttitudeBelief:
        return self.estimator.initial(AttitudePrior(meas))

    def step(self, belief, control: AttitudeControl, dt_s: float, meas: AttitudeMeasurement):
        """``predict`` over ``dt_s`` with the inputs held over it, ``update`` with ``meas``."""
        est = self.estimator
        return est.update(est.predict(belief, dt_s, control), meas)

    @staticmethod
    def centre(belief: AttitudeBelief) -> np.ndarray:
        """``(q, w)`` per run, ``(R, 7)``."""
        return np.atleast_2d(belief.centre())

    @staticmethod
    def inside(belief: AttitudeBelief, truth: np.ndarray) -> np.ndarray:
        """Per run: truth ``(q, w, ...)`` in the belief."""
        return belief.inside(np.atleast_2d(truth)[:, 0:7])

    @staticmethod
    def empty_steps(belief: AttitudeBelief) -> np.ndarray:
        return belief.empty_counts

    @staticmethod
    def unbounded_steps(belief: AttitudeBelief) -> np.ndarray:
        """Per run: predictions whose set was the whole space (the set estimators'
        ``n_unbounded``; zero for the others). The truth is inside such a set, so these
        steps are reported beside ``truth_outside`` rather than hidden in it."""
        return belief.unbounded_counts

    @staticmethod
    def attitude_bound_rad(belief: AttitudeBelief) -> np.ndarray:
        return belief.attitude_bound_rad()

    @staticmethod
    def axis_hull(belief: AttitudeBelief) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """Per run, the reference attitude ``q_ref`` ``(R, 4)`` and the centre and radius
        ``(R, 6)`` of the belief's per-axis hull in its coordinates ``(log(q_ref^-1 q), w)``:
        the box's own sides, a set's hull (``hull()``); None for a belief that is not a set
        with axes of that kind (the UKF, ``perfect``)."""
        from kalman_vs_infoset.estim.attitude.box.estimator import BoxAttitudeBelief
        from kalman_vs_infoset.estim.attitude.sets.common import SetAttitudeBelief, box_cr

        if isinstance(belief, SetAttitudeBelief):
            c, r = belief.hull()
        elif isinstance(belief, BoxAttitudeBelief):
            c, r = box_cr(belief)
        else:
            return None
        return np.array(belief.q_ref, dtype=float), np.array(c), np.array(r)
