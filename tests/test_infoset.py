"""The information set of seed 003 (SPEC 1.4): set operations and the guarantee."""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from estim.infoset import STRIP_MARGIN, InformationSet, InformationSetEstimator
from estim.model import Bearing, ChannelModel, Range

MODEL = ChannelModel()  # seed 003 section 6: e = 58 km/s, nu = 0.005 m/s^2, eps = 5 km
EST = InformationSetEstimator(MODEL, n_sections=29)
B_Y, D_VY, B_X = (-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3)


def _sample_in_sections(s: InformationSet, rng, per=200):
    """Random convex combinations of each section's vertices, as (alpha, omega, x)."""
    out = []
    for i in range(s.n_sections):
        v = s.polygons.polygon(i)
        lam = rng.dirichlet(np.ones(len(v)), size=per)
        p = lam @ v
        x = np.full(per, s.x_m[i])
        out.append(
            np.column_stack(
                [p[:, 0] * s.alpha_scale_rad, MODEL.omega_from_w(p[:, 1] * s.w_scale_m, x), x]
            )
        )
    return np.vstack(out)


def test_initial_set_is_the_image_of_the_boxes_seed003_section4():
    """Brute force: (y, Vy) drawn in B x D map into the section at their x; corners
    map to vertices; area = box area x |det| of the linear map."""
    s = EST.initial(B_Y, D_VY, B_X)
    assert s.n_sections == 29
    rng = np.random.default_rng(1)
    for j in (0, 14, 28):
        x = s.x_m[j]
        y = rng.uniform(*B_Y, 50)
        vy = rng.uniform(*D_VY, 50)
        for yi, vyi in zip(y, vy, strict=True):
            omega = vyi / x + yi * MODEL.e / x**2  # alpha = y/x, omega = d(y/x)/dt, Vx = -e
            assert s.contains([yi / x, omega, x])
        det = (1 / x) * (x / MODEL.e) / (s.alpha_scale_rad * s.w_scale_m)
        assert s.polygons.areas()[j] == pytest.approx(20e3 * 200 * det, rel=1e-12)
    # a point outside the velocity box is outside
    x = s.x_m[5]
    assert not s.contains([0.0, 150.0 / x, x])


def test_bearing_update_equals_shapely_intersection_with_range_dependent_strips():
    s = EST.initial(B_Y, D_VY, B_X)
    alpha_m = 3e-4
    u = EST.update(s, Bearing(alpha_m))
    half = MODEL.bearing_bound(s.x_m) * (1 + STRIP_MARGIN) + STRIP_MARGIN * 1e-4  # outward rounding
    for j in range(s.n_sections):
        geom = shapely.MultiPoint(s.polygons.polygon(j)).convex_hull
        lo, hi = (alpha_m - half[j]) / 1e-4, (alpha_m + half[j]) / 1e-4
        expected = geom.intersection(shapely.box(lo, -1e9, hi, 1e9))
        got = shapely.Polygon(u.polygons.polygon(j))
        assert got.symmetric_difference(expected).area < 1e-9 * expected.area


def test_prediction_contains_every_propagated_point_and_is_tight():
    """Brute force: points of each section propagated by the exact step with any
    constant |v| <= nu land in the predicted section; the section's vertices are
    reached (tightness) by vertices propagated with v = +-nu."""
    rng = np.random.default_rng(2)
    s = EST.update(EST.initial(B_Y, D_VY, B_X), Bearing(1e-4))
    p = EST.predict(s, 0.5)
    np.testing.assert_allclose(p.x_m, s.x_m - MODEL.e * 0.5)
    pts = _sample_in_sections(s, rng, per=40)
    for v in (-MODEL.nu_mps2, MODEL.nu_mps2, 0.3 * MODEL.nu_mps2):
        moved = MODEL.step(pts, 0.5, v)
        assert all(p.contains(q) for q in moved[::7])
    for j in (0, 20):
        verts = s.vertices()[s.polygons.owner() == j]
        ends = np.vstack([MODEL.step(verts, 0.5, v) for v in (-MODEL.nu_mps2, MODEL.nu_mps2)])
        w = MODEL.zero_effort_miss_m(ends[:, 1], ends[:, 2])
        hull = shapely.MultiPoint(np.column_stack([ends[:, 0] / 1e-4, w])).convex_hull
        got = shapely.Polygon(p.polygons.polygon(j))
        assert got.symmetric_difference(hull).area < 1e-9 * hull.area


def test_impulse_shifts_omega_by_k_over_x():
    s = EST.initial(B_Y, D_VY, B_X)
    k = 5.0
    t = EST.shift(s, k)
    own = s.polygons.owner()
    d_omega = t.vertices()[:, 1] - s.vertices()[:, 1]
    np.testing.assert_allclose(d_omega, k / s.x_m[own], rtol=1e-9)
    np.testing.assert_allclose(t.vertices()[:, 0], s.vertices()[:, 0])


def test_threshold_drops_sections_passing_under_eps_and_ends_terminal():
    est = InformationSetEstimator(MODEL, n_sections=5)
    s = est.initial(B_Y, D_VY, (20e3, 80e3))  # sections at 20, 35, 50, 65, 80 km
    p = est.predict(s, 0.5)  # 29 km per step: 20 km section passes under 5 km
    np.testing.assert_allclose(p.x_m, [6e3, 21e3, 36e3, 51e3])
    for _ in range(3):
        p = est.predict(p, 0.5)
    assert p.is_empty and p.status == "terminal"


