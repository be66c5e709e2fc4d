"""``extremes`` of the attitude beliefs keep the interface's promise (``estim/base.py``):
sound bounds of a function over the belief, or ``TypeError``. Every attitude belief
bounds the body rate about an axis (:class:`RateComponent`); the sets refuse other
functions (|w|^2 read 9.1e-8 to 9.1e-8 from the box's vertices while its body holds
w = 0). Checked against brute force: states sampled in the belief."""

from __future__ import annotations

import numpy as np
import pytest
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
    RateComponent,
)

from kalman_vs_infoset.numerics.rotations import qexp, qmul

MODEL = AttitudeModel(np.array([4.0, 5.0, 6.0]), 1e-3, 1e-3, 2e-4)
SETS = ("box", "zonotope", "ellipsoid")


def _belief(name: str):
    """A belief after one prediction and one update, rates near zero (so the rate
    interval straddles w = 0, where |w|^2 is least)."""
    est = registry.get("attitude", name).build(None, MODEL)
    q = np.array([[0.1, -0.2, 0.3, 0.9]])
    q /= np.linalg.norm(q)
    w = np.array([[1e-5, -2e-5, 5e-6]])
    b = est.initial(AttitudePrior(AttitudeMeasurement(q, w)))
    b = est.predict(b, 0.1, AttitudeControl.zero(1))
    return est.update(b, AttitudeMeasurement(q, w + 3e-5))


def _samples(b, rng, n=4000) -> np.ndarray:
    """States around the belief's centre (error rotations and rates up to 1.2x the
    bounds), those the belief holds."""
    c = b.centre()[0]
    e = rng.uniform(-1, 1, (n, 3)) * 1.2 * MODEL.meas_angle_bound_rad
    pts = np.concatenate(
        [qmul(np.broadcast_to(c[0:4], (n, 4)), qexp(e)),
         c[4:7] + rng.uniform(-1, 1, (n, 3)) * 1.2 * MODEL.meas_rate_bound_radps],
        axis=-1,
    )  # fmt: skip
    return pts[_inside(b, pts)]


def _inside(b, pts: np.ndarray) -> np.ndarray:
    return np.array([bool(b.inside(p[None, :])[0]) for p in pts])


@pytest.mark.parametrize("name", [*SETS, "ukf"])
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_rate_extremes_hold_every_sampled_state_and_are_attained(name, axis):
    b = _belief(name)
    fn = RateComponent(axis)
    ext = b.extremes(fn)
    pts = _samples(b, np.random.default_rng(axis))
    assert len(pts) > 50
    vals = fn(pts)
    assert ext.min_value <= vals.min() and vals.max() <= ext.max_value
    # the arguments are states of the belief at those values (the box's and the
    # ellipsoid's are exact; a set's hull vertex may lie outside the set itself)
    assert fn(ext.argmin[None, :])[0] == ext.min_value
    assert fn(ext.argmax[None, :])[0] == ext.max_value
    if name == "box":
        assert all(b.inside(arg[None, :], 1e-9)[0] for arg in (ext.argmin, ext.argmax))
    if name == "ukf":
        args = np.stack([ext.argmin, ext.argmax])
        assert np.allclose(b.mahalanobis(args), b.gate, rtol=1e-6)
        # the gate ellipsoid sampled on its surface (it reaches beyond the samples above):
        # no point beyond the closed form, and the closed form nearly reached
        u = np.random.default_rng(9).normal(size=(20000, 6))
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        w = b.mean[0, 3 + axis] + b.gate * (u @ np.linalg.cholesky(b.cov[0, :6, :6]).T)[:, 3 + axis]
        span = ext.max_value - ext.min_value
        assert ext.min_value - 1e-12 * span <= w.min() and w.max() <= ext.max_value + 1e-12 * span
        assert w.max() - w.min() > 0.98 * span
    if name == "box":  # the exact range: brute force comes close to it
        assert vals.max() - vals.min() > 0.8 * (ext.max_value - ext.min_value)


@pytest.mark.parametrize("name", [*SETS, "ukf"])
def test_a_function_other_than_a_rate_component_is_refused(name):
    """|w|^2 over a box straddling w = 0: its vertices give no extreme of it."""
    b = _belief(name)
    with pytest.raises(TypeError, match="RateComponent"):
        b.extremes(lambda s: np.sum(np.asarray(s)[..., 4:7] ** 2, axis=-1))


