"""The docs' tables against the results files of the commands that wrote them.

``TABLES`` compares a table cell by cell with the records of a results file (a row names
its record by its label cells; every number of a checked cell must be the record's value
rounded to the printed digits, and a number in a cell no key reads fails). The
inventory test lists every table of the README and ``docs/*.md`` that prints numbers: each
is checked here, checked row by row by ``test_docs_numbers.CHECKS``, rebuilt whole from
its files by a test (``REBUILT``), listed in ``NOT_RESULTS`` (settings, names), or listed
in ``UNBACKED`` with the command that would back it, so a new table cannot appear
unchecked and the open ones stay visible. ``docs/models.md`` and ``docs/references.md``
are exempt: their tables hold the papers' inputs and bibliographic data, not results.
"""

from __future__ import annotations

import pytest
from docs_numbers import NUMBER, ROOT, TableCheck, results, table_mismatches, tables

MISS4 = ("miss_m/mean", "miss_m/p50", "miss_m/p90", "miss_m/max")
FUEL4 = ("fuel_mps/mean", "fuel_mps/p50", "fuel_mps/p90", "fuel_mps/max")
INT = "docs/intercept.md"
#: miss, fuel mean / p90, steps outside, runs diverged / emptied
FAMILY_CELLS = {
    2: MISS4,
    3: ("fuel_mps/mean", "fuel_mps/p90"),
    4: ("truth_outside",),
    5: ("diverged", "empty_set"),
}


def _fig5(header: str, path: str) -> TableCheck:
    """A ``kvi fig5`` summary table: per variant and noise, miss, fuel and the counts."""
    cells = {2: MISS4, 3: FUEL4, 4: ("truth_outside",), 5: ("empty_set",), 6: ("failures",)}
    return TableCheck(INT, header, path, "variants", {0: "variant", 1: "noise"}, cells)


def _paired_cells(first: int) -> dict[int, tuple[str, ...]]:
    """The cells of a paired-differences table from column ``first`` (its runs) on."""
    cells: dict[int, tuple[str, ...]] = {first: ("miss_m/runs",)}
    for k, m in enumerate(("miss_m", "fuel_mps")):
        col = first + 1 + 3 * k
        cells[col] = (f"{m}/mean", f"{m}/ci/0", f"{m}/ci/1", f"{m}/median")
        cells[col + 1] = (f"{m}/larger_share",)
        cells[col + 2] = (f"{m}/wilcoxon_p",)
    return cells


