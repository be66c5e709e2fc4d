"""Fine decision steps: a run's cost is bounded for every legal step (docs/models.md
§1.4, the node set's vertex cap). At ``dt = 0.125 s`` (four times the seed's steps) the
Fig. 3 engagement once hung: slices grew by four vertices a prediction without bound.
It finishes, the truth inside the set at every step, and the slices stay at or under
the cap (the simplified count is reported)."""

from __future__ import annotations

import pandas as pd
from harness_texts import cli_inproc


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
