"""Honest extremes of the node set (estim.nodeset_belief): sound bounds or a refusal.

Between its nodes the node set is known through bounds only, so its ``extremes``
bounds the two recognised costs over the whole body and refuses any other function
(its values at the node vertices would be inner values passed off as extremes);
``attained`` gives values at states the set holds (the witnesses an adversary aims
at), never wider than the bounds; the rate has its own sound interval. The references
are the belief's own vertices at the pieces' closing-speed ends, evaluated here.
"""

import numpy as np
import pytest
from kalman_vs_infoset.estim.intercept.costs import MissForecast, ZeroEffortMiss
from kalman_vs_infoset.estim.intercept.describe import describe_channel
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    Impulse,
    Range,
)
from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator

MODEL = ChannelModel()  # seed 003 section 6
DT = 0.5
PRIOR = ChannelPrior((-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3))
SPEEDS = (57.9e3, 58.1e3)  # Fig. 5's closing-speed interval


@pytest.fixture(scope="module")
def beliefs():
    """Node sets along an approach with bearings, impulses and two range measurements."""
    est = NodeSetEstimator(MODEL, closing_speed_mps=SPEEDS)
    b = est.initial(PRIOR)
    rng = np.random.default_rng(11)
    out = [b]
    x = 5801.3e3
    for k in range(60):
        b = est.update(b, Bearing(-1.0e-3 + rng.uniform(-1.5e-4, 1.5e-4)))
        if k in (10, 40):
            b = est.update(b, Range(x * (1 + rng.uniform(-0.05, 0.05))))
        out.append(b)
        b = est.predict(b, DT, Impulse(float(rng.uniform(-2, 2)), 0.1))
        x -= MODEL.e * DT
    return out


def _vertex_rows(b):
    """Every live vertex at both ends of its piece's ``u`` (rows alpha, omega, x)."""
    own = b.polygons.owner()
    p, tau = b.piece[own], b.tau_s[own]
    rows = []
    for u in (b.u_lo[p], b.u_hi[p]):
        x = tau / u
        w = b.polygons.xy[:, 1] / (u * MODEL.e) ** 2
        rows.append(np.column_stack([b.polygons.xy[:, 0] * b.alpha_scale_rad,
                                     MODEL.omega_from_w(w, x), x]))  # fmt: skip
    return np.vstack(rows)


@pytest.mark.parametrize(
    "fn", [lambda p: p[:, 0], lambda p: p[:, 1] * p[:, 2], MODEL.miss_forecast_m]
)
def test_a_plain_function_is_refused(beliefs, fn):
    """Vertex values are not extremes: a function the set cannot bound over its whole
    body (even the miss forecast passed as a plain function) raises, naming the way
    out."""
    with pytest.raises(TypeError, match="attained"):
        beliefs[-1].extremes(fn)


@pytest.mark.parametrize("cost", [MissForecast(MODEL), ZeroEffortMiss(MODEL)])
def test_recognised_costs_bound_every_state_the_set_holds(beliefs, cost):
    """The recognised costs' extremes bound their values at every vertex (both speed
    ends), and ``attained`` returns the largest of those values at a state the set
    contains."""
    for b in beliefs[::6]:
        ext, att = b.extremes(cost), b.attained(cost)
        vals = cost(_vertex_rows(b))
        assert ext.min_value <= vals.min() and vals.max() <= ext.max_value
        assert att.max_value == vals.max() and att.min_value == vals.min()
        for v, arg in ((att.min_value, att.argmin), (att.max_value, att.argmax)):
            assert float(cost(arg[None, :])[0]) == v
            assert b.contains(arg)


def test_attained_takes_any_function_at_the_sets_own_states(beliefs):
    b = beliefs[-1]
    att = b.attained(lambda p: p[:, 0] - 1e-3 * p[:, 1])
    assert att.min_value < att.max_value
    assert b.contains(att.argmin) and b.contains(att.argmax)
    lo, hi = b.alpha_range_rad()
    att = b.attained(lambda p: p[:, 0])
    assert lo <= att.min_value and att.max_value <= hi


def test_the_rate_interval_bounds_every_vertex_and_the_trace_uses_it(beliefs):
    """``omega_range_radps`` is an outer interval of the rate (each cell's ``w`` over
    its ``x``); the trace's rate columns are that interval (the node set refuses the
    plain column function the trace asks other beliefs about)."""
    for b in beliefs[::6]:
        lo, hi = b.omega_range_radps()
        omega = _vertex_rows(b)[:, 1]
        assert lo <= omega.min() and omega.max() <= hi
        row = describe_channel(b, MODEL)
        assert (row["omega_lo_radps"], row["omega_hi_radps"]) == (lo, hi)
        assert row["alpha_lo_rad"] <= row["alpha_hi_rad"]
