"""Soundness of the set estimators in physical coordinates (docs/models.md §1.4).

The truth is drawn the way the a-priori data describe it, not in the estimator's
own coordinates: lateral position ``Y`` and velocity ``V`` in their boxes, initial
range ``x0`` in its box and a closing speed ``e`` anywhere in the estimator's
interval, with every end of every interval drawn with positive probability (the
corners are where an initial set built at the nominal ``e`` loses states). It moves
by the auxiliary model of one channel in physical form, exactly linear::

    x(t) = x0 - e t,   Y'' = v (constant over a step, |v| <= nu),   V += k (impulse)

and is seen by the estimator as ``(alpha, omega, x) = (Y/x, (V x + e Y)/x^2, x)``
(``omega x^2 = V x + e Y``). Bearings are ``Y/x + zeta`` with ``|zeta| <= a(x)``:
uniform, at a random bound every step, held at one bound, or held at ``+a`` and
switched to ``-a`` once. The estimator must contain the truth after every update,
impulse and prediction.

A new set estimator joins these tests with one line in ``FACTORIES``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.intercept.costs import ZeroEffortMiss
from kalman_vs_infoset.estim.intercept.model import Bearing, ChannelModel, ChannelPrior, Range
from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator
from kalman_vs_infoset.estim.intercept.sections.box import BoxFamily
from kalman_vs_infoset.estim.intercept.sections.ellipsoid import EllipsoidFamily
from kalman_vs_infoset.estim.intercept.sections.zonotope import ZonotopeFamily
from kalman_vs_infoset.estim.intercept.slabs.estimator import InformationSetEstimator
from kalman_vs_infoset.guidance.intercept.law import ForecastCentringLaw

MODEL = ChannelModel()  # seed 003 section 6: e_nom = 58 km/s, nu = 0.005 m/s^2, eps = 5 km
DT_S = 0.5


@dataclass(frozen=True)
class Box:
    """A-priori data of one channel (kp_fig5's estimator boxes)."""

    y_m: tuple[float, float] = (-10e3, 10e3)
    v_mps: tuple[float, float] = (-100.0, 100.0)
    x_m: tuple[float, float] = (5301.3e3, 6301.3e3)
    e_mps: tuple[float, float] = (57.9e3, 58.1e3)


BOX = Box()


def _infoset(model: ChannelModel, box: Box, **options):
    est = InformationSetEstimator(model, closing_speed_mps=box.e_mps, **options)
    return est, est.initial(ChannelPrior(box.y_m, box.v_mps, box.x_m))


def _nodes(model: ChannelModel, box: Box, **options):
    est = NodeSetEstimator(model, closing_speed_mps=box.e_mps, **options)
    return est, est.initial(ChannelPrior(box.y_m, box.v_mps, box.x_m))


#: name -> factory(model, box) -> (estimator, initial belief). One line per estimator.
FACTORIES: dict[str, Callable] = {
    # the seed's set: the node set's kinematic margin adds the two-body term with its
    # sign, which this truth (no such term) can push against at a corner of everything;
    # the default node set holds the Cartesian truth below
    "nodes": lambda m, b: _nodes(m, b, kinematic_margin=False),
    "slabs": _infoset,
    # the auxiliary-model truth needs no kinematic margin: the discretisation alone
    "slabs-no-margin": lambda m, b: _infoset(m, b, kinematic_margin=False),
    "ellipsoid": lambda m, b: _infoset(m, b, family=EllipsoidFamily()),
    "zonotope": lambda m, b: _infoset(m, b, family=ZonotopeFamily()),
    "box": lambda m, b: _infoset(m, b, family=BoxFamily()),
}
#: factories whose sets may report ``Status.DIVERGED`` near eps (emptied, not
#: propagated): a box never narrows ``w`` (estim.intercept.sections.box), so near the target its
#: kinematic margin bounds line-of-sight rates of rad/s; the run ends there, the truth
#: contained until then
MAY_DIVERGE = (FACTORIES["box"],)


def _cartesian(y_m: float, v_mps: float, x_m: float, e_mps: float) -> np.ndarray:
    """``(alpha, omega, x)`` of the same state read as Cartesian (``alpha = atan2(y,
    x)``): the two-body motion the kinematic margin is for."""
    return MODEL.from_cartesian(y_m, v_mps, x_m, -e_mps)


def _observed(y_m: float, v_mps: float, x_m: float, e_mps: float) -> np.ndarray:
    """``(alpha, omega, x)`` of a physical state of the auxiliary model."""
    return np.array([y_m / x_m, (v_mps * x_m + e_mps * y_m) / x_m**2, x_m])


def _ends_or_inside(lo: float, hi: float):
    """Either end of ``[lo, hi]`` (corners with positive probability) or a float inside."""
    return st.one_of(st.sampled_from([lo, hi]), st.floats(lo, hi))


def _bearing_error(mode: str, bound: float, t_s: float, switch_s: float, rng) -> float:
    return {
        "uniform": lambda: rng.uniform(-bound, bound),
        "bounds": lambda: bound * rng.choice([-1.0, 1.0]),
        "bias_high": lambda: bound,
        "bias_low": lambda: -bound,
        "switch": lambda: bound if t_s < switch_s else -bound,
    }[mode]()


def _run(factory, y, v, x0, e, mode, v_mode, controls, switch_s, seed, steps, dt_s=DT_S,
         cartesian=False):  # fmt: skip
    """Drive truth and set with steps of ``dt_s``; assert containment after every
    operation. Returns the number of steps run and the last set (a divergence reported
    by a factory of ``MAY_DIVERGE`` ends the run). ``cartesian``: the same motion read
    as Cartesian (bearings ``atan2(y, x) + zeta``, the state :func:`_cartesian`)."""
    est, s = factory(MODEL, BOX)
    rng = np.random.default_rng(seed)
    law = ForecastCentringLaw(MODEL)
    x = x0
    observe = _cartesian if cartesian else _observed
    assert s.contains(observe(y, v, x, e)), "initial set"
    for step in range(steps):
        if x - e * dt_s < MODEL.eps_m or s.is_empty:
            break
        t = step * dt_s
        zeta = _bearing_error(mode, float(MODEL.bearing_bound(x)), t, switch_s, rng)
        s = est.update(s, Bearing((np.arctan2(y, x) if cartesian else y / x) + zeta))
        assert s.status == "ok" and s.contains(observe(y, v, x, e)), f"bearing, step {step}"
        if controls == "range" and step % 4 == 1:
            b = MODEL.range_rel_bound
            # one channel of the auxiliary model: the range is x itself (no off-axis angle)
            s = est.update(s, Range(x * (1 + rng.choice([-b, b])), off_axis_rad=0.0))
            assert s.contains(observe(y, v, x, e)), f"range, step {step}"
        k = 0.0
        if controls == "random" and step % 3 == 0:
            k = float(rng.uniform(-7.5, 7.5))
        elif controls == "law":
            k = law.impulse_mps(s, 0.0)
        v += k
        acc = {"uniform": rng.uniform(-1, 1), "bounds": rng.choice([-1.0, 1.0]), "zero": 0.0}
        acc = float(acc[v_mode]) * MODEL.nu_mps2
        s = est.predict(s, dt_s, k)  # the impulse acts at the step's start
        if s.status == "diverged" and factory in MAY_DIVERGE:
            break
        y, v, x = y + v * dt_s + 0.5 * acc * dt_s**2, v + acc * dt_s, x - e * dt_s
        if abs(y / x) > 1.0:
            break  # an unguided truth far off the axis near eps: outside the channel model
        assert s.status == "ok" and s.contains(observe(y, v, x, e)), f"predict, step {step}"
    return step, s


@pytest.mark.parametrize("name", FACTORIES)
def test_issue12_corner_is_in_the_initial_set_and_stays_in(name):
    """A counterexample: y = -10 km, Vy = -100 m/s, x0 = 6301.299 km, true
    closing speed 58.1 km/s (kp_fig5 boxes) has w = (e y + Vy x)/e_nom = -20881.55 m;
    an initial set built at e = e_nom reached down to -20864.31 m only. Bearings held
    at -a for 20 s: the state satisfies every bearing, the box and nu."""
    y, v, x0, e = -10e3, -100.0, 6301.299e3, 58.1e3
    est, s0 = FACTORIES[name](MODEL, BOX)
    w = float(ZeroEffortMiss(MODEL)(_observed(y, v, x0, e)))
    assert w == pytest.approx(-20881.55, abs=0.01)
    assert s0.extremes(ZeroEffortMiss(MODEL)).min_value <= w
    steps, _ = _run(FACTORIES[name], y, v, x0, e, "bias_low", "zero", "none", 0.0, 0, 40)
    assert steps == 39


@pytest.mark.parametrize("name", FACTORIES)
def test_initial_set_holds_every_corner_of_box_and_speed_interval(name):
    """All 16 corners of (Y, V, x0, e): the initial set must contain each of them."""
    _, s0 = FACTORIES[name](MODEL, BOX)
    corners = np.stack(
        np.meshgrid(BOX.y_m, BOX.v_mps, BOX.x_m, BOX.e_mps, indexing="ij"), -1
    ).reshape(-1, 4)
    missing = [tuple(c) for c in corners if not s0.contains(_observed(*c))]
    assert missing == []


#: the truths of the guarantee tests: every end of every interval with positive probability
_TRUTHS = dict(
    y=_ends_or_inside(*BOX.y_m),
    v=_ends_or_inside(*BOX.v_mps),
    x0=_ends_or_inside(*BOX.x_m),
    e=_ends_or_inside(*BOX.e_mps),
    mode=st.sampled_from(["uniform", "bounds", "bias_high", "bias_low", "switch"]),
    v_mode=st.sampled_from(["uniform", "bounds", "zero"]),
    controls=st.sampled_from(["none", "random", "law", "range"]),
    switch_s=st.floats(0.0, 60.0),
    seed=st.integers(0, 2**32 - 1),
    long=st.booleans(),
)


@pytest.mark.parametrize("name", FACTORIES)
@settings(max_examples=100, deadline=None)
@given(**_TRUTHS)
@example(
    y=-10e3, v=-100.0, x0=6301.299e3, e=58.1e3, mode="bias_low", v_mode="zero",
    controls="none", switch_s=0.0, seed=0, long=False,
)  # fmt: skip
# a range interval at the truth's edge emptied the node set's band of the truth (fixed:
# a piece emptied by a range interval is re-gridded where its bracket meets the limits)
@example(
    y=10e3, v=-100.0, x0=5799013.0, e=57926.0, mode="bias_high", v_mode="zero",
    controls="range", switch_s=60.0, seed=124, long=False,
)  # fmt: skip
@example(
    y=-9166.0, v=-100.0, x0=5301.3e3, e=58007.0, mode="uniform", v_mode="bounds",
    controls="range", switch_s=0.0, seed=1277, long=False,
)  # fmt: skip
def test_set_contains_physical_truth_at_every_step(
    name, y, v, x0, e, mode, v_mode, controls, switch_s, seed, long
):
    """The guarantee for truths drawn in physical coordinates (module docstring):
    30 steps of 0.5 s, or down to eps in 1 s steps for a fifth of the examples, guided
    by the package's law so that the truth stays in the channel model's domain. (They
    were 60 steps, and the long runs in 0.5 s steps, at twice the CPU time: the node
    set's work per step grows along the approach. The corner schedules of
    tests/test_nodeset_invariants.py run the node set down to eps in 0.5 s steps.)"""
    _guarantee_run(FACTORIES[name], y, v, x0, e, mode, v_mode, controls, switch_s, seed, long)


def _guarantee_run(factory, y, v, x0, e, mode, v_mode, controls, switch_s, seed, long,
                   cartesian=False):  # fmt: skip
    """30 steps of 0.5 s, or (``long`` with the law) down to eps in 1 s steps."""
    if long and controls == "law":  # down to eps in 1 s steps: half the steps
        _run(factory, y, v, x0, e, mode, v_mode, controls, switch_s, seed, 200, 1.0, cartesian)
    else:  # the switch at the same fraction of the short run as at 60 steps
        _run(factory, y, v, x0, e, mode, v_mode, controls, switch_s / 2, seed, 30,
             cartesian=cartesian)  # fmt: skip


@settings(max_examples=50, deadline=None)
@given(**_TRUTHS)
# every coordinate at a corner, the disturbance at nu against the kinematic term's
# sign (fuzz seed 1205051105): the auxiliary-model truth left the default set at step
# 1; read as Cartesian, the motion the margin is for, it stays inside
@example(
    y=-10e3, v=-100.0, x0=5301.3e3, e=58.1e3, mode="bias_low", v_mode="bounds",
    controls="random", switch_s=0.0, seed=0, long=False,
)  # fmt: skip
def test_default_node_set_contains_the_cartesian_truth_at_every_step(
    y, v, x0, e, mode, v_mode, controls, switch_s, seed, long
):
    """The default node set (kinematic margin on) against the truth it models: the
    motion above read as Cartesian (``x`` along the closing direction, ``Y'' = v``
    across it, bearings ``atan2(y, x)``), corners of the prior included. Its margin
    holds the two-body term ``-2 omega^2 x tan(alpha)`` that this reading carries."""
    _guarantee_run(_nodes, y, v, x0, e, mode, v_mode, controls, switch_s, seed, long, True)