def test_range_update_keeps_bracketing_sections_only():
    s = EST.initial(B_Y, D_VY, B_X)
    d_m = 5801.3e3
    u = EST.update(s, Range(d_m))
    lo, hi = d_m / 1.05, d_m / 0.95
    inside = (s.x_m >= lo * (1 - 1e-4)) & (s.x_m <= hi)
    assert u.n_sections == inside.sum() + 2  # one neighbour each side
    assert u.x_m[0] < lo <= u.x_m[1] and u.x_m[-2] <= hi < u.x_m[-1]


def test_contradicting_measurement_is_a_status_not_a_crash():
    s = EST.initial(B_Y, D_VY, B_X)
    u = EST.update(s, Bearing(0.5))  # far outside every section
    assert u.status == "contradiction" and u.contradictions == 1
    assert u.n_sections == s.n_sections and not u.is_empty


def test_beliefs_are_immutable_values():
    s = EST.initial(B_Y, D_VY, B_X)
    xy0, x0 = s.polygons.xy.copy(), s.x_m.copy()
    for op in (
        lambda b: EST.update(b, Bearing(0.0)),
        lambda b: EST.shift(b, 3.0),
        lambda b: EST.predict(b, 0.5),
        lambda b: EST.update(b, Range(5.8e6)),
    ):
        new = op(s)
        assert new is not s
    np.testing.assert_array_equal(s.polygons.xy, xy0)
    np.testing.assert_array_equal(s.x_m, x0)
    with pytest.raises(ValueError):
        s.polygons.xy[0, 0] = 1.0
    with pytest.raises(ValueError):
        s.x_m[0] = 1.0
    with pytest.raises(AttributeError):
        s.status = "x"


def test_extremes_of_miss_forecast_bound_brute_force_samples():
    """Pi over the set (seed 003 section 5) from vertices and omega=0 crossings is
    >= every sampled value and attained up to sampling resolution."""
    rng = np.random.default_rng(3)
    s = EST.update(EST.initial(B_Y, D_VY, B_X), Bearing(-2e-4))
    ext = s.extremes(MODEL.miss_forecast_m)
    pts = _sample_in_sections(s, rng, per=400)
    vals = MODEL.miss_forecast_m(pts)
    assert vals.max() <= ext.max_value + 1e-9 and vals.min() >= ext.min_value - 1e-9
    assert ext.max_value - vals.max() < 0.05 * (ext.max_value - ext.min_value)
    assert ext.argmax[2] in s.x_m and ext.argmin[2] in s.x_m


# -- the guarantee (property test) ------------------------------------------------------
noise_modes = st.sampled_from(["uniform", "bounds", "bias_high", "bias_low"])


@settings(max_examples=25, deadline=None)
@given(
    y=st.floats(*B_Y),
    vy=st.floats(*D_VY),
    j=st.integers(14, 28),
    dt=st.sampled_from([0.25, 0.5]),
    mode=noise_modes,
    v_mode=st.sampled_from(["uniform", "bounds", "zero"]),
    seed=st.integers(0, 2**32 - 1),
)
def test_truth_stays_inside_under_admissible_noise_seed003_guarantee(
    y, vy, j, dt, mode, v_mode, seed
):
    """SPEC 1.4: with admissible errors and disturbances the true state is inside the
    set after every update, shift and prediction (200 steps). The truth follows the
    auxiliary model exactly; its range is one of the section ranges. The set is not
    trivially large: after each prediction its alpha-extent is < 3 strip widths."""
    rng = np.random.default_rng(seed)
    s = EST.initial(B_Y, D_VY, B_X)
    x = s.x_m[j]
    truth = np.array([y / x, vy / x + y * MODEL.e / x**2, x])
    assert s.contains(truth)
    for step in range(200):
        if truth[2] - MODEL.e * dt < MODEL.eps_m:
            break
        bound = float(MODEL.bearing_bound(truth[2]))
        zeta = {
            "uniform": rng.uniform(-bound, bound),
            "bounds": bound * rng.choice([-1.0, 1.0]),
            "bias_high": bound,
            "bias_low": -bound,
        }[mode]
        s = EST.update(s, Bearing(truth[0] + zeta))
        assert s.status == "ok" and s.contains(truth), f"update, step {step}"
        if step % 4 == 1:
            d = truth[2] * (1 + rng.uniform(-0.05, 0.05))
            s = EST.update(s, Range(d))
            assert s.contains(truth), f"range, step {step}"
        k = rng.uniform(-7.5, 7.5) if step % 3 == 0 else 0.0
        s = EST.shift(s, k)
        truth = truth + np.array([0.0, k / truth[2], 0.0])
        assert s.contains(truth), f"shift, step {step}"
        v = {"uniform": rng.uniform(-1, 1), "bounds": rng.choice([-1.0, 1.0]), "zero": 0.0}[v_mode]
        s = EST.predict(s, dt)
        truth = MODEL.step(truth, dt, v * MODEL.nu_mps2)
        assert s.contains(truth), f"predict, step {step}"
        lo, hi = s.alpha_range_rad()
        assert hi - lo < 3 * 2 * float(MODEL.bearing_bound(s.x_m).max())
