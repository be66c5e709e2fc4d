"""``kvi fig5``: the statistics of seed 003 Fig. 5 (the main experiment).

Four variants, {bearing only, bearing + range} x {random, game} noise, 50 runs each
on the same seeds; writes the per-run table (Parquet, CSV), a summary table
(markdown) and the CDFs of miss and fuel (PNG, SVG) with the paper's Fig. 3
single-run numbers and the lower bounds marked.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import pandas as pd
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import plots
from kalman_vs_infoset.experiments.cmd_intercept import positive_int, seed_int
from kalman_vs_infoset.experiments.report import summary_markdown, write_tables, write_text
from kalman_vs_infoset.experiments.runner import run_experiment, summarise
from kalman_vs_infoset.experiments.scenario import load_scenario, scenario_folder

VARIANTS = (("kp_fig5.toml", "bearing only"), ("kp_fig5_range.toml", "bearing + range"))


def add_arguments(p) -> None:
    p.add_argument("--runs", type=positive_int, default=50, help="runs per variant (default 50)")
    p.add_argument("--seed", type=seed_int, help="root seed (default: the scenario's)")
    p.add_argument("--estimator", choices=registry.names("intercept"), default="infoset")
    p.add_argument("--workers", type=positive_int, help="local worker processes (default: CPUs)")
    p.add_argument("--scheduler", help="Dask scheduler address")
    p.add_argument("--scenarios", help="folder of the scenario files (default: the bundled ones)")
    p.add_argument("--out", default="results/fig5", help="output directory")
    p.add_argument("--no-progress", action="store_true")


def miss_floor_m(sc) -> float:
    """Miss floor set by the last bearings: bound at eps times eps (docs/models.md §1.8)."""
    m = sc.model
    return m.bearing_bound_end_rad * m.eps_km * 1e3


def run(args) -> dict[str, Any]:
    t0 = time.perf_counter()
    out = Path(args.out)
    frames, rows = [], []
    sc = None
    for fname, variant in VARIANTS:
        sc = load_scenario(scenario_folder(args.scenarios) / fname)
        seed = sc.experiment.seed if args.seed is None else args.seed
        for noise in ("random", "game"):
            t1 = time.perf_counter()
            df = run_experiment(
                sc, args.estimator, noise, args.runs, seed, out / "runs",
                args.workers, args.scheduler, not args.no_progress,
            )  # fmt: skip
            summary = summarise(df, sc, args.estimator, noise, seed, time.perf_counter() - t1)
            summary["variant"] = variant
            rows.append(summary)
            frames.append(df.assign(variant=variant))
    table = pd.concat(frames, ignore_index=True)
    files = write_tables(table, out / "fig5_runs")
    ref = sc.reference
    floor = float(table["fuel_perfect_info_mps"].mean())
    marks = {
        "miss_m": [
            (ref.miss_random_m, "seed Fig. 3 random"),
            (ref.miss_game_m, "seed Fig. 3 game"),
            (miss_floor_m(sc), "bearing floor"),
        ],
        "fuel_mps": [
            (ref.fuel_random_mps, "seed Fig. 3 random"),
            (ref.fuel_game_mps, "seed Fig. 3 game"),
            (floor, "perfect info (mean)"),
        ],
    }
    marks = {k: [(v, lab) for v, lab in vals if v is not None] for k, vals in marks.items()}
    fig = plots.cdf_figure(
        table,
        ["variant", "noise"],
        f"Seed 003 Fig. 5: {args.estimator}, {args.runs} runs per variant",
        marks,
    )
    files += plots.save(fig, out / "fig5_cdf")
    md = summary_markdown(rows, ["variant", "noise", "estimator"])
    md += f"\nLower bounds: perfect-information fuel {floor:.1f} m/s (mean over runs), "
    md += f"bearing-limited miss floor {miss_floor_m(sc):.2f} m.\n"
    files.append(write_text(out / "fig5_summary.md", md))
    return {
        "runs": args.runs,
        "variants": rows,
        "fuel_perfect_info_mps": floor,
        "miss_floor_m": miss_floor_m(sc),
        "out": str(out),
        "files": [str(f) for f in files],
        "wall_s": time.perf_counter() - t0,
    }


def render(result: dict[str, Any]) -> str:
    md = summary_markdown(result["variants"], ["variant", "noise", "estimator"])
    return md + "files:\n" + "\n".join("  " + f for f in result["files"])
