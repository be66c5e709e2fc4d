"""``kvi attitude SCENARIO.toml [--controller NAME] [--noise ...]`` (docs/models.md §3.1).

Loads the scenario (``--set`` overrides as for the intercept), takes the controller from
``--controller`` or the file's top-level ``controller`` key and dispatches by name to the
module that validates it and runs it:

* ``pd``, ``lqr``        -> :mod:`kalman_vs_infoset.experiments.attitude_rw`
* ``energy``, ``euler``  -> :mod:`kalman_vs_infoset.experiments.attitude_cmg`
* ``game``               -> :mod:`kalman_vs_infoset.experiments.attitude_gyrostat`

Each module offers ``prepare`` (validation), ``task`` (the rows of a chunk of runs),
``CHUNK`` and ``summarise`` (the JSON from the rows); the runs go through the same
runner as the intercept (:mod:`experiments.runner`: workers, Dask, resume, failures
with their run ids, results named by scenario, controller, estimator, noise and seed).
Modules are imported lazily; one that is not importable gives the one-line error
"controller X is not available" (exit status 2).
"""

from __future__ import annotations

import argparse
import importlib
import json
import time
from functools import partial
from pathlib import Path
from typing import Any

import pandas as pd
from kalman_vs_infoset.experiments import traces
from kalman_vs_infoset.experiments.attitude_est import resolve_estimators, write_figure
from kalman_vs_infoset.experiments.attitude_traces import TRACERS
from kalman_vs_infoset.experiments.cmd_intercept import add_limit, positive_int, runs_int, seed_int
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.runner import (
    Job,
    batched_task,
    check_seed,
    job_path,
    run_job,
    run_seed,
)
from kalman_vs_infoset.experiments.scenario import SCENARIO_HELP, read
from kalman_vs_infoset.experiments.sim.estimator_loop import NOISES
from kalman_vs_infoset.experiments.sim.intercept_config import check_name

#: controller name -> module exposing prepare, task, CHUNK and summarise
DISPATCH = {
    "pd": "kalman_vs_infoset.experiments.attitude_rw",
    "lqr": "kalman_vs_infoset.experiments.attitude_rw",
    "energy": "kalman_vs_infoset.experiments.attitude_cmg",
    "euler": "kalman_vs_infoset.experiments.attitude_cmg",
    "game": "kalman_vs_infoset.experiments.attitude_gyrostat",
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", help=SCENARIO_HELP)
    parser.add_argument("--controller", default=None, help="one of " + ", ".join(DISPATCH))
    parser.add_argument("--noise", default="none", help="none | random | game (default none)")
    parser.add_argument("--runs", type=runs_int, default=1, help="number of runs (default 1)")
    parser.add_argument("--seed", type=seed_int, default=0, help="root seed (default 0)")
    parser.add_argument(
        "--estimator",
        default=None,
        help="perfect | ukf | box (or another registered name), or a comma list run on the "
        "same realisations (default: the scenario's 'estimator', else perfect for --noise "
        "none, box otherwise)",
    )
    parser.add_argument(
        "--out", default=None, help="output directory (default: results/attitude/<scenario>)"
    )
    parser.add_argument("--workers", type=positive_int, help="local worker processes")
    parser.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    add_limit(parser)
    traces.add_argument(parser)
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="TABLE.KEY=VALUE",
        dest="overrides",
        help="override a scenario field with a TOML value, e.g. simulation.duration_s=60 "
        "(repeatable; validated like the file; the scenario's name gets a +key=value suffix)",
    )


def resolve_module(controller: str) -> Any:
    """Import the module running ``controller`` (InputError if unknown or not available)."""
    if controller not in DISPATCH:
        raise InputError(f"unknown controller '{controller}' (allowed: {', '.join(DISPATCH)})")
    name = DISPATCH[controller]
    try:
        return importlib.import_module(name)
    except ModuleNotFoundError as exc:
        if exc.name != name:
            raise
        raise InputError(f"controller {controller} is not available") from None


