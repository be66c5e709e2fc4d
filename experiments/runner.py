"""Monte Carlo runner: tasks on an Executor, paired seeding, atomic resumable Parquet.

* Seeding: run ``j`` uses ``SeedSequence(seed).spawn(runs)[j]``; the realisation
  depends only on (scenario, seed, j), never on the worker count or the order,
  and is the same for every estimator (paired comparison).
* Executor: runs in this process for one worker, a ``ProcessPoolExecutor`` for
  several, or a Dask cluster's ``Client.get_executor()`` with ``scheduler`` (same
  results either way).
* Results: one Parquet file per (scenario, estimator, noise, seed) with one row per
  run, the resolved scenario as JSON beside it; both written atomically
  (temporary file + ``os.replace``). Rerunning the same command completes only the
  missing runs; a failing run is recorded with its error and does not stop the others.
  The JSON also records which code wrote the runs (:mod:`experiments.provenance`);
  a file written by another scenario or other sources is refused, not extended.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Iterator
from concurrent.futures import (
    BrokenExecutor,
    CancelledError,
    Executor,
    ProcessPoolExecutor,
    as_completed,
)
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from tqdm import tqdm

from estim import _kernels as _k
from experiments import provenance
from experiments.engagement import timed_engagement
from experiments.errors import InputError
from experiments.files import atomic_write
from experiments.intercept_scenario import InterceptScenario
from experiments.provenance import code_identity
from experiments.stats import summary_stats

SAVE_EVERY_S = 2.0


def run_seed(seed: int, runs: int, j: int) -> np.random.SeedSequence:
    """The seed of run ``j``: ``SeedSequence(seed).spawn(runs)[j]`` (independent of ``runs``)."""
    return np.random.SeedSequence(seed, spawn_key=(j,))


@contextmanager
def make_executor(workers: int | None = None, scheduler: str | None = None) -> Iterator[Executor]:
    """Local processes by default, a Dask cluster when ``scheduler`` is given."""
    if scheduler:
        try:
            from distributed import Client
        except ImportError:
            raise InputError(
                "--scheduler needs dask.distributed (pip install '.[cluster]')"
            ) from None
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError) as exc:
            raise InputError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
        try:
            _check_workers_code(client, scheduler)
            yield client.get_executor()
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    _k.warm_up()  # forked workers inherit the loaded kernels
    pool = ProcessPoolExecutor(max_workers=n)
    try:
        yield pool
    finally:
        pool.shutdown(wait=False, cancel_futures=True)


def _check_workers_code(client, scheduler: str) -> None:
    """Refuse a cluster whose workers run other sources than this process: their rows
    would be recorded under this process's code identity."""
    here = code_identity()["sources_sha256"]
    try:
        theirs = client.run(provenance.sources_sha256)  # imported on each worker
    except Exception as exc:  # e.g. the package is not installed on a worker
        raise InputError(
            f"Dask workers at {scheduler} cannot run this package ({type(exc).__name__}: {exc})"
        ) from None
    for worker, h in sorted(theirs.items()):
        if h != here:
            raise InputError(
                f"Dask worker {worker} runs other code (sources {h[:12]}, here {here[:12]}); "
                "install the same version on every worker"
            )


def results_path(out_dir: Path, sc: InterceptScenario, estimator: str, noise: str, seed: int):
    return Path(out_dir) / f"{sc.name}-{estimator}-{noise}-s{seed}.parquet"


def _write_rows(path: Path, rows: list[dict[str, Any]]) -> None:
    df = pd.DataFrame(rows).sort_values("run").reset_index(drop=True)
    atomic_write(path, lambda tmp: df.to_parquet(tmp, index=False))


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
) -> pd.DataFrame:
    """Run (or complete) an experiment and return its per-run table."""
    path = results_path(out_dir, sc, estimator, noise, seed)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"--out {out_dir}: cannot create the folder ({exc.strerror})") from None
    meta = {
        "scenario": sc.to_dict(),
        "estimator": estimator,
        "noise": noise,
        "seed": seed,
        "code": code_identity(),
    }
    meta_path = path.with_suffix(".json")
    rows: list[dict[str, Any]] = []
    if path.exists():
        _check_resumable(path, meta_path, meta)
        try:
            rows = pd.read_parquet(path).to_dict("records")
        except Exception as exc:  # a corrupt file is never produced by atomic writes
            raise InputError(f"{path}: cannot read previous results ({exc})") from None
        rows = [r for r in rows if r["run"] < runs]
    atomic_write(meta_path, lambda tmp: Path(tmp).write_text(json.dumps(meta, indent=2)))
    done = {int(r["run"]) for r in rows}
    todo = [j for j in range(runs) if j not in done]
    base = {"scenario": sc.name, "estimator": estimator, "noise": noise, "seed": seed}
    if todo:
        bar = tqdm(
            total=runs,
            initial=len(done),
            desc=f"{sc.name} {estimator}/{noise}",
            file=sys.stderr,
            disable=not progress or None,
            leave=False,
        )
        last_save = time.monotonic()
        try:
            for j, row in _results(
                sc, estimator, noise, seed, runs, todo, executor, workers, scheduler
            ):
                rows.append({**base, "run": j, **row})
                bar.update(1)
                if time.monotonic() - last_save > SAVE_EVERY_S:
                    _write_rows(path, rows)
                    last_save = time.monotonic()
        finally:
            bar.close()
            if rows:
                _write_rows(path, rows)  # also on Ctrl-C: finished runs are kept
    df = pd.DataFrame(rows).sort_values("run").reset_index(drop=True)
    return df


