"""``kvi intercept SCENARIO.toml``: Monte Carlo of the intercept (docs/models.md §3.1).

``--estimators`` and ``--noise`` are comma lists (default: the scenario's
``experiment.estimator`` and ``experiment.noise``); each estimator x noise is one
results table, every one on the same seeds.
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from kalman_vs_infoset.experiments import options
from kalman_vs_infoset.experiments.errors import runs_text, stat_text
from kalman_vs_infoset.experiments.noise import NOISES
from kalman_vs_infoset.experiments.stats import KEYS

#: the runs use the compiled kernels (the command line announces their compilation)
COMPILED_KERNELS = True


def add_arguments(p: argparse.ArgumentParser) -> None:
    options.add_common(p)
    options.add_trace(p)
    options.add_estimators(p, "intercept", None, "the scenario's")
    options.add_noise(p, NOISES, None, "the scenario's")


def run(args) -> dict[str, Any]:
    # here, not at import: declaring the arguments needs none of the runs' libraries
    from kalman_vs_infoset.experiments import traces
    from kalman_vs_infoset.experiments.intercept_runs import run_grid, write_traces

    sc, runs, seed, out = options.resolve(args)
    estimators = args.estimators or [sc.experiment.estimator]
    noises = args.noise or [sc.experiment.noise]
    traced = traces.check_runs(args.trace, runs)
    t0 = time.perf_counter()
    rows, frames = run_grid(sc, args, runs, seed, out, estimators, noises)
    wall_s = time.perf_counter() - t0
    result = dict(rows[0]) if len(rows) == 1 else {"scenario": sc.name, "rows": rows}
    result.update(out=str(out), wall_s=wall_s)
    if traced:
        pairs = [(e, n) for e in estimators for n in noises]
        files = write_traces(sc, traced, pairs, frames, seed, out)
        if files:
            result["files"] = [str(f) for f in files]
    return result


def _summary(r: dict[str, Any]) -> list[str]:
    m, f = r["miss_m"], r["fuel_mps"]
    premise = []
    if "pointing_premise_failed_steps" in r:  # an attitude loop holds the axis
        failed, over = r["pointing_premise_failed_steps"], r["pointing_bound_exceeded_steps"]
        # (read as a failure when it said "exceeded ... at 0 bearings")
        held = "held at every bearing" if not failed else f"failed at {failed} bearings"
        premise = [
            f"  pointing premise (the true residual within the knowledge bound the sets took, "
            f"as their guarantee needs): {held}; the loop's own bound exceeded it at {over}"
        ]
    # said only when it happened: a set too wide to bound the miss forecast issues nothing
    n_unbounded = r.get("unbounded_steps") or 0
    unbounded = [
        f"  no impulse for want of a bounded forecast: {n_unbounded} channel steps"
    ] if n_unbounded else []  # fmt: skip
    return [
        f"{r['scenario']}: {r['estimator']} / {r['noise']} noise, "
        f"{runs_text(r['runs'])}, seed {r['seed']}",
        # "-" where no run gave a value (every run failed)
        "  miss  m   " + "  ".join(f"{k} {stat_text(m[k], '.2f')}" for k in KEYS),
        "  fuel m/s  " + "  ".join(f"{k} {stat_text(f[k], '.1f')}" for k in KEYS),
        f"  truth outside belief: {r['truth_outside']} steps; empty set: "
        f"{runs_text(r['empty_set'])}; diverged: {runs_text(r['diverged'])}; "
        f"failures: {r['failures']}",
        *unbounded,
        *premise,
    ]


def render(result: dict[str, Any]) -> str:
    lines = [line for r in result.get("rows", [result]) for line in _summary(r)]
    return "\n".join(
        [
            *lines,
            f"  results in {result['out']} ({result['wall_s']:.1f} s)",
            *(f"  {f}" for f in result.get("files", [])),
        ]
    )
