"""The information set of seed 003 (docs/models.md §1.4): set operations and the guarantee."""

import numpy as np
import pytest
import shapely
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.intercept.kinematic import (
    MAX_BEARING_RAD,
    STRIP_MARGIN,
    kinematic_margin_mps2,
)
from kalman_vs_infoset.estim.intercept.model import Bearing, ChannelModel, Range, off_axis_bound_rad
from kalman_vs_infoset.estim.intercept.slabs.estimator import (
    InformationSet,
    InformationSetEstimator,
)

MODEL = ChannelModel()  # seed 003 section 6: e = 58 km/s, nu = 0.005 m/s^2, eps = 5 km
SLABS = InformationSetEstimator(MODEL, n_sections=29)
POINTS = InformationSetEstimator(MODEL, n_sections=29, sections="points")
B_Y, D_VY, B_X = (-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3)


def _sample_in_sections(s: InformationSet, rng, per=200):
    """Random convex combinations of each section's vertices, with x drawn in the
    section's interval, as rows (alpha, omega, x)."""
    out = []
    for i in range(s.n_sections):
        v = s.polygons.polygon(i)
        p = rng.dirichlet(np.ones(len(v)), size=per) @ v
        x = rng.uniform(s.x_lo_m[i], s.x_hi_m[i], per)
        omega = MODEL.omega_from_w(p[:, 1] * s.w_scale_m, x)
        out.append(np.column_stack([p[:, 0] * s.alpha_scale_rad, omega, x]))
    return np.vstack(out)


def _cartesian(y, vy, x):
    """(alpha, omega, x) of the auxiliary model: alpha = y/x, omega = d(y/x)/dt, Vx = -e."""
    return np.array([y / x, vy / x + y * MODEL.e / x**2, x])


@pytest.mark.parametrize("est", [SLABS, POINTS], ids=["slabs", "points"])
def test_initial_set_contains_the_image_of_the_boxes_seed003_section4(est):
    """Brute force: (y, Vy, x) drawn in B x D map into the set; points: the section
    at x_j is the parallelogram of area box area x |det| of the linear map."""
    s = est.from_boxes(B_Y, D_VY, B_X)
    assert s.n_sections == 29
    rng = np.random.default_rng(1)
    for _ in range(300):
        x = rng.uniform(*B_X) if est is SLABS else s.x_lo_m[rng.integers(29)]
        assert s.contains(_cartesian(rng.uniform(*B_Y), rng.uniform(*D_VY), x))
    assert not s.contains(_cartesian(0.0, 150.0, 5.8e6))  # outside the velocity box
    assert not s.contains(_cartesian(0.0, 0.0, 6.4e6))  # outside the range box
    if est is POINTS:
        x = s.x_lo_m[14]
        det = (1 / x) * (x / MODEL.e) / (s.alpha_scale_rad * s.w_scale_m)
        assert s.polygons.areas()[14] == pytest.approx(20e3 * 200 * det, rel=1e-12)
    else:
        np.testing.assert_allclose(s.x_hi_m[:-1], s.x_lo_m[1:])  # a partition of B_X


def test_bearing_update_equals_shapely_intersection_with_range_dependent_strips():
    s = SLABS.from_boxes(B_Y, D_VY, B_X)
    alpha_m = 3e-4
    u = SLABS.update(s, Bearing(alpha_m))
    half = MODEL.bearing_bound(s.x_lo_m) * (1 + STRIP_MARGIN) + STRIP_MARGIN * 1e-4
    for j in range(s.n_sections):
        geom = shapely.MultiPoint(s.polygons.polygon(j)).convex_hull
        lo, hi = (alpha_m - half[j]) / 1e-4, (alpha_m + half[j]) / 1e-4
        expected = geom.intersection(shapely.box(lo, -1e9, hi, 1e9))
        got = shapely.Polygon(u.polygons.polygon(j))
        assert got.symmetric_difference(expected).area < 1e-9 * expected.area


