"""The paper's numbers marked on the control-process figures say whose they are: the
Fig. 5 scenarios carry the seed's Fig. 3 single run (their ``[reference]``), and the
legend says so instead of "paper: miss 4.3 m" as if it were Fig. 5's."""

from __future__ import annotations

import pytest
from kalman_vs_infoset.experiments import plots_intercept
from kalman_vs_infoset.experiments.intercept_runs import paper_marks
from kalman_vs_infoset.experiments.plots import plt

from kalman_vs_infoset.api import load_scenario, trace


@pytest.mark.parametrize(
    "name, label",
    [("kp_fig3", "paper"), ("kp_fig5", "paper Fig. 3, one run"),
     ("kp_fig5_range", "paper Fig. 3, one run")],
)  # fmt: skip
def test_the_marks_are_labelled_with_their_source(name, label):
    sc = load_scenario(name)
    assert paper_marks(sc)["random"] == (4.3, 244.7, label)
    steps, _ = trace(sc, "ekf", "random")
    fig = plots_intercept.control_processes(steps, 0, "ekf", ["random"], paper=paper_marks(sc))
    texts = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().texts]
    plt.close(fig)
    assert f"{label}: miss 4.3 m" in texts and f"{label}: fuel 244.7 m/s" in texts


def test_the_forecast_panel_s_legend_leaves_the_interval_uncovered():
    """The forecast-miss interval fills its panel: its legend sits below the panel,
    within the figure and over no axes (where "best" had put it over the interval; a
    band above the data, in two columns, spilled past the panel's left edge)."""
    sc = load_scenario("kp_fig3")
    steps, _ = trace(sc, "infoset", "random")
    fig = plots_intercept.control_processes(steps, 0, "infoset", ["random"], paper=paper_marks(sc))
    fig.canvas.draw()
    ax = fig.axes[2]
    assert ax.get_ylabel().startswith("forecast miss Pi, m\n(symmetric log")
    legend_box = ax.get_legend().get_window_extent()
    panel = ax.get_window_extent()
    overlaps = [a.get_ylabel() for a in fig.axes if legend_box.overlaps(a.get_window_extent())]
    inside = fig.bbox.x0 <= legend_box.x0 and legend_box.x1 <= fig.bbox.x1
    plt.close(fig)
    assert legend_box.y1 <= panel.y0 and not overlaps and inside
    assert panel.x0 <= legend_box.x0 and legend_box.x1 <= panel.x1
