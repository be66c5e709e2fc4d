"""``kvi attitude SCENARIO.toml [--controller NAME] [--estimators ...] [--noise ...]``
(docs/models.md §3.1).

Loads the scenario (``--set`` overrides as for the intercept) into an
:class:`AttitudeRequest`: the controller from ``--controller`` or the file's top-level
``controller`` key, its simulation (:func:`experiments.attitude_loops.loop_of`: reaction
wheels for ``pd`` and ``lqr``, gyrodines for ``energy`` and ``euler``, the gyrostat for
``game``), the estimators and noises (comma lists, every pair on the same
realisations), all validated before the first run. The runs go through the same runner
as the intercept (:mod:`experiments.runner`: workers, Dask, resume, failures with their
run ids, results named by scenario, controller, estimator, noise and seed).
"""

from __future__ import annotations

import argparse
import json
import time
from functools import partial
from typing import TYPE_CHECKING, Any

from kalman_vs_infoset.experiments import options, usage
from kalman_vs_infoset.experiments.attitude_loops import LOOPS, check_plug_ins
from kalman_vs_infoset.experiments.attitude_request import AttitudeRequest, request
from kalman_vs_infoset.experiments.errors import runs_text, stat_text
from kalman_vs_infoset.experiments.sim.estimator_loop import NOISES

if TYPE_CHECKING:  # the runs' libraries are imported by run(), not to parse
    import pandas as pd

#: the runs import the compiled kernels (the command line announces a compilation)
COMPILED_KERNELS = True


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", help=options.SCENARIO_HELP)
    parser.add_argument(
        "--controller",
        default=None,
        help="one of " + ", ".join(LOOPS) + " (default: the scenario's 'controller')",
    )
    options.add_noise(parser, NOISES, None, "none")
    parser.add_argument("--runs", type=options.runs_int, default=1,
                        help="number of runs (default 1)")  # fmt: skip
    parser.add_argument("--seed", type=options.seed_int, default=0, help="root seed (default 0)")
    options.add_estimators(
        parser, "attitude", None,
        "the scenario's 'estimator', else perfect for --noise none, box otherwise",
    )  # fmt: skip
    parser.add_argument(
        "--out", default=None, help="output directory (default: results/attitude/<scenario>)"
    )
    options.add_runner(parser)
    options.add_trace(parser, "run 0 when --runs is 1, else none")
    options.add_overrides(parser, "simulation.control_period_s=0.02")


def run(args: argparse.Namespace) -> dict[str, Any]:
    # here, not at import: declaring the arguments needs none of the runs' libraries
    import pandas as pd
    from kalman_vs_infoset.experiments import paired, traces
    from kalman_vs_infoset.experiments.runner import (
        Job,
        batched_task,
        job_path,
        run_job,
        run_seed,
    )
    from kalman_vs_infoset.experiments.sim.estimator_tables import tables_kept

    req = request(args)
    # a single run is shown as its time histories (a CDF of one run is one step)
    traced = traces.check_runs(args.trace if args.trace is not None else
                               ([0] if req.runs == 1 else []), req.runs)  # fmt: skip
    loop, controller, seed = req.loop, req.controller, req.seed
    # every noise's set-up is validated before the first run
    setups = {n: loop.prepare(req.source, dict(req.scenario), controller, n) for n in req.noises}
    check_plug_ins(loop, setups, req.estimators)  # a plug-in that cannot be built: one line
    scenario = json.loads(json.dumps(dict(req.scenario), default=str))
    results, frames, files, histories = [], [], [], []
    for est in req.estimators:
        for noise in req.noises:
            t0, cpu0 = time.perf_counter(), usage.cpu_s()
            choice = {"controller": controller, "estimator": est, "noise": noise}
            base = {"scenario": req.name, **choice, "seed": seed}
            job = Job(
                name=req.name,
                label=f"{controller}-{est}-{noise}",
                seed=seed,
                meta={"scenario": scenario, **choice, "seed": seed},
                base=base,
                task=partial(
                    batched_task, partial(loop.task, setups[noise], controller, noise, est), seed
                ),  # fmt: skip
                chunk=loop.chunk,
                problem="attitude",
                # a loop's estimator reads its own options table only (EstimatorLoop)
                decides=partial(tables_kept, "attitude", ("estimator_options",), frozenset({est})),
            )
            df = run_job(
                job, req.runs, req.out, args.workers, args.scheduler, not args.no_progress,
                limits=options.run_limits(args), rerun_other_code=args.rerun_other_code,
            )  # fmt: skip
            ok = df[df["status"] == "ok"] if len(df) else df
            failures = int((df["status"] != "ok").sum()) if len(df) else 0
            res = loop.summarise(setups[noise], controller, noise, est, req.runs, seed, ok,
                                 failures)  # fmt: skip
            res["wall_s"] = time.perf_counter() - t0
            # as the intercept's: a remote cluster's workers are not this process's children
            local = not args.scheduler
            res["cpu_s"] = usage.cpu_s() - cpu0 if local else None
            res["worker_peak_rss_mb"] = usage.peak_rss_mb(children=True) if local else None
            results.append(res)
            frames.append(df)
            files.append(str(job_path(req.out, job)))
            ok_runs = traces.traceable(traced, df, job.desc)
            if ok_runs:
                tracer = partial(loop.trace, setups[noise], controller, noise, est)
                runs = [tracer(run_seed(seed, j)).assign(**base, run=j) for j in ok_runs]
                path = traces.trace_paths(job_path(req.out, job))[0]
                files.append(str(traces.write_parquet(pd.concat(runs, ignore_index=True), path)))
                histories += runs
    result = dict(results[0])
    if len(results) > 1:
        result["rows"] = results
    table = pd.concat(frames, ignore_index=True)
    # several estimators: each against the box, run by run (the same seeds)
    compared = paired.comparison(table, req.estimators, "attitude")
    if compared is not None:
        result["paired"] = compared
    files += _figures(req, table, histories)
    result["files"] = files
    return result


