"""The estimator registry (issue 15): toy estimators registered from this file run through
``compare`` and the attitude loop without any edit of the package, and one contract test
runs every registered estimator through the same checks."""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from itertools import product
from typing import Any

import numpy as np
import pandas as pd
import pytest
from harness_texts import RANGE_FINDER, SHORT, TINY_RW
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeBelief,
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
    draw_measurement,
)
from kalman_vs_infoset.estim.base import Belief, Estimator, Extremes, Status
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    ChannelSetting,
    Impulse,
    Range,
    impulse_parts,
)
from kalman_vs_infoset.experiments.cli import main
from pydantic import BaseModel, ConfigDict, Field

from kalman_vs_infoset.numerics.rotations import qinv, qlog, qmul


# -- a toy intercept estimator: an (alpha, omega, x) box, corners moved by the model ----
class ToyOptions(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    widen: float = Field(1.0, ge=1.0, description="factor on the box after each step")


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
        return belief

    def update(self, belief, measurement):
        return self._of(measurement)


@pytest.fixture
def toys():
    registry.register(
        "toy", "intercept", ToyOptions, lambda o, s: ToyEstimator(s.model, o.widen), "a box"
    )
    registry.register(
        "toy_att", "attitude", ToyOptions, lambda o, m: ToyAttitudeEstimator(m), "last measurement"
    )
    yield
    registry.unregister("intercept", "toy")
    registry.unregister("attitude", "toy_att")


def _main(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    assert code == 0, out.err
    return json.loads(out.out.strip().splitlines()[-1])


def test_a_toy_estimator_runs_through_compare_without_editing_the_package(toys, tmp_path, capsys):
    scenario = tmp_path / "short.toml"
    scenario.write_text(SHORT + RANGE_FINDER)
    result = _main(
        capsys, "compare", scenario, "--estimators", "toy,infoset", "--noise", "random,game",
        "--runs", 2, "--workers", 1, "--out", tmp_path, "--no-progress", "--json",
    )  # fmt: skip
    rows = {(r["estimator"], r["noise"]): r for r in result["rows"]}
    assert set(rows) == {(e, n) for e in ("toy", "infoset") for n in ("random", "game")}
    assert all(r["failures"] == 0 and r["runs"] == 2 for r in rows.values())
    assert np.isfinite(rows[("toy", "random")]["miss_m"]["mean"])
    # paired: both estimators saw the same truths
    table = pd.read_parquet(tmp_path / "short-compare.parquet")
    by = table.groupby("estimator")
    np.testing.assert_array_equal(
        by.get_group("toy").sort_values(["noise", "run"])["x0_km"],
        by.get_group("infoset").sort_values(["noise", "run"])["x0_km"],
    )


def test_a_toy_attitude_estimator_runs_in_the_attitude_loop(toys, tmp_path, capsys):
    scenario = tmp_path / "tiny_rw.toml"
    scenario.write_text(TINY_RW)
    result = _main(
        capsys, "attitude", scenario, "--estimator", "toy_att,box", "--noise", "random",
        "--runs", 2, "--out", tmp_path, "--json",
    )  # fmt: skip
    assert result["failures"] == 0 and result["estimator"] == "toy_att"
    assert [r["estimator"] for r in result["rows"]] == ["toy_att", "box"]
    assert result["truth_outside"] == 0  # the measurement bounds hold the truth


# -- the contract every registered estimator keeps ---------------------------------------
MODEL = ChannelModel()
SETTING = ChannelSetting(MODEL, (57.9e3, 58.1e3))
PRIOR = ChannelPrior((-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3), (57e3, 59e3))
ATT_MODEL = AttitudeModel(np.diag([1.0, 1.5, 2.0]), 1e-4, np.radians(0.01), np.radians(0.001))


def _registered():
    return [(p, n) for p in registry.PROBLEMS for n in registry.names(p)]


def _frozen(belief) -> None:
    with pytest.raises(AttributeError):  # FrozenInstanceError is one
        belief.status = Status.DIVERGED


@pytest.mark.parametrize(("problem", "name"), _registered())
def test_every_registered_estimator_keeps_the_contract(problem, name):
    reg = registry.get(problem, name)
    assert reg.options.model_config.get("extra") == "forbid"
    if problem == "intercept":
        _intercept_contract(reg.build(None, SETTING))
    else:
        _attitude_contract(reg.build(None, ATT_MODEL))


def _intercept_contract(est: Estimator) -> None:
    b0 = est.initial(PRIOR)
    assert isinstance(b0, Belief) and b0.status is Status.OK and b0.contradictions == 0
    assert not b0.is_empty
    assert b0.contains(PRIOR.centre_state(MODEL))
    _frozen(b0)
    centre = b0.centre().copy()
    fc = MissForecast(MODEL)
    ext = b0.extremes(fc)
    assert np.isfinite([ext.min_value, ext.max_value]).all() and ext.min_value <= ext.max_value
    b1 = est.update(b0, Bearing(float(centre[0])))
    b2 = est.predict(b1, 0.5, Impulse(2.0, 0.1))
    b3 = est.update(est.predict(b2, 0.5, 1.0), Range(float(centre[2]) - 58e3))
    for b in (b1, b2, b3):
        assert isinstance(b, type(b0)) and isinstance(b.status, Status)
        assert isinstance(b.contradictions, int)
    np.testing.assert_array_equal(b0.centre(), centre)  # beliefs are values
    assert np.isfinite(b3.extremes(fc).max_value)
    # predicting past the blind range ends the belief, reported by its status (a set
    # without measurements may say it diverged on the way)
    b = b3
    for _ in range(400):
        b = est.predict(b, 0.5)
        if b.is_empty:
            break
    assert b.is_empty and b.status in (Status.TERMINAL, Status.DIVERGED)


def _attitude_contract(est: Estimator) -> None:
    rng = np.random.default_rng(0)
    x = np.zeros((2, 10))
    x[:, 3] = 1.0
    meas = AttitudeMeasurement(x[:, 0:4], x[:, 4:7])
    b0 = est.initial(AttitudePrior(meas))
    assert isinstance(b0, AttitudeBelief) and b0.runs == 2 and b0.status is Status.OK
    assert np.all(b0.inside(x)) and b0.contradictions == 0
    _frozen(b0)
    centre = b0.centre().copy()
    ctrl = AttitudeControl.held(np.full((2, 3), 1e-3), np.zeros((2, 3)), 0.05)
    b1 = est.update(est.predict(b0, 0.05, ctrl), draw_measurement(x, ATT_MODEL, rng))
    assert isinstance(b1, type(b0)) and isinstance(b1.status, Status)
    assert b1.empty_counts.shape == (2,) and b1.attitude_bound_rad().shape == (2,)
    assert np.all(np.isfinite(b1.attitude_bound_rad()))
    np.testing.assert_array_equal(b0.centre(), centre)
