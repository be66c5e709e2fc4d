"""``kvi adversaries SCENARIO.toml``: how strong can the adversary be?

Three rules against the same estimators on the same truths (paired runs, the runner's
seeding), strongest search last:

* ``game``: the seed's adversary (its own information set, the worst point kept in the
  measurement's interval; :class:`kalman_vs_infoset.experiments.noise.GameNoise`);
* ``targeted``: white box, greedy over one step (:class:`experiments.adversary.TargetedNoise`);
* ``lookahead``: white box, k-step best response by tree search over the pursuer's own
  estimator and law (:class:`experiments.adversary.LookaheadNoise`; ``--lookahead K``
  sets k, the scenario's ``[adversary]`` table the candidates).

For each estimator x rule: fuel and miss (mean / p50 / p90), and where the seed's game
fuel (the scenario's ``reference.fuel_game_mps``, 521.7 m/s on Fig. 3) falls in the fuel
distribution: the share of runs that spent at least that much. Writes the per-run table
(Parquet, CSV), the CDFs with the seed's numbers marked, and the summary as markdown.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import options
from kalman_vs_infoset.experiments.errors import InputError, runs_text, stats_text

#: the runs use the compiled kernels (the command line announces their compilation)
COMPILED_KERNELS = True
RULES = ("game", "targeted", "lookahead")


def add_arguments(p) -> None:
    options.add_common(p)
    seed = registry.reference("intercept").name  # the set the seed's game reasons with
    options.add_estimators(p, "intercept", [seed], f"{seed}, the paper's")
    p.add_argument(
        "--lookahead",
        type=options.positive_int,
        help="depth k of the look-ahead search, decision steps (default: the scenario's "
        "adversary.lookahead_steps; given, it names the results like --set does)",
    )


def seed_fuel_share(fuel: np.ndarray, seed_fuel: float | None) -> float:
    """Share of runs whose fuel reached the seed's (NaN without a reference or runs)."""
    fuel = fuel[np.isfinite(fuel)]
    if seed_fuel is None or not len(fuel):
        return float("nan")
    return float(np.mean(fuel >= seed_fuel))


def run(args) -> dict[str, Any]:
    # here, not at import: declaring the arguments needs none of the runs' libraries
    import pandas as pd
    from kalman_vs_infoset.experiments import figstyle as fs
    from kalman_vs_infoset.experiments import plots
    from kalman_vs_infoset.experiments.intercept_runs import run_grid
    from kalman_vs_infoset.experiments.report import write_tables, write_text

    key = "adversary.lookahead_steps"
    if args.lookahead is not None:
        if any(o.partition("=")[0].strip() == key for o in args.overrides):
            raise InputError(f"--lookahead and --set {key} both set the depth; give one of them")
        args.overrides = [*args.overrides, f"{key}={args.lookahead}"]
    try:
        sc, runs, seed, out = options.resolve(args)
    except InputError as exc:
        # the field's check, said of the option given (the override is this command's)
        field = f"field '{key}' "
        if args.lookahead is not None and field in str(exc):
            why = str(exc).split(field, 1)[1]
            raise InputError(f"--lookahead {args.lookahead}: {why}") from None
        raise
    t0 = time.perf_counter()
    rows, frames = run_grid(sc, args, runs, seed, out, args.estimators, RULES)
    ref = sc.reference
    for row, df in zip(rows, frames, strict=True):
        ok = df[df["status"] == "ok"] if "status" in df else df.iloc[0:0]
        row["rule"] = row.pop("noise")
        fuel = ok["fuel_mps"].to_numpy(dtype=float) if len(ok) else np.zeros(0)
        row["runs_at_seed_fuel"] = seed_fuel_share(fuel, ref.fuel_game_mps)
        if "adversary_skipped" in ok:
            row["adversary_skipped"] = int(ok["adversary_skipped"].sum())
    table = pd.concat(frames, ignore_index=True)
    stem = out / f"{sc.name}-adversaries"
    files = write_tables(table, stem)
    paper = fs.paper_fig3("game")
    marks = {
        "miss_m": [(ref.miss_game_m, paper)] if ref.miss_game_m else [],
        "fuel_mps": [(ref.fuel_game_mps, paper)] if ref.fuel_game_mps else [],
    }
    fig = plots.cdf_figure(
        table, ["estimator", "noise"], f"{sc.name}: adversary strength, {runs} paired runs", marks
    )
    files += plots.save(fig, out / f"{sc.name}-adversaries-cdf")
    adv = sc.adversary
    result = {
        "scenario": sc.name,
        "runs": runs,
        "seed": seed,
        "seed_fuel_game_mps": ref.fuel_game_mps,
        "seed_miss_game_m": ref.miss_game_m,
        "candidates": adv.candidates,
        "lookahead_steps": adv.lookahead_steps,
        "lookahead_candidates": adv.lookahead_candidates,
        "rows": rows,
        "out": str(out),
        "wall_s": 0.0,
    }
    files.append(write_text(stem.parent / f"{stem.name}.md", table_markdown(result)))
    result["files"] = [str(f) for f in files]
    result["wall_s"] = time.perf_counter() - t0
    return result


def table_markdown(result: dict[str, Any]) -> str:
    """The adversary-strength table (one line per estimator x rule)."""
    seed_fuel = result["seed_fuel_game_mps"]
    share = f"runs >= {seed_fuel:g} m/s" if seed_fuel else "runs >= the paper's fuel"
    head = ["estimator", "rule", "runs", "fuel mean / p50 / p90, m/s",
            "miss mean / p50 / p90, m", share, "truth outside (steps)", "failures"]  # fmt: skip
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in result["rows"]:
        f, m = r["fuel_mps"], r["miss_m"]
        at = r["runs_at_seed_fuel"]
        cells = [
            r["estimator"], r["rule"], str(r["runs"]),
            # "-" where no run gave a value (every run failed)
            stats_text(f, ".1f", ("mean", "p50", "p90")),
            stats_text(m, ".2f", ("mean", "p50", "p90")),
            "n/a" if np.isnan(at) else f"{at:.0%}",
            str(r["truth_outside"]), str(r["failures"]),
        ]  # fmt: skip
        lines.append("| " + " | ".join(cells) + " |")
    k, c = result["lookahead_steps"], result["lookahead_candidates"]
    lines.append("")
    lines.append(
        f"targeted: greedy over {result['candidates']} candidate errors; lookahead: "
        f"{k} steps x {c} candidates a step ({sum(c**j for j in range(1, k + 1))} updates "
        "a decision step and channel)."
    )
    return "\n".join(lines) + "\n"


def render(result: dict[str, Any]) -> str:
    fuel, miss = result["seed_fuel_game_mps"], result["seed_miss_game_m"]
    # a scenario without the paper's numbers (no [reference] table) says nothing of them
    paper = [f"fuel {fuel} m/s"] if fuel is not None else []
    paper += [f"miss {miss} m"] if miss is not None else []
    return (
        f"{result['scenario']}: adversary strength, {runs_text(result['runs'])}, "
        f"seed {result['seed']}"
        + (f" (the paper's game: {', '.join(paper)})" if paper else "")
        + "\n"
        + table_markdown(result)
        + "files:\n"
        + "\n".join("  " + f for f in result["files"])
    )
