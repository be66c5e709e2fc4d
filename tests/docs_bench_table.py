"""docs/performance.md's table of every kept ``kvi bench --json`` reading, built from the
files themselves (``docs/results/bench*.json``), oldest first, with the goals beside.

``test_docs_performance.py`` checks that the page prints exactly this table and the
ranges under it, so a new reading cannot be left out. After keeping a new reading, print
the table to paste (in a clone: ``.venv/bin/python tests/docs_bench_table.py``).
"""

from __future__ import annotations

from pathlib import Path

from docs_numbers import ROOT, results

HEADER = (
    "| `kvi bench --json` file | date, UTC | load | UKF / set step, us "
    "| Fig. 3 engagement, game / random, UKF steps | whole approach, UKF steps "
    "| cost exponent | runs per CPU-s, 1 / 2 workers | `--help`, CPU-s | compiling, CPU-s |"
)
#: the issue's goals, in the columns' units (the Monte Carlo's is against a release)
GOALS = (
    "| goal | | | | <= 60 / 40 | <= 0.5 | <= 1.2 | 5x release 35e3739 | <= 0.5 | once per install |"
)


def readings() -> list[tuple[str, dict]]:
    """Every kept reading, ``(file name, contents)``, by the date it was measured."""
    paths = sorted((ROOT / "docs/results").glob("bench*.json"))
    rows = [(p.name, results(str(p.relative_to(ROOT)))) for p in paths]
    return sorted(rows, key=lambda row: (row[1]["machine"]["date"], row[0]))


def _row(name: str, r: dict) -> str:
    m = r["machine"]
    cells = (
        f"`{name}`",
        m["date"].removesuffix(" UTC"),
        f"{m['load_average']:.2f}",
        f"{r['step_us']['ukf']:.0f} / {r['step_us']['infoset']:.0f}",
        f"{r['engagement_in_ukf_steps']:.0f} / {r['engagement_random_in_ukf_steps']:.0f}",
        f"{r['whole_approach_ratio']:.2f}",
        f"{r['cost_exponent']:.2f}",
        f"{r['runs_per_cpu_s']['1']:.2f} / {r['runs_per_cpu_s']['2']:.2f}",
        f"{r['help_cpu_s_max']:.2f}",
        f"{r['first_run_compile_s']:.1f}",
    )
    return "| " + " | ".join(cells) + " |"


def table() -> str:
    """The markdown table: header, one row a reading, the goals' row."""
    sep = "|" + "---|" * HEADER.count(" | ") + "---|"
    return "\n".join([HEADER, sep, *(_row(n, r) for n, r in readings()), GOALS])


def ranges() -> dict[str, tuple[float, float]]:
    """Least and largest of each goal's quantity over the readings."""
    rs = [r for _, r in readings()]
    series = {
        "game": [r["engagement_in_ukf_steps"] for r in rs],
        "random": [r["engagement_random_in_ukf_steps"] for r in rs],
        "whole": [r["whole_approach_ratio"] for r in rs],
        "exponent": [r["cost_exponent"] for r in rs],
        "help": [r["help_cpu_s_max"] for r in rs],
    }
    return {k: (min(v), max(v)) for k, v in series.items()}


if __name__ == "__main__":
    print(table())
    print(f"({len(readings())} readings; {Path(__file__).name})")
