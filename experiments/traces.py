"""Traces: the per-step history of chosen runs, as long-format Parquet in ``_traces/``.

``--trace RUNS`` (``intercept``, ``compare``, ``attitude``) replays the runs ``RUNS`` of
a job with the simulation layer's recorder on (:mod:`experiments.sim.trace`; the option:
:func:`experiments.options.add_trace`): run ``j`` is seeded exactly as in the run table
(:func:`experiments.runner.run_seed`), so its trace is the history of that table row
(recording only observes; the tests check the final fuel and miss against the row). The
runs themselves go through the runner as before; a trace is rewritten whenever it is
asked for.

Files, in ``_traces/`` beside ``<job>.parquet`` (Parquet readers skip the folder):

* ``<job>-trace.parquet``: intercept, one row per (run, step, channel) (the columns of
  :func:`kalman_vs_infoset.experiments.sim.trace.channel_row` plus ``step``, ``t_s``, ``channel``,
  ``impulse_mps``, ``fuel_mps``, ``checked``, and the run's ``miss_m`` and
  ``final_fuel_mps``); attitude, one row per (run, step, axis)
  (the per-axis quantities, with the per-step ones repeated on the three axis rows);
  both with the job's ``scenario``, ``estimator``, ``noise``, ``seed`` and ``run``;
* ``<job>-trace-sets.parquet`` (intercept, polygon sets only): one row per vertex of
  every section, before (``phase = "prior"``, first steps) and after the measurements.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.files import atomic_write
from kalman_vs_infoset.experiments.results import TRACE_DIR
from kalman_vs_infoset.experiments.sim.intercept import run_engagement
from kalman_vs_infoset.experiments.sim.trace import Recorder


def check_runs(traced: list[int] | None, runs: int) -> list[int]:
    """The traced runs, each below ``runs`` (InputError otherwise)."""
    traced = traced or []
    bad = [j for j in traced if j >= runs]
    if bad:
        raise InputError(f"--trace {bad[0]}: there are only runs 0..{runs - 1} (--runs {runs})")
    return traced


def traceable(traced: list[int], df: pd.DataFrame, what: str) -> list[int]:
    """The traced runs that finished (a failed run is replayed by no trace: its error is
    in the run table and on stderr already)."""
    ok = set(df.loc[df["status"] == "ok", "run"].astype(int)) if len(df) else set()
    skipped = [j for j in traced if j not in ok]
    if skipped:
        print(f"{what}: no trace of the failed runs {skipped}", file=sys.stderr)
    return [j for j in traced if j in ok]


def trace_paths(results: Path) -> tuple[Path, Path]:
    """``(<stem>-trace.parquet, <stem>-trace-sets.parquet)`` of a results table, in the
    ``_traces`` subfolder of its folder (so that the folder reads as one table)."""
    stem = results.name.removesuffix(".parquet")
    folder = results.parent / TRACE_DIR
    return folder / f"{stem}-trace.parquet", folder / f"{stem}-trace-sets.parquet"


def write_parquet(df: pd.DataFrame, path: Path) -> Path:
    atomic_write(path, lambda tmp: df.to_parquet(tmp, index=False))
    return path


# -- intercept ------------------------------------------------------------------------
def intercept_trace(sc, estimator: str, noise: str, seed: int, runs: list[int], sets_every=10):
    """Replay ``runs`` of a job with the recorder on: ``(steps, sets)`` DataFrames and
    the replayed results by run (for checks)."""
    from kalman_vs_infoset.experiments.runner import run_seed

    frames, set_frames, results = [], [], {}
    base = {"scenario": sc.name, "estimator": estimator, "noise": noise, "seed": seed}
    for j in runs:
        rec = Recorder(sets_every=sets_every)
        rng = np.random.default_rng(run_seed(seed, j))
        res = results[j] = run_engagement(sc, estimator, noise, rng, rec)
        final = {"miss_m": res.miss_m, "final_fuel_mps": res.fuel_mps}  # the run's outcome
        frames.append(pd.DataFrame(rec.rows).assign(**base, run=j, **final))
        for snap in rec.sets:
            n = len(snap["x_m"])
            cols = {
                k: (v if isinstance(v, np.ndarray) else np.repeat(v, n)) for k, v in snap.items()
            }
            set_frames.append(pd.DataFrame(cols).assign(**base, run=j))
    steps = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    sets = pd.concat(set_frames, ignore_index=True) if set_frames else pd.DataFrame()
    return steps, sets, results


def write_intercept_trace(sc, estimator, noise, seed, runs, results_path: Path) -> list[Path]:
    """Write the trace files of ``runs`` beside ``results_path``; returns their paths."""
    steps, sets, _ = intercept_trace(sc, estimator, noise, seed, runs)
    path, sets_path = trace_paths(results_path)
    out = [write_parquet(steps, path)]
    if len(sets):
        out.append(write_parquet(sets, sets_path))
    elif sets_path.exists():
        sets_path.unlink()  # a stale picture of another estimator's sets
    return out


# -- attitude -------------------------------------------------------------------------
def long_rows(
    time_s: np.ndarray,
    per_axis: dict[str, np.ndarray],
    per_step: dict[str, np.ndarray] | None = None,
    **const: Any,
) -> pd.DataFrame:
    """One row per (step, axis) from ``(n, 3)`` per-axis and ``(n,)`` per-step arrays
    (shorter arrays, e.g. torques held over ``n - 1`` steps, are padded with NaN)."""
    n = len(time_s)

    def pad(a: np.ndarray) -> np.ndarray:
        a = np.asarray(a, dtype=float)
        if len(a) >= n:
            return a[:n]
        fill = np.full((n - len(a), *a.shape[1:]), np.nan)
        return np.concatenate([a, fill])

    cols: dict[str, Any] = {
        "step": np.repeat(np.arange(n), 3),
        "t_s": np.repeat(np.asarray(time_s, dtype=float), 3),
        "axis": np.tile(np.arange(1, 4), n),
    }
    for name, arr in per_axis.items():
        cols[name] = pad(arr).reshape(-1)
    for name, arr in (per_step or {}).items():
        a = np.asarray(arr)
        cols[name] = np.repeat(a if a.dtype == bool and len(a) == n else pad(a), 3)
    df = pd.DataFrame(cols)
    for k, v in const.items():
        df[k] = v
    return df