def _figures(req: AttitudeRequest, table: pd.DataFrame, histories: list) -> list[str]:
    """The CDFs of the runs and the time histories of the traced ones; their names
    carry what distinguishes them: controller, estimators, noises, seed."""
    from kalman_vs_infoset.experiments.attitude_est import write_figure

    ok = table[table["status"] == "ok"] if len(table) else table
    # every row to the figure: a curve's label counts the failed runs it leaves out
    # '+' joins several names: a comma is awkward in file names on every shell
    stem = (
        f"{req.name}-{req.controller}-{'+'.join(req.estimators)}-{'+'.join(req.noises)}-s{req.seed}"
    )
    files = write_figure(req.out, stem, table) if len(ok) and req.runs > 1 else []
    if histories:
        from kalman_vs_infoset.experiments import figstyle, plots_attitude

        # words, not the file stem (the legend names each traced run's estimator and noise)
        runs = sorted({int(h["run"].iloc[0]) for h in histories if "run" in h})
        title = plots_attitude.history_title(req.name, req.controller, runs, req.seed)
        fig = plots_attitude.time_histories(histories, title)
        files += [str(f) for f in figstyle.save(fig, req.out / f"{stem}-history")]
    return files


def _summary(r: dict[str, Any]) -> list[str]:
    """One row's lines, as the intercept command prints its runs."""
    s, e, a = r["settle_time_s"], r["energy_N2m2s"], r["final_angle_deg"]
    st = stat_text  # the lines below print a dozen statistics
    lines = [
        f"{r['scenario']}: {r['controller']} on {r['estimator']} / {r['noise']} noise, "
        f"{runs_text(r['runs'])}, seed {r['seed']}",
        f"  settle s            mean {st(s['mean'], '.2f')}  p90 {st(s['p90'], '.2f')}  "
        f"max {st(s['max'], '.2f')}  (not settled: {runs_text(r.get('not_settled', 0))})",
        f"  energy N^2 m^2 s    mean {st(e['mean'], '.4g')}  max {st(e['max'], '.4g')}",
        f"  final angle deg     mean {st(a['mean'], '.3g')}  max {st(a['max'], '.3g')}",
        f"  truth outside belief: {r['truth_outside']} steps; empty: {r['empty_steps']} "
        f"steps; unbounded: {r['unbounded_steps']} steps; failures: {r['failures']}",
    ]
    if r.get("diverged"):
        lines.append(
            f"  diverged: {runs_text(r['diverged'])} (the closed loop left what its integration "
            "resolves; left out of the statistics above, counted in the estimator's steps)"
        )
    if r.get("guaranteed_time_s") is not None:
        lines.append(f"  guaranteed settle time tau: {r['guaranteed_time_s']:.1f} s")
    ref = r.get("seed_reference")
    if ref and ref.get("settle_time_s") is not None:
        lines.append(f"  paper: settles in {ref['settle_time_s']} s ({ref['source']})")
    return lines


def render(result: dict[str, Any]) -> str:
    """The runs of every estimator x noise, then the cost and the files written."""
    rows = result.get("rows", [result])
    cpu = [r.get("cpu_s") for r in rows]
    cost = f"{sum(r['wall_s'] for r in rows):.1f} s"
    if all(c is not None for c in cpu):
        cost += f", {sum(cpu):.1f} CPU-s"
    from kalman_vs_infoset.experiments import paired

    more = paired.section(result.get("paired"), "attitude").strip("\n")
    return "\n".join(
        [
            *(line for r in rows for line in _summary(r)),
            *([more] if more else []),
            f"  done ({cost}); files:",
            *(f"  {f}" for f in result.get("files", [])),
        ]
    )