def test_point_prediction_is_the_seed_map_plus_the_disturbance_segment():
    """Points (the seed's model): the predicted section equals the convex hull of the
    section's vertices propagated by the exact step with v = -nu and v = +nu."""
    s = POINTS.update(POINTS.from_boxes(B_Y, D_VY, B_X), Bearing(1e-4))
    p = POINTS.predict(s, 0.5)
    np.testing.assert_allclose(p.x_lo_m, s.x_lo_m - MODEL.e * 0.5)
    for j in (0, 20):
        verts = s.vertices()[s.polygons.owner() == j]
        ends = np.vstack([MODEL.step(verts, 0.5, v) for v in (-MODEL.nu_mps2, MODEL.nu_mps2)])
        w = MODEL.zero_effort_miss_m(ends[:, 1], ends[:, 2])
        hull = shapely.MultiPoint(np.column_stack([ends[:, 0] / 1e-4, w])).convex_hull
        got = shapely.Polygon(p.polygons.polygon(j))
        assert got.symmetric_difference(hull).area < 1e-9 * hull.area


def test_slab_prediction_contains_every_propagated_state():
    """Brute force: states of each slab (any x in its interval, any closing speed in
    the interval, any constant |v| <= nu) land in the predicted set."""
    rng = np.random.default_rng(2)
    est = InformationSetEstimator(MODEL, closing_speed_mps=(57.0e3, 59.0e3))
    s = est.update(est.from_boxes(B_Y, D_VY, B_X), Bearing(1e-4))
    p = est.predict(s, 0.5)
    pts = _sample_in_sections(s, rng, per=30)
    for _ in range(3):
        v = rng.choice([-1.0, 1.0, rng.uniform(-1, 1)]) * MODEL.nu_mps2
        e_true = rng.uniform(57.0e3, 59.0e3)
        moved = MODEL.step(pts, 0.5, v, closing_speed_mps=e_true)
        assert all(p.contains(q) for q in moved[::5])


@pytest.mark.parametrize("est", [SLABS, POINTS], ids=["slabs", "points"])
def test_impulse_shifts_omega_by_k_over_x(est):
    s = est.from_boxes(B_Y, D_VY, B_X)
    k = 5.0
    t = est._impulse(s, k)
    rng = np.random.default_rng(4)
    pts = _sample_in_sections(s, rng, per=20)
    shifted = pts + np.column_stack([np.zeros(len(pts)), k / pts[:, 2], np.zeros(len(pts))])
    assert all(t.contains(q) for q in shifted[::3])
    if est is POINTS:  # exact translation of every vertex
        d_omega = t.vertices()[:, 1] - s.vertices()[:, 1]
        np.testing.assert_allclose(d_omega, k / s.x_lo_m[s.polygons.owner()], rtol=1e-9)


def test_threshold_drops_sections_passing_under_eps_and_ends_terminal():
    est = InformationSetEstimator(MODEL, n_sections=5, sections="points")
    s = est.from_boxes(B_Y, D_VY, (20e3, 80e3))  # sections at 20, 35, 50, 65, 80 km
    p = est.predict(s, 0.5)  # 29 km per step: the 20 km section passes under 5 km
    np.testing.assert_allclose(p.x_lo_m, [6e3, 21e3, 36e3, 51e3])
    for _ in range(3):
        p = est.predict(p, 0.5)
    assert p.is_empty and p.status == "terminal"
    slabs = InformationSetEstimator(MODEL, n_sections=3).from_boxes(B_Y, D_VY, (20e3, 80e3))
    q = InformationSetEstimator(MODEL, n_sections=3).predict(slabs, 0.5)
    # [20, 40] -> [5 (clipped at eps), 11], the others move by 29 km
    np.testing.assert_allclose(q.x_lo_m, [5e3, 11e3, 31e3])
    np.testing.assert_allclose(q.x_hi_m, [11e3, 31e3, 51e3])


