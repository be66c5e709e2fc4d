"""The range-finder tightness rows of ``docs/infoset.md`` against the results files written by the
command that produced them (``kvi tightness data/scenarios/kp_fig5_range.toml --seed
S --out docs/results/tightness``): a stale number fails here."""

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ROW = re.compile(r"^\| kp_fig5_range \((\d+)\) \| random \| none \|(.*)\|$", re.M)


def test_infoset_page_range_finder_tightness_rows_match_their_results_files():
    rows = ROW.findall((ROOT / "docs" / "infoset.md").read_text(encoding="utf-8"))
    assert len(rows) == 5
    for seed, cells in rows:
        path = (
            ROOT / f"docs/results/tightness/kp_fig5_range-tightness-infoset-random-seed{seed}.json"
        )
        res = json.loads(path.read_text())
        assert [float(c) for c in cells.split("|")] == [round(r, 3) for r in res["ratio"]]
        assert all(res["exact_inside"]) and res["times_s"] == [10.0, 30.0, 60.0, 90.0, 95.0]


#: a row of the main tightness table: (slab set,) scenario, seed, errors, guidance, ratios
MAIN_ROW = re.compile(
    r"^\| (29 slabs \(option\), )?(kp_fig[35]) \((\d+)\) \| (random|bias|switch|game)[^|]* \| "
    r"(none|law) \|(.*)\|$",
    re.M,
)


def test_infoset_page_tightness_table_matches_its_results_files():
    """The main and the game tables (``kvi tightness kp_fig3|kp_fig5 --noise N --seed S
    [--guided] [--set 'estimator.infoset.sections="slabs"'] --json``, one results file a
    row)."""
    rows = MAIN_ROW.findall((ROOT / "docs" / "infoset.md").read_text(encoding="utf-8"))
    assert len(rows) == 32  # 12 + 4 slab rows, 16 game rows
    for slabs, scenario, seed, noise, guidance, cells in rows:
        stem = f"{scenario}-tightness-infoset-{noise}-seed{seed}"
        stem += "-guided" * (guidance == "law") + "-slabs" * bool(slabs)
        res = json.loads((ROOT / f"docs/results/tightness/{stem}.json").read_text())
        assert res["guided"] is (guidance == "law") and res["seed"] == int(seed)
        assert [float(c) for c in cells.split("|")] == [round(r, 3) for r in res["ratio"]], stem
        assert all(res["exact_inside"]) and res["times_s"] == [10.0, 30.0, 60.0, 90.0, 95.0]
