"""The intercept's runs on the generic runner (:mod:`experiments.runner`).

The runner knows no problem: this module makes the intercept's :class:`Job` (one run a
task, :func:`timed_engagement`), names its results files, summarises its tables
(docs/models.md §3.1) and runs a grid of estimators x noises on the same seeds, the
experiment behind ``kvi intercept``, ``compare``, ``sweep``, ``adversaries`` and ``fig5``.
A run that takes long shows its steps (:func:`experiments.progress.step_progress`).
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from concurrent.futures import Executor
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments import usage
from kalman_vs_infoset.experiments.errors import built_or_refused
from kalman_vs_infoset.experiments.limits import RunLimits, reraise_timeout
from kalman_vs_infoset.experiments.options import run_limits
from kalman_vs_infoset.experiments.progress import step_progress
from kalman_vs_infoset.experiments.runner import Job, check_seed, run_job, run_seed
from kalman_vs_infoset.experiments.scenario import estimator_option
from kalman_vs_infoset.experiments.sim.estimator_tables import tables_kept
from kalman_vs_infoset.experiments.sim.intercept import (
    Engagement,
    EngagementResult,
    build_estimator,
    estimators_read,
)
from kalman_vs_infoset.experiments.sim.intercept_config import InterceptScenario
from kalman_vs_infoset.experiments.stats import summary_stats


def results_path(out_dir: Path, sc: InterceptScenario, estimator: str, noise: str, seed: int):
    """The results table of one estimator x noise (the runner's :func:`job_path`)."""
    return Path(out_dir) / f"{sc.name}-{estimator}-{noise}-s{seed}.parquet"


def intercept_job(
    sc: InterceptScenario, estimator: str, noise: str, seed: int, chunk: int = 1
) -> Job:
    """The runs of an intercept scenario with one estimator and one noise, ``chunk``
    runs a task (1 by default: ``kvi bench`` measures 1 against several runs a task,
    ``runs_per_cpu_s_by_chunk``, and several did not pay; docs/performance.md)."""
    choice = {"estimator": estimator, "noise": noise}
    read = estimators_read(estimator, noise)
    return Job(
        name=sc.name,
        label=f"{estimator}-{noise}",
        seed=seed,
        meta={"scenario": sc.model_dump(mode="json"), **choice, "seed": seed},
        base={"scenario": sc.name, **choice, "seed": seed},
        task=partial(_intercept_chunk, sc, estimator, noise, seed),
        chunk=chunk,
        problem="intercept",
        # another estimator's options table decides none of these runs, nor its code
        decides=partial(tables_kept, "intercept", ("estimator", "options"), read),
        reads=read - {estimator},
        text=frozenset({"final_status"}),
    )


def _intercept_chunk(sc, estimator: str, noise: str, seed: int, runs: list[int]):
    # looked up at call time: tests replace it
    return [(j, timed_engagement(sc, estimator, noise, run_seed(seed, j))) for j in runs]


def run_engagement(
    sc: InterceptScenario, estimator: str, noise: str, rng: np.random.Generator
) -> EngagementResult:
    """One engagement (the loop of :func:`experiments.sim.intercept.run_engagement`),
    its steps shown when it takes long."""
    eng = Engagement(sc, estimator, noise, rng)
    key = getattr(rng.bit_generator.seed_seq, "spawn_key", ())
    run = f" run {key[-1]}" if key else ""  # the runner's run index
    with step_progress(eng.max_steps, f"{sc.name} {estimator}-{noise}{run}") as shown:
        while eng.step():
            shown(eng.step_index)
    return eng.finish()


def timed_engagement(sc, estimator_name, noise_name, seed_seq) -> dict[str, Any]:
    """Run one engagement from a ``SeedSequence``; returns a result row (never raises,
    but for ``MemoryError``: a resource, not the run, which the runner reports)."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed_seq)
    try:
        res = run_engagement(sc, estimator_name, noise_name, rng).as_row()
        res.update(status="ok", error="")
    except MemoryError:
        raise
    except Exception as exc:  # a failing run is recorded, not fatal
        reraise_timeout(exc)  # but a CPU limit's timeout is the limit's to report
        res = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
    res["wall_s"] = time.perf_counter() - t0
    return res


def run_experiment(
    sc: InterceptScenario,
    estimator: str,
    noise: str,
    runs: int,
    seed: int,
    out_dir: Path,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    executor: Executor | None = None,
    limits: RunLimits | None = None,
    chunk: int = 1,
    rerun_other_code: bool = False,
) -> pd.DataFrame:
    """Run (or complete) an intercept experiment and return its per-run table
    (``chunk``: runs a task, :func:`intercept_job`; the table does not depend on it;
    ``rerun_other_code``: :func:`experiments.runner.run_job`)."""
    job = intercept_job(sc, estimator, noise, check_seed(seed), chunk)
    return run_job(job, runs, out_dir, workers, scheduler, progress, executor, limits,
                   rerun_other_code)  # fmt: skip


def summarise(df: pd.DataFrame, sc: InterceptScenario, estimator, noise, seed, wall_s) -> dict:
    """The intercept JSON object of docs/models.md §3.1 for one estimator x noise."""
    ok = df[df["status"] == "ok"] if "status" in df else df.iloc[0:0]
    return {
        "scenario": sc.name,
        "estimator": estimator,
        "noise": noise,
        "runs": int(len(df)),
        "seed": int(seed),
        # every finished run enters, a value that is not finite too (it would be a fault
        # to see in the statistics, not one to drop from them)
        "miss_m": summary_stats(_values(ok, "miss_m"), finite_only=False),
        "fuel_mps": summary_stats(_values(ok, "fuel_mps"), finite_only=False),
        "truth_outside": int(ok["truth_outside"].sum()) if len(ok) else 0,
        "empty_set": int((ok["contradictions"] > 0).sum()) if len(ok) else 0,
        # beliefs reported Status.DIVERGED: emptied, so guidance stopped early
        "diverged": int(ok["diverged"].sum()) if len(ok) else 0,
        # steps the law had no bounded forecast to centre (no impulse)
        "unbounded_steps": int(ok["unbounded_steps"].sum()) if "unbounded_steps" in ok else 0,
        "failures": int((df["status"] != "ok").sum()) if "status" in df else 0,
        "wall_s": float(wall_s),
        **_pointing_premise(ok),
    }


def _pointing_premise(ok: pd.DataFrame) -> dict[str, int]:
    """With an attitude loop holding the axis (``[attitude]``): the bearings at which
    the sets' premise failed (the true pointing residual over the knowledge bound they
    took: their guarantee does not hold there, so steps outside are no fault of theirs)
    and at which the loop's bound grew past it (the premise no longer guaranteed),
    summed over the runs; nothing without the loop."""
    cols = {"pointing_premise_failed_steps": "pointing_residual_over_bound_steps",
            "pointing_bound_exceeded_steps": "pointing_bound_exceeded_steps"}  # fmt: skip
    if cols["pointing_premise_failed_steps"] not in ok:
        return {}
    return {key: int(ok[col].sum()) for key, col in cols.items()}


def _values(ok: pd.DataFrame, column: str) -> np.ndarray:
    return ok[column].to_numpy(dtype=float) if len(ok) else np.empty(0)


def run_grid(
    sc: InterceptScenario,
    args,
    runs: int,
    seed: int,
    out: Path,
    estimators: Sequence[str],
    noises: Sequence[str],
) -> tuple[list[dict], list[pd.DataFrame]]:
    """Every estimator x noise on the same seeds (paired runs): summaries and run tables,
    in the order estimator-major. ``args`` holds the runner's options
    (:func:`experiments.options.add_runner`)."""
    check_plug_ins(sc, estimators)
    warn_unread_tables(getattr(args, "overrides", None) or (), estimators, noises)
    rows, frames = [], []
    for est in estimators:
        for noise in noises:
            t1, cpu1 = time.perf_counter(), usage.cpu_s()
            df = run_experiment(
                sc, est, noise, runs, seed, out, args.workers, args.scheduler,
                not args.no_progress, limits=run_limits(args),
                rerun_other_code=args.rerun_other_code,
            )  # fmt: skip
            row = summarise(df, sc, est, noise, seed, time.perf_counter() - t1)
            # a remote cluster's workers are not this process's children: not counted
            local = not args.scheduler
            row["cpu_s"] = usage.cpu_s() - cpu1 if local else None
            row["worker_peak_rss_mb"] = usage.peak_rss_mb(children=True) if local else None
            rows.append(row)
            frames.append(df)
    return rows, frames


def warn_unread_tables(
    overrides: Sequence[str], estimators: Sequence[str], noises: Sequence[str]
) -> None:
    """One warning for each ``--set estimator.NAME.KEY`` whose table no run of the
    command reads (:func:`estimators_read`: the run's estimator, and under game errors
    the adversary's set): its results would equal the original's under another name."""
    read = set().union(*(estimators_read(e, n) for e in estimators for n in noises))
    for item in overrides:
        found = estimator_option(item)
        if found is not None and found[1] not in read:
            warnings.warn(
                f"--set {found[0]} has no effect: no run here reads [estimator.{found[1]}] "
                f"(these runs read {', '.join(sorted(read))})",
                UserWarning,
                stacklevel=2,
            )


def check_plug_ins(sc: InterceptScenario, estimators: Sequence[str]) -> None:
    """Build each plug-in estimator of ``estimators`` once, on each channel of ``sc``
    with the scenario's options and prior: one whose factory (or ``initial``) raises
    is refused here in one line (:class:`InputError`, exit status 2), where every
    run would otherwise fail with the same error. The runs' own channel model may still
    differ (an attitude loop widens it), so a run can fail later. The package's own
    estimators are not built: their options models validate what they accept, and
    building them here would load their compiled kernels in this process."""
    from kalman_vs_infoset.experiments.provenance import plug_ins

    for name in plug_ins("intercept", estimators):
        for channel in sc.channels:
            what = f"estimator {name!r} cannot be built for {sc.name} (options "
            what += f"[estimator.{name}], {channel} channel)"
            built_or_refused(what, build_estimator, name, sc, sc.channel_model(), channel)


def miss_floor_m(sc: InterceptScenario) -> float:
    """Miss floor set by the last bearings: bound at eps times eps (docs/models.md §1.8)."""
    m = sc.model
    return m.bearing_bound_end_rad * m.eps_km * 1e3


def paper_marks(sc: InterceptScenario) -> dict[str, tuple[float | None, float | None, str]]:
    """The scenario's ``[reference]`` as ``{noise: (miss_m, fuel_mps, label)}``."""
    ref = sc.reference
    return {"random": (ref.miss_random_m, ref.fuel_random_mps, ref.label),
            "game": (ref.miss_game_m, ref.fuel_game_mps, ref.label)}  # fmt: skip


def draw_traces(files, sc: InterceptScenario) -> list:
    """The figures of freshly written traces, with the paper's printed miss and fuel of
    the scenario's ``[reference]`` marked."""
    from kalman_vs_infoset.experiments.plots_traces import plot_files  # matplotlib: lazily

    steps = [f for f in files if str(f).endswith("-trace.parquet")]
    return plot_files(steps, paper=paper_marks(sc))


def write_traces(
    sc: InterceptScenario,
    traced: list[int],
    pairs: Sequence[tuple[str, str]],
    frames: Sequence[pd.DataFrame],
    seed: int,
    out: Path,
) -> list:
    """The traces of runs ``traced`` of each (estimator, noise) in ``pairs`` whose run
    table (``frames``, in the same order) has them finished, and their figures."""
    from kalman_vs_infoset.experiments import traces

    written = []
    for (est, noise), df in zip(pairs, frames, strict=True):
        ok = traces.traceable(traced, df, f"{sc.name} {est}-{noise}")
        if ok:
            path = results_path(out, sc, est, noise, seed)
            written += traces.write_intercept_trace(sc, est, noise, seed, ok, path)
    return written + draw_traces(written, sc) if written else []
