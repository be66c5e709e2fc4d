"""docs/intercept.md's sentence on the node grid (``kvi sweep kp_fig5 --key
estimator.infoset.n_nodes``) quotes the extremes over the grid: computed here from the
results file, so a re-run that moves which grid is extreme cannot leave it stale."""

from __future__ import annotations

import re

from docs_numbers import ROOT, agrees, results


def test_node_grid_sentence_quotes_the_least_and_largest_mean_over_the_grid():
    text = " ".join((ROOT / "docs/intercept.md").read_text(encoding="utf-8").split())
    found = re.search(
        r"\(mean miss ([\d.]+)-([\d.]+) m, fuel ([\d.]+)-([\d.]+) m/s\)\. Under the game the "
        r"mean miss moves between ([\d.]+) and ([\d.]+) m in no clear direction and the fuel "
        r"between ([\d.]+) and ([\d.]+) m/s",
        text,
    )
    assert found, "the sentence was rewritten: re-point this test"
    rows = results("docs/results/sweeps/kp_fig5-n_nodes.json")["rows"]
    printed = iter(found.groups())
    for noise in ("random", "game"):
        mine = [r for r in rows if r["estimator"] == "infoset" and r["noise"] == noise]
        assert len(mine) == 4
        for key in ("miss_m", "fuel_mps"):
            means = [r[key]["mean"] for r in mine]
            lo, hi = next(printed), next(printed)
            assert agrees(lo, min(means)) and agrees(hi, max(means)), (noise, key, lo, hi)
