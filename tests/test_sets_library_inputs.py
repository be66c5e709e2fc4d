"""Bad input to the reusable set library: a clear error or a sound answer, never an
obscure one.

``ConvexPolygons`` (``estim/common/polygons.py``) and the ``Box``, ``Zonotope`` and
``Ellipsoid`` sets (``estim/common/sets``) are public value types. A review found input
they took without a word or answered with an error from deep inside numpy, numba,
scipy or Python:

* ``simplify(max_vertices=2**70)`` failed in numba's typing, NaN and ``None`` in
  ``int()``; ``select([])`` raised ``IndexError`` (an empty list is a float array);
  ``polygon(1.5)`` and ``polygon(True)`` quietly read polygon 1.
* ``Zonotope.contains`` of an infinite point raised linprog's "b_ub must not contain
  values inf" on a flat zonotope, and a zonotope without generators held it; a set of
  dimension 0 was built and then failed ("k must be a non-negative integer").
* ``support(d)`` of every family returned NaN for a NaN direction and a numpy matmul
  or einsum error for one of another length.
* ``Box([[0, 0], [1, 1]], [[1, 1], [2, 2]])`` was flattened into a 4-D box.
* ``Ellipsoid`` at extreme scales: a unit ball plus one of 1e-155 was all NaN (the
  ratio of the traces overflowed), ``ball(c, 1e200)`` raised ``OverflowError`` and a
  strip cut from ``1e300 I`` was NaN (products and norms overflowed). The fixed results
  are checked against points sampled from the exact sum or intersection.
"""

import numpy as np
import pytest
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons
from kalman_vs_infoset.estim.common.sets import Box, Ellipsoid, Zonotope

SQUARE = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
TRIANGLE = [[2.0, 0.0], [3.0, 0.0], [3.0, 1.0]]


def _two() -> ConvexPolygons:
    return ConvexPolygons.from_list([SQUARE, TRIANGLE])


# -- 1. ConvexPolygons ------------------------------------------------------------------
@pytest.mark.parametrize("cap", [2**70, np.nan, np.inf, None, True, "5", 2.5, 2])
def test_simplify_refuses_a_vertex_cap_that_is_not_an_integer_from_3_to_int64(cap):
    """2**70 failed in numba's typing, NaN and ``None`` in ``int()``."""
    with pytest.raises(ValueError, match="max_vertices must be an integer >= 3"):
        _two().simplify(max_vertices=cap)


@pytest.mark.parametrize("cap", [2**63 - 1, np.int64(4), 4.0])
def test_simplify_takes_any_integer_cap_up_to_int64(cap):
    out = _two().simplify(rel_area_tol=0.0, max_vertices=cap)
    np.testing.assert_array_equal(out.xy, _two().xy)


@pytest.mark.parametrize("empty", [[], (), np.array([], dtype=int)])
def test_select_of_an_empty_sequence_selects_no_polygons(empty):
    """``select([])`` raised IndexError (numpy reads ``[]`` as floats)."""
    out = _two().select(empty)
    assert out.n == 0 and len(out.xy) == 0


def test_select_refuses_float_and_multi_dimensional_indices():
    with pytest.raises(TypeError, match="boolean mask or integer indices"):
        _two().select([1.5])
    with pytest.raises(ValueError, match="1-D"):
        _two().select([[0]])


@pytest.mark.parametrize("index", [1.5, 1.0, True, np.bool_(True), "1"])
def test_polygon_refuses_an_index_that_is_not_an_integer(index):
    """``polygon(1.5)`` quietly returned polygon 1."""
    with pytest.raises(TypeError, match="polygon index must be an integer"):
        _two().polygon(index)


def test_polygon_takes_integer_indices_and_refuses_outside_the_batch():
    p = _two()
    np.testing.assert_array_equal(p.polygon(np.int64(1)), TRIANGLE)
    with pytest.raises(IndexError, match="out of range for 2 polygons"):
        p.polygon(2)


# -- 2. Zonotope.contains and dimension 0 -----------------------------------------------
ZONOTOPES = {
    "flat": Zonotope([0.0, 0.0], [[1.0], [1.0]]),  # the linear programme
    "full": Zonotope([0.0, 0.0], np.eye(2)),  # the facets
    "point": Zonotope([0.0, 0.0], np.zeros((2, 0))),
}


@pytest.mark.parametrize("name", ZONOTOPES)
def test_zonotope_holds_no_point_with_a_coordinate_that_is_not_finite(name):
    """linprog raised "b_ub must not contain values inf" (flat), the point held an
    infinite point by its own slack; a box and an ellipsoid answer False."""
    z = ZONOTOPES[name]
    others = (Box([0.0, 0.0], [0.0, 0.0]), Ellipsoid([0.0, 0.0], np.zeros((2, 2))))
    for x in ([np.inf, np.inf], [np.inf, 0.0], [-np.inf, 0.0], [np.nan, 0.0]):
        assert z.contains(x) is False
        assert all(s.contains(x) is False for s in others)  # the same answer
    got = z.contains([[np.inf, np.inf], [0.0, 0.0], [np.nan, 0.0], [5.0, 5.0]])
    np.testing.assert_array_equal(got, [False, True, False, False])
    with pytest.raises(ValueError, match="points must have shape"):
        z.contains([np.inf, 0.0, 0.0])


