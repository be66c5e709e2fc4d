"""``kvi compare SCENARIO.toml``: estimators x noises, paired by run.

Every (estimator, noise) pair runs on the same seeds, so run ``j`` has the same
initial truth (and, for random noise, the same noise stream) for every estimator.
Writes one Parquet table of all runs, CDFs of miss and fuel with one curve per
estimator x noise, and a summary table.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import pandas as pd
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import plots, traces
from kalman_vs_infoset.experiments.cmd_fig5 import miss_floor_m
from kalman_vs_infoset.experiments.cmd_intercept import add_common, draw_traces, resolve
from kalman_vs_infoset.experiments.report import summary_markdown, write_tables, write_text
from kalman_vs_infoset.experiments.runner import results_path, run_experiment, summarise
from kalman_vs_infoset.experiments.sim.intercept_config import NOISES


def _list_of(allowed):
    def parse(text: str) -> list[str]:
        items = [t.strip() for t in text.split(",") if t.strip()]
        bad = [t for t in items if t not in allowed]
        if not items or bad:
            raise argparse.ArgumentTypeError(
                f"expected a comma-separated list of {', '.join(allowed)}; got {text!r}"
            )
        twice = sorted({t for t in items if items.count(t) > 1})
        if twice:  # each would be run and tabled twice
            raise argparse.ArgumentTypeError(f"{', '.join(twice)} given twice in {text!r}")
        return items

    return parse


def add_arguments(p) -> None:
    add_common(p)
    traces.add_argument(p)
    estimators = registry.names("intercept")
    p.add_argument(
        "--estimators",
        type=_list_of(estimators),
        default=list(estimators),
        help=f"comma-separated, from {','.join(estimators)} (default: all)",
    )
    p.add_argument(
        "--noise",
        type=_list_of(NOISES),
        default=["random", "game"],
        help=f"comma-separated, from {','.join(NOISES)} (default: random,game)",
    )


def run_grid(sc, args, runs: int, seed: int, out) -> tuple[list[dict], list[pd.DataFrame]]:
    """Every estimator x noise of ``args`` on the same seeds: summaries and run tables."""
    rows, frames = [], []
    for est in args.estimators:
        for noise in args.noise:
            t1 = time.perf_counter()
            df = run_experiment(
                sc, est, noise, runs, seed, out / "runs", args.workers, args.scheduler,
                not args.no_progress, limit_s=args.run_cpu_limit_s,
            )  # fmt: skip
            rows.append(summarise(df, sc, est, noise, seed, time.perf_counter() - t1))
            frames.append(df)
    return rows, frames


def run(args) -> dict[str, Any]:
    sc, runs, seed, out = resolve(args)
    traced = traces.check_runs(getattr(args, "trace", None), runs)
    t0 = time.perf_counter()
    rows, frames = run_grid(sc, args, runs, seed, out)
    table = pd.concat(frames, ignore_index=True)
    stem = out / f"{sc.name}-compare"
    files = write_tables(table, stem)
    marks = {
        "miss_m": [(miss_floor_m(sc), "bearing floor")],
        "fuel_mps": [(float(table["fuel_perfect_info_mps"].mean()), "perfect info (mean)")],
    }
    fig = plots.cdf_figure(
        table, ["estimator", "noise"], f"{sc.name}: estimators x noise, {runs} paired runs", marks
    )
    files += plots.save(fig, out / f"{sc.name}-compare-cdf")
    files.append(
        write_text(out / f"{sc.name}-compare.md", summary_markdown(rows, ["estimator", "noise"]))
    )
    if traced:  # one trace per estimator x noise, drawn together
        written = []
        for (est, noise), df in zip(
            [(e, n) for e in args.estimators for n in args.noise], frames, strict=True
        ):
            ok = traces.traceable(traced, df, f"{sc.name} {est}-{noise}")
            path = results_path(out / "runs", sc, est, noise, seed)
            if ok:
                written += traces.write_intercept_trace(sc, est, noise, seed, ok, path)
        files += written + draw_traces(written, sc)
    return {
        "scenario": sc.name,
        "runs": runs,
        "rows": rows,
        "out": str(out),
        "files": [str(f) for f in files],
        "wall_s": time.perf_counter() - t0,
    }


def render(result: dict[str, Any]) -> str:
    return (
        summary_markdown(result["rows"], ["estimator", "noise"])
        + "files:\n"
        + "\n".join("  " + f for f in result["files"])
    )
