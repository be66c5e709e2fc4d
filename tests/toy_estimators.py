"""Toy estimators for the registry's tests: an intercept box and an attitude point set.

Self-contained (the package's public interface only): ``tests/test_families.py`` copies
this file into a new family folder as its ``estimator.py``. Each options model builds
its estimator (``build(setting)``), so a registration needs no factory.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from itertools import product
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeBelief,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
)
from kalman_vs_infoset.estim.attitude.model import check_step as check_step_attitude
from kalman_vs_infoset.estim.base import Belief, Estimator, Extremes, Status
from kalman_vs_infoset.estim.intercept.model import (
    ChannelModel,
    ChannelPrior,
    Range,
    check_step,
    impulse_parts,
)
from pydantic import BaseModel, ConfigDict, Field

from kalman_vs_infoset.numerics.rotations import qinv, qlog, qmul


# -- a toy intercept estimator: an (alpha, omega, x) box, corners moved by the model ----
class ToyOptions(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    widen: float = Field(1.0, ge=1.0, description="factor on the box after each step")

    def build(self, setting) -> ToyEstimator:
        return ToyEstimator(setting.model, self.widen)


class ToyAttitudeOptions(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    def build(self, model: AttitudeModel) -> ToyAttitudeEstimator:
        return ToyAttitudeEstimator(model)


@dataclass(frozen=True, eq=False)
class ToyBelief(Belief):
    lo: np.ndarray
    hi: np.ndarray
    status: Status = Status.OK
    contradictions: int = 0

    @property
    def is_empty(self) -> bool:
        return self.status is Status.TERMINAL

    def centre(self):
        return 0.5 * (self.lo + self.hi)

    def corners(self):
        return np.array([np.where(s, self.hi, self.lo) for s in product((0, 1), repeat=3)])

    def extremes(self, fn) -> Extremes:
        pts = self.corners()
        v = np.asarray(fn(pts), dtype=float)
        i, j = int(np.argmin(v)), int(np.argmax(v))
        return Extremes(float(v[i]), pts[i], float(v[j]), pts[j])

    def contains(self, state) -> bool:
        s = np.asarray(state, dtype=float)
        return bool(np.all((self.lo <= s) & (s <= self.hi)))


@dataclass(frozen=True)
class ToyEstimator(Estimator[ToyBelief, ChannelPrior]):
    model: ChannelModel
    widen: float = 1.0

    def _box(self, pts, **changes) -> ToyBelief:
        return ToyBelief(pts.min(axis=0), pts.max(axis=0), **changes)

    def initial(self, prior: ChannelPrior) -> ToyBelief:
        speed = prior.closing_speed_mps or (self.model.e, self.model.e)
        boxes = (prior.lateral_m, prior.lateral_vel_mps, prior.x_m, speed)
        pts = np.array([self.model.from_cartesian(y, v, x, -c) for y, v, x, c in product(*boxes)])
        return self._box(pts)

    def predict(self, belief: ToyBelief, dt_s: float, control: Any = None) -> ToyBelief:
        check_step(dt_s)  # the contract: a bad step is refused, not propagated
        if belief.is_empty:
            return belief
        pts = belief.corners()
        if control is not None:
            pts[:, 1] += impulse_parts(control)[0] / pts[:, 2]
        pts = self.model.step(pts, dt_s)
        if pts[:, 2].max() < self.model.eps_m:
            return dataclasses.replace(belief, status=Status.TERMINAL)
        mid = pts.mean(axis=0)
        return self._box(mid + self.widen * (pts - mid), contradictions=belief.contradictions)

    def update(self, belief: ToyBelief, measurement: Any) -> ToyBelief:
        if belief.is_empty or isinstance(measurement, Range):
            return belief
        b = float(self.model.bearing_bound(belief.lo[2]))
        lo = max(belief.lo[0], measurement.alpha_rad - b)
        hi = min(belief.hi[0], measurement.alpha_rad + b)
        if lo > hi:
            return dataclasses.replace(
                belief, status=Status.CONTRADICTION, contradictions=belief.contradictions + 1
            )
        return dataclasses.replace(belief, lo=np.r_[lo, belief.lo[1:]], hi=np.r_[hi, belief.hi[1:]])


# -- a toy attitude estimator: the last measurement with its error bounds as the set ----
@dataclass(frozen=True, eq=False)
class ToyAttitudeBelief(AttitudeBelief):
    state: np.ndarray
    angle_bound_rad: float
    rate_bound_radps: float
    status: Status = Status.OK
    contradictions: int = 0

    @property
    def runs(self) -> int:
        return self.state.shape[0]

    @property
    def is_empty(self) -> bool:
        return False

    @property
    def empty_counts(self):
        return np.zeros(self.runs, dtype=int)

    def centre(self):
        return self.state.copy()

    def inside(self, state):
        x = np.atleast_2d(state)
        angle = np.linalg.norm(qlog(qmul(qinv(self.state[:, 0:4]), x[:, 0:4])), axis=-1)
        rate = np.max(np.abs(x[:, 4:7] - self.state[:, 4:7]), axis=-1)
        return (angle <= self.angle_bound_rad * (1 + 1e-9)) & (rate <= self.rate_bound_radps)

    def contains(self, state) -> bool:
        return bool(np.all(self.inside(state)))

    def attitude_bound_rad(self):
        return np.full(self.runs, self.angle_bound_rad)

    def extremes(self, fn) -> Extremes:
        v = float(np.asarray(fn(self.state[:1]))[0])
        return Extremes(v, self.state[0], v, self.state[0])


@dataclass(frozen=True)
class ToyAttitudeEstimator(Estimator[ToyAttitudeBelief, AttitudePrior]):
    model: AttitudeModel

    def _of(self, meas: AttitudeMeasurement) -> ToyAttitudeBelief:
        return ToyAttitudeBelief(
            np.concatenate([meas.quat, meas.rate_radps], axis=-1),
            float(np.linalg.norm(self.model.meas_angle_bound_rad)),
            float(np.max(self.model.meas_rate_bound_radps)),
        )

    def initial(self, prior: AttitudePrior) -> ToyAttitudeBelief:
        return self._of(prior.measurement)

    def predict(self, belief, dt_s, control=None):
        check_step_attitude(dt_s)
        return belief

    def update(self, belief, measurement):
        return self._of(measurement)
