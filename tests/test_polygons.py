"""The ragged convex-polygon kernels against shapely (an independent computation)."""

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.common.polygons import ConvexPolygons


def _random_convex(rng, n_poly, kind="polygon"):
    polys = []
    for _ in range(n_poly):
        centre = rng.normal(size=2) * 3
        if kind == "point":
            pts = centre[None, :]
        elif kind == "segment":
            pts = np.array([centre, centre + rng.normal(size=2)])
        else:
            pts = centre + rng.normal(size=(rng.integers(3, 12), 2)) * rng.uniform(0.1, 3, size=2)
        hull = shapely.MultiPoint(pts).convex_hull
        if hull.geom_type == "Polygon":
            xy = np.asarray(hull.exterior.coords)[:-1]
            if shapely.Polygon(xy).exterior.is_ccw is False:
                xy = xy[::-1]
        else:
            xy = np.asarray(hull.coords) if hull.geom_type == "LineString" else pts
        polys.append(xy)
    return polys


def _same_set(a_xy, b_geom, tol=1e-9):
    """Two convex sets are equal iff each lies within tol of the other."""
    a = shapely.MultiPoint(a_xy).convex_hull if len(a_xy) else shapely.Polygon()
    if a.is_empty or b_geom.is_empty:
        return a.is_empty == b_geom.is_empty or max(a.area, b_geom.area) < tol
    return a.hausdorff_distance(b_geom) < tol * max(1.0, max(abs(c) for c in a.bounds))


seeds = st.integers(0, 2**32 - 1)


@settings(max_examples=40, deadline=None)
@given(seed=seeds, kind=st.sampled_from(["polygon", "polygon", "segment", "point"]))
def test_clip_slab_equals_shapely_intersection(seed, kind):
    rng = np.random.default_rng(seed)
    polys = _random_convex(rng, 7, kind)
    batch = ConvexPolygons.from_list(polys)
    lo = rng.normal(size=7) * 3
    hi = lo + rng.uniform(0, 4, size=7)
    out = batch.clip_slab(0, lo, hi)
    for i, p in enumerate(polys):
        geom = shapely.MultiPoint(p).convex_hull
        strip = shapely.box(lo[i], -1e3, hi[i], 1e3)
        expected = geom.intersection(strip)
        assert _same_set(out.polygon(i), expected), (i, out.polygon(i), expected)


def test_clip_strip_that_misses_a_section_empties_it_and_touching_gives_a_point():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    batch = ConvexPolygons.from_list([square, square, square])
    out = batch.clip_slab(0, [2.0, 1.0, 0.25], [3.0, 1.5, 0.5])
    assert out.counts[0] == 0  # strip misses the section
    assert len(out.polygon(1)) == 2  # touches an edge: a segment
    np.testing.assert_allclose(out.polygon(1)[:, 0], 1.0)
    assert out.areas()[2] == pytest.approx(0.25)
    touch_corner = ConvexPolygons.from_list([square]).clip_halfplanes([1.0, 1.0], [0.0])
    np.testing.assert_allclose(touch_corner.polygon(0), [[0.0, 0.0]])


@settings(max_examples=40, deadline=None)
@given(seed=seeds, kind=st.sampled_from(["polygon", "polygon", "segment", "point"]))
def test_minkowski_segment_equals_hull_of_translates(seed, kind):
    """P + [-g, g] = conv((P - g) U (P + g)), computed by shapely."""
    rng = np.random.default_rng(seed)
    polys = _random_convex(rng, 6, kind)
    g = rng.normal(size=(6, 2)) * rng.uniform(0.01, 2)
    out = ConvexPolygons.from_list(polys).minkowski_segment(g)
    for i, p in enumerate(polys):
        expected = shapely.MultiPoint(np.vstack([p - g[i], p + g[i]])).convex_hull
        assert _same_set(out.polygon(i), expected)
        poly = out.polygon(i)
        if len(poly) >= 3 and expected.area > 1e-9:
            # output is a proper CCW convex polygon, not just the right hull
            assert out.areas()[i] == pytest.approx(expected.area, rel=1e-9)