TABLES: list[TableCheck] = [
    # make run: kvi fig5 --out results/fig5 --json
    _fig5(
        "| variant | noise | miss mean / p50 / p90 / max, m | fuel mean / p50 / p90 / max, m/s "
        "| truth outside | empty set | failures |",
        "docs/results/fig5.json",
    ),
    # kvi fig5 --runs 1000 --workers 2 --json, re-run with the along-sight drift
    _fig5(
        "| variant | noise | 1000 runs: miss mean / p50 / p90 / max, m |",
        "docs/results/study/fig5-w2-1000-drift.json",
    ),
    # its paired variants (the range finder minus bearings only)
    TableCheck(
        INT,
        "| variant | noise | estimator | paired runs |",
        "docs/results/study/fig5-w2-1000-drift.json",
        "paired/rows",
        {0: "variant", 1: "noise", 2: "estimator"},
        _paired_cells(3),
    ),
    # kvi compare kp_fig5 --runs 50 --estimators infoset,ekf,ukf --noise random,bias,game
    TableCheck(
        INT,
        "| estimator | noise | miss mean / p50 / p90 / max, m | fuel mean / p50 / p90 / max, m/s "
        "| steps with truth outside the belief",
        "docs/results/compare_kp_fig5.json",
        "rows",
        {0: "estimator", 1: "noise"},
        {2: MISS4, 3: FUEL4, 4: ("truth_outside",)},
    ),
    # the same command's paired differences against the information set
    TableCheck(
        INT,
        "| estimator | noise | paired runs | miss - infoset: mean [95 % CI] / median, m |",
        "docs/results/compare_kp_fig5.json",
        "paired/rows",
        {0: "estimator", 1: "noise"},
        _paired_cells(2),
    ),
    # kvi compare kp_fig5_kalman_constrained --estimators ekf,ukf --noise random,game --runs 50
    TableCheck(
        INT,
        "| estimator | noise | miss mean / p50 / p90 / max, m | fuel mean, m/s |",
        "docs/results/constrained/compare_kp_fig5_kalman_constrained.json",
        "rows",
        {0: "estimator", 1: "noise"},
        {2: MISS4, 3: ("fuel_mps/mean",), 4: ("truth_outside",)},
    ),
    # kvi compare kp_fig5 --estimators infoset,ellipsoid,zonotope,box,ekf,ukf,hinf,pf
    # --noise random,bias,game,targeted --runs 50
    TableCheck(
        INT,
        "| estimator | noise | miss mean / p50 / p90 / max, m | fuel mean / p90, m/s |",
        "docs/results/families/compare_kp_fig5_families.json",
        "rows",
        {0: "estimator", 1: "noise"},
        FAMILY_CELLS,
    ),
    # the same with --estimators infoset --set 'estimator.infoset.sections="slabs"'
    TableCheck(
        INT,
        "| slab option | noise |",
        "docs/results/families/compare_kp_fig5_slabs.json",
        "rows",
        {1: "noise"},
        FAMILY_CELLS,
    ),
    # kvi adversaries kp_fig5 --runs 10 --estimators infoset,ekf,ukf,hinf,pf
    TableCheck(
        INT,
        "| estimator | rule | miss mean / p50 / p90, m |",
        "docs/results/adversaries/kp_fig5-adversaries.json",
        "rows",
        {0: "estimator", 1: "rule"},
        {
            2: ("miss_m/mean", "miss_m/p50", "miss_m/p90"),
            3: ("fuel_mps/mean", "fuel_mps/p50", "fuel_mps/p90"),
            4: ("truth_outside",),
            5: ("runs_at_seed_fuel",),
        },
    ),
    # kvi adversaries kp_fig3 --runs 1 --estimators infoset,ekf,ukf,hinf,pf
    TableCheck(
        INT,
        "| estimator | game | targeted | lookahead |",
        "docs/results/adversaries/kp_fig3-adversaries.json",
        "rows",
        {0: "estimator"},
        {c: ("miss_m/mean", "fuel_mps/mean", "truth_outside") for c in (1, 2, 3)},
        {1: {"rule": "game"}, 2: {"rule": "targeted"}, 3: {"rule": "lookahead"}},
    ),
    # kvi sweep kp_fig5 --key estimator.infoset.n_nodes --values "[6, 8, 12, 16]"
    # --estimators infoset --noise random,game --runs 50
    TableCheck(
        INT,
        "| n_nodes | estimator | noise |",
        "docs/results/sweeps/kp_fig5-n_nodes.json",
        "rows",
        {0: "value", 1: "estimator", 2: "noise"},
        {3: ("miss_m/mean",), 4: ("fuel_mps/mean",), 5: ("truth_outside",)},
    ),
    # kvi sweep kp_fig5_kalman_inflated --key estimator.ekf.noise_inflation,
    # estimator.ukf.noise_inflation --values "[1, 3, 10, 30]" --estimators ekf,ukf
    # --noise random,game,bias --runs 50
    TableCheck(
        INT,
        "| s | estimator | noise | miss mean, m | fuel mean, m/s |",
        "docs/results/sweeps/kp_fig5_kalman_inflated-noise_inflation.json",
        "rows",
        {0: "value", 1: "estimator", 2: "noise"},
        {3: ("miss_m/mean",), 4: ("fuel_mps/mean",), 5: ("truth_outside",)},
    ),
    # kvi attitude gyrostat_game --noise none,random,game --runs 20 --seed 1 --json
    TableCheck(
        "docs/attitude.md",
        "| noise | disturbance | settle mean / max, s |",
        "docs/results/attitude/gyrostat_game-seed1.json",
        "rows",
        {0: "noise", 1: "disturbance"},
        {
            2: ("settle_time_s/mean", "settle_time_s/max"),
            4: ("max_torque_ratio",),
            5: ("energy_N2m2s/mean",),
            6: ("final_angle_deg/mean",),
        },
    ),
]

