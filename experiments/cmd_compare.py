"""``kvi compare SCENARIO.toml``: estimators x noises, paired by run.

Every (estimator, noise) pair runs on the same seeds, so run ``j`` has the same
initial truth (and, for random noise, the same noise stream) for every estimator.
Writes one Parquet table of all runs, CDFs of miss and fuel with one curve per
estimator x noise, a summary table and, with two estimators or more, the paired
differences of miss and fuel against the reference estimator (the registry's reference,
the information set, when compared; else the first named) run by run
(:mod:`~kalman_vs_infoset.experiments.paired`).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from kalman_vs_infoset.experiments import options

#: the runs use the compiled kernels (the command line announces their compilation)
COMPILED_KERNELS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    options.add_grid(p)


def summary_stem(args: argparse.Namespace, name: str) -> str:
    """The summary files' stem: ``<scenario>-compare``, with the estimators, noises and
    seed when they are not the defaults (as ``fig5``'s), so that a compare of other
    estimators or another seed never replaces another's summary in one ``--out``."""
    from kalman_vs_infoset.estim import registry

    parts = [f"{name}-compare"]
    if list(args.estimators) != list(registry.names("intercept")):
        parts.append("+".join(args.estimators))
    if list(args.noise) != list(options.GRID_NOISES):
        parts.append("+".join(args.noise))
    if args.seed is not None:
        parts.append(f"s{args.seed}")
    return "-".join(parts)


def run(args) -> dict[str, Any]:
    # here, not at import: declaring the arguments needs none of the runs' libraries
    import pandas as pd
    from kalman_vs_infoset.experiments import figstyle as fs
    from kalman_vs_infoset.experiments import paired, plots, traces
    from kalman_vs_infoset.experiments.intercept_runs import miss_floor_m, run_grid, write_traces
    from kalman_vs_infoset.experiments.report import summary_markdown, write_tables, write_text
    from kalman_vs_infoset.experiments.stats import ok_mean

    sc, runs, seed, out = options.resolve(args)
    traced = traces.check_runs(args.trace, runs)
    t0 = time.perf_counter()
    rows, frames = run_grid(sc, args, runs, seed, out / "runs", args.estimators, args.noise)
    table = pd.concat(frames, ignore_index=True)
    stem = out / summary_stem(args, sc.name)
    files = write_tables(table, stem)
    floor = ok_mean(table, "fuel_perfect_info_mps")  # None when every run failed
    marks = {
        "miss_m": [(miss_floor_m(sc), fs.MISS_SCALE_MARK)],
        "fuel_mps": [(floor, fs.PERFECT_INFO_MARK)] if floor is not None else [],
    }
    fig = plots.cdf_figure(
        table, ["estimator", "noise"], f"{sc.name}: estimators x noise, {runs} paired runs", marks
    )
    files += plots.save(fig, stem.with_name(stem.name + "-cdf"))
    compared = paired.comparison(table, args.estimators, "intercept")
    text = summary_markdown(rows, ["estimator", "noise"]) + paired.section(compared)
    files.append(write_text(stem.with_name(stem.name + ".md"), text))
    if traced:  # one trace per estimator x noise, drawn together
        pairs = [(e, n) for e in args.estimators for n in args.noise]
        files += write_traces(sc, traced, pairs, frames, seed, out / "runs")
    return {
        "scenario": sc.name,
        "runs": runs,
        "rows": rows,
        "paired": compared,
        "out": str(out),
        "files": [str(f) for f in files],
        "wall_s": time.perf_counter() - t0,
    }


def render(result: dict[str, Any]) -> str:
    from kalman_vs_infoset.experiments import paired
    from kalman_vs_infoset.experiments.report import summary_markdown

    return (
        summary_markdown(result["rows"], ["estimator", "noise"])
        + paired.section(result.get("paired"))
        + "files:\n"
        + "\n".join("  " + f for f in result["files"])
    )
