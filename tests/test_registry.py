"""The estimator registry: toy estimators registered from this file run through
``compare`` and the attitude loop without any edit of the package, and one contract test
runs every registered estimator through the same checks."""

from __future__ import annotations

import json

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
from kalman_vs_infoset.estim.base import Belief, Estimator, Status
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    ChannelSetting,
    Impulse,
    Range,
)
from kalman_vs_infoset.experiments.cli import main
from toy_estimators import ToyAttitudeEstimator, ToyEstimator, ToyOptions


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
    table = pd.read_parquet(tmp_path / "short-compare-toy+infoset.parquet")
    by = table.groupby("estimator")
    np.testing.assert_array_equal(
        by.get_group("toy").sort_values(["noise", "run"])["x0_km"],
        by.get_group("infoset").sort_values(["noise", "run"])["x0_km"],
    )


def test_a_toy_attitude_estimator_runs_in_the_attitude_loop(toys, tmp_path, capsys):
    scenario = tmp_path / "tiny_rw.toml"
    scenario.write_text(TINY_RW)
    result = _main(
        capsys, "attitude", scenario, "--estimators", "toy_att,box", "--noise", "random",
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
    # a step back in time, a NaN step or a non-finite impulse is refused in one clear
    # error (a NaN step left the node set's belief NaN with status ok)
    for dt_s, control in ((-0.5, None), (np.nan, None), (0.5, np.nan), (0.5, -np.inf)):
        with pytest.raises(ValueError, match="dt_s must be|impulse must be"):
            est.predict(b1, dt_s, control)
    with pytest.raises(ValueError, match="impulse must be"):
        Impulse(np.nan, 0.1)
    with pytest.raises(TypeError, match="an impulse is a number"):  # "3" read as 3 m/s
        est.predict(b1, 0.5, "3")
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
    # a step that is not a finite positive time, a NaN torque or a zero quaternion is
    # refused in one clear error (a NaN torque gave NaN beliefs with status ok)
    for dt_s in (-0.05, 0.0, np.nan, np.inf):
        with pytest.raises(ValueError, match="dt_s must be"):
            est.predict(b0, dt_s, ctrl)
    with pytest.raises(ValueError, match="torque_Nm must be finite"):
        AttitudeControl.held(np.full((2, 3), np.nan), np.zeros((2, 3)), 0.05)
    with pytest.raises(ValueError, match="quat must be"):
        AttitudeMeasurement(np.zeros((2, 4)), np.zeros((2, 3)))
    assert isinstance(b1, type(b0)) and isinstance(b1.status, Status)
    assert b1.empty_counts.shape == (2,) and b1.attitude_bound_rad().shape == (2,)
    assert np.all(np.isfinite(b1.attitude_bound_rad()))
    np.testing.assert_array_equal(b0.centre(), centre)


def test_an_unknown_problem_is_named_not_an_empty_list():
    """``registry.get("nosuch", "intercept")`` (arguments swapped) read "unknown nosuch
    estimator 'intercept' (allowed: )"; an unknown problem is now a ValueError naming
    the problems, and the front door's ``get_estimator(name, problem)`` says its order."""
    from kalman_vs_infoset.api import get_estimator

    for call in (lambda: registry.get("nosuch", "ukf"), lambda: registry.names("Intercept")):
        with pytest.raises(ValueError, match="unknown problem .*allowed: intercept, attitude"):
            call()
    with pytest.raises(ValueError, match=r"get_estimator takes \(name, problem\)"):
        get_estimator("intercept", "nosuch")
    assert get_estimator("ukf", "attitude").name == "ukf"


def test_a_plug_in_bounding_the_forecast_at_no_range_fails_its_runs(tmp_path):
    """A plug-in belief whose extremes have finite values at NaN states ran every step
    without an impulse and reported its runs ``ok`` (each step counted "unbounded"):
    its runs now fail, with the reason, as when it returns NaN values."""
    import dataclasses

    from kalman_vs_infoset.estim.base import Extremes
    from toy_estimators import ToyBelief

    from kalman_vs_infoset import api

    @dataclasses.dataclass(frozen=True, eq=False)
    class NoRange(ToyBelief):
        def extremes(self, fn) -> Extremes:
            e = super().extremes(fn)
            return Extremes(e.min_value, np.full(3, np.nan), e.max_value, np.full(3, np.nan))

    @dataclasses.dataclass(frozen=True)
    class NoRangeEstimator(ToyEstimator):
        def _box(self, pts, **changes):
            return NoRange(pts.min(axis=0), pts.max(axis=0), **changes)

    registry.register("toy_norange", "intercept", ToyOptions,
                      lambda o, s: NoRangeEstimator(s.model, o.widen))  # fmt: skip
    try:
        scenario = tmp_path / "short.toml"
        scenario.write_text(SHORT)
        df = api.run_experiment(scenario, "toy_norange", "random", runs=2)
    finally:
        registry.unregister("intercept", "toy_norange")
    assert list(df["status"]) == ["failed", "failed"]
    assert df["error"].str.contains("bounds the miss forecast").all()


def test_a_plug_in_s_own_check_of_a_field_is_said_without_a_wrong_type(tmp_path):
    """A plug-in option whose validator refuses a value of the right type read "must be
    a string; mode 'weird' is not supported" of a string: the field's type is said as
    what it is, then the plug-in's reason."""
    from kalman_vs_infoset.experiments.errors import InputError
    from pydantic import BaseModel, ConfigDict, field_validator

    from kalman_vs_infoset import api

    class Picky(BaseModel):
        model_config = ConfigDict(extra="forbid")
        mode: str = "plain"

        @field_validator("mode")
        @classmethod
        def _known(cls, v: str) -> str:
            if v != "plain":
                raise ValueError(f"mode {v!r} is not supported")
            return v

    registry.register("toy_picky_mode", "intercept", Picky,
                      lambda o, s: ToyEstimator(s.model))  # fmt: skip
    try:
        with pytest.raises(InputError) as caught:
            api.load_scenario("kp_fig3", estimator={"toy_picky_mode": {"mode": "weird"}})
    finally:
        registry.unregister("intercept", "toy_picky_mode")
    said = str(caught.value)
    assert "field 'estimator.toy_picky_mode.mode' (a string): mode 'weird' is not supported" in said
    assert "must be a string" not in said


def test_the_python_api_refuses_a_plug_in_that_cannot_be_built_before_any_run():
    """A plug-in whose factory raises gave one failed row per run from
    ``run_experiment``; it is built once first, as the commands do, and refused in one
    ``InputError`` naming it."""
    from kalman_vs_infoset.experiments.errors import InputError

    from kalman_vs_infoset import api

    def broken(options, setting):
        raise RuntimeError("no licence for the solver")

    registry.register("toy_unbuildable", "intercept", ToyOptions, broken)
    try:
        with pytest.raises(InputError, match="'toy_unbuildable' cannot be built.*licence"):
            api.run_experiment("kp_fig3", "toy_unbuildable", "random", runs=3)
    finally:
        registry.unregister("intercept", "toy_unbuildable")