#: tables checked row by row by ``test_docs_numbers.CHECKS`` (document, header start)
BY_ROWS = [
    ("README.md", "| paper, figure | quantity | paper | ours |"),
    (INT, "| | miss, m | fuel, m/s | truth outside | empty set |"),
    ("docs/attitude.md", "| quantity | ours | seed |"),
    ("docs/figures.md", "| reading | energy-saving law | Euler-axis baseline (calibrated) |"),
    ("docs/infoset.md", "| scenario (seed) | errors | guidance | 10 s |"),  # and tightness test
    ("docs/infoset.md", "| step, s | errors | miss, m | fuel, m/s |"),
    ("docs/performance.md", "| quantity | measured | target |"),
    ("docs/performance.md", "| variant | noise | CPU-s, 50 runs, 1 worker |"),
    ("docs/performance.md", "| `--set` | noise | miss mean, m |"),
    (INT, "| | miss, m | fuel, m/s | truth outside | pointing error max |"),
]

#: tables a test rebuilds whole from their results files: (document, header start) -> by what
REBUILT = {
    ("docs/performance.md", "| `kvi bench --json` file | date, UTC |"): (
        "docs_bench_table.table(), every docs/results/bench*.json (test_docs_performance)"
    ),
}

#: tables whose numbers are not results: (document, header start) -> what they are
NOT_RESULTS = {
    (INT, "| name | what | per section / state |"): "estimators' settings and citations",
    ("docs/usage.md", "| layer | path | what |"): "module names and settings",
    ("docs/results.md", "| column | unit | meaning |"): "the data dictionary: names, units",
}

#: tables whose numbers no committed results file backs yet: (document, header start)
#: -> the command that would write it (and why it is not here yet)
UNBACKED = {
    (INT, "| reading of the rule | miss, m | fuel, m/s |"): (
        "readings of earlier releases' code (history; the current one is the Fig. 3 table)"
    ),
    (INT, "| estimator | width / exact width at 10-60 s |"): (
        "kvi tightness kp_fig3|kp_fig5 --estimator NAME --noise N --seed 3|5 --json, "
        "32 runs per estimator (ranges over them)"
    ),
}


@pytest.mark.parametrize("check", TABLES, ids=[f"{c.doc}:{c.results}" for c in TABLES])
def test_docs_table_matches_its_results_file(check):
    text = (ROOT / check.doc).read_text(encoding="utf-8")
    assert table_mismatches(text, check, results(check.results)) == []


def _numeric_tables() -> list[tuple[str, str]]:
    """(document, header) of every table printing a number in a row, outside the exempt
    documents."""
    docs = ["README.md"] + sorted(
        f"docs/{p.name}"
        for p in (ROOT / "docs").glob("*.md")
        if p.name not in ("models.md", "references.md")
    )
    return [
        (doc, head)
        for doc in docs
        for head, rows in tables((ROOT / doc).read_text(encoding="utf-8")).items()
        if any(NUMBER.search(" ".join(r)) for r in rows)
    ]


def test_every_table_with_numbers_is_checked_or_listed():
    known = [(c.doc, c.header) for c in TABLES] + BY_ROWS + list(UNBACKED) + list(NOT_RESULTS)
    known += list(REBUILT)
    unknown = [
        (doc, head)
        for doc, head in _numeric_tables()
        if not any(doc == d and head.startswith(h) for d, h in known)
    ]
    assert unknown == []
    stale = [(d, h) for d, h in known if not any(doc == d and head.startswith(h)
                                                 for doc, head in _numeric_tables())]  # fmt: skip
    assert stale == []


def test_a_changed_cell_in_a_copy_of_a_table_fails():
    """Each number of each checked table, bumped in its last digit in a copy of the
    document, is reported; so is a row that names no record."""
    for check in TABLES:
        text = (ROOT / check.doc).read_text(encoding="utf-8")
        data = results(check.results)
        start = text.index(check.header)
        end = text.find("\n\n", start)
        for m in NUMBER.finditer(text, text.index("\n", start), end):
            digit = str((int(m.group()[-1]) + 5) % 10)
            copy = text[: m.end() - 1] + digit + text[m.end() :]
            assert table_mismatches(copy, check, data) != [], (check.doc, m.group())
    fig5 = TABLES[0]
    text = (ROOT / fig5.doc).read_text(encoding="utf-8")
    copy = text.replace("| bearing only | random |", "| bearing only | random (7 runs) |", 1)
    assert table_mismatches(copy, fig5, results(fig5.results)) != []
