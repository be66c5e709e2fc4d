"""The node set (estim.intercept.nodeset): exact slices at moving nodes, sound bounds between them.

Independent references: the auxiliary model's own exact step (ChannelModel.step,
seed 003 section 4) for the truth, a dense node set (the same exact slices at 10x
the nodes) for the bounds between nodes, and shapely for the slices themselves.
"""

import numpy as np
import pytest
import shapely
from docs_numbers import ROOT
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.base import Status
from kalman_vs_infoset.estim.intercept.costs import MissForecast, ZeroEffortMiss
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    Impulse,
    Range,
)
from kalman_vs_infoset.estim.intercept.nodeset.estimator import NodeSetEstimator

MODEL = ChannelModel()  # seed 003 section 6: e = 58 km/s, nu = 0.005 m/s^2, eps = 5 km
E, DT = MODEL.e, 0.5
PRIOR = ChannelPrior((-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3))
SPEEDS = (57.9e3, 58.1e3)  # Fig. 5's closing-speed interval


def _truth_row(y, vy, x, e):
    """(alpha, omega, x) of the auxiliary model: alpha = Y/x, omega x^2 = Vy x + e Y."""
    return np.array([y / x, (vy * x + e * y) / x**2, x])


def _run(est, truth, e_true, steps, errors, impulses, v_mps2, check=None):
    """Drive ``est`` and the auxiliary-model truth ``(Y, V, x)`` through ``steps``
    steps; ``check(belief, row)`` after every update and prediction."""
    b = est.initial(PRIOR)
    y, vy, x = truth
    for k in range(steps):
        a = float(MODEL.bearing_bound(x))
        b = est.update(b, Bearing(y / x + errors(k, a)))
        if check:
            check(b, _truth_row(y, vy, x, e_true))
        k_mps = impulses(k)
        b = est.predict(b, DT, k_mps)
        vy += k_mps
        v = v_mps2(k)
        y, vy, x = y + vy * DT + v * DT**2 / 2, vy + v * DT, x - e_true * DT
        if b.is_empty or x < MODEL.eps_m + E * DT:
            break
        if check:
            check(b, _truth_row(y, vy, x, e_true))
    return b


def _assert_inside(b, row):
    assert b.status in (Status.OK, Status.TERMINAL), b.status
    assert b.is_empty or b.contains(row), (b.status, row)


@settings(max_examples=12, deadline=None)
@given(
    y=st.one_of(st.sampled_from([-10e3, 10e3]), st.floats(-10e3, 10e3)),
    vy=st.one_of(st.sampled_from([-100.0, 100.0]), st.floats(-100.0, 100.0)),
    x0=st.one_of(st.sampled_from([5301.3e3, 6301.3e3]), st.floats(5301.3e3, 6301.3e3)),
    e=st.one_of(st.sampled_from(list(SPEEDS)), st.floats(*SPEEDS)),
    kind=st.sampled_from(["uniform", "bound", "switch"]),
    seed=st.integers(0, 2**16),
)
@example(y=-10e3, vy=-100.0, x0=6301.299e3, e=58.1e3, kind="bound", seed=0)  # once failed
# every corner at once, the disturbance at +nu against the kinematic term's sign: with
# the (physical) kinematic margin on, this auxiliary-model truth left the set by 0.6 %
# of nu (fuzz seed 1205051103); the margin is off here, see the docstring
@example(y=10e3, vy=100.0, x0=5301.3e3, e=58.1e3, kind="bound", seed=236)
def test_truth_inside_at_every_step_in_physical_coordinates(y, vy, x0, e, kind, seed):
    """Seed 003 section 4's guarantee, for any state of the a-priori box (corners
    included) and any closing speed of the interval: errors uniform, held at the
    bound or switched, disturbances at +-nu, impulses of either sign.

    The truth moves by the seed's auxiliary model (``Y'' = v``, ``|v| <= nu``), so the
    set is the seed's: without the kinematic margin, which adds the physical motion's
    term ``-2 omega^2 x tan(alpha)`` with its sign (a truth of the auxiliary model
    pushing against that sign at a corner of everything can then lie outside the
    set by a fraction of the term). Physical truths with the margin on are
    ``test_soundness_physical.py``'s."""
    rng = np.random.default_rng(seed)
    est = NodeSetEstimator(
        MODEL, closing_speed_mps=SPEEDS, n_nodes=8, min_live_nodes=4, kinematic_margin=False
    )
    sign = rng.choice([-1.0, 1.0])

    def errors(k, a):
        a = a * (1 - 1e-9)
        if kind == "uniform":
            return rng.uniform(-a, a)
        return sign * a * (1.0 if kind == "bound" or k < 60 else -1.0)

    _run(
        est, (y, vy, x0), e, 120, errors,
        impulses=lambda k: float(rng.choice([0.0, 0.0, 2.0, -3.0])),
        v_mps2=lambda k: float(rng.choice([-1.0, 1.0])) * MODEL.nu_mps2,
        check=_assert_inside,
    )  # fmt: skip


