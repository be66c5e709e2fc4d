"""``kvi intercept SCENARIO.toml``: Monte Carlo of the intercept (docs/models.md §3.1)."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import traces
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.runner import (
    MAX_RUNS,
    results_path,
    run_experiment,
    summarise,
)
from kalman_vs_infoset.experiments.scenario import SCENARIO_HELP, load_scenario
from kalman_vs_infoset.experiments.sim.intercept_config import NOISES


def _int_at_least(lo: int, what: str):
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            value = lo - 1
        if value < lo:
            raise argparse.ArgumentTypeError(f"expected a {what} integer, got {text!r}")
        return value

    return parse


positive_int = _int_at_least(1, "positive")


def runs_int(text: str) -> int:
    """A run count: an integer in [1, 10^6] (the runner holds the run indices)."""
    value = positive_int(text)
    if value > MAX_RUNS:
        raise argparse.ArgumentTypeError(f"expected an integer in [1, {MAX_RUNS}], got {text!r}")
    return value


def cpu_limit_s(text: str) -> float:
    """A CPU-time limit of a run, in seconds: a number in (0, 1e6]."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0.0 < value <= 1e6:
        raise argparse.ArgumentTypeError(f"expected seconds in (0, 1e6], got {text!r}")
    return value


def add_limit(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--run-cpu-limit-s",
        type=cpu_limit_s,
        help="CPU-time limit of one run, s (a run over it is recorded as failed, with the "
        "reason; local runs only; default: none)",
    )


def seed_int(text: str) -> int:
    """A root seed: an integer in [0, 2^63 - 1] (the results tables hold it as int64)."""
    value = _int_at_least(0, "non-negative")(text)
    if value > 2**63 - 1:
        raise argparse.ArgumentTypeError(f"expected an integer in [0, 2^63 - 1], got {text!r}")
    return value


def add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help=SCENARIO_HELP)
    p.add_argument("--runs", type=runs_int, help="number of runs (default: the scenario's)")
    p.add_argument("--seed", type=seed_int, help="root seed (default: the scenario's)")
    p.add_argument("--workers", type=positive_int, help="local worker processes (default: CPUs)")
    p.add_argument("--scheduler", help="Dask scheduler address (tcp://host:8786)")
    p.add_argument("--out", help="output directory (default: results/<scenario name>)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    add_limit(p)
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="TABLE.KEY=VALUE",
        dest="overrides",
        help="override a scenario field with a TOML value, e.g. "
        "estimator.ekf.noise_inflation=10 (repeatable; validated like the file; "
        "the scenario's name gets a +key=value suffix)",
    )


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_common(p)
    traces.add_argument(p)
    estimators = registry.names("intercept")
    p.add_argument("--estimator", choices=estimators, help="default: the scenario's")
    p.add_argument("--noise", choices=NOISES, help="default: the scenario's")


def resolve(args) -> tuple[Any, int, int, Path]:
    sc = load_scenario(args.scenario, args.overrides)
    runs = args.runs or sc.experiment.runs
    seed = sc.experiment.seed if args.seed is None else args.seed
    out = Path(args.out) if args.out else Path("results") / sc.name
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: not a directory")
    return sc, runs, seed, out


def run(args) -> dict[str, Any]:
    sc, runs, seed, out = resolve(args)
    estimator = args.estimator or sc.experiment.estimator
    noise = args.noise or sc.experiment.noise
    traced = traces.check_runs(args.trace, runs)
    t0 = time.perf_counter()
    df = run_experiment(
        sc, estimator, noise, runs, seed, out, args.workers, args.scheduler,
        not args.no_progress, limit_s=args.run_cpu_limit_s,
    )  # fmt: skip
    result = summarise(df, sc, estimator, noise, seed, time.perf_counter() - t0)
    result["out"] = str(out)
    traced = traces.traceable(traced, df, f"{sc.name} {estimator}-{noise}")
    if traced:
        path = results_path(out, sc, estimator, noise, seed)
        files = traces.write_intercept_trace(sc, estimator, noise, seed, traced, path)
        files += draw_traces(files, sc)
        result["files"] = [str(f) for f in files]
    return result


def draw_traces(files, sc) -> list:
    """The figures of freshly written traces (:mod:`experiments.cmd_plot`), with the
    paper's printed miss and fuel of the scenario's ``[reference]`` marked."""
    from kalman_vs_infoset.experiments.cmd_plot import plot_files

    steps = [f for f in files if str(f).endswith("-trace.parquet")]
    return plot_files(steps, paper=paper_marks(sc))


def paper_marks(sc) -> dict[str, tuple[float | None, float | None]]:
    """The scenario's ``[reference]`` as ``{noise: (miss_m, fuel_mps)}``."""
    ref = sc.reference
    return {"random": (ref.miss_random_m, ref.fuel_random_mps),
            "game": (ref.miss_game_m, ref.fuel_game_mps)}  # fmt: skip


def render(result: dict[str, Any]) -> str:
    m, f = result["miss_m"], result["fuel_mps"]
    return "\n".join(
        [
            f"{result['scenario']}: {result['estimator']} / {result['noise']} noise, "
            f"{result['runs']} runs, seed {result['seed']}",
            f"  miss  m   mean {m['mean']:.2f}  p50 {m['p50']:.2f}  p90 {m['p90']:.2f}  "
            f"max {m['max']:.2f}",
            f"  fuel m/s  mean {f['mean']:.1f}  p50 {f['p50']:.1f}  p90 {f['p90']:.1f}  "
            f"max {f['max']:.1f}",
            f"  truth outside belief: {result['truth_outside']} steps; empty set: "
            f"{result['empty_set']} runs; diverged: {result['diverged']} runs; "
            f"failures: {result['failures']}",
            f"  results in {result['out']} ({result['wall_s']:.1f} s)",
            *(f"  {f}" for f in result.get("files", [])),
        ]
    )
