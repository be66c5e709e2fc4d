"""Paired differences between estimators (or variants, or swept values) run on the same
truths: ``kvi compare``, ``attitude``, ``fig5`` and ``sweep``.

Run ``j`` of every (estimator, noise) row of a comparison starts from the same truth and
seed (:func:`~kalman_vs_infoset.experiments.runner.run_seed`): random errors come from
the same stream, while an adversary (the game) chooses them against each engagement as
it unfolds. So estimators are compared run by run: for a metric ``x`` (miss, fuel), the
difference

.. math:: d_j = x_j(\\text{estimator}) - x_j(\\text{reference})

over the runs both finished. Reported per estimator x noise: the mean of ``d`` with
Student's t confidence interval :math:`\\bar d \\pm t_{n-1,(1+c)/2}\\, s_d / \\sqrt{n}`
(from ``scipy.stats.ttest_1samp``), the median of ``d``, the share of runs where the
estimator's value is the larger, and the two-sided p-value of Wilcoxon's signed-rank
test (distribution-free; :func:`signed_rank_p`): zero differences are dropped, tied
ones share their mean rank, and up to :data:`EXACT_MAX` nonzero differences the
p-value is exact (the share of the ``2^n`` equally likely sign patterns whose rank sum
is at least as far from its mean), above that the normal approximation with the tie
correction (``scipy.stats.wilcoxon``). Differences within :data:`TIE_RTOL` of the
largest are one value: settle times on a control grid differ by exactly equal steps
that the subtraction rounds apart.
Heavy tails (a filter that loses the target in a few runs) widen the t interval; the
median, the share and the signed-rank test do not depend on them. Runs that all repeat
one engagement (the same values on both sides for every metric: a fixed truth under a
deterministic adversary) are one pair, not ``n`` independent ones (``distinct_runs``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments.errors import stat_text

#: per problem, the metrics compared: (column of the per-run table, printed name, unit,
#: format of the printed values)
COLUMNS = {
    "intercept": (("miss_m", "miss", "m", ".2f"), ("fuel_mps", "fuel", "m/s", ".1f")),
    "attitude": (
        ("settle_time_s", "settle time", "s", ".2f"),
        ("energy_N2m2s", "energy", "N^2 m^2 s", ".4g"),
        ("final_angle_deg", "final angle", "deg", ".3g"),
    ),
}
#: the intercept's metrics (``kvi compare``)
METRICS = tuple(c[0] for c in COLUMNS["intercept"])
#: the confidence level of the mean difference's interval
CONFIDENCE = 0.95
#: what identifies a run across the rows of one comparison
RUN_KEYS = ("noise", "seed", "run")


#: differences closer than this share of the largest |difference| are tied (and zero)
TIE_RTOL = 1e-9
#: up to this many nonzero differences the signed-rank p-value is exact
EXACT_MAX = 50


def signed_rank_p(d: np.ndarray) -> float | None:
    """Two-sided p-value of Wilcoxon's signed-rank test of the differences ``d``.

    With the ``n`` nonzero differences ranked by magnitude (ties: mean ranks) and
    ``T+`` the sum of the positive ones' ranks, under the null hypothesis every sign
    pattern is equally likely; the p-value is the share of the ``2^n`` patterns with
    ``|T+ - E T+| >= |t+ - E T+|``, counted exactly on doubled (integer) ranks for
    ``n <= EXACT_MAX`` (Hollander, Wolfe & Chicken, *Nonparametric Statistical
    Methods*, 3rd ed., 2014, sec. 3.1, conditional on the ties), else the normal
    approximation with the tie correction (scipy). ``None`` when every difference is
    zero (within :data:`TIE_RTOL`).
    """
    from scipy import stats  # here: kvi --help stays light

    d = np.asarray(d, dtype=float)
    scale = float(np.max(np.abs(d), initial=0.0))
    if not scale > 0:
        return None
    # integers: rounding-level gaps are ties (d / scale first: TIE_RTOL * scale
    # underflows to 0 for subnormal differences, found by `make fuzz`)
    k = np.round(d / scale / TIE_RTOL)
    k = k[k != 0]
    n = k.size
    if n > EXACT_MAX:
        return float(stats.wilcoxon(k, method="approx").pvalue)
    ranks2 = np.rint(2.0 * stats.rankdata(np.abs(k))).astype(np.int64)  # mean ranks x 2
    total = int(ranks2.sum())
    counts = np.zeros(total + 1)  # patterns by T+ (x2); exact in float64 up to 2^53
    counts[0] = 1.0
    for r in ranks2:
        counts[r:] = counts[r:] + counts[: total + 1 - r]
    t_obs = int(ranks2[k > 0].sum())
    far = np.abs(2 * np.arange(total + 1) - total) >= abs(2 * t_obs - total)
    return float(min(1.0, counts[far].sum() / 2.0**n))


def paired_stats(d: np.ndarray, confidence: float = CONFIDENCE) -> dict[str, Any]:
    """Summary of the paired differences ``d`` (module docstring); ``None`` where a
    statistic is undefined (no runs; one run has no interval; all differences zero give
    no signed-rank test)."""
    from scipy import stats  # here: kvi --help stays light

    d = np.asarray(d, dtype=float)
    n = int(d.size)
    out: dict[str, Any] = {"mean": None, "ci": None, "median": None, "larger_share": None,
                           "wilcoxon_p": None}  # fmt: skip
    if n == 0:
        return out
    out["mean"] = float(np.mean(d))
    out["median"] = float(np.median(d))
    out["larger_share"] = float(np.count_nonzero(d > 0.0) / n)
    if n >= 2:
        if np.all(d == d[0]):  # no spread: the interval is the point
            out["ci"] = [float(d[0]), float(d[0])]
        else:
            ci = stats.ttest_1samp(d, 0.0).confidence_interval(confidence)
            out["ci"] = [float(ci.low), float(ci.high)]
    out["wilcoxon_p"] = signed_rank_p(d)
    return out


def paired_rows(
    table: pd.DataFrame,
    reference: str,
    metrics: Sequence[str] = METRICS,
    confidence: float = CONFIDENCE,
    by: str = "estimator",
) -> list[dict[str, Any]]:
    """Per value of the column ``by`` (the estimator; ``kvi fig5``: the variant) other
    than ``reference``, and per noise, the paired differences of each metric against
    ``reference`` over the runs both finished (status ``ok``, finite values), matched by
    noise, seed and run index."""
    ok = table[table["status"] == "ok"] if "status" in table else table
    keys = list(RUN_KEYS)
    ref = ok[ok[by] == reference].set_index(keys)
    rows = []
    for (value, noise), part in ok.groupby([by, "noise"], sort=False):
        if value == reference:
            continue
        mine = part.set_index(keys)
        both = mine.index.intersection(ref.index)
        row: dict[str, Any] = {by: value, "noise": noise}
        pairs = {m: (mine.loc[both, m].to_numpy(dtype=float),
                     ref.loc[both, m].to_numpy(dtype=float)) for m in metrics}  # fmt: skip
        # runs that repeat one engagement (a fixed truth and a deterministic adversary)
        # are one observation, not n independent ones: no interval, no test from them
        one = _replicas(pairs.values())
        for m, (a, b) in pairs.items():
            finite = np.isfinite(a) & np.isfinite(b)
            d = a[finite] - b[finite]
            distinct = min(len(d), 1) if one else len(d)
            row[m] = {"runs": int(finite.sum()), "distinct_runs": distinct,
                      **paired_stats(d[:distinct], confidence)}  # fmt: skip
        rows.append(row)
    return rows


def _replicas(pairs) -> bool:
    """Whether every paired run (two or more) gives the same values as the first, on
    both sides and for every metric: the runs repeat one engagement."""
    pairs = list(pairs)
    if not pairs or len(pairs[0][0]) < 2:
        return False
    return all(np.array_equal(x, np.full_like(x, x[0]), equal_nan=True)
               for a, b in pairs for x in (a, b))  # fmt: skip


def reference_of(problem: str, estimators: Sequence[str]) -> str:
    """The estimator the others are paired against: the registry's reference for the
    problem (the information set; the guaranteed box for attitude) when it is among
    ``estimators``, else the first named."""
    from kalman_vs_infoset.estim import registry

    ref = registry.reference(problem).name
    return ref if ref in estimators else estimators[0]


def comparison(table: pd.DataFrame, estimators: Sequence[str], problem: str) -> dict | None:
    """The ``paired`` object of a command's JSON: ``reference``, ``confidence``,
    ``metrics`` and ``rows`` (:func:`paired_rows`); ``None`` with one estimator."""
    if len(set(estimators)) < 2:
        return None
    ref = reference_of(problem, estimators)
    # (a loop without one of the problem's metrics has no column for it)
    metrics = [c[0] for c in COLUMNS[problem] if c[0] in table.columns]
    return {"reference": ref, "confidence": CONFIDENCE, "metrics": metrics,
            "rows": paired_rows(table, ref, metrics)}  # fmt: skip


def along(table: pd.DataFrame, column: str, reference: str) -> dict[str, Any]:
    """The ``paired`` object of a command whose rows share truths and seeds along
    ``column`` (``kvi fig5``: the variant; ``kvi sweep``: the swept value): each value
    minus ``reference``, per estimator and noise, on the intercept's metrics."""
    rows = []
    for estimator, part in table.groupby("estimator", sort=False):
        rows += [{**r, "estimator": estimator}
                 for r in paired_rows(part, reference, METRICS, by=column)]  # fmt: skip
    return {"reference": reference, "by": column, "confidence": CONFIDENCE,
            "metrics": list(METRICS), "rows": rows}  # fmt: skip


