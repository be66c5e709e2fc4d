"""Fine decision steps: a run's cost is bounded for every legal step (docs/models.md
§1.4, the node set's vertex cap). At ``dt = 0.125 s`` (four times the seed's steps) the
Fig. 3 engagement once hung: slices grew by four vertices a prediction without bound.
It finishes, the truth inside the set at every step, and the slices stay at or under
the cap (the simplified count is reported)."""

from __future__ import annotations

import numpy as np
import pandas as pd
from harness_texts import cli_inproc
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.sim.intercept import run_engagement


def test_fig3_engagement_at_an_eighth_of_a_second_finishes_with_the_truth_inside(capsys, tmp_path):
    out = tmp_path / "out"
    r = cli_inproc(
        capsys, "intercept", "kp_fig3", "--set", "model.dt_s=0.125", "--runs", "1",
        "--no-progress", "--out", out,
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    (table,) = out.rglob("kp_fig3*-infoset-*.parquet")
    runs = pd.read_parquet(table)
    assert list(runs["status"]) == ["ok"]
    assert int(runs["truth_outside"].sum()) == 0
    assert "simplified_slices" in runs.columns


def test_fig3_game_at_a_twentieth_of_a_second_keeps_the_truth_inside():
    """At 0.05 s steps the game adversary holds the truth on the set's boundary every
    step, and the set's disturbance widens a slice by only ``nu dt^2 / 2`` (6e-6 m) a
    step: a truth whose relative position jittered by the rounding of 1 AU (~2e-8 km a
    step, before the truth's relative step) was found outside at 44 of 620 steps of
    this shortened Fig. 3 approach (66 of 1999 over the whole one). The engagement
    starts at 1801 km, 2.5 km off the axis, inside a box of the same proportions."""
    over = [
        "model.dt_s=0.05", "truth.x_km=[1801.3, 1801.3]", "truth.y_km=[-2.5, -2.5]",
        "estimator.x_km=[1301.3, 2301.3]", "estimator.y_km=[-4.0, 4.0]",
    ]  # fmt: skip
    sc = load_scenario("kp_fig3", over)
    r = run_engagement(sc, "infoset", "game", np.random.default_rng(0))
    assert r.checked_steps > 600
    assert r.truth_outside == 0
