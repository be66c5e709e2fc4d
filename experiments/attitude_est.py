"""Attitude loops as consumers of estimators (docs/models.md §2.5): the names and the outputs.

The loops themselves run a registered estimator through
:class:`kalman_vs_infoset.experiments.sim.estimator_loop.EstimatorLoop`; this module draws
the CDF figures (settle time, energy index and final error, one curve per controller x
estimator x noise) of the per-run tables.
"""

from __future__ import annotations

import time
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

PANELS = (
    ("settle_time_s", "settle time, s"),
    ("energy_N2m2s", "energy index sum M^T M dt, N^2 m^2 s"),
    ("final_angle_deg", "final attitude error, deg"),
)


def _never_settled(df: pd.DataFrame, col: str) -> tuple[int, int]:
    """Of the runs a CDF curve is drawn over (finished, with a value of ``col``), those
    whose value is ``+inf`` (never settled), and their number."""
    ok = df[df["status"] == "ok"] if "status" in df else df
    values = ok[col].to_numpy(dtype=float) if col in ok else np.empty(0)
    values = values[~np.isnan(values)]
    return int(np.sum(values == np.inf)), int(values.size)


def write_figure(out_dir: Path, stem: str, df: pd.DataFrame) -> list[str]:
    """CDF figures (PNG, SVG) of the runs' rows, one curve per controller x estimator x
    noise (the tables themselves are the runner's)."""
    from kalman_vs_infoset.experiments import figstyle as fs
    from kalman_vs_infoset.experiments import plots  # matplotlib only when writing files

    fig, grid = fs.figure(1, 3, size=(15, 4.4))
    axes = grid[0]
    groups = list(df.groupby(["controller", "estimator", "noise"], sort=True))
    for ax, (col, label) in zip(axes, PANELS, strict=True):
        for key, grp in groups:
            name = f"{key[0]} / {fs.words(key[1])} / {key[2]}"
            plots.curve(ax, name, grp, col, **fs.line(key[1], key[2]))
        ax.set_xlabel(label)
        ax.set_ylabel(plots.CDF_LABEL)
        ax.set_ylim(0, 1.02)
        # the runs drawn (finished, with a value: failed and diverged runs are not) that
        # never settled (+inf): their curves end below 1, said here
        unsettled, drawn = _never_settled(df, col)
        if col == "settle_time_s" and unsettled:
            why = ("no run settled" if unsettled == drawn else
                   f"{unsettled} of {drawn} runs never settled:\ncurves end below 1")  # fmt: skip
            ax.text(0.02, 0.97, why, transform=ax.transAxes, va="top", fontsize=7)
        vals = df[col].to_numpy(dtype=float)
        vals = vals[np.isfinite(vals)]
        if (
            col == "final_angle_deg"
            and vals.size
            and vals.min() > 0
            and vals.max() > 20 * vals.min()
        ):
            ax.set_xscale("log")
    fs.figure_legend(fig, axes)  # a panel may be empty (no run settled)
    # the scenario and its runs, not the files' stem (estimators, noises, seed run together)
    name = str(df["scenario"].iloc[0]) if "scenario" in df and len(df) else stem
    per = max((len(g) for _, g in groups), default=0)
    seed = f", seed {df['seed'].iloc[0]}" if "seed" in df and len(df) else ""
    fig.suptitle(f"{name}: {per} runs per curve{seed}; curves: controller / estimator / noise "
                 "(colour: estimator, line: noise)")  # fmt: skip
    return [str(f) for f in plots.save(fig, out_dir / f"{stem}-cdf")]


def rows_of(metrics: dict[str, np.ndarray], runs: int) -> list[dict[str, float | int]]:
    """One row per run from a vectorised loop's per-run arrays ``(runs,)`` (other
    entries, e.g. recorded histories, are left out); counts stay integers, as every
    loop's rows hold them."""
    keys = [k for k, v in metrics.items() if np.ndim(v) == 1]
    kind = {k: int if np.issubdtype(np.asarray(metrics[k]).dtype, np.integer) else float
            for k in keys}  # fmt: skip
    return [{k: kind[k](metrics[k][i]) for k in keys} for i in range(runs)]


def run_here(loop, source, scenario, controller, noise, runs, seed, estimator) -> dict[str, Any]:
    """A loop's attitude runs (:class:`experiments.attitude_loops.AttitudeLoop`) in this
    process, without files (tests, notebooks): the same chunks, retries and summary as
    the command (:mod:`experiments.runner`)."""
    from kalman_vs_infoset.experiments.runner import batched_task

    t0 = time.perf_counter()
    setup = loop.prepare(source, dict(scenario), controller, noise)
    simulate = partial(loop.task, setup, controller, noise, estimator)
    pairs = []
    for start in range(0, runs, loop.chunk):
        pairs += batched_task(simulate, seed, list(range(start, min(start + loop.chunk, runs))))
    df = pd.DataFrame([{"run": j, **row} for j, row in pairs])
    ok = df[df["status"] == "ok"]
    failures = int((df["status"] != "ok").sum())
    result = loop.summarise(setup, controller, noise, estimator, runs, seed, ok, failures)
    result["wall_s"] = time.perf_counter() - t0
    return result