def _check_resumable(path: Path, meta_path: Path, meta: dict[str, Any]) -> None:
    """Refuse (one line) to add runs to results of another scenario or other code."""
    fix = "use another --out or delete the file"
    try:
        old = json.loads(meta_path.read_text())
    except (OSError, ValueError):
        raise InputError(
            f"{path}: no readable {meta_path.name} to check it against; {fix}"
        ) from None
    if old.get("scenario") != json.loads(json.dumps(meta["scenario"])):
        raise InputError(f"{path}: results of a different scenario; {fix}")
    before = (old.get("code") or {}).get("sources_sha256")
    if before != meta["code"]["sources_sha256"]:
        was = f"sources {before[:12]}" if before else "code that recorded no identity"
        raise InputError(
            f"{path}: results written by other code ({was}, now "
            f"{meta['code']['sources_sha256'][:12]}); {fix}"
        )


class WorkerLost(RuntimeError):
    """A worker process died; finished runs are saved, the lost ones are missing."""


def _results(sc, estimator, noise, seed, runs, todo, executor, workers, scheduler):
    """Yield ``(run, row)`` as runs finish: in order in this process for one local
    worker (so Ctrl-C stops between runs), else as completed on the executor."""
    if executor is None and scheduler is None and (workers or os.cpu_count() or 1) == 1:
        for j in todo:
            yield j, timed_engagement(sc, estimator, noise, run_seed(seed, runs, j))
        return
    with executor_or(executor, workers, scheduler) as ex:
        futs = {
            ex.submit(timed_engagement, sc, estimator, noise, run_seed(seed, runs, j)): j
            for j in todo
        }
        lost = 0
        for fut in as_completed(futs):
            try:
                row = fut.result()
            except InputError:
                raise
            except (BrokenExecutor, CancelledError):
                lost += 1  # a worker died: the run is missing, not failed (resumable)
                continue
            except Exception as exc:  # the run itself raised outside the engagement
                row = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
            yield futs[fut], row
        if lost:
            raise WorkerLost(f"{lost} runs lost to a dead worker; rerun the same command")


@contextmanager
def executor_or(executor: Executor | None, workers, scheduler) -> Iterator[Executor]:
    if executor is not None:
        yield executor
    else:
        with make_executor(workers, scheduler) as ex:
            yield ex


def summarise(df: pd.DataFrame, sc: InterceptScenario, estimator, noise, seed, wall_s) -> dict:
    """The intercept JSON object of SPEC 3.1 for one estimator x noise."""
    ok = df[df["status"] == "ok"] if "status" in df else df.iloc[0:0]
    return {
        "scenario": sc.name,
        "estimator": estimator,
        "noise": noise,
        "runs": int(len(df)),
        "seed": int(seed),
        "miss_m": summary_stats(ok["miss_m"].to_numpy(dtype=float) if len(ok) else []),
        "fuel_mps": summary_stats(ok["fuel_mps"].to_numpy(dtype=float) if len(ok) else []),
        "truth_outside": int(ok["truth_outside"].sum()) if len(ok) else 0,
        "empty_set": int((ok["contradictions"] > 0).sum()) if len(ok) else 0,
        # beliefs reported Status.DIVERGED: emptied, so guidance stopped early
        "diverged": int(ok["diverged"].sum()) if len(ok) else 0,
        "failures": int((df["status"] != "ok").sum()) if "status" in df else 0,
        "wall_s": float(wall_s),
    }
