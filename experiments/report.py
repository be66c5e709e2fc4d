"""Tables of experiment summaries (markdown) and the per-run table files."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pandas as pd
from kalman_vs_infoset.experiments.errors import stats_text
from kalman_vs_infoset.experiments.files import derived_write
from kalman_vs_infoset.experiments.stats import KEYS


def summary_markdown(rows: Sequence[dict[str, Any]], label_keys: Sequence[str]) -> str:
    """A markdown table with one line per summary object (docs/models.md §3.1 intercept JSON)."""
    head = [
        *label_keys,
        "runs",
        "miss mean / p50 / p90 / max, m",
        "fuel mean / p50 / p90 / max, m/s",
    ]
    head += ["truth outside (steps)", "empty set (runs)", "diverged (runs)", "failures"]
    # with an attitude loop holding the axis: where the sets' premise failed (steps
    # outside are read against it)
    premise = any("pointing_premise_failed_steps" in r for r in rows)
    head += ["pointing premise failed (bearings)"] if premise else []
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        m, f = r["miss_m"], r["fuel_mps"]
        cells = [str(r[k]) for k in label_keys] + [str(r["runs"])]
        # "-" where no run gave a value (every run failed), as the attitude tables say
        cells += [stats_text(m, ".2f", KEYS), stats_text(f, ".1f", KEYS)]
        cells += [str(r["truth_outside"]), str(r["empty_set"]), str(r.get("diverged", 0))]
        cells.append(str(r["failures"]))
        cells += [str(r.get("pointing_premise_failed_steps", "-"))] if premise else []
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def write_tables(df: pd.DataFrame, stem: Path) -> list[Path]:
    """A command's combined table (every run of its estimators, noises or variants, one
    row each) as Parquet and CSV, atomically. The Parquet file is marked as combined
    (:data:`~kalman_vs_infoset.experiments.results.COMBINED_KEY`), so that
    ``load_results`` of the folder reads the runs' own tables and not both."""
    from kalman_vs_infoset.experiments.results import write_table

    # appended, not with_suffix: names may hold dots (--set suffixes, "fig5.v2")
    pq, csv = (stem.parent / f"{stem.name}.{ext}" for ext in ("parquet", "csv"))
    write_table(pq, df, None, combined=True)
    derived_write(csv, lambda tmp: df.to_csv(tmp, index=False))
    return [pq, csv]


def write_text(path: Path, text: str) -> Path:
    derived_write(path, lambda tmp: Path(tmp).write_text(text))
    return path
