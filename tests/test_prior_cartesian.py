"""The set estimators' initial sets hold every Cartesian state of the a-priori box
(:meth:`ChannelPrior.auxiliary_box`), for boxes wide against their range too.

The sets take ``(Y, V) = (alpha x, omega x - c alpha)`` for ``(y, Vy)`` (a small-angle
map); the exact bearing ``atan2(y, x)`` and rate ``omega = (x Vy + c y) / (x^2 + y^2)``
move a state out of the box when ``(2/3) c |y| / x`` exceeds ``|Vy|``'s face: a box of
+-100 km at 5301 km (``kvi compare kp_fig5 --set "estimator.y_km=[-100.0,100.0]"``) left
the truth outside the node set for its first 77 steps. Checked against the exact map
(``ChannelModel.from_cartesian``) at the box's corners and on its faces, by brute force.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.intercept.model import ChannelModel, ChannelPrior
from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator
from kalman_vs_infoset.estim.intercept.sections.zonotope import ZonotopeFamily
from kalman_vs_infoset.estim.intercept.slabs.estimator import InformationSetEstimator

MODEL = ChannelModel()
SPEED = (57.9e3, 58.1e3)


def _exact_yv(y, vy, x, c):
    """``(Y, V)`` of Cartesian states, from the exact bearing and rate."""
    alpha, omega, _ = np.moveaxis(MODEL.from_cartesian(y, vy, x, -c), -1, 0)
    return alpha * x, omega * x - c * alpha


def _within(values, lo: float, hi: float, terms: float = 0.0) -> bool:
    """``values`` in ``[lo, hi]`` up to the rounding of the exact map: 1e-12 of the
    magnitudes, ``terms`` among them (``V = omega x - c alpha`` cancels terms of
    ``c |alpha|``; ``atan2`` and the rate are each a few ulps off)."""
    tol = 1e-12 * max(abs(lo), abs(hi), float(np.abs(values).max()), terms) + 1e-300
    return bool(values.min() >= lo - tol and values.max() <= hi + tol)


def _grid(prior: ChannelPrior, n: int = 9):
    """States on the box's faces and corners (every closing speed of the interval)."""
    axes = [np.linspace(lo, hi, n) for lo, hi in (prior.lateral_m, prior.lateral_vel_mps)]
    axes += [np.array(prior.x_m), np.linspace(*SPEED, 3)]
    return [a.ravel() for a in np.meshgrid(*axes, indexing="ij")]


def test_seed_003_boxes_need_no_widening():
    """kp_fig3/kp_fig5's boxes (+-10 km, +-100 m/s, from 5301.3 km, up to 59 km/s): the
    initial sets, and so every published number, are as before."""
    box = ChannelPrior((-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3))
    assert box.auxiliary_box(59e3) is box
    y, vy, x, c = _grid(box)
    yy, vv = _exact_yv(y, vy, x, c)
    assert _within(yy, -10e3, 10e3) and _within(vv, -100.0, 100.0, 59e3 * 10e3 / 5301.3e3)


_BOXES = dict(
    y_lo=st.floats(-2e6, 1e6),
    y_width=st.floats(0.0, 2e6),
    v_lo=st.floats(-2e3, 1e3),
    v_width=st.floats(0.0, 2e3),
    x_lo=st.floats(2e6, 8e6),
)


@settings(max_examples=300, deadline=None)
@given(**_BOXES)
@example(y_lo=-100e3, y_width=200e3, v_lo=-100.0, v_width=200.0, x_lo=5301.3e3)
@example(y_lo=5e3, y_width=5e5, v_lo=0.0, v_width=50.0, x_lo=3e6)
def test_the_auxiliary_box_holds_the_exact_image_of_the_box(y_lo, y_width, v_lo, v_width, x_lo):
    """Brute force over the faces: no exact ``(Y, V)`` beyond the widened box, which
    only ever widens."""
    box = ChannelPrior((y_lo, y_lo + y_width), (v_lo, v_lo + v_width), (x_lo, 1.2 * x_lo))
    aux = box.auxiliary_box(SPEED[1])
    assert aux.lateral_m[0] <= y_lo and aux.lateral_m[1] >= y_lo + y_width
    assert aux.lateral_vel_mps[0] <= v_lo and aux.lateral_vel_mps[1] >= v_lo + v_width
    yy, vv = _exact_yv(*_grid(box, 21))
    terms = SPEED[1] * max(abs(y_lo), abs(y_lo + y_width)) / x_lo
    assert _within(yy, *aux.lateral_m) and _within(vv, *aux.lateral_vel_mps, terms)


FACTORIES = {
    "nodes": lambda: NodeSetEstimator(MODEL, closing_speed_mps=SPEED),
    "slabs": lambda: InformationSetEstimator(MODEL, closing_speed_mps=SPEED),
    "zonotope": lambda: InformationSetEstimator(
        MODEL, closing_speed_mps=SPEED, family=ZonotopeFamily()
    ),
}


@pytest.mark.parametrize("name", FACTORIES)
@pytest.mark.parametrize("half_km", [15.0, 100.0, 1000.0])
def test_a_wide_box_is_held_by_the_initial_set_at_its_corners_and_faces(name, half_km):
    box = ChannelPrior((-half_km * 1e3, half_km * 1e3), (-100.0, 100.0), (5301.3e3, 6301.3e3))
    s0 = FACTORIES[name]().initial(box)
    y, vy, x, c = _grid(box, 5)
    states = MODEL.from_cartesian(y, vy, x, -c)
    missing = [tuple(p) for p, st_ in zip(zip(y, vy, x, c, strict=True), states, strict=True)
               if not s0.contains(st_)]  # fmt: skip
    assert missing == []


@pytest.mark.parametrize("name", FACTORIES)
def test_the_auxiliary_model_s_set_takes_a_wide_box_as_it_is(name):
    """Without the kinematic margin a set is the auxiliary model's (``kvi tightness``):
    it holds the box's auxiliary-model states, corners included, and no more than the
    box in ``V``: its zero-effort-miss interval is the raw box's, narrower than the
    widened one of the two-body set (their boxes differ by 0.4 m/s here)."""
    from dataclasses import replace

    from kalman_vs_infoset.estim.intercept.costs import ZeroEffortMiss

    box = ChannelPrior((-100e3, 100e3), (-100.0, 100.0), (5301.3e3, 6301.3e3))
    two_body = FACTORIES[name]()
    auxiliary = replace(two_body, kinematic_margin=False)
    assert box.auxiliary_box(SPEED[1]) != box  # a box the two-body set widens
    s_aux, s_two = auxiliary.initial(box), two_body.initial(box)
    y, vy, x, c = _grid(box, 5)
    states = np.stack([y / x, (vy * x + c * y) / x**2, x], axis=-1)  # the auxiliary map
    assert all(s_aux.contains(s) for s in states)
    zem = ZeroEffortMiss(MODEL)
    (lo_a, hi_a), (lo_t, hi_t) = ((b.extremes(zem).min_value, b.extremes(zem).max_value)
                                  for b in (s_aux, s_two))  # fmt: skip
    assert lo_t < lo_a < hi_a < hi_t