def test_bounds_between_nodes_hold_the_dense_set_and_are_tight():
    """The same data into 8 nodes and into 80 (exact slices both): every node slice of
    the dense set lies under the coarse set's bounds (soundness between nodes), and
    the coarse interval of w is within 5 % of the dense set's (tightness)."""
    rng = np.random.default_rng(2)
    coarse = NodeSetEstimator(MODEL, n_nodes=8, min_live_nodes=4)
    dense = NodeSetEstimator(MODEL, n_nodes=80, min_live_nodes=40)
    bc, bd = coarse.initial(PRIOR), dense.initial(PRIOR)
    y, vy, x = -8e3, 20.0, 5801.3e3
    for k in range(170):
        a = float(MODEL.bearing_bound(x))
        m = Bearing(y / x + rng.uniform(-a, a))
        bc, bd = coarse.update(bc, m), dense.update(bd, m)
        if k % 10 == 9:
            lo, hi = bc.w_bounds_m()
            zs = bd.polygons.xy[:, 1]  # e = e_nom: zs is w
            assert lo <= zs.min() and zs.max() <= hi
            d_lo, d_hi = bd.w_bounds_m()
            assert hi - lo <= 1.05 * (d_hi - d_lo)
        k_mps = 1.0 if k % 7 == 0 else 0.0
        bc, bd = coarse.predict(bc, DT, k_mps), dense.predict(bd, DT, k_mps)
        vy += k_mps
        y, x = y + vy * DT, x - E * DT


