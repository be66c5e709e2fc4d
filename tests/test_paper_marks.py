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