def test_range_update_intersects_intervals():
    s = SLABS.from_boxes(B_Y, D_VY, B_X)
    d_m = 5801.3e3
    u = SLABS.update(s, Range(d_m))
    lo, hi = d_m / 1.05 * np.cos(MODEL.max_off_axis_rad), d_m / 0.95
    assert u.x_lo_m.min() == pytest.approx(max(lo, B_X[0]))
    assert u.x_hi_m.max() == pytest.approx(min(hi, B_X[1]), rel=1e-8)
    assert u.n_sections == np.sum((s.x_hi_m >= lo) & (s.x_lo_m <= hi))
    p = POINTS.update(POINTS.from_boxes(B_Y, D_VY, B_X), Range(d_m))
    inside = (POINTS.from_boxes(B_Y, D_VY, B_X).x_lo_m >= lo) & (
        POINTS.from_boxes(B_Y, D_VY, B_X).x_lo_m <= hi
    )
    assert p.n_sections == min(inside.sum() + 2, 29)  # one neighbour each side


@given(
    y_m=st.floats(-3e3, 3e3),
    z_m=st.floats(-3e3, 3e3),
    x_m=st.floats(5e3, 1e6),
    err=st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)),
)
@example(y_m=1.3e3, z_m=0.0, x_m=7.77e3, err=(1.0, 1.0, 1.0))  # 0.17 rad > the 0.1 default
def test_range_update_with_measured_off_axis_bound_keeps_the_true_x(y_m, z_m, x_m, err):
    """Geometry of a range measurement (``off_axis_bound_rad``): with bearings of both
    axes and the range measured within their bounds, the range update keeps a section
    holding the true ``x = d cos(phi)`` (brute force: the Cartesian truth itself), and
    the bound is never below the true off-axis angle."""
    d_true = float(np.sqrt(x_m**2 + y_m**2 + z_m**2))
    bound = 2e-3
    a_meas = [np.arctan2(y_m, x_m) + err[0] * bound, np.arctan2(z_m, x_m) + err[1] * bound]
    d_meas = d_true * (1 + err[2] * MODEL.range_rel_bound)
    phi = off_axis_bound_rad(a_meas, [bound, bound])
    assert phi >= np.arccos(x_m / d_true) - 1e-12
    s = SLABS.from_boxes(B_Y, D_VY, (0.5 * x_m, 2.0 * x_m))
    u = SLABS.update(s, Range(d_meas, off_axis_rad=phi))
    assert u.status == "ok"
    assert np.any((u.x_lo_m <= x_m) & (u.x_hi_m >= x_m))


def test_range_measurement_rejects_an_off_axis_bound_outside_0_to_pi_over_2():
    with pytest.raises(ValueError, match="off_axis_rad"):
        Range(1e5, off_axis_rad=-0.1)
    with pytest.raises(ValueError, match="off_axis_rad"):
        Range(1e5, off_axis_rad=2.0)


def test_contradicting_measurement_is_a_status_not_a_crash():
    s = SLABS.from_boxes(B_Y, D_VY, B_X)
    u = SLABS.update(s, Bearing(0.5))  # far outside every section
    assert u.status == "contradiction" and u.contradictions == 1
    assert u.n_sections == s.n_sections and not u.is_empty
    r = SLABS.update(s, Range(100e3))  # no section within range
    assert r.status == "contradiction"


def test_beliefs_are_immutable_values():
    s = SLABS.from_boxes(B_Y, D_VY, B_X)
    xy0, x0 = s.polygons.xy.copy(), s.x_lo_m.copy()
    for op in (
        lambda b: SLABS.update(b, Bearing(0.0)),
        lambda b: SLABS._impulse(b, 3.0),
        lambda b: SLABS.predict(b, 0.5),
        lambda b: SLABS.update(b, Range(5.8e6)),
    ):
        assert op(s) is not s
    np.testing.assert_array_equal(s.polygons.xy, xy0)
    np.testing.assert_array_equal(s.x_lo_m, x0)
    with pytest.raises(ValueError):
        s.polygons.xy[0, 0] = 1.0
    with pytest.raises(ValueError):
        s.x_lo_m[0] = 1.0
    with pytest.raises(AttributeError):
        s.status = "x"


