"""The zero-noise attitude "estimator": the measurement is taken as the state (docs/models.md §2.5).

Behind the same interface as the box and the UKF (:class:`estim.attitude.model.AttitudeBelief`,
batched over runs), so an attitude loop runs it like any other estimator. A point is
not a set: with noisy measurements the truth is outside it at every step, which the
loops count.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
    NeverEmptyBelief,
    check_runs,
    check_step,
    run_states,
)
from kalman_vs_infoset.estim.base import Estimator, Extremes, StateFunction, Status
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.rotations import qinv, qlog, qmul

FloatArray = NDArray[np.float64]
#: per-component tolerance of :meth:`AttitudePointBelief.inside` (rad, rad/s)
EQUAL_TOL = 1e-12


@dataclass(frozen=True, eq=False)
class AttitudePointBelief(NeverEmptyBelief):
    """Points ``(q, w)`` per run, ``(R, 7)``."""

    state: FloatArray
    status: Status = Status.OK
    contradictions: int = 0

    def __post_init__(self) -> None:
        state = np.array(np.atleast_2d(self.state), dtype=float)
        state.setflags(write=False)
        object.__setattr__(self, "state", state)

    @classmethod
    def of(cls, meas: AttitudeMeasurement) -> AttitudePointBelief:
        return cls(np.concatenate([meas.quat, meas.rate_radps], axis=-1))

    @property
    def runs(self) -> int:
        return self.state.shape[0]

    def centre(self) -> FloatArray:
        return self.state.copy()

    def inside(self, state: ArrayLike) -> NDArray[np.bool_]:
        """Per run: the state equals the point within :data:`EQUAL_TOL`."""
        x, c = run_states(state, self.runs), self.state
        da = qlog(qmul(qinv(c[:, 0:4]), x[:, 0:4]))
        diff = np.concatenate([da, c[:, 4:7] - x[:, 4:7]], axis=-1)
        return np.all(np.abs(diff) <= EQUAL_TOL, -1)

    def contains(self, state: ArrayLike) -> bool:
        return bool(np.all(self.inside(state)))

    def attitude_bound_rad(self) -> FloatArray:
        """Zero: a point claims to know the attitude exactly."""
        return np.zeros(self.runs)

    def knowledge_bound_rad(self, model: AttitudeModel) -> FloatArray:
        """The measurement's angle bound: the point is the measurement."""
        return np.full(self.runs, np.linalg.norm(model.meas_angle_bound_rad))

    def extremes(self, fn: StateFunction) -> Extremes:
        """``fn`` at run 0's point."""
        p = self.state[0]
        value = float(np.asarray(fn(p[None, :]))[0])
        return Extremes(value, p.copy(), value, p.copy())


class PerfectAttitudeEstimator(Estimator[AttitudePointBelief, AttitudePrior]):
    """Every measurement replaces the point; prediction keeps it (the next measurement
    comes before the controller reads it)."""

    def initial(self, prior: AttitudePrior) -> AttitudePointBelief:
        return AttitudePointBelief.of(prior.measurement)

    def predict(
        self, belief: AttitudePointBelief, dt_s: float, control: Any = None
    ) -> AttitudePointBelief:
        check_step(dt_s)
        return belief

    def update(self, belief: AttitudePointBelief, measurement: Any) -> AttitudePointBelief:
        if not isinstance(measurement, AttitudeMeasurement):
            raise TypeError("measurement must be an AttitudeMeasurement")
        check_runs(belief.runs, measurement.runs, "measurement")
        return AttitudePointBelief.of(measurement)
