"""Bounds between nodes next to a pair of nodes much closer than the cell they bound.

The secant through nodes ``i-1, i`` bounds the cell ``[tau_i, tau_i+1]`` (docs/infoset.md,
the bounds between nodes: the support of a convex body's slices is concave along it).
Its slope is a difference quotient, so rounding of the two nodes' slices (a few ulps: two
replays of the log never round alike) is divided by their spacing and multiplied by the
cell's length. A pair 1e-12 apart beside a cell 1e12 times longer turns 4 ulps into a
bound 1e-3 too low: states of the body fall outside it. Concavity allows any earlier
node in place of ``i-1``; the bounds take the nearest one far enough for the rounding to
stay under ``BOUND_RTOL`` (``_geometry.MAX_SECANT_REACH``).

The body here is a prism (the same slice at every ``tau``), so its support is constant
along it and every secant of exact values bounds it exactly: the limiting case of
concavity, where a rounded secant cuts it.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.common import _kernels as _k
from kalman_vs_infoset.estim.intercept.nodeset import _contains
from kalman_vs_infoset.estim.intercept.nodeset import _geometry as _ng
from kalman_vs_infoset.estim.intercept.nodeset.bounds import BOUND_RTOL

from kalman_vs_infoset.numerics.arrays import readonly

SCALE = 1e-4  # alpha_scale_rad
E_NOM = 58e3  # m/s
Y_MAX, V_MAX = 0.05, 1e-4  # the prism: |Y~| <= Y_MAX, |V~| <= V_MAX at every tau
HARD_HI = 250.0  # the body ends here (s); the last node, past it, is empty
ULP = 2.0**-52


def _to_node(yv: np.ndarray, tau: float) -> np.ndarray:
    """Rows ``(Y~, V~)`` at ``tau`` in the node set's ``(a, zs)``: ``a = Y~ / (scale
    tau)``, ``zs = e_nom (Y~ + V~ tau)`` (bounds.py)."""
    return np.c_[yv[:, 0] / (SCALE * tau), E_NOM * (yv[:, 0] + yv[:, 1] * tau)]


def _slice(tau: float) -> np.ndarray:
    """The prism's slice at ``tau`` in ``(a, zs)``."""
    yv = np.array([[-Y_MAX, -V_MAX], [Y_MAX, -V_MAX], [Y_MAX, V_MAX], [-Y_MAX, V_MAX]])
    return _to_node(yv, tau)


def _summarised(polys, labels, hard_lo: float, hard_hi: float):
    """The hulls of node polygons ``polys`` (an empty one: no states) at ``labels``,
    one piece at ``e_nom``, and their summary (``_geometry.summarise``)."""
    off = np.r_[0, np.cumsum([len(p) for p in polys])].astype(np.int64)
    xy, off = _k.convex_hulls(np.concatenate(polys).reshape(-1, 2), off)
    # read-only, as a node set holds them: the kernels' compiled (and cached) versions
    xy, off, u = readonly(xy), readonly(off, np.int64), readonly([1.0 / E_NOM])
    out = _ng.summarise(
        xy, off, readonly(labels), readonly(np.zeros(len(labels)), np.int64), 0.0, u, u,
        readonly([hard_lo]), readonly([hard_hi]), SCALE, E_NOM, BOUND_RTOL,
    )  # fmt: skip
    return xy, off, out


def _admits_state(xy, off, labels, summary, y: float, v: float, tau: float) -> bool:
    """Whether the summary admits the state ``Y~ = y, V~ = v`` at ``tau``."""
    table, tau4, span, cpiece = summary[:4]
    alpha = y / tau
    omega = (v + alpha) / tau  # V~ = omega tau - alpha
    u = readonly([1.0 / E_NOM])
    return bool(
        _contains.contains_state(
            xy,
            off,
            np.asarray(labels, float),
            np.diff(off) > 0,
            cpiece,
            span,
            table,
            tau4,
            u,
            u,
            alpha,
            omega,
            tau * E_NOM,
            1e-9,
            SCALE,
            E_NOM,
        )  # fmt: skip
    )


def _summary(labels, shrink):
    """The prism's slices at ``labels`` (the last node empty), node ``k`` shrunk by
    ``shrink[k]`` ulps towards the origin, as rounding could leave it; summarised."""
    polys = [_slice(t) * (1.0 - s * ULP) for t, s in zip(labels[:-1], shrink, strict=True)]
    return _summarised([*polys, np.empty((0, 2))], labels, 50.0, HARD_HI)


def _admits(labels, shrink, tau: float, y: float) -> bool:
    """Whether the summary of the nodes admits ``Y~ = y, V~ = 0`` at ``tau``."""
    xy, off, summary = _summary(labels, shrink)
    return _admits_state(xy, off, labels, summary, y, 0.0, tau)


#: a pair of live nodes 1e-12 apart (relative) at 100 s, one node at 90 s before them,
#: the empty node past the body's end
LABELS = [90.0, 100.0, 100.0 * (1 + 1e-12), 300.0]