@pytest.mark.parametrize("est", [SLABS, POINTS], ids=["slabs", "points"])
def test_extremes_of_miss_forecast_bound_brute_force_samples(est):
    """Pi over the set (seed 003 section 5) is >= every sampled value and attained
    up to sampling resolution."""
    rng = np.random.default_rng(3)
    s = est.update(est.from_boxes(B_Y, D_VY, B_X), Bearing(-2e-4))
    ext = s.extremes(MODEL.miss_forecast_m)
    vals = MODEL.miss_forecast_m(_sample_in_sections(s, rng, per=400))
    assert vals.max() <= ext.max_value + 1e-9 and vals.min() >= ext.min_value - 1e-9
    assert ext.max_value - vals.max() < 0.05 * (ext.max_value - ext.min_value)


# -- the guarantee (property tests) -----------------------------------------------------
def _run_guarantee(est, s, truth, dt, mode, v_mode, rng, e_true, steps=200):
    """Drive set and auxiliary-model truth through update / range / shift / predict,
    asserting containment after every operation. Returns the last set and the set
    when the truth first came within 1000 km (None if it never did)."""
    at_1000km = None
    for step in range(steps):
        if truth[2] - e_true * dt < MODEL.eps_m:
            break
        bound = float(MODEL.bearing_bound(truth[2]))
        zeta = {
            "uniform": rng.uniform(-bound, bound),
            "bounds": bound * rng.choice([-1.0, 1.0]),
            "bias_high": bound,
            "bias_low": -bound,
        }[mode]
        s = est.update(s, Bearing(truth[0] + zeta))
        assert s.status == "ok" and s.contains(truth), f"update, step {step}"
        if step % 4 == 1:
            b = MODEL.range_rel_bound
            s = est.update(s, Range(truth[2] * (1 + rng.choice([-b, b, rng.uniform(-b, b)]))))
            assert s.contains(truth), f"range, step {step}"
        k = rng.uniform(-7.5, 7.5) if step % 3 == 0 else 0.0
        s = est._impulse(s, k)
        truth = truth + np.array([0.0, k / truth[2], 0.0])
        assert s.contains(truth), f"shift, step {step}"
        v = {"uniform": rng.uniform(-1, 1), "bounds": rng.choice([-1.0, 1.0]), "zero": 0.0}[v_mode]
        s = est.predict(s, dt)
        truth = MODEL.step(truth, dt, v * MODEL.nu_mps2, closing_speed_mps=e_true)
        if abs(truth[0]) > MAX_BEARING_RAD:
            # the linear model's bearing has left the channel model's domain (an
            # unguided truth kilometres off the axis, at eps): no bearing of a real
            # line of sight exceeds pi/2; the set may say so by reporting "diverged"
            assert s.status in ("ok", "diverged", "terminal")
            break
        assert s.contains(truth), f"predict, step {step}"
        if truth[2] > 1e6:
            # not trivially large: after a prediction the alpha-extent stays within
            # 3 strip widths (closer in, the range uncertainty spreads it further)
            lo, hi = s.alpha_range_rad()
            assert hi - lo < 3 * 2 * float(MODEL.bearing_bound(s.x_lo_m).max())
        elif at_1000km is None:
            at_1000km = s
    assert np.all(np.isfinite(s.polygons.xy))
    return s, at_1000km


noise_modes = st.sampled_from(["uniform", "bounds", "bias_high", "bias_low"])
v_modes = st.sampled_from(["uniform", "bounds", "zero"])


