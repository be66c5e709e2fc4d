"""The 3-D set figures (:mod:`experiments.plots_sets`)."""

import io

import numpy as np
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments import plots_sets


def _sections():
    """A triangle and a pentagon at two ranges (km, mrad, km): a ragged list."""
    tri = np.array([[100.0, 0.1, -1.0], [100.0, 0.3, 0.0], [100.0, 0.1, 1.0]])
    ang = np.linspace(0.0, 2.0 * np.pi, 5, endpoint=False)
    pent = np.column_stack([np.full(5, 90.0), 0.2 + 0.1 * np.cos(ang), np.sin(ang)])
    return [tri, pent]


def test_ragged_sections_are_drawn_without_uninitialised_padding():
    """matplotlib issue #32272: a ragged list given to Poly3DCollection is padded with
    uninitialised memory that is projected anyway, so whatever it holds can overflow
    the projection (the RuntimeWarning 'overflow encountered in dot' seen now and then
    in full test runs). Filling any padding with the largest float, as the issue's
    reproduction does, must not overflow: the figure's collections have none."""
    fs.setup()
    fig = fs.plt.figure()
    ax = fig.add_subplot(projection="3d")
    polys = _sections()
    plots_sets._draw_3d(ax, polys, "C0", True, "set")
    plots_sets._limits_3d(ax, polys)
    (coll,) = ax.collections
    invalid = np.broadcast_to(coll._invalid_vertices, coll._faces.shape[:2])
    coll._faces[invalid] = np.finfo(float).max
    with np.errstate(over="raise", invalid="raise"):
        fig.savefig(io.BytesIO(), format="png")
    fs.plt.close(fig)


def test_padding_repeats_the_last_vertex_so_each_outline_is_unchanged():
    """Each padded polygon, with the repeated vertices dropped, is the polygon given."""
    polys = _sections()
    out = plots_sets._equal_length(polys)
    assert out.shape == (2, 5, 3)
    for given, padded in zip(polys, out, strict=True):
        keep = np.r_[True, np.any(np.diff(padded, axis=0) != 0.0, axis=1)]
        np.testing.assert_array_equal(padded[keep], given)