def test_regridded_nodes_equal_nodes_followed_from_the_start():
    """Refinement replays the log: a node created late is the slice a node at the
    same label followed from the initial set would have."""
    est = NodeSetEstimator(MODEL, n_nodes=9, min_live_nodes=4)
    rng = np.random.default_rng(5)
    b = est.initial(PRIOR)
    y, x = -3e3, 5801.3e3
    for k in range(60):
        a = float(MODEL.bearing_bound(x))
        b = est.update(b, Bearing(y / x + rng.uniform(-a, a)))
        b = est.predict(b, DT, 0.5 if k % 5 == 0 else None)
        y, x = y + 0.5 * DT * (k // 5 + 1), x - E * DT
    labels = b.label_s[b.live][:3]
    again = est._regrid(b, 0, labels)
    for lab in labels:
        i = int(np.flatnonzero((b.label_s == lab) & (b.piece == 0))[0])
        j = int(np.flatnonzero((again.label_s == lab) & (again.piece == 0))[0])
        p, q = b.polygons.polygon(i), again.polygons.polygon(j)
        np.testing.assert_allclose(p, q, rtol=0, atol=1e-9 * np.abs(p).max())


def test_node_slice_is_the_exact_polygon_of_the_seed_operations():
    """One node (known range and closing speed): its slice equals the polygon built
    with shapely from the same operations -- strip intersections, the shear of
    seed 003's exact step and the Minkowski sum with the disturbance set (the seed's
    segment of constant disturbances plus +-nu dt^2/4 in Y for one varying within
    the step, :func:`test_disturbance_set_holds_every_varying_disturbance`)."""
    est = NodeSetEstimator(MODEL, n_nodes=4, min_live_nodes=4, kinematic_margin=False)
    x0 = 5801.3e3
    prior = ChannelPrior((-10e3, 10e3), (-100.0, 100.0), (x0, x0))
    b = est.initial(prior)
    scale = est.alpha_scale_rad
    corners = [(y, v) for y, v in [(-1e4, -100), (1e4, -100), (1e4, 100), (-1e4, 100)]]
    poly = shapely.Polygon([(y / x0 / scale, y + v * x0 / E) for y, v in corners])
    rng = np.random.default_rng(9)
    x = x0
    for _ in range(40):
        alpha_m = -1e-3 + rng.uniform(-1.4e-4, 1.4e-4)
        b = est.update(b, Bearing(alpha_m))
        h = float(MODEL.bearing_bound(x)) / scale
        strip = shapely.box(alpha_m / scale - h, -1e9, alpha_m / scale + h, 1e9)
        poly = poly.intersection(strip)
        b = est.predict(b, DT)
        x1 = x - E * DT
        c = MODEL.step_coefficients(x, DT)
        sheared = shapely.affinity.affine_transform(
            poly, [1.0, float(c["a_w"]) / scale, 0.0, 1.0, 0.0, 0.0]
        )
        g = np.array([float(c["g_alpha"]) / scale, float(c["g_w"])]) * MODEL.nu_mps2
        lens = np.array([0.5 * g[0], MODEL.nu_mps2 * DT**2 / 4])  # Y += +-nu dt^2/4
        shifts = [sg * g + sl * lens for sg in (-1, 1) for sl in (-1, 1)]
        pts = np.vstack([np.array(sheared.exterior.coords) + d for d in shifts])
        poly = shapely.convex_hull(shapely.MultiPoint(pts))
        x = x1
    node = b.polygons.polygon(int(np.flatnonzero(b.live)[0]))
    ours = shapely.Polygon(node)
    assert ours.symmetric_difference(poly).area <= 1e-7 * poly.area


@pytest.mark.parametrize("family", ["nodes", "slabs"])
def test_an_impulse_moves_the_auxiliary_model_set_by_exactly_k_x_over_e(family):
    """The auxiliary model's impulse is ``V += k`` whatever the bearing, so ``w = (V x +
    e Y) / e`` moves by ``k x / e`` at every state: the set of that model alone (no
    kinematic margin) moves both ends of its interval of ``w`` by exactly that, 0.3 rad
    off the axis. The set of the two-body motion spreads it by the impulse's geometry
    (``k cos^2(alpha)``, docs/models.md §1.3: at least half of ``k sin^2(alpha) x / e``
    here); before this release the auxiliary-model set spread it too (601 times the
    exact width in case 70830 of tests/fuzz_tightness.py, docs/infoset.md)."""
    from kalman_vs_infoset.estim.intercept.slabs.estimator import InformationSetEstimator

    x0, k = 300e3, 40.0
    prior = ChannelPrior((0.30 * x0, 0.31 * x0), (-10.0, 10.0), (x0, x0))
    spread = k * np.sin(0.30) ** 2 * x0 / E
    for margin in (False, True):
        if family == "nodes":
            est = NodeSetEstimator(MODEL, kinematic_margin=margin)
        else:
            est = InformationSetEstimator(MODEL, sections="slabs", kinematic_margin=margin)
        b = est.update(est.initial(prior), Bearing(0.305))
        ext = [est.predict(b, DT, dv).extremes(ZeroEffortMiss(MODEL)) for dv in (0.0, k)]
        (lo0, hi0), (lo1, hi1) = ((e.min_value, e.max_value) for e in ext)
        if margin:
            assert (hi1 - lo1) - (hi0 - lo0) >= 0.5 * spread
        else:
            assert lo1 - lo0 == pytest.approx(k * x0 / E, abs=1e-6)
            assert hi1 - hi0 == pytest.approx(k * x0 / E, abs=1e-6)


@settings(max_examples=30, deadline=None)
@given(v=st.lists(st.floats(-1.0, 1.0), min_size=1, max_size=40))
def test_disturbance_set_holds_every_varying_disturbance(v):
    """Y'' = v(t), |v| <= nu, piecewise constant over any number of sub-steps: the
    change (dY, dV) over the step lies in the segment of constant disturbances
    {(c dt^2/2, c dt) : |c| <= nu} plus [-nu dt^2/4, nu dt^2/4] in Y (the largest
    departure, at dV = 0, is the bang-bang pair +nu then -nu)."""
    nu = MODEL.nu_mps2
    h = DT / len(v)
    acc = np.asarray(v) * nu
    dv = float(np.sum(acc) * h)
    # exact integral of a piecewise-constant acceleration
    t_left = DT - h * (np.arange(len(v)) + 0.5)
    dy = float(np.sum(acc * h * t_left))
    c = dv / DT  # the constant disturbance with the same dV
    assert abs(c) <= nu * (1 + 1e-12)
    assert abs(dy - c * DT**2 / 2) <= nu * DT**2 / 4 * (1 + 1e-12)


def test_contradicting_bearing_is_rejected_and_reported():
    est = NodeSetEstimator(MODEL)
    b = est.initial(PRIOR)
    out = est.update(b, Bearing(0.5))  # 0.5 rad: no state of the box sees that
    assert out.status is Status.CONTRADICTION and out.contradictions == 1
    assert out.n_sections == b.n_sections  # the set before the update is kept


def test_every_node_under_eps_makes_the_set_terminal():
    est = NodeSetEstimator(MODEL)
    b = est.initial(ChannelPrior((-1e3, 1e3), (-1.0, 1.0), (30e3, 40e3)))
    for _ in range(40):
        if b.is_empty:
            break
        b = est.predict(b, DT)
    assert b.is_empty and b.status is Status.TERMINAL


def test_range_measurement_drops_the_nodes_outside_its_interval():
    est = NodeSetEstimator(MODEL)
    b = est.update(est.initial(PRIOR), Range(5.8e6, off_axis_rad=0.0))
    lo, hi = b.x_range_m()
    assert lo >= 5.8e6 / 1.05 * (1 - 1e-6) and hi <= 5.8e6 / 0.95 * (1 + 1e-6)
    assert b.contains(_truth_row(0.0, 0.0, 5.8e6, E))


def test_contains_rejects_states_the_last_bearing_rules_out():
    """``contains`` is what every experiment's ``truth_outside`` count relies on, so it
    must also say *no*: a state whose bearing lies three bounds off the last measured
    one (seed 003 section 4: ``|alpha - alpha_m| <= a(x)``) is outside the set, for any
    closing speed, and so is one whose zero-effort miss lies beyond the set's sound
    bounds (``extremes``) by their width (and the 1 % the closing speed can scale it).
    States are set vertices with the bearing or the rate moved (both sides), on a
    Fig. 5 approach (closing speed unknown within 57.9-58.1 km/s)."""
    est = NodeSetEstimator(MODEL, closing_speed_mps=SPEEDS)
    b = est.initial(PRIOR)
    rng = np.random.default_rng(4)
    y, vy, x, checked = 2e3, -30.0, 5.8e6, 0
    for k in range(190):
        alpha_m = y / x + rng.uniform(-1.0, 1.0) * float(MODEL.bearing_bound(x))
        b = est.update(b, Bearing(alpha_m))
        if k % 10 == 0:
            ext = b.extremes(ZeroEffortMiss(MODEL))
            lo, hi = ext.min_value, ext.max_value
            far = (hi - lo) + 0.01 * max(abs(lo), abs(hi)) + 1.0
            verts = b.vertices()
            for st in verts[rng.choice(len(verts), min(20, len(verts)), replace=False)]:
                assert b.contains(st)  # a vertex of the set itself
                off = 3.0 * float(MODEL.bearing_bound(st[2]))
                for side in (1.0, -1.0):
                    assert not b.contains([alpha_m + side * off, st[1], st[2]]), (k, side)
                    w = hi + far if side > 0 else lo - far
                    omega = float(MODEL.omega_from_w(w, st[2]))
                    assert not b.contains([st[0], omega, st[2]]), (k, side, w)
                    checked += 2
        b = est.predict(b, DT)
        y, x = y + vy * DT, x - E * DT
    assert checked >= 600
    assert not b.contains([np.nan, 0.0, x]) and not b.contains([0.0, np.inf, x])


def test_forecast_extremes_bound_the_miss_of_every_node_vertex():
    """Pi and w over the set bound their values at every vertex of every node."""
    est = NodeSetEstimator(MODEL, closing_speed_mps=SPEEDS)
    b = est.initial(PRIOR)
    rng = np.random.default_rng(3)
    for _ in range(50):
        b = est.predict(est.update(b, Bearing(rng.uniform(-2e-4, 2e-4))), DT, Impulse(1.0, 0.1))
    for cost in (MissForecast(MODEL), ZeroEffortMiss(MODEL)):
        ext = b.extremes(cost)
        vals = cost(b.vertices())
        assert ext.min_value <= vals.min() and vals.max() <= ext.max_value


def test_compiled_forecast_attained_equals_the_general_path_bit_for_bit():
    """``attained(MissForecast)`` (compiled, the game adversary's question) gives the
    general path's values and rows exactly, on sets with several bands and pieces, a
    range interval and impulses, from the a-priori box to the end of the approach."""
    est = NodeSetEstimator(MODEL, closing_speed_mps=SPEEDS)
    forecast = MissForecast(MODEL)
    rng = np.random.default_rng(7)
    b, x, seen = est.initial(PRIOR), 5800e3, 0
    while not b.is_empty and x > MODEL.eps_m + E * DT:
        b = est.update(b, Bearing(rng.uniform(-2e-4, 2e-4)))
        if rng.uniform() < 0.1:
            b = est.update(b, Range(x, off_axis_rad=0.0))
        if b.is_empty:
            break
        fast = b.attained(forecast)
        general = b.attained(lambda pts: forecast(pts))  # not a MissForecast: numpy
        assert (fast.min_value, fast.max_value) == (general.min_value, general.max_value)
        assert np.array_equal(fast.argmin, general.argmin)
        assert np.array_equal(fast.argmax, general.argmax)
        seen += 1
        b = est.predict(b, DT, Impulse(rng.uniform(-2.0, 2.0), 0.1))
        x -= E * DT
    assert seen > 150 and len(b.u_lo) > 1  # the whole approach, several pieces


def test_beliefs_are_never_mutated():
    est = NodeSetEstimator(MODEL, closing_speed_mps=SPEEDS)
    b = est.initial(PRIOR)
    xy = b.polygons.xy.copy()
    est.predict(est.update(b, Bearing(1e-4)), DT, 2.0)
    b.extremes(MissForecast(MODEL))
    np.testing.assert_array_equal(b.polygons.xy, xy)
    assert not b.polygons.xy.flags.writeable


@pytest.mark.parametrize("bad", [dict(n_bands=0), dict(min_live_nodes=3), dict(split_ratio=1.0)])
def test_bad_options_are_refused(bad):
    with pytest.raises(ValueError):
        NodeSetEstimator(MODEL, **bad)


def test_thin_piece_with_few_nodes_is_refined_until_bounded(monkeypatch):
    """Regression (found by the n_nodes sweep): with ``n_nodes = 6`` a closing-speed
    piece narrowed to a sliver kept one live node after four re-grids, the cells beside
    it were unbounded and the guidance's impulse became nan (kp_fig5, seed 5, run 38 of
    50, at 99.5 s). Now every forecast the law asks for is finite and the truth stays
    inside."""
    from kalman_vs_infoset.experiments.runner import run_seed
    from kalman_vs_infoset.experiments.scenario import load_scenario
    from kalman_vs_infoset.experiments.sim.intercept import Engagement
    from kalman_vs_infoset.guidance.intercept.law import ForecastCentringLaw

    forecasts = []
    law_forecast = ForecastCentringLaw.forecast

    def recording(law, belief):
        ext = law_forecast(law, belief)
        forecasts.append((ext.min_value, ext.max_value))
        return ext

    monkeypatch.setattr(ForecastCentringLaw, "forecast", recording)
    sc = load_scenario(str(ROOT / "data/scenarios/kp_fig5.toml"), ["estimator.infoset.n_nodes=6"])
    eng = Engagement(sc, "infoset", "random", np.random.default_rng(run_seed(5, 38)), None)
    while eng.step():
        pass
    result = eng.finish()
    assert forecasts and np.isfinite(forecasts).all()
    assert result.truth_outside == 0