def variants(table: pd.DataFrame, reference: str) -> dict[str, Any]:
    """``kvi fig5``'s ``paired`` object: each variant minus ``reference`` (bearings
    only; :func:`along`)."""
    return along(table, "variant", reference)


def title(paired: dict[str, Any]) -> str:
    """The line above :func:`paired_markdown`'s table."""
    what = paired.get("by", "estimator")
    return (
        f"Paired by run, each {what} minus {paired['reference']} over the runs both "
        f"finished (run j: the same initial state and seed for every {what}):"
    )


def section(paired: dict[str, Any] | None, problem: str = "intercept") -> str:
    """The paired differences as a command prints them after its summary: a blank line,
    :func:`title`, the table (:func:`paired_markdown`); nothing when there is no pair."""
    if paired is None or not paired["rows"]:
        return ""
    return "\n" + title(paired) + "\n\n" + paired_markdown(paired, problem)


def paired_markdown(paired: dict[str, Any], problem: str = "intercept") -> str:
    """The paired differences as a markdown table (:func:`comparison`); the paired runs
    of each metric, once when they agree."""
    ref, level = paired["reference"], round(100 * paired["confidence"])
    columns = tuple(c for c in COLUMNS[problem] if c[0] in paired["metrics"])
    labels = [paired.get("by", "estimator"), "noise"]
    if "by" in paired:  # kvi fig5: the estimator too
        labels.append("estimator")
    head = [*labels, "paired runs"]
    for _, name, unit, _ in columns:
        head += [f"{name} - {ref}: mean [{level} % CI] / median, {unit}",
                 f"share of larger {name}", "Wilcoxon p"]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]

    for r in paired["rows"]:
        runs = [_runs_text(r[c[0]]) for c in columns]
        cells = [str(r[k]) for k in labels]
        cells.append(runs[0] if len(set(runs)) == 1 else " / ".join(runs))
        for m, _, _, fmt in columns:
            s = r[m]
            # "-" for a statistic no run gave (None, or NaN), as the summaries print it
            ci = "-" if s["ci"] is None else ", ".join(stat_text(v, fmt) for v in s["ci"])
            cells.append(f"{stat_text(s['mean'], fmt)} [{ci}] / {stat_text(s['median'], fmt)}")
            cells += [stat_text(s["larger_share"], ".2f"), stat_text(s["wilcoxon_p"], ".2g")]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _runs_text(metric: dict[str, Any]) -> str:
    """A metric's paired runs, and how many of them are distinct when they repeat one
    engagement (``4 (one engagement)``)."""
    runs, distinct = metric["runs"], metric.get("distinct_runs", metric["runs"])
    return str(runs) if distinct == runs else f"{runs} (one engagement)"