def test_minkowski_segment_parallel_to_a_segment_extends_it():
    seg = np.array([[0.0, 0.0], [2.0, 0.0]])
    out = ConvexPolygons.from_list([seg]).minkowski_segment([[1.0, 0.0]])
    hull = shapely.MultiPoint(out.polygon(0)).convex_hull
    assert hull.geom_type == "LineString"
    np.testing.assert_allclose(hull.bounds, [-1.0, 0.0, 3.0, 0.0])


@settings(max_examples=30, deadline=None)
@given(seed=seeds)
def test_affine_and_translate_equal_shapely_affine_transform(seed):
    rng = np.random.default_rng(seed)
    polys = _random_convex(rng, 5)
    mats = np.eye(2) + rng.normal(size=(5, 2, 2)) * 0.3
    mats[np.linalg.det(mats) < 0, 0, :] *= -1
    off = rng.normal(size=(5, 2))
    out = ConvexPolygons.from_list(polys).affine(mats, off).translate(-off)
    for i, p in enumerate(polys):
        m = mats[i]
        geom = shapely.affinity.affine_transform(
            shapely.Polygon(p), [m[0, 0], m[0, 1], m[1, 0], m[1, 1], 0.0, 0.0]
        )
        assert _same_set(out.polygon(i), geom)
        assert out.areas()[i] > 0  # orientation kept CCW


def test_select_and_bounds_and_negative_determinant_rejected():
    polys = [np.array([[0.0, 0], [1, 0], [0, 1]]), np.zeros((0, 2)), np.array([[5.0, 5]])]
    batch = ConvexPolygons.from_list(polys)
    kept = batch.select(batch.nonempty())
    assert kept.n == 2
    np.testing.assert_array_equal(kept.polygon(1), [[5.0, 5.0]])
    np.testing.assert_array_equal(kept.bounds()[0], [0, 0, 1, 1])
    with pytest.raises(ValueError):
        batch.affine(np.diag([1.0, -1.0]))


@settings(max_examples=60, deadline=None)
@given(seed=seeds, runs=st.integers(1, 20), negative=st.booleans())
def test_select_equals_the_polygons_picked_one_by_one(seed, runs, negative):
    """``select`` (copied in runs of consecutive polygons when there are few runs) keeps
    exactly the chosen polygons in the order asked, for masks, runs, permutations,
    repeats and negative indices alike: compared with the polygons picked one by one."""
    rng = np.random.default_rng(seed)
    polys = _random_convex(rng, 30, "polygon")
    polys[3] = np.zeros((0, 2))  # an empty polygon among them
    batch = ConvexPolygons.from_list(polys)
    starts = rng.integers(0, 30, size=runs)
    idx = np.concatenate([np.arange(a, min(a + rng.integers(1, 6), 30)) for a in starts])
    if negative:
        idx = idx - 30  # the same polygons, counted from the end
    for chosen in (idx, rng.permutation(30), rng.random(30) < 0.5):
        out = batch.select(chosen)
        picked = np.arange(30)[chosen]
        assert out.n == len(picked)
        for k, i in enumerate(picked):
            np.testing.assert_array_equal(out.polygon(k), polys[i])


@settings(max_examples=40, deadline=None)
@given(seed=seeds, n_a=st.integers(0, 12), n_b=st.integers(0, 12))
def test_take_polygons_gathers_from_two_batches_as_picked_one_by_one(seed, n_a, n_b):
    """The node set's merge kernel (``take_polygons``): index ``i < n_a`` picks polygon
    ``i`` of the first batch, ``i >= n_a`` polygon ``i - n_a`` of the second, in any
    order and with repeats; compared with the polygons picked one by one."""
    from kalman_vs_infoset.estim.common import _kernels as k

    rng = np.random.default_rng(seed)
    polys_a, polys_b = _random_convex(rng, n_a), _random_convex(rng, n_b)
    if n_a:
        polys_a[0] = np.zeros((0, 2))  # an empty polygon among them
    a, b = ConvexPolygons.from_list(polys_a), ConvexPolygons.from_list(polys_b)
    both = polys_a + polys_b
    index = rng.integers(0, max(len(both), 1), size=rng.integers(0, 20)) if both else []
    index = np.asarray(index, dtype=np.int64)
    out = ConvexPolygons._make(*k.take_polygons(a.xy, a.offsets, b.xy, b.offsets, index))
    assert out.n == len(index)
    for j, i in enumerate(index):
        np.testing.assert_array_equal(out.polygon(j), both[i])


