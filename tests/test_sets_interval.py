"""estim.common.sets.interval: brute-force containment, and the one-pass contraction against the
exact interval hull of box ∩ strip computed by linear programming."""

import numpy as np
import pytest
import sets_sampling as S
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.common.sets import Box, EmptyIntersectionError
from scipy.optimize import linprog

SEEDS = st.integers(0, 2**32 - 1)
DIMS = st.integers(1, 5)
FEW = settings(max_examples=40, deadline=None)


def _hull_by_lp(box: Box, a: np.ndarray, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """min and max of each coordinate over box ∩ {lo <= a.x <= hi}, by 2n LPs."""
    n = box.dim
    a_ub = np.vstack([a, -a])
    b_ub = np.array([hi, -lo])
    keep = np.isfinite(b_ub)
    bounds = list(zip(box.lo, box.hi, strict=True))
    out = np.zeros((2, n))
    for i in range(n):
        for k, sign in enumerate((1.0, -1.0)):
            cost = np.zeros(n)
            cost[i] = sign
            res = linprog(cost, A_ub=a_ub[keep], b_ub=b_ub[keep], bounds=bounds)
            assert res.status == 0
            out[k, i] = sign * res.fun
    return out[0], out[1]


@FEW
@given(SEEDS, DIMS)
def test_affine_and_minkowski_sum_contain_mapped_points(seed, n):
    rng = np.random.default_rng(seed)
    b1, b2 = S.random_box(rng, n), S.random_box(rng, n)
    a = rng.normal(size=(int(rng.integers(1, 5)), n))
    p1, p2 = S.sample_box(b1, rng), S.sample_box(b2, rng)
    img = b1.affine(a, np.ones(a.shape[0]))
    assert np.all(img.contains(p1 @ a.T + 1.0))
    # the interval hull is exact: each face is reached by a mapped corner
    corners = b1.lo + np.array(np.meshgrid(*[[0, 1]] * n)).reshape(n, -1).T * (b1.hi - b1.lo)
    mapped = corners @ a.T + 1.0
    np.testing.assert_allclose(img.lo, mapped.min(axis=0), atol=1e-12)
    np.testing.assert_allclose(img.hi, mapped.max(axis=0), atol=1e-12)
    assert np.all(b1.minkowski_sum(b2).contains(p1 + p2))


@FEW
@given(SEEDS, DIMS)
def test_strip_contraction_is_the_exact_interval_hull(seed, n):
    rng = np.random.default_rng(seed)
    box = S.random_box(rng, n)
    pts = S.sample_box(box, rng, 600)
    a, b, r = S.cutting_strip(pts, rng)
    a[rng.uniform(size=n) < 0.2] = 0.0  # some coordinates the strip does not involve
    if not np.any(a):
        a[0] = 1.0
    s = pts @ a
    b = float(np.clip(b, s.min(), s.max()))  # zeroing moved the range of a.x
    out = box.intersect_strip(a, b, r)
    assert np.all(out.contains(S.points_in_slab(pts, a, b - r, b + r)))
    lo, hi = _hull_by_lp(box, a, b - r, b + r)
    np.testing.assert_allclose(out.lo, lo, atol=1e-9)
    np.testing.assert_allclose(out.hi, hi, atol=1e-9)


@FEW
@given(SEEDS, DIMS)
def test_halfspace_contraction_is_the_exact_interval_hull(seed, n):
    rng = np.random.default_rng(seed)
    box = S.random_box(rng, n)
    pts = S.sample_box(box, rng, 600)
    a, b, _ = S.cutting_strip(pts, rng)
    out = box.intersect_halfspace(a, b)
    assert np.all(out.contains(S.points_in_slab(pts, a, -np.inf, b)))
    lo, hi = _hull_by_lp(box, a, -np.inf, b)
    np.testing.assert_allclose(out.lo, lo, atol=1e-9)
    np.testing.assert_allclose(out.hi, hi, atol=1e-9)


def _far_box_point_and_cut(seed: int, n: int, cut: str):
    """A box up to 1e8 from the origin and 1e-4 to 1e2 wide, a point of it (a corner,
    a face or inside) and a slab with the point on its edge."""
    rng = np.random.default_rng(seed)
    c = rng.normal(size=n) * 10.0 ** rng.uniform(-3, 8)
    r = 10.0 ** rng.uniform(-4, 2, size=n)
    box = Box(c - r, c + r)
    side = rng.choice([-1.0, 1.0], size=n)
    depth = np.where(rng.random(n) < 0.5, 1.0, rng.uniform(size=n))  # 1: on a face
    x = np.clip(c + r * side * depth, box.lo, box.hi)
    a = rng.normal(size=n)
    ax = float(a @ x)
    return box, x, a, S.edge_slab(ax, cut)


@FEW
@given(SEEDS, DIMS, st.sampled_from(["below", "above", "plane"]))
# failed before the contraction covered its rounding (found by a search over seeds):
# points at 3.6e7 and 8.4e6 fell outside by more than the containment's tolerance
@example(seed=4, n=2, cut="below")
@example(seed=4, n=2, cut="plane")
@example(seed=81, n=2, cut="above")
def test_cut_through_a_point_of_a_far_box_keeps_it(seed, n, cut):
    """A point of the box on the edge of the slab is in both, so the contraction must
    hold it wherever the box lies: its sums and quotients are rounded to the
    coordinates' magnitude, which it covers."""
    box, x, a, (lo, hi) = _far_box_point_and_cut(seed, n, cut)
    assert S.cut_by_slab(box, a, lo, hi).contains(x)


def test_strip_contraction_worked_by_hand():
    box = Box([-1.0, -1.0], [1.0, 1.0])
    # x + y in [1.4, 1.6]: x >= 1.4 - max(y) = 0.4, same for y; the upper bounds stay
    out = box.intersect_strip([1.0, 1.0], 1.5, 0.1)
    np.testing.assert_allclose(out.lo, [0.4, 0.4])
    np.testing.assert_allclose(out.hi, [1.0, 1.0])
    # 2x - y in [-0.5, 0.5] with y in [-1, 1]: 2x in [-1.5, 1.5] -> x in [-0.75, 0.75]
    out = box.intersect_strip([2.0, -1.0], 0.0, 0.5)
    np.testing.assert_allclose(out.lo, [-0.75, -1.0])
    np.testing.assert_allclose(out.hi, [0.75, 1.0])
    assert box.intersect_strip([1.0, 0.0], 0.0, 2.0) is box
    with pytest.raises(EmptyIntersectionError):
        box.intersect_strip([1.0, 1.0], 3.0, 0.5)
    corner = box.intersect_halfspace([-1.0, -1.0], -2.0)  # touches the corner (1, 1)
    np.testing.assert_allclose([corner.lo, corner.hi], [[1.0, 1.0], [1.0, 1.0]])


@FEW
@given(SEEDS, DIMS)
def test_support_and_extremes_are_exact(seed, n):
    rng = np.random.default_rng(seed)
    box = S.random_box(rng, n)
    d = rng.normal(size=(8, n))
    corners = box.lo + (d > 0) * (box.hi - box.lo)  # the maximising corner per direction
    np.testing.assert_allclose(box.support(d), np.einsum("ij,ij->i", corners, d))
    assert np.all(S.sample_box(box, rng) @ d.T <= box.support(d) + 1e-12)
    lo, hi = box.extremes(d[0])
    assert (lo, hi) == pytest.approx((-box.support(-d[0]), box.support(d[0])))


def test_validation_and_immutability():
    with pytest.raises(ValueError):
        Box([1.0], [0.0])
    with pytest.raises(ValueError):
        Box([0.0, 0.0], [1.0])
    box = Box.from_centre([1.0, 2.0], 0.5)
    assert box.contains([1.5, 2.5]) and not box.contains([1.6, 2.0])
    with pytest.raises(ValueError):
        box.lo[0] = 0.0


@pytest.mark.parametrize("family", ["box", "zonotope", "ellipsoid"])
@pytest.mark.parametrize("point", [[0.5], [0.5, 0.5, 0.5], [[[0.5, 0.5]]]])
def test_contains_refuses_a_point_of_another_dimension(family, point):
    """A 1-D point against a 2-D set was broadcast (and read inside); it is an error."""
    from kalman_vs_infoset.estim.common.sets import Box, Ellipsoid, Zonotope

    sets = {
        "box": Box([0.0, 0.0], [1.0, 1.0]),
        "zonotope": Zonotope([0.5, 0.5], [[0.5, 0.0], [0.0, 0.5]]),
        "ellipsoid": Ellipsoid.ball([0.5, 0.5], 0.5),
    }
    with pytest.raises(ValueError, match=r"shape \(2,\) or \(k, 2\)"):
        sets[family].contains(point)
    assert sets[family].contains([0.5, 0.5]) and not sets[family].contains([np.nan, 0.5])


def test_a_box_far_from_the_origin_holds_points_rounded_onto_its_faces():
    """docs/usage.md: ``contains`` allows a few ulps of the coordinates. The image of a
    corner under a map, rounded, lay an ulp (7e-9 at 3.4e7) past the face of the box
    ``affine`` returned when the image was not widened by its own rounding; it now lies
    inside with no slack at all, and clearly outside stays out."""
    from kalman_vs_infoset.estim.common.sets import Box

    box = Box([18917110.7, 15851629.4], [18917111.2, 15851630.200000001])
    image = box.affine([[-2.8, 1.2]])
    corner = -2.8 * 18917110.7 + 1.2 * 15851630.200000001  # the largest corner
    assert image.lo[0] <= corner <= image.hi[0]
    assert image.contains([corner], tol=0.0)
    assert not image.contains([image.hi[0] + 1e-6], tol=0.0)


@settings(max_examples=60, deadline=None)
@given(SEEDS, DIMS, st.sampled_from([0.0, 1e4, 1e8, 1e12]))
def test_affine_image_holds_every_mapped_corner_in_exact_arithmetic(seed, n, offset):
    """An outer bound in floating point: every corner of the box, mapped exactly
    (rational arithmetic on the stored doubles), lies within ``[lo, hi]`` of the
    computed image, with no tolerance, near the origin and far from it."""
    from fractions import Fraction
    from itertools import product

    rng = np.random.default_rng(seed)
    centre = offset * rng.uniform(-1, 1, n) + rng.normal(size=n)
    box = Box.from_centre(centre, rng.uniform(0, 2, n))
    a = rng.normal(size=(int(rng.integers(1, 5)), n)) * 10.0 ** rng.integers(-3, 4)
    b = offset * rng.uniform(-1, 1, a.shape[0])
    image = box.affine(a, b)
    for pick in product((0, 1), repeat=n):
        x = [Fraction(float((box.lo, box.hi)[k][i])) for i, k in enumerate(pick)]
        for row in range(a.shape[0]):
            exact = sum(Fraction(float(a[row, i])) * x[i] for i in range(n))
            exact += Fraction(float(b[row]))
            assert Fraction(float(image.lo[row])) <= exact <= Fraction(float(image.hi[row]))


def test_box_contains_no_point_with_an_infinite_or_nan_coordinate():
    """``contains([inf, 0.5])`` read True: the rounding slack grows with |x|, and an
    infinite coordinate made it infinite (the zonotope and the ellipsoid said False)."""
    box = Box([0.0, 0.0], [1.0, 1.0])
    assert not box.contains([np.inf, 0.5]) and not box.contains([-np.inf, 0.5])
    assert not box.contains([np.nan, 0.5])
    np.testing.assert_array_equal(box.contains([[0.5, 0.5], [np.inf, 0.5]]), [True, False])


@pytest.mark.parametrize("tol", [-1.0, np.inf, np.nan])
def test_every_set_refuses_a_negative_or_non_finite_tolerance(tol):
    from kalman_vs_infoset.estim.common.sets import Ellipsoid, Zonotope

    sets = [Box([0.0, 0.0], [1.0, 1.0]), Zonotope([0.0, 0.0], np.eye(2)),
            Ellipsoid([0.0, 0.0], np.eye(2))]  # fmt: skip
    for s in sets:
        with pytest.raises(ValueError, match="tol must be finite"):
            s.contains([0.5, 0.5], tol=tol)
