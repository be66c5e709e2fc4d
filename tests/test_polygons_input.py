"""The public constructor of ConvexPolygons: an independent copy of checked input.

The kernels build their outputs through the unchecked ``ConvexPolygons._make``; a
caller's arrays go through ``ConvexPolygons(xy, offsets)``, which copies them and
refuses non-finite vertices, bad offsets, clockwise and non-convex polygons.
"""

import numpy as np
import pytest
import shapely
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons

SQUARE = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])  # CCW, area 1


def test_the_polygons_do_not_change_with_the_callers_arrays():
    xy = SQUARE.copy()
    offsets = np.array([0, 4])
    p = ConvexPolygons(xy, offsets)
    xy[0, 0] = 99.0
    offsets[1] = 3
    np.testing.assert_array_equal(p.xy, SQUARE)
    np.testing.assert_array_equal(p.offsets, [0, 4])
    assert p.areas()[0] == pytest.approx(1.0)
    assert not p.xy.flags.writeable and not p.offsets.flags.writeable


def test_the_internal_constructor_neither_copies_nor_checks():
    """``_make`` (the kernels' hot path) keeps the arrays it is given, unchecked."""
    xy = SQUARE[::-1].copy()  # clockwise: refused by the public constructor
    p = ConvexPolygons._make(xy, np.array([0, 4]))
    assert np.shares_memory(p.xy, xy)
    assert p.areas()[0] == pytest.approx(-1.0)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_a_vertex_that_is_not_finite_is_refused(bad):
    xy = np.vstack([SQUARE, [[5.0, 5.0], [6.0, bad]]])
    with pytest.raises(ValueError, match=r"vertex 5 \(polygon 1\) is not finite"):
        ConvexPolygons(xy, np.array([0, 4, 6]))


def test_a_clockwise_square_is_refused_and_the_message_says_so():
    with pytest.raises(ValueError, match="polygon 1 is clockwise.*counter-clockwise"):
        ConvexPolygons.from_list([SQUARE, SQUARE[::-1]])


def test_a_non_convex_quadrilateral_is_refused():
    # counter-clockwise (positive area) but turning right at (1, 0.5)
    dart = np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.5], [1.0, 2.0]])
    assert shapely.Polygon(dart).exterior.is_ccw
    with pytest.raises(ValueError, match="polygon 0 is not convex"):
        ConvexPolygons.from_list([dart])


def test_a_star_polygon_turning_left_everywhere_is_refused():
    """A pentagram turns left at every vertex but winds around twice."""
    t = np.arange(5) * 4 * np.pi / 5
    star = np.column_stack([np.cos(t), np.sin(t)])
    with pytest.raises(ValueError, match="winds around 2 times"):
        ConvexPolygons.from_list([star])


@pytest.mark.parametrize(
    ("offsets", "what"),
    [([0, 3], "end at the number of vertices"), ([1, 4], "start at 0"),
     ([0, 3, 1, 4], "non-decreasing"), ([0.0, 2.5, 4.0], "integers")],
)  # fmt: skip
def test_bad_offsets_are_refused(offsets, what):
    with pytest.raises(ValueError, match=what):
        ConvexPolygons(SQUARE, np.array(offsets))


def test_valid_ccw_convex_polygons_with_a_point_a_segment_and_an_empty_one_are_accepted():
    triangle = np.array([[0.0, 0.0], [3.0, 0.0], [0.0, 2.0]])
    collinear = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])  # a degenerate polygon
    # a square far from the origin with a repeated vertex and rounding in its corners
    rotated = SQUARE @ np.array([[np.cos(0.3), np.sin(0.3)], [-np.sin(0.3), np.cos(0.3)]])
    far = np.insert(rotated * 1e-3 + 1e6, 1, rotated[0] * 1e-3 + 1e6, axis=0)
    polys = [SQUARE, np.zeros((0, 2)), [[5.0, 5.0]], [[1.0, 1.0], [4.0, 2.0]], triangle,
             collinear, far]  # fmt: skip
    batch = ConvexPolygons.from_list(polys)
    assert batch.n == 7
    np.testing.assert_array_equal(batch.counts, [4, 0, 1, 2, 3, 3, 5])
    np.testing.assert_allclose(batch.areas()[:6], [1.0, 0.0, 0.0, 0.0, 3.0, 0.0])
    for i, p in enumerate(polys):
        np.testing.assert_array_equal(batch.polygon(i), np.reshape(p, (-1, 2)))
    # the tolerance is relative to the coordinates, yet far below this square's size
    with pytest.raises(ValueError, match="polygon 0 is clockwise"):
        ConvexPolygons.from_list([far[::-1]])


def test_a_kernels_output_is_accepted_by_the_public_constructor():
    """Degenerate outputs (a segment summed along itself emits a - g, a + g, b - g,
    b + g: collinear points out of order) pass the checks as they come."""
    seg = np.array([[0.0, 0.0], [2.0, 0.0]])
    out = ConvexPolygons.from_list([seg, [[3.0, 4.0]], SQUARE]).minkowski_segment(
        [[1.5, 0.0], [1.0, 1.0], [0.5, 0.0]]
    )
    again = ConvexPolygons(out.xy, out.offsets)
    np.testing.assert_array_equal(again.xy, out.xy)