def test_all_sections_empty():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    out = ConvexPolygons.from_list([square] * 4).clip_slab(0, 5.0, 6.0)
    assert not out.nonempty().any()
    assert out.select(out.nonempty()).n == 0
    assert out.minkowski_segment([1.0, 1.0]).n == 4


@settings(max_examples=150, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(1, 14),
    scale=st.floats(1e-3, 1e5),
    collinear=st.booleans(),
)
def test_convex_hulls_kernel_equals_shapely_convex_hull(seed, n, scale, collinear):
    """The prediction's hull step (estim.common._kernels.convex_hulls) is shapely's convex hull
    of the vertices, counter-clockwise, also with (nearly) collinear points."""
    from kalman_vs_infoset.estim.common import _kernels as k

    rng = np.random.default_rng(seed)
    pts = rng.normal(size=(n, 2)) * scale
    if collinear and n >= 3:
        pts[1] = 0.5 * (pts[0] + pts[2])
    xy, off = k.convex_hulls(pts, np.array([0, n], dtype=np.int64))
    assert off.tolist() == [0, len(xy)]
    assert _same_set(xy, shapely.MultiPoint(pts).convex_hull)
    if len(xy) >= 3 and shapely.Polygon(xy).area > 1e-9 * np.abs(xy).max() ** 2:
        # (a sliver of nearly collinear points has no meaningful orientation)
        assert shapely.Polygon(xy).exterior.is_ccw
        d1, d2 = np.roll(xy, -1, 0) - xy, np.roll(xy, -2, 0) - np.roll(xy, -1, 0)
        cross = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
        # convex: no reflex vertex left (beyond the rounding of nearly collinear input)
        assert np.all(cross > -1e-12 * np.abs(xy).max() ** 2)


def test_a_nan_bound_or_segment_is_refused_not_an_empty_set():
    """A NaN bound compared every vertex as outside and emptied the polygons silently;
    an infinite bound stays a bound (no limit on that side)."""
    sq = ConvexPolygons.from_list([[[0, 0], [1, 0], [1, 1], [0, 1]]])
    for call in (
        lambda: sq.clip_slab(0, [np.nan], [1.0]),
        lambda: sq.clip_slab(1, [0.0], [np.nan]),
        lambda: sq.clip_halfplanes([1.0, 0.0], [np.nan]),
        lambda: sq.clip_halfplanes([np.nan, 0.0], [0.5]),
        lambda: sq.minkowski_segment([np.nan, 0.0]),
        lambda: sq.minkowski_segment([np.inf, 0.0]),
    ):
        with pytest.raises(ValueError, match="NaN|finite"):
            call()
    assert sq.clip_slab(0, [-np.inf], [np.inf]).counts.tolist() == [4]


@pytest.mark.parametrize("offset", [1e4, 1e6, 1e8])
def test_small_polygons_far_from_the_origin_keep_their_area_and_interior(offset):
    """Areas and point containment of polygons 1e-4 to 1 wide at ``offset`` from the
    origin, against shapely on coordinates taken relative to the polygon (exact there).
    Shoelace sums on raw coordinates cancelled: a 1e-4 square at 1e6 read an area of
    -1.2e-4, and its centre was outside it."""
    rng = np.random.default_rng(int(offset))
    for size in (1e-4, 1e-2, 1.0):
        polys = [offset + size * p / 10 for p in _random_convex(rng, 40)]
        polys = [p for p in polys if len(p) >= 3]
        cp = ConvexPolygons.from_list(polys)
        for i, p in enumerate(polys):
            local = shapely.Polygon(p - p[0])
            np.testing.assert_allclose(cp.areas()[i], local.area, rtol=1e-6)
            inner = local.representative_point()
            point = p[0] + np.array([inner.x, inner.y])
            assert cp.contains_point([i], point, 0.0), (offset, size, i)