@settings(max_examples=100, deadline=None)
@given(
    y=st.floats(*B_Y),
    vy=st.floats(*D_VY),
    x=st.floats(*B_X),
    e_true=st.floats(57.0e3, 59.0e3),
    dt=st.sampled_from([0.25, 0.5]),
    mode=noise_modes,
    v_mode=v_modes,
    seed=st.integers(0, 2**32 - 1),
)
# found by this test: a hair-reflex vertex after the shear, which the outer
# simplification extended into a fold (the prediction now takes the hull first)
@example(
    y=9159.0, vy=0.0, x=5301300.0, e_true=57000.0, dt=0.25, mode="uniform",
    v_mode="uniform", seed=57347,
)  # fmt: skip
# found by make fuzz: 7.5 km off the axis, unguided, the linear model's bearing jumps
# from 0.6 to 4 rad in the last step onto x = eps (the set reports "diverged")
@example(
    y=7514.0, vy=100.0, x=5301965.0, e_true=58530.0, dt=0.5, mode="uniform",
    v_mode="uniform", seed=764,
)  # fmt: skip
def test_slab_set_contains_truth_under_admissible_noise_seed003_guarantee(
    y, vy, x, e_true, dt, mode, v_mode, seed
):
    """docs/models.md §1.4 guarantee: with admissible errors (uniform, at the bounds, biased),
    admissible disturbances and any closing speed in the estimator's interval, the
    true state (anywhere in B x D, not on a section) is inside the set after every
    update, range update, shift and prediction, for 200 steps or until the truth's
    bearing leaves the channel model's domain (|alpha| > MAX_BEARING_RAD)."""
    est = InformationSetEstimator(MODEL, closing_speed_mps=(57.0e3, 59.0e3))
    s0 = est.from_boxes(B_Y, D_VY, B_X)
    truth = _cartesian(y, vy, x)
    assert s0.contains(truth)
    rng = np.random.default_rng(seed)
    s_end, s = _run_guarantee(est, s0, truth, dt, mode, v_mode, rng, e_true)
    # information was gained: at 1000 km (or at the end, if still farther) the
    # zero-effort-miss extent shrank by 4x or more. Not at the end when it comes
    # close: this truth is unguided, kilometres off the line of sight, and near the
    # target the kinematic margin rightly widens such a set.
    s = s_end if s is None else s
    w0, w1 = s0.polygons.xy[:, 1], s.polygons.xy[:, 1]
    assert np.ptp(w1) < 0.25 * np.ptp(w0)


@settings(max_examples=40, deadline=None)
@given(
    y=st.floats(*B_Y),
    vy=st.floats(*D_VY),
    j=st.integers(14, 28),
    mode=noise_modes,
    v_mode=v_modes,
    seed=st.integers(0, 2**32 - 1),
)
def test_point_sections_contain_an_on_grid_truth_seed003_model(y, vy, j, mode, v_mode, seed):
    """The seed's point sections are exact for a truth on a section's range moving at
    the nominal closing speed (the seed's own model)."""
    s = POINTS.from_boxes(B_Y, D_VY, B_X)
    truth = _cartesian(y, vy, s.x_lo_m[j])
    rng = np.random.default_rng(seed)
    _run_guarantee(POINTS, s, truth, 0.5, mode, v_mode, rng, MODEL.e)