def test_a_rate_component_names_an_axis():
    with pytest.raises(ValueError, match="axis"):
        RateComponent(3)


@pytest.mark.parametrize("name", SETS)
@pytest.mark.parametrize("axis", [0, 1, 2])
def test_attained_values_are_at_states_of_the_belief_within_the_extremes(name, axis):
    """``attained`` gives witnesses: each argument a state the belief holds, its value
    that state's, and the interval inside :meth:`extremes` (the sets' hull vertices,
    their extremes' arguments, may lie outside the set)."""
    b = _belief(name)
    fn = RateComponent(axis)
    ext, att = b.extremes(fn), b.attained(fn)
    for arg, value in ((att.argmin, att.min_value), (att.argmax, att.max_value)):
        assert b.inside(np.broadcast_to(arg, (b.runs, 7)))[0]
        assert fn(arg[None, :])[0] == value
    assert ext.min_value <= att.min_value <= att.max_value <= ext.max_value
    with pytest.raises(TypeError, match="RateComponent"):
        b.attained(lambda s: np.asarray(s)[..., 0])


def test_measurement_and_control_shapes_are_checked_in_one_line():
    """A (2, 3) "quaternion" was taken as a measurement (the point belief returned a
    (2, 6) state, the others failed as numpy broadcast errors), and a measurement or
    control of one run was broadcast over a belief of two, silently."""
    w = np.zeros((1, 3))
    with pytest.raises(ValueError, match=r"quat must be \(R, 4\)"):
        AttitudeMeasurement(np.ones((2, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="quat has 2 runs and rate_radps 1"):
        AttitudeMeasurement(np.tile([1.0, 0, 0, 0], (2, 1)), w)
    with pytest.raises(ValueError, match=r"must be \(R, 3\) each"):
        AttitudeControl(np.zeros((2, 3)), np.zeros((1, 3)), np.zeros((1, 3)))
    q2 = np.tile([[1.0, 0.0, 0.0, 0.0]], (2, 1))
    for name in registry.names("attitude"):
        est = registry.get("attitude", name).build(None, MODEL)
        b = est.initial(AttitudePrior(AttitudeMeasurement(q2, np.zeros((2, 3)))))
        with pytest.raises(ValueError, match="the belief holds 2 runs and the measurement 1"):
            est.update(b, AttitudeMeasurement(q2[:1], w))
        if name != "perfect":  # (the point belief takes no inputs)
            with pytest.raises(ValueError, match="the belief holds 2 runs and the control 1"):
                est.predict(b, 0.1, AttitudeControl.zero(1))
        est.predict(b, 0.1, AttitudeControl.zero(2))  # one row a run: taken


@pytest.mark.parametrize("name", SETS)
def test_the_counts_of_a_set_belief_are_values_too(name):
    """The zonotope's and ellipsoid's ``n_empty``, ``last_empty`` were writable and shared
    by successive beliefs (a write into one changed the belief before it)."""
    b1 = _belief(name)
    b2 = registry.get("attitude", name).build(None, MODEL).predict(b1, 0.1, AttitudeControl.zero(1))
    for b in (b1, b2):
        for field in ("n_empty", "last_empty"):
            arr = getattr(b, field, None)
            if arr is not None:
                with pytest.raises(ValueError, match="read-only"):
                    arr[0] = 5
    assert b1.contradictions == b2.contradictions


def test_a_state_of_another_run_count_is_refused_by_every_belief():
    """``box.contains(state of one run)`` on a belief of two runs broadcast the state over
    both and answered True; the other beliefs failed with a numpy concatenate error."""
    q2 = np.tile([[1.0, 0.0, 0.0, 0.0]], (2, 1))
    for name in registry.names("attitude"):
        est = registry.get("attitude", name).build(None, MODEL)
        b = est.initial(AttitudePrior(AttitudeMeasurement(q2, np.zeros((2, 3)))))
        states = np.concatenate([q2, np.zeros((2, 3))], axis=1)
        assert b.inside(states).shape == (2,)
        for bad in (states[0], states[:, :5], np.tile(states, (2, 1))):
            with pytest.raises(ValueError, match=r"a state \(q, w, \.\.\.\) per run: \(2, 7\)"):
                b.contains(bad)