@pytest.mark.parametrize("shrink", [(0, 0, 4), (0, 4, 0), (3, 0, 5)])
def test_a_rounded_close_pair_keeps_the_far_end_of_the_cell_beside_it(shrink):
    """bounds.py (secants of a concave support): a state of the prism near the far end
    of the cell beside the close pair stays inside, whichever node the rounding
    shrank."""
    inside = Y_MAX * (1 - 1e-8)
    assert _admits(LABELS, shrink, 240.0, inside)
    assert _admits(LABELS, shrink, 240.0, -inside)


@pytest.mark.parametrize("shrink", [(0, 0, 4), (0, 4, 0)])
def test_a_rounded_close_pair_bounds_the_zero_effort_miss_of_the_cell_beside_it(shrink):
    """The bound of ``zs`` over the cell ``[tau_2, 250 s]`` is at least the prism's
    exact largest ``zs`` there, ``e_nom (Y_MAX + V_MAX 250)`` (at the cell's far end), and
    still finite and tight (within 1e-6): the secant uses the node at 90 s."""
    _, _, (table, _, span, _, zs, *_rest) = _summary(LABELS, shrink)
    c = int(np.flatnonzero(table[:, 1] == 2)[0])
    assert span[c, 1] == HARD_HI
    exact = E_NOM * (Y_MAX + V_MAX * HARD_HI)
    assert zs[c, 0] >= exact
    assert zs[c, 0] <= exact * (1 + 1e-6)
    assert -zs[c, 2] >= exact  # the lower bound, by symmetry
    assert table[c, 0] == 0  # the secant from the far node, not the near one


def test_nodes_spaced_like_the_cell_use_their_nearest_neighbour():
    """Away from close pairs the bounds use the nearest node, as before: a node within
    ``MAX_SECANT_REACH`` times the cell's length of it."""
    labels = [90.0, 100.0, 110.0, 300.0]
    _, _, (table, *_rest) = _summary(labels, (0, 0, 0))
    c = int(np.flatnonzero(table[:, 1] == 2)[0])
    assert table[c, 0] == 1
    assert _ng.MAX_SECANT_REACH * 10.0 > 140.0


def test_without_a_farther_node_the_cell_is_bounded_from_the_other_side_only():
    """A close pair with no node before it gives no left secant: the cell beside it has
    no bound from that side (sound), and the state stays inside."""
    labels = [100.0, 100.0 * (1 + 1e-12), 300.0]
    assert _admits(labels, (0, 4), 240.0, Y_MAX * (1 - 1e-8))


def _body_slice(pts: np.ndarray, tau: float) -> np.ndarray:
    """The slice at ``tau`` of the convex hull of ``pts`` (rows ``Y~, V~, tau``): the
    hull of the points where the segments between them cross ``tau`` (every point of
    the slice is a convex combination of two hull points on either side of it)."""
    out = [p[:2] for p in pts if p[2] == tau]
    for i in range(len(pts)):
        for j in range(len(pts)):
            a, b = pts[i], pts[j]
            if a[2] < tau < b[2]:
                s = (tau - a[2]) / (b[2] - a[2])
                out.append(a[:2] + s * (b[:2] - a[:2]))
    return np.array(out).reshape(-1, 2)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n_pts=st.integers(4, 9),
    n_nodes=st.integers(3, 9),
    near_rel=st.sampled_from([0.0, 1e-12, 1e-11, 1e-9, 1e-6]),
    ulps=st.integers(0, 8),
)
def test_bounds_between_rounded_nodes_hold_every_state_of_a_random_convex_body(
    seed, n_pts, n_nodes, near_rel, ulps
):
    """bounds.py, against the body itself: the convex hull of random points in ``(Y~,
    V~, tau)`` (the scales of seed 003's Fig. 5: ``|Y~| <= 0.05``, ``|V~| <= 1e-4``,
    ``tau`` in 80-120 s), its exact slices at random nodes (one of them doubled at
    ``near_rel`` of its label), each moved by up to ``ulps`` ulps as rounding could.
    Every sampled state of the body is admitted by the containment test, and its
    ``zs`` lies within the bounds of its cell."""
    rng = np.random.default_rng(seed)
    pts = np.c_[rng.uniform(-0.05, 0.05, n_pts), rng.uniform(-1e-4, 1e-4, n_pts),
                rng.uniform(80.0, 120.0, n_pts)]  # fmt: skip
    t_lo, t_hi = pts[:, 2].min(), pts[:, 2].max()
    labels = np.sort(np.r_[rng.uniform(t_lo, t_hi, n_nodes), t_lo - 5.0, t_hi + 5.0])
    if near_rel:
        k = int(rng.integers(1, len(labels) - 1))
        labels = np.sort(np.r_[labels, labels[k] * (1.0 + near_rel)])
    polys = [
        _to_node(_body_slice(pts, t), t) * (1.0 + rng.integers(-ulps, ulps + 1) * ULP)
        for t in labels
    ]
    xy, off, summary = _summarised(polys, labels, 0.0, 1e3)
    span, zs = summary[2], summary[4]
    w = rng.dirichlet(np.ones(n_pts), 200)
    for y, v, tau in w @ pts:
        assert _admits_state(xy, off, labels, summary, y, v, tau), (y, v, tau)
        c = np.flatnonzero((span[:, 0] <= tau) & (tau <= span[:, 1]))
        z = E_NOM * (y + v * tau)
        assert len(c) and np.any((zs[c, 2] <= z) & (z <= zs[c, 0])), (tau, z)