@pytest.mark.parametrize(
    "make",
    [
        lambda: Zonotope([], np.zeros((0, 0))),
        lambda: Zonotope.from_box([], []),
        lambda: Box([], []),
        lambda: Box.from_centre([], 1.0),
        lambda: Ellipsoid([], np.zeros((0, 0))),
        lambda: Ellipsoid.ball([], 1.0),
        lambda: Ellipsoid.from_box([], []),
    ],
)
def test_every_family_refuses_a_set_of_dimension_zero(make):
    """A zonotope of dimension 0 failed in ``contains`` ("k must be a non-negative
    integer"); a box and an ellipsoid of dimension 0 were built too."""
    with pytest.raises(ValueError, match="at least one coordinate"):
        make()


@pytest.mark.parametrize("s", [Box([0, 0], [1, 1]), ZONOTOPES["full"], Ellipsoid.ball([0, 0], 1)])
def test_an_affine_map_to_dimension_zero_is_refused(s):
    with pytest.raises(ValueError, match="at least one row"):
        s.affine(np.zeros((0, 2)))


# -- 3. support ----------------------------------------------------------------------
FAMILIES = {
    "box": Box([0.0, 0.0], [1.0, 1.0]),
    "zonotope": Zonotope([0.5, 0.5], 0.5 * np.eye(2)),
    "ellipsoid": Ellipsoid.ball([0.5, 0.5], 0.5),
}


@pytest.mark.parametrize("name", FAMILIES)
def test_support_refuses_a_direction_that_is_not_finite_or_of_another_length(name):
    """``Box.support([nan, 1])`` was NaN; a wrong length a numpy matmul/einsum error."""
    s = FAMILIES[name]
    for d in ([np.nan, 1.0], [np.inf, 0.0], [[1.0, 0.0], [np.nan, 1.0]]):
        with pytest.raises(ValueError, match="d must be finite"):
            s.support(d)
    for d in ([1.0, 1.0, 1.0], [[1.0, 0.0, 0.0]], 1.0, np.ones((2, 2, 2))):
        with pytest.raises(ValueError, match=r"d must have shape \(2,\) or \(k, 2\)"):
            s.support(d)
    # one direction and several, as before, and the same as extremes
    assert s.support([1.0, 0.0]) == pytest.approx(s.extremes([1.0, 0.0])[1])
    assert s.support(np.eye(2)).shape == (2,)


# -- 4. one-dimensional vectors --------------------------------------------------------
@pytest.mark.parametrize(
    "make",
    [
        lambda: Box([[0, 0], [1, 1]], [[1, 1], [2, 2]]),
        lambda: Box([[0], [0]], [[1], [1]]),
        lambda: Box.from_centre([[0.0, 0.0]], 1.0),
        lambda: Zonotope([[0.0, 0.0]], np.eye(2)),
        lambda: Zonotope.from_box([[0, 0]], [[1, 1]]),
        lambda: Ellipsoid([[0.0, 0.0]], np.eye(2)),
        lambda: Ellipsoid.ball([[0.0, 0.0]], 1.0),
        lambda: Box([0, 0], [1, 1]).translate([[1.0, 1.0]]),
        lambda: Ellipsoid.ball([0, 0], 1.0).intersect_strip([[1.0, 0.0]], 0.0, 1.0),
    ],
)
def test_a_vector_of_two_or_more_dimensions_is_refused_not_flattened(make):
    """``Box([[0,0],[1,1]], [[1,1],[2,2]])`` was a 4-D box."""
    with pytest.raises(ValueError, match="must be one-dimensional"):
        make()


def test_a_number_is_still_a_vector_of_length_one():
    """A scalar for a 1-D set was taken before (and is unambiguous): kept."""
    assert Box(0.0, 1.0).dim == 1
    assert Zonotope(0.0, [[1.0]]).dim == 1
    assert Ellipsoid(0.0, [[1.0]]).extremes(1.0) == pytest.approx((-1.0, 1.0))


# -- 5. Ellipsoid at extreme scales ----------------------------------------------------
def _unit_ball(rng, k, n=2):
    u = rng.normal(size=(k, n))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return u, u * rng.uniform(0.0, 1.0, (k, 1)) ** (1.0 / n)