def test_the_minkowski_sum_of_a_valid_square_has_shapelys_area():
    g = np.array([0.5, 0.0])
    out = ConvexPolygons.from_list([SQUARE]).minkowski_segment(g)
    expected = shapely.MultiPoint(np.vstack([SQUARE - g, SQUARE + g])).convex_hull
    assert expected.area == pytest.approx(2.0)
    assert out.areas()[0] == pytest.approx(expected.area, rel=1e-12)
    assert shapely.Polygon(out.polygon(0)).is_valid


def _two_squares() -> ConvexPolygons:
    return ConvexPolygons(np.vstack([SQUARE, SQUARE + 3.0]), np.array([0, 4, 8]))


@pytest.mark.parametrize("index", [[2], [-1], [0, 5]])
def test_contains_point_refuses_a_polygon_index_outside_the_batch(index):
    """The kernel reads the offsets unchecked: an index past them read other memory."""
    with pytest.raises(IndexError, match="out of range"):
        _two_squares().contains_point(index, (0.5, 0.5), 0.0)


@pytest.mark.parametrize("point", [(np.nan, 0.5), (0.5, np.inf), (0.5,), (0.5, 0.5, 0.5)])
def test_contains_point_refuses_a_point_that_is_not_two_finite_numbers(point):
    """A NaN point compared as inside every polygon (no comparison with NaN is true)."""
    with pytest.raises(ValueError, match="point must be two finite numbers"):
        _two_squares().contains_point([0, 1], point, 0.0)


@pytest.mark.parametrize("tol", [-1e-9, np.nan, np.inf])
def test_contains_point_refuses_a_negative_or_non_finite_tolerance(tol):
    with pytest.raises(ValueError, match="tol must be finite"):
        _two_squares().contains_point([0], (0.5, 0.5), tol)


def test_contains_point_still_answers_for_valid_input():
    p = _two_squares()
    assert p.contains_point([0], (0.5, 0.5), 0.0)
    assert not p.contains_point([0], (3.5, 3.5), 0.0)
    assert p.contains_point([0, 1], (3.5, 3.5), 0.0)
    assert p.contains_point(1, (3.5, 3.5), 0.0)


@pytest.mark.parametrize(
    "matrix, offset",
    [(np.eye(2) * np.nan, (0.0, 0.0)), (np.eye(2), (np.inf, 0.0)), (np.eye(2), (0.0, np.nan))],
)
def test_affine_refuses_maps_and_offsets_that_are_not_finite(matrix, offset):
    """A NaN map passed the determinant check (NaN <= 0 is false) and wrote NaN vertices."""
    with pytest.raises(ValueError, match="must be finite"):
        _two_squares().affine(matrix, offset)


def test_translate_refuses_an_offset_that_is_not_finite():
    with pytest.raises(ValueError, match="offset must be finite"):
        _two_squares().translate((np.nan, 0.0))


@pytest.mark.parametrize(
    ("dy", "half_y", "message"),
    [
        (np.array([0.5]), np.array([0.1]), "dy must hold one value per polygon"),
        (np.zeros(2), np.zeros(3), "half_y must hold one value per polygon"),
        (np.zeros((2, 1)), np.zeros(2), "dy must hold one value per polygon"),
        (np.zeros(2), np.array([0.1, np.nan]), "half_y must be finite"),
        (np.array([np.inf, 0.0]), np.zeros(2), "dy must be finite"),
        (np.zeros(2), np.array([0.1, -0.1]), "half_y must be >= 0"),
    ],
)
def test_shift_band_refuses_what_its_kernel_would_read_past_or_invert(dy, half_y, message):
    """One value short read past the arrays in the compiled kernel (2000 squares and
    one value: a bound of -1.4e306, memory beyond the input); NaN, inf and a negative
    half-width gave NaN or inverted polygons."""
    with pytest.raises(ValueError, match=message):
        _two_squares().shift_band(dy, half_y)


def test_shift_band_takes_one_value_for_all_and_moves_as_the_arrays_do():
    p = _two_squares()
    one = p.shift_band(0.5, 0.1)
    per = p.shift_band(np.full(2, 0.5), np.full(2, 0.1))
    np.testing.assert_array_equal(one.xy, per.xy)
    # the unit square moved up by 0.5 and swept by +-0.1 along y: the box [0,1]x[0.4,1.6]
    got = shapely.Polygon(one.polygon(0))
    assert got.symmetric_difference(shapely.box(0, 0.4, 1, 1.6)).area == pytest.approx(0, abs=1e-12)


def test_polygon_index_counts_from_the_end_and_refuses_outside_the_batch():
    p = _two_squares()
    np.testing.assert_array_equal(p.polygon(-1), p.polygon(1))
    for i in (2, -3):
        with pytest.raises(IndexError, match="out of range for 2 polygons"):
            p.polygon(i)


def test_clip_slab_refuses_an_axis_other_than_x_or_y():
    """Axis 2 clipped y without a word."""
    with pytest.raises(ValueError, match="axis must be 0"):
        _two_squares().clip_slab(2, 0.0, 1.0)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"max_vertices": 0}, "max_vertices must be an integer >= 3"),
    ({"max_vertices": -5}, "max_vertices must be an integer >= 3"),
    ({"max_vertices": 3.5}, "max_vertices must be an integer >= 3"),
    ({"rel_area_tol": -1.0}, "rel_area_tol must be finite"),
    ({"rel_area_tol": np.nan}, "rel_area_tol must be finite"),
])  # fmt: skip
def test_simplify_refuses_a_cap_it_would_ignore(kwargs, message):
    with pytest.raises(ValueError, match=message):
        _two_squares().simplify(**kwargs)
