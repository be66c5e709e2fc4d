"""The shared polygon kernels write only within their buffers, whatever the input.

A prior box with an infinite side (``ChannelPrior((-inf, 1e3), ...)``) once reached
``convex_hulls`` with non-finite vertices: every orientation test failed, both chains
of the hull kept every point, and the kernel wrote past its output (glibc: "free():
invalid next size", the process killed). Boxes are now refused as non-finite; the
kernels themselves are bounded too: the hull writes at most ``m`` vertices a polygon,
and a clip sizes its output for two vertices an edge, which a polygon whose signs
alternate along the line reaches (the oracle below is a plain Sutherland-Hodgman).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.common import _kernels as k
from kalman_vs_infoset.estim.intercept.model import ChannelPrior


def _batch(polys: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    off = np.zeros(len(polys) + 1, dtype=np.int64)
    off[1:] = np.cumsum([len(p) for p in polys])
    return np.concatenate(polys).astype(float), off


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_convex_hulls_of_non_finite_vertices_stay_within_the_input_size(bad):
    rng = np.random.default_rng(3)
    polys = [rng.normal(size=(m, 2)) for m in (3, 8, 17)]
    for p in polys:
        p[1, 0] = bad
        p[-1, 1] = bad
    xy, off = _batch(polys)
    hull, hoff = k.convex_hulls(xy, off)
    counts = np.diff(hoff)
    assert hoff[-1] == len(hull) <= len(xy)
    assert np.all(counts >= 1) and np.all(counts <= np.diff(off))


def _sutherland_hodgman(poly: np.ndarray, nx: float, ny: float, bound: float) -> int:
    """Vertices one clip writes (before dropping duplicates), in plain Python."""
    out = 0
    m = len(poly)
    for j in range(m):
        a, c = poly[j], poly[(j + 1) % m]
        sa, sc = a @ (nx, ny) - bound, c @ (nx, ny) - bound
        out += int(sa <= 0.0) + int((sa <= 0.0) != (sc <= 0.0))
    return out


@settings(max_examples=60, deadline=None)
@given(
    m=st.integers(3, 40),
    n=st.integers(1, 4),
    seed=st.integers(0, 2**32 - 1),
)
def test_a_clip_of_polygons_whose_signs_alternate_stays_within_its_buffer(m, n, seed):
    """Zigzags across the line x = 0 (each vertex on the other side of its neighbour)
    give a clip 1.5 m vertices before duplicates drop, more than the m + 1 of a convex
    polygon: the output holds them, and keeps exactly the inside vertices and the
    crossings."""
    rng = np.random.default_rng(seed)
    polys = []
    for _ in range(n):
        x = np.where(np.arange(m) % 2 == 0, -1.0, 1.0) * rng.uniform(0.5, 2.0, m)
        polys.append(np.column_stack([x, np.arange(m, dtype=float)]))
    xy, off = _batch(polys)
    ones, zeros = np.ones(n), np.zeros(n)
    out, oo = k.clip_halfplanes(xy, off, ones, zeros, zeros)
    assert oo[-1] == len(out)
    for i, p in enumerate(polys):
        written = _sutherland_hodgman(p, 1.0, 0.0, 0.0)
        assert oo[i + 1] - oo[i] <= written
        assert np.all(out[oo[i] : oo[i + 1], 0] <= 1e-12)  # crossings: x = 0 to rounding


def test_a_prior_box_must_be_finite():
    with pytest.raises(ValueError, match="finite interval"):
        ChannelPrior((-np.inf, 1e3), (-100.0, 100.0), (7e5, 9e5))
    with pytest.raises(ValueError, match="finite interval"):
        ChannelPrior((-1e3, 1e3), (-100.0, np.nan), (7e5, 9e5))