def test_a_polygon_is_clipped_and_summed_alike_alone_and_beside_a_huge_one():
    """Rounding tolerances are each polygon's own: beside a 1e9 square a 1e-6 triangle
    was clipped to one vertex by a half-plane that does not touch it, and its sum with
    a segment came out not convex (the batch's largest coordinate set the tolerances)."""
    big = np.array([[0.0, 0.0], [1e9, 0.0], [1e9, 1e9], [0.0, 1e9]])
    tiny = np.array([[0.0, 0.0], [1e-6, 0.0], [0.0, 1e-6]])
    both, alone = ConvexPolygons.from_list([big, tiny]), ConvexPolygons.from_list([tiny])
    np.testing.assert_array_equal(
        both.clip_halfplanes([1.0, 1.0], [2e9, 2e9]).polygon(1),
        alone.clip_halfplanes([1.0], [2e9]).polygon(0),
    )
    # one half-segment a polygon: the square +-(1, 0), the triangle +-(0, 1e-11)
    summed = both.minkowski_segment([[1.0, 0.0], [0.0, 1e-11]]).polygon(1)
    np.testing.assert_array_equal(summed, alone.minkowski_segment([[0.0, 1e-11]]).polygon(0))
    exact = shapely.MultiPoint(np.vstack([tiny - [0.0, 1e-11], tiny + [0.0, 1e-11]]))
    assert _same_set(summed, exact.convex_hull)
    ConvexPolygons.from_list([summed])  # convex and counter-clockwise: accepted


def test_contains_point_means_within_tol_of_the_polygon_even_past_a_sharp_corner():
    """A point beyond the apex of a 1e-3 rad sliver, 1000 tol from it, lies within tol
    of both edges' lines; the "every line" test took it for inside, shapely puts it
    1000 tol away. It is refused now; a point tol/2 past the apex is accepted."""
    theta, tol = 1e-3, 1e-6
    sliver = np.array([[0.0, 0.0], [1.0, -np.tan(theta / 2)], [1.0, np.tan(theta / 2)]])
    cp = ConvexPolygons.from_list([sliver])
    far = (-1000 * tol, 0.0)
    assert shapely.Polygon(sliver).distance(shapely.Point(far)) == pytest.approx(1000 * tol)
    assert not cp.contains_point([0], far, tol)
    assert cp.contains_point([0], (-tol / 2, 0.0), tol)


@settings(max_examples=40, deadline=None)
@given(seeds, st.sampled_from(["polygon", "segment", "point"]))
def test_contains_point_agrees_with_shapelys_distance(seed, kind):
    """Accepted iff shapely's distance to the polygon is at most ``tol``, for points
    around random polygons, segments and points (outside a band of 1e-9 of ``tol``,
    where the two roundings may disagree)."""
    rng = np.random.default_rng(seed)
    polys = _random_convex(rng, 4, kind)
    cp = ConvexPolygons.from_list(polys)
    tol = float(rng.choice([0.0, 1e-3, 0.1, 1.0]))
    for i, p in enumerate(polys):
        geom = shapely.MultiPoint(p).convex_hull
        for q in p.mean(axis=0) + rng.normal(size=(30, 2)) * rng.uniform(0.1, 5):
            d = geom.distance(shapely.Point(q))
            if abs(d - tol) <= 1e-9 * max(1.0, tol) or (tol == 0 and d < 1e-9):
                continue
            assert cp.contains_point([i], q, tol) == (d <= tol), (i, q, d, tol)


@pytest.mark.parametrize("turn_deg", [0.0, 30.0, 72.0, 117.0])
def test_a_parallelogram_asked_for_three_vertices_keeps_four(turn_deg):
    """Removing an edge of a parallelogram extends two parallel neighbours: rotated,
    rounding made them meet 1e16 away, and ``simplify(max_vertices=3)`` returned a
    triangle of area 1e17 whose edge left a vertex out (by 4e-18 in exact arithmetic).
    Neighbours parallel to rounding are not extended: the parallelogram stays."""
    th = np.radians(turn_deg)
    rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    par = np.array([[0.0, 0.0], [3.0, 0.1], [4.0, 2.1], [1.0, 2.0]]) @ rot.T + [1e3, -50.0]
    polys = ConvexPolygons.from_list([par])
    out = polys.simplify(rel_area_tol=0.0, max_vertices=3)
    assert out.counts[0] == 4
    assert out.areas()[0] == pytest.approx(polys.areas()[0], rel=1e-12)
    assert np.abs(out.polygon(0) - [1e3, -50.0]).max() < 10.0
