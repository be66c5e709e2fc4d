"""The summary statistics every command reports: mean / p50 / p90 / max."""

from __future__ import annotations

from collections.abc import Iterable
from fractions import Fraction
from typing import Any

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
            "p50": percentile(v, 50.0),
            "p90": percentile(v, 90.0),
            "max": float(np.max(v)),
        }


def percentile(values: np.ndarray, q: float) -> float:
    """The ``q``-th percentile by numpy's default (linear) rule, exact with infinities.

    The rule is ``x[lo] + t (x[hi] - x[lo])`` at the position ``h = (n - 1) q / 100``
    of the sorted samples, ``lo``, ``hi`` its neighbours and ``t = h - lo``. numpy
    evaluates it in a form that reads NaN as soon as a neighbour is infinite
    (``inf - inf`` or ``0 * inf``): its p50 of ``[1, 2, inf]`` is NaN where the rule
    gives 2. Finite samples keep numpy's value to the last digit. With infinite ones
    the position is taken exactly (a rational: rounding must not make a neighbour of
    an exact hit), an exact hit is that sample, and between a finite and an infinite
    sample the rule gives the infinite one. A NaN sample has no place in the order:
    the percentile is NaN (sorted last, it read as a large value: p50 of ``[1, NaN, 3]``
    was 3).
    """
    x = np.asarray(values, dtype=float).ravel()
    if np.all(np.isfinite(x)):
        return float(np.percentile(x, q))
    if np.isnan(x).any():
        return float("nan")
    x = np.sort(x)  # numpy sorts its own copy; only this path needs the order
    h = Fraction(q) * (x.size - 1) / 100
    lo = int(h)  # h >= 0
    a, b = x[lo], x[min(lo + 1, x.size - 1)]
    t = h - lo
    if t == 0 or a == b:
        return float(a)
    if np.isfinite(a) and np.isfinite(b):
        return float(a + float(t) * (b - a))
    if np.isfinite(a) or np.isfinite(b):
        return float(b if np.isfinite(a) else a)
    return float("nan")  # -inf and +inf


def not_settled(settle_s: Iterable[float]) -> int:
    """The runs that never settled (settle time inf), as every attitude summary counts
    them."""
    return int(np.sum(~np.isfinite(np.asarray(list(settle_s), dtype=float))))


def ok_mean(table, column: str) -> float | None:
    """Mean of ``column`` over a results table's successful runs (finite values), or
    None when no run succeeded (a failed run's row has no such column)."""
    ok = table[table["status"] == "ok"] if "status" in table else table
    if column not in ok:
        return None
    values = ok[column].astype(float)
    values = values[np.isfinite(values)]
    return float(values.mean()) if len(values) else None  # pandas' mean, as before


def estimator_counts(ok) -> dict[str, Any]:
    """What every attitude summary says of the estimator over the runs ``ok`` (a results
    table): steps with the truth outside, updates the data contradicted, predictions
    that were the whole space (each summed over the runs), and the statistics of the
    runs' mean knowledge bound (deg). A column the table lacks counts as none."""

    def total(key: str) -> int:
        return int(np.sum(ok[key].to_numpy(dtype=float))) if key in ok else 0

    bounds = ok["mean_knowledge_bound_deg"] if "mean_knowledge_bound_deg" in ok else []
    bounds = np.asarray(bounds, dtype=float)
    return {
        "truth_outside": total("truth_outside"),
        "empty_steps": total("empty_steps"),
        "unbounded_steps": total("unbounded_steps"),
        # a run whose set was the whole space on some step has an infinite mean bound:
        # it enters the statistics (as a run that never settled does), not left out
        "mean_knowledge_bound_deg": summary_stats(bounds[~np.isnan(bounds)], finite_only=False),
    }