@settings(max_examples=300, deadline=None)
@given(
    y0=st.floats(-20e3, 20e3),
    vy=st.floats(-500.0, 500.0),
    x0=st.floats(5e3 + 58e3 * 0.5, 2e6),
    e=st.floats(57e3, 59e3),
    dt=st.sampled_from([0.25, 0.5]),
)
def test_kinematic_margin_bounds_the_exact_neglected_term_of_free_motion(y0, vy, x0, e, dt):
    """The term the auxiliary model folds into ``v`` (estim.intercept.slabs.estimator docstring),
    taken from the exact Cartesian motion, not from the formula: for free straight-line
    relative motion the model's ``v`` is ``d(omega x^2)/dt / x`` with ``omega = (x Vy -
    y Vx) / (x^2 + y^2)``, differentiated here by the complex step (exact to rounding;
    central differences lose ~1 % to cancellation far out, where ``v`` is 1e-10). It
    stays within ``kinematic_margin_mps2`` over the whole step."""
    t = np.linspace(0.0, dt, 401)
    h = 1e-30  # complex step
    xc, yc = x0 - e * (t + 1j * h), y0 + vy * (t + 1j * h)
    x, y = xc.real, yc.real
    omega_c = (xc * vy + yc * e) / (xc**2 + yc**2)  # Vx = -e
    v = np.imag(omega_c * xc**2) / h / x
    omega = omega_c.real
    alpha0, w0 = np.arctan2(y0, x0), omega[0] * x0**2 / e
    bound = kinematic_margin_mps2(w0, alpha0, x[-1], x0, dt, e, 0.0)
    assert np.max(np.abs(v)) <= bound * (1 + 1e-9) + 1e-15  # m/s^2: rounding
    # and not vacuous where the model is used (bearing under 0.3 rad): within 50x of
    # the worst value (a brute-force scan of 2e5 steps found 24x at worst, where the
    # range shrinks 2.5x within the step and the bearing crosses zero)
    if bound > 1e-6 and np.max(np.abs(np.arctan2(y, x))) < 0.3:
        assert np.max(np.abs(v)) > bound / 50


def test_wide_slab_near_eps_splits_or_is_reported_diverged_not_overflowed():
    """A slab reaching eps while spanning hundreds of km holds states that swing at
    rad/s; their kinematic margin feeds on itself. Split into thin slabs (the default)
    the set stays finite and informative; unsplit it is reported ``"diverged"`` (empty,
    counted by the caller) instead of overflowing to inf/nan; without the margin it
    stays finite (and unguaranteed)."""
    boxes = ((-1e3, 1e3), (-100.0, 100.0), (40e3, 400e3))
    statuses = {}
    for margin, split in ((True, 1.5), (True, np.inf), (False, np.inf)):
        est = InformationSetEstimator(
            MODEL,
            n_sections=3,
            closing_speed_mps=(57e3, 59e3),
            kinematic_margin=margin,
            split_ratio=split,
        )
        s = est.update(est.from_boxes(*boxes), Bearing(0.0))
        for _ in range(5):
            s = est.update(est.predict(s, 0.5), Bearing(0.0))
            if s.is_empty:
                break
            assert np.all(np.isfinite(s.polygons.xy))
        statuses[margin, split] = s.status
        if split == 1.5:
            assert s.n_sections > 3  # split (each piece at most 1.5x wide when cut)
    assert statuses == {(True, 1.5): "ok", (True, np.inf): "diverged", (False, np.inf): "ok"}


def test_uncertain_impulse_keeps_every_possible_truth():
    """An Impulse(k, dk) widens the set so that any actual impulse in [k-dk, k+dk]
    keeps the truth inside (thrust misalignment from a pointing error)."""
    from kalman_vs_infoset.estim.intercept.model import Impulse

    rng = np.random.default_rng(5)
    s = SLABS.update(SLABS.from_boxes(B_Y, D_VY, B_X), Bearing(0.0))
    t = SLABS._impulse(s, Impulse(5.0, 0.5))
    pts = _sample_in_sections(s, rng, per=10)
    for k_true in (4.5, 5.5, 5.0):
        shifted = pts + np.column_stack(
            [np.zeros(len(pts)), k_true / pts[:, 2], np.zeros(len(pts))]
        )
        assert all(t.contains(q) for q in shifted[::2])
    assert t.polygons.areas().sum() > SLABS._impulse(s, 5.0).polygons.areas().sum()
