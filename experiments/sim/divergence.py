"""Runs whose closed loop diverged, as every attitude loop's rows report them.

A loop that leaves what its fixed-step integration resolves raises
:class:`kalman_vs_infoset.guidance.attitude.plant.LoopDiverged`. Simulated alone, such a
run ends there and is a finished run with ``diverged = 1``: the time it diverged
(``diverged_time_s``), the estimator's counts over the steps before (truth outside,
empty and unbounded steps, the mean knowledge bound) and no value (NaN) for what
measures the turn's end (settle time, energy, final errors, peak torques), which it
never reached. Simulated in a batch, it raises, and the runner simulates each run of
the batch alone (:func:`kalman_vs_infoset.experiments.runner.batched_task`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np


def diverged_rows(
    metrics: Mapping[str, np.ndarray], diverged_time_s: np.ndarray, performance: Iterable[str]
) -> dict[str, np.ndarray]:
    """Per-run metrics with the runs that diverged marked.

    Parameters
    ----------
    metrics : mapping of str to ndarray (runs,)
        The loop's per-run values (a diverged run's may be anything).
    diverged_time_s : ndarray (runs,)
        When each run diverged, inf for the runs that did not (as a settle time: never).
    performance : iterable of str
        The keys that measure the turn's end: NaN for a diverged run.
    """
    when = np.asarray(diverged_time_s, dtype=float)
    hit = np.isfinite(when)
    out = dict(metrics)
    for key in performance:
        out[key] = np.where(hit, np.nan, np.asarray(out[key], dtype=float))
    out["diverged"] = hit.astype(int)
    out["diverged_time_s"] = when
    return out


def resolved(ok):
    """The rows of a results table whose loop did not diverge (a table written before
    the column existed: every row)."""
    return ok[ok["diverged"] == 0] if "diverged" in ok else ok


def diverged_runs(ok) -> int:
    """The runs of a results table whose loop diverged."""
    return int(np.sum(ok["diverged"].to_numpy(dtype=float))) if "diverged" in ok else 0