def run(args: argparse.Namespace) -> dict[str, Any]:
    data, source = read(args.scenario, args.overrides)
    controller = args.controller if args.controller is not None else data.get("controller")
    if controller is None:
        raise InputError(f"{args.scenario}: no --controller and no top-level 'controller' key")
    if not isinstance(controller, str):
        raise InputError(f"{args.scenario}: field 'controller' must be a string")
    if args.noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{args.noise}'")
    seed = check_seed(args.seed)
    # a single run is shown as its time histories (a CDF of one run is one step)
    traced = traces.check_runs(args.trace if args.trace is not None else
                               ([0] if args.runs == 1 else []), args.runs)  # fmt: skip
    module = resolve_module(controller)
    given = data.get("controller")
    if args.controller is not None and isinstance(given, str) and given in DISPATCH:
        if DISPATCH[given] != DISPATCH[controller]:  # another simulation's scenario

            def takes(c: str) -> str:
                return ", ".join(repr(k) for k, v in DISPATCH.items() if v == DISPATCH[c])

            raise InputError(
                f"{source}: field 'controller' {given!r} makes it a scenario of {takes(given)}; "
                f"--controller {controller} runs scenarios of {takes(controller)}"
            )
    default_est = data.pop("estimator", None)
    if default_est is not None and not isinstance(default_est, str):
        raise InputError(f"{args.scenario}: field 'estimator' must be a string")
    estimators = resolve_estimators(args.estimator, default_est, args.noise)
    try:
        name = check_name(data["name"])
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from None
    setup = module.prepare(source, data, controller, args.noise)
    out_dir = Path(args.out) if args.out else Path("results") / "attitude" / name
    if out_dir.exists() and not out_dir.is_dir():
        raise InputError(f"--out {out_dir}: not a directory")
    scenario = json.loads(json.dumps(data, default=str))
    results, frames, files, histories = [], [], [], []
    for est in estimators:
        t0 = time.perf_counter()
        choice = {"controller": controller, "estimator": est, "noise": args.noise}
        simulate = partial(module.task, setup, controller, args.noise, est)
        job = Job(
            name=name,
            label=f"{controller}-{est}-{args.noise}",
            seed=seed,
            meta={"scenario": scenario, **choice, "seed": seed},
            base={"scenario": name, **choice, "seed": seed},
            task=partial(batched_task, simulate, seed),
            chunk=module.CHUNK,
        )
        df = run_job(
            job, args.runs, out_dir, args.workers, args.scheduler, not args.no_progress,
            limit_s=args.run_cpu_limit_s,
        )  # fmt: skip
        ok = df[df["status"] == "ok"] if len(df) else df
        failures = int((df["status"] != "ok").sum()) if len(df) else 0
        res = module.summarise(setup, controller, args.noise, est, args.runs, seed, ok, failures)
        res["wall_s"] = time.perf_counter() - t0
        results.append(res)
        frames.append(df)
        files.append(str(job_path(out_dir, job)))
        ok_runs = traces.traceable(traced, df, job.desc)
        if ok_runs:
            tracer = partial(TRACERS[controller], setup, controller, args.noise, est)
            base = {"scenario": name, **choice, "seed": seed}
            runs = [tracer(run_seed(seed, 0, j)).assign(**base, run=j) for j in ok_runs]
            path = traces.trace_paths(job_path(out_dir, job))[0]
            files.append(str(traces.write_parquet(pd.concat(runs, ignore_index=True), path)))
            histories += runs
    result = dict(results[0])
    if len(results) > 1:
        result["rows"] = results
    table = pd.concat(frames, ignore_index=True)
    ok = table[table["status"] == "ok"] if len(table) else table
    # the figures' names carry what distinguishes them: estimators, noise, seed
    stem = f"{name}-{controller}-{','.join(estimators)}-{args.noise}-s{seed}"
    if len(ok) and args.runs > 1:
        files += write_figure(out_dir, stem, ok)
    if histories:
        from kalman_vs_infoset.experiments import figstyle, plots_attitude

        fig = plots_attitude.time_histories(histories, f"{stem}: time histories")
        files += [str(f) for f in figstyle.save(fig, out_dir / f"{stem}-history")]
    result["files"] = files
    return result
