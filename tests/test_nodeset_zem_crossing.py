"""The node set's bound of the zero-effort miss between two nodes (docs/models.md §1.4):
the largest value over a cell of the smaller of the two sides' secant quadratics
(``_geometry._max_on_segment``), against a brute-force maximum on a fine grid.

The maximum sits where the two quadratics cross when one rises and the other falls.
Sides of almost equal curvature make the quadratic term of their difference vanish
(1e-13 against 1e1): the textbook root ``(-b + sqrt(b^2 - 4ac)) / 2a`` then loses the
crossing to cancellation (14.5035 s instead of 14.5287 s), and the bound came out
0.39 m too tight: random scenarios (``tests/fuzz_scenarios.py``, case 71041 under
``kvi tightness``) found the auxiliary-model truth below the node set's lower bound of
the miss, with the exact set's interval outside the set's.
"""

from __future__ import annotations

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.intercept.nodeset import _geometry as ng

#: the cell of case 71041 at 13 s (the lower bound's quadratics, negated: ``coef[side]
#: = (c0, c1, c2)``), found by the search
CASE_71041 = (
    np.array([[63.3268971, 15.4676186, 1.43176451e-13], [374.332062, -5.93863995, 1.02268894e-13]]),
    14.001828760042361,
    14.696607699508029,
)


def _brute(coef: np.ndarray, p: float, q: float, n: int = 200_001) -> float:
    t = np.linspace(p, q, n)
    vals = [coef[k, 0] + coef[k, 1] * t + coef[k, 2] * t * t for k in range(2)]
    return float(np.minimum(*vals).max())


def _bound(coef: np.ndarray, p: float, q: float) -> float:
    best, _ = ng._max_on_segment(coef, p, q, -np.inf, p, np.empty(8))
    return float(best)


def test_the_crossing_of_sides_of_equal_curvature_is_found_case_71041():
    """The analytic crossing (a linear equation: the curvatures cancel) and the grid
    agree; the bound reaches them (it read 287.66 against 288.05)."""
    coef, p, q = CASE_71041
    t_cross = (coef[1, 0] - coef[0, 0]) / (coef[0, 1] - coef[1, 1])  # c2 terms ~1e-13
    at_cross = coef[0, 0] + coef[0, 1] * t_cross
    assert p < t_cross < q and abs(at_cross - 288.0513) < 1e-3
    grid, step = _brute(coef, p, q), (q - p) / 200_000
    assert grid - 1e-9 <= _bound(coef, p, q) <= grid + 25.0 * step  # slopes below 25
    assert abs(_bound(coef, p, q) - at_cross) < 1e-9


@settings(max_examples=200, deadline=None)
@given(
    c0=st.tuples(st.floats(-1e3, 1e3), st.floats(-1e3, 1e3)),
    c1=st.tuples(st.floats(-50.0, 50.0), st.floats(-50.0, 50.0)),
    curvature=st.floats(-1e-3, 1e-3),
    skew=st.sampled_from([0.0, 1e-16, 1e-14, 1e-12, 1e-8, 1e-4]),
    p=st.floats(0.5, 100.0),
    width=st.floats(0.01, 5.0),
)
@example(c0=(63.3, 374.3), c1=(15.47, -5.94), curvature=1.4e-13, skew=1e-14, p=14.0, width=0.7)
def test_the_bound_is_the_maximum_of_the_smaller_side(c0, c1, curvature, skew, p, width):
    """Against the grid: never below it (beyond the grid's own resolution), and never
    above the true maximum (the grid's value plus the slope times a grid step)."""
    coef = np.array([[c0[0], c1[0], curvature], [c0[1], c1[1], curvature + skew]])
    q = p + width
    got, grid = _bound(coef, p, q), _brute(coef, p, q, 20_001)
    step = width / 20_000
    slope = max(abs(coef[k, 1]) + 2 * abs(coef[k, 2]) * q for k in range(2))
    scale = 1e-9 * (1.0 + max(abs(got), abs(grid)))
    assert grid - scale <= got <= grid + slope * step + scale
