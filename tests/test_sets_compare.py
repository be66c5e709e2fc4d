"""The three set families side by side against the exact polytope (shapely, in 2-D).

The exact set-membership recursion of a planar linear system with a box disturbance and
scalar strip measurements keeps a convex polygon: an affine image, a Minkowski sum with
the disturbance box (the hull of the vertex sums) and an intersection with a strip. Every
outer family must contain that polygon, and so the truth, at every step.
"""

import numpy as np
import pytest
import shapely
from kalman_vs_infoset.estim.common.sets import Box, Ellipsoid, Zonotope
from shapely import affinity


def _strip_polygon(a: np.ndarray, b: float, r: float, length: float = 1e4) -> shapely.Polygon:
    n = a / np.linalg.norm(a)
    t = np.array([-n[1], n[0]])
    x0, w = n * b / np.linalg.norm(a), r / np.linalg.norm(a)
    return shapely.Polygon(
        [x0 - w * n - length * t, x0 + w * n - length * t, x0 + w * n + length * t,
         x0 - w * n + length * t]
    )  # fmt: skip


def _vertices(poly: shapely.Polygon) -> np.ndarray:
    return np.asarray(poly.exterior.coords)[:-1]


def _exact_step(poly, a_mat, w_half, a, y, r):
    """Exact: (A P + W) ∩ strip for the next measurement (the strip is applied first)."""
    poly = poly.intersection(_strip_polygon(a, y, r))
    poly = affinity.affine_transform(poly, [*a_mat[0], *a_mat[1], 0.0, 0.0])
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * w_half
    sums = (_vertices(poly)[:, None, :] + corners[None]).reshape(-1, 2)
    return shapely.MultiPoint(sums).convex_hull


def _holds(family, pts: np.ndarray) -> bool:
    return bool(np.all(family.contains(pts, tol=1e-7)))


def test_families_contain_the_exact_polygon_after_the_same_strips():
    rng = np.random.default_rng(12)
    truth = np.array([0.3, -0.4])
    lo, hi = np.array([-2.0, -2.0]), np.array([2.0, 2.0])
    exact = shapely.box(*lo, *hi)
    ell, zon, box = Ellipsoid.from_box(lo, hi), Zonotope.from_box(lo, hi), Box(lo, hi)
    for _ in range(8):
        a = rng.normal(size=2)
        r = rng.uniform(0.1, 0.6)
        y = float(a @ truth + rng.uniform(-r, r))
        exact = exact.intersection(_strip_polygon(a, y, r))
        ell = ell.intersect_strip(a, y, r)
        zon = zon.intersect_strip(a, y, r)
        box = box.intersect_strip(a, y, r)
        verts = _vertices(exact)
        for fam in (ell, zon, box):
            assert _holds(fam, verts) and fam.contains(truth)
        # exact support functions dominate the polygon's in every direction
        d = np.stack([np.cos(np.linspace(0, 2 * np.pi, 64)), np.sin(np.linspace(0, 2 * np.pi, 64))])
        h_exact = (verts @ d).max(axis=0)
        for fam in (ell, zon, box):
            assert np.all(fam.support(d.T) >= h_exact - 1e-9)
    # the box and the zonotope's polygon contain the polygon; areas are no smaller
    assert shapely.Polygon(zon.vertices_2d()).area >= exact.area - 1e-12
    assert np.prod(box.hi - box.lo) >= exact.area - 1e-12
    assert np.pi * np.sqrt(np.linalg.det(ell.shape)) >= exact.area - 1e-12


@pytest.mark.parametrize("seed", [0, 1])
def test_set_filters_contain_the_truth_for_50_steps(seed):
    """x+ = A x + w, |w|_inf <= 0.05; y = a_k.x + v, |v| <= 0.1, a_k turning by 0.7 rad.
    Disturbances are drawn at the bounds half the time (the hard cases for a set)."""
    rng = np.random.default_rng(seed)
    th = 0.2
    a_mat = 0.98 * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    w_half, v_bound = 0.05, 0.1
    lo, hi = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    truth = rng.uniform(lo, hi)
    w_ell = Ellipsoid.from_box([-w_half] * 2, [w_half] * 2)
    w_zon = Zonotope.from_box([-w_half] * 2, [w_half] * 2)
    w_box = Box([-w_half] * 2, [w_half] * 2)
    ell, zon, box = Ellipsoid.from_box(lo, hi), Zonotope.from_box(lo, hi), Box(lo, hi)
    exact = shapely.box(*lo, *hi)
    for k in range(50):
        a = np.array([np.cos(0.7 * k), np.sin(0.7 * k)])
        v = v_bound * (rng.choice([-1.0, 1.0]) if rng.uniform() < 0.5 else rng.uniform(-1, 1))
        y = float(a @ truth + v)
        ell = ell.intersect_strip(a, y, v_bound)
        zon = zon.intersect_strip(a, y, v_bound)
        box = box.intersect_strip(a, y, v_bound)
        for fam in (ell, zon, box):
            assert fam.contains(truth), (k, fam)
        verts = _vertices(exact.intersection(_strip_polygon(a, y, v_bound)))
        for fam in (ell, zon, box):
            assert _holds(fam, verts), (k, fam)
        # predict
        w = w_half * np.where(rng.uniform(size=2) < 0.5, rng.choice([-1.0, 1.0], 2), 0.0)
        w = np.where(w == 0.0, rng.uniform(-w_half, w_half, 2), w)
        truth = a_mat @ truth + w
        exact = _exact_step(exact, a_mat, w_half, a, y, v_bound)
        ell = ell.affine(a_mat).minkowski_sum(w_ell)
        zon = zon.affine(a_mat).minkowski_sum(w_zon).reduce(8)
        box = box.affine(a_mat).minkowski_sum(w_box)
    # all three stay bounded (none of them blows up over 50 steps)
    for fam in (ell, zon, box):
        assert np.all(np.diff(np.array(fam.interval_hull()), axis=0) < 2.0)


def test_a_sum_of_two_families_is_a_type_error_and_a_bad_method_a_value_error():
    """``Box.minkowski_sum(Zonotope)`` raised AttributeError ('no attribute lo') and
    ``Zonotope.contains(method="foo")`` was taken for ``"auto"``."""
    from kalman_vs_infoset.estim.common.sets import Box, Ellipsoid, Zonotope

    box = Box([0.0, 0.0], [1.0, 1.0])
    zon, ell = Zonotope.from_box([0.0, 0.0], [1.0, 1.0]), Ellipsoid.ball([0.0, 0.0], 1.0)
    for a, b in ((box, zon), (zon, ell), (ell, box)):
        with pytest.raises(TypeError, match="minkowski_sum takes"):
            a.minkowski_sum(b)
    with pytest.raises(ValueError, match="method must be"):
        zon.contains([0.5, 0.5], method="foo")
    for s in (box, zon, ell):  # plain floats, as annotated
        assert all(type(v) is float for v in s.extremes([1.0, 2.0]))