@pytest.mark.parametrize("criterion", ["trace", "volume"])
@pytest.mark.parametrize(
    ("r1", "r2"), [(1.0, 1e-155), (1e-155, 1.0), (1.0, 1e-300), (1e100, 3e99), (1e-140, 2e-140)]
)
def test_the_sum_of_balls_of_extreme_scales_holds_the_exact_sum(r1, r2, criterion):
    """A unit ball plus one of 1e-155 was all NaN (trace criterion: the ratio of the
    traces overflowed; the reverse order worked); at 1e100 the norms of the rounding
    cover overflowed, at 1e-140 the centre's cover divided by an underflowed square.
    The result must hold points of the exact sum: ``c1 + c2 + (r1 + r2) u`` on its
    boundary and sums of points sampled in each ball."""
    rng = np.random.default_rng(7)
    c1, c2 = np.array([0.3, 0.0]) * r1, np.array([0.0, -0.2]) * r2
    out = Ellipsoid.ball(c1, r1).minkowski_sum(Ellipsoid.ball(c2, r2), criterion)
    assert np.isfinite(out.shape).all() and np.isfinite(out.centre).all()
    u, v1 = _unit_ball(rng, 2000)
    _, v2 = _unit_ball(rng, 2000)
    assert out.contains(c1 + c2 + r1 * u + r2 * u).all()  # the exact sum's boundary
    assert out.contains(c1 + r1 * v1 + c2 + r2 * v2).all()
    # not a gross outer bound either: the larger radius to a few ulps
    assert np.sqrt(np.linalg.eigvalsh(out.shape).max()) <= 2.0 * (r1 + r2)


def test_a_ball_whose_square_overflows_is_refused_and_a_tiny_one_kept():
    """``ball(c, 1e200)`` raised ``OverflowError``; under 1e-162 a ball was its centre."""
    with pytest.raises(ValueError, match="radius must be at most 1.34e\\+154"):
        Ellipsoid.ball([0.0, 0.0], 1e200)
    tiny = Ellipsoid.ball([0.0, 0.0], 1e-200)
    assert np.all(np.diag(tiny.shape) >= 1e-200**2) and np.diag(tiny.shape).min() > 0.0
    assert tiny.contains([1e-200, 0.0], tol=0.0)


def test_a_result_beyond_the_float_range_is_refused_by_name():
    big = Ellipsoid.ball([0.0, 0.0], 1e154)  # shape 1e308 I
    with pytest.raises(ValueError, match="beyond the floating-point range"):
        big.minkowski_sum(big)
    with pytest.raises(ValueError, match="beyond the floating-point range"):
        Ellipsoid.ball([0.0, 0.0], 1e150).affine(1e10 * np.eye(2))


@pytest.mark.parametrize("criterion", ["volume", "trace"])
@pytest.mark.parametrize("scale", [1e300, 1e-300, 1e200])
def test_a_strip_cut_at_extreme_scales_holds_the_exact_intersection(scale, criterion):
    """``Ellipsoid(0, 1e300 I).intersect_strip([1, 0], 0, 1e149)`` was NaN (``P a a^T P``
    and the covers' norms overflowed). The result must be finite, smaller than the
    input by its criterion and hold points sampled from the exact intersection."""
    rng = np.random.default_rng(11)
    f = rng.normal(size=(2, 2))
    q = f @ f.T + 0.3 * np.eye(2)  # E(c, scale q) = c + sqrt(scale) L u
    root = np.sqrt(scale)
    e = Ellipsoid(np.array([0.2, -0.1]) * root, q * scale)
    a = np.array([1.0, 0.5])
    half, m = np.sqrt(a @ q @ a) * root, float(a @ e.centre)
    lam, vec = np.linalg.eigh(q)
    u, inner = _unit_ball(rng, 40000)
    for b, r in [(m + 0.3 * half, 0.2 * half), (m - 0.9 * half, 0.3 * half), (m, 0.1 * half)]:
        out = e.intersect_strip(a, b, r, criterion)
        assert np.isfinite(out.shape).all() and np.isfinite(out.centre).all()
        if criterion == "trace":
            assert np.trace(out.shape) < np.trace(e.shape)
        else:  # smaller volume, on the normalised shapes (the determinant overflows)
            assert np.linalg.det(out.shape / scale) < np.linalg.det(q)
        pts = e.centre + root * ((inner * np.sqrt(lam)) @ vec.T)
        edge = e.centre + root * ((u * np.sqrt(lam)) @ vec.T)
        pts = np.vstack([pts, edge])
        keep = pts[np.abs(pts @ a - b) <= r]
        assert len(keep) > 500
        assert out.contains(keep).all()
    # the brief's case: a narrow strip through the centre of 1e300 I
    cut = Ellipsoid([0.0, 0.0], np.eye(2) * 1e300).intersect_strip([1.0, 0.0], 0.0, 1e149)
    assert np.isfinite(cut.shape).all() and cut.shape[0, 0] < 1e300
    assert cut.contains([[1e149, 0.0], [0.0, 1e150], [-1e149, 0.99e150 * np.sqrt(0.99)]]).all()


def test_a_halfspace_with_a_huge_normal_and_a_miss_in_the_given_units():
    """``a`` of 1e120 is rescaled too; an empty intersection says the given numbers."""
    e = Ellipsoid([0.0, 0.0], np.eye(2) * 1e300)
    out = e.intersect_halfspace([1e120, 0.0], 0.0)
    assert np.isfinite(out.shape).all() and out.contains([[-1e150, 0.0], [0.0, 1e150]]).all()
    with pytest.raises(ValueError, match=r"slab \[1e\+151, 1e\+151\] misses"):
        e.intersect_strip([1.0, 0.0], 1e151, 0.0)
