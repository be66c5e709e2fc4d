"""The summary statistics every command reports: mean / p50 / p90 / max."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

KEYS = ("mean", "p50", "p90", "max")


def summary_stats(values: Iterable[float], finite_only: bool = True) -> dict[str, float]:
    """mean / p50 / p90 / max of ``values`` (NaN when there are none; JSON prints null).

    ``finite_only=False`` keeps infinities (e.g. runs that never settled), so that a
    statistic they enter becomes ``inf`` (also printed as null) instead of silently
    leaving them out.
    """
    v = np.asarray(list(values) if not isinstance(values, np.ndarray) else values, dtype=float)
    v = v.ravel()
    if finite_only:
        v = v[np.isfinite(v)]
    if v.size == 0:
        return dict.fromkeys(KEYS, float("nan"))
    with np.errstate(invalid="ignore"):
        return {
            "mean": float(np.mean(v)),
            "p50": float(np.percentile(v, 50)),
            "p90": float(np.percentile(v, 90)),
            "max": float(np.max(v)),
        }


def ok_mean(table, column: str) -> float | None:
    """Mean of ``column`` over a results table's successful runs (finite values), or
    None when no run succeeded (a failed run's row has no such column)."""
    ok = table[table["status"] == "ok"] if "status" in table else table
    if column not in ok:
        return None
    values = ok[column].astype(float)
    values = values[np.isfinite(values)]
    return float(values.mean()) if len(values) else None  # pandas' mean, as before
