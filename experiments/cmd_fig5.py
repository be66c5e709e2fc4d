"""``kvi fig5``: the statistics of seed 003 Fig. 5 (the main experiment).

Four variants, {bearing only, bearing + range} x {random, game} noise, 50 runs each
on the same seeds; writes the per-run table (Parquet, CSV), a summary table
(markdown), the range finder's effect run by run (the variants share truths and seeds:
:func:`~kalman_vs_infoset.experiments.paired.variants`) and the CDFs of miss and fuel
(PNG, SVG) with the paper's Fig. 3 single-run numbers and the lower bounds marked.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import options

#: the runs use the compiled kernels (the command line announces their compilation)
COMPILED_KERNELS = True

VARIANTS = (("kp_fig5.toml", "bearing only"), ("kp_fig5_range.toml", "bearing + range"))


def seed_estimators() -> list[str]:
    """The seed's estimator, the registry's reference: its files keep the plain names
    (fig5_runs, fig5_cdf, ...)."""
    return [registry.reference("intercept").name]


def add_arguments(p) -> None:
    p.add_argument("--runs", type=options.runs_int, default=50,
                   help="runs per variant (default 50)")  # fmt: skip
    p.add_argument("--seed", type=options.seed_int, help="root seed (default: the scenario's)")
    ref = seed_estimators()
    options.add_estimators(p, "intercept", ref, f"{ref[0]}, the paper's")
    p.add_argument("--scenarios", type=options.non_empty,
                   help="folder of the scenario files (default: the bundled ones)")  # fmt: skip
    p.add_argument("--out", default="results/fig5", help="output directory (default: %(default)s)")
    options.add_runner(p)
    # both variants take them (e.g. a node-set option); the files' stem names them
    options.add_overrides(p, "estimator.infoset.min_split_tau_s=1")


def variant_keys(folder: Path) -> list[str]:
    """The fields (``table.key``) in which the variants' scenario files differ, but for
    their names and descriptions: what makes a variant."""
    from kalman_vs_infoset.experiments.scenario import dotted_fields, load_toml

    a, b = (dotted_fields(load_toml(folder / fname)) for fname, _ in VARIANTS)
    keys = sorted(k for k in a.keys() | b.keys() if a.get(k) != b.get(k))
    return [k for k in keys if k not in ("name", "description")]


def _refuse_variant_overrides(folder: Path, overrides: list[str]) -> None:
    """A ``--set`` of a field that makes a variant would run both variants alike under
    their own labels (``range_finder.enabled=true``: "bearing only" rows with the range
    finder): refused in one line."""
    from kalman_vs_infoset.experiments.errors import InputError

    defining = variant_keys(folder)
    for item in overrides:
        key = item.partition("=")[0].strip()
        if key in defining:
            names = " and ".join(v for _, v in VARIANTS)
            raise InputError(
                f"--set {key}: fig5's variants ({names}) differ in it, each from its own "
                f"file; to change it, run `kvi intercept` or `kvi compare` on a scenario"
            )


def _stem(args) -> str:
    """The files' stem: ``fig5``, with the estimators and seed when not the seed's and
    the ``--set`` overrides (as a scenario's name takes them), so another choice never
    replaces the seed's figure."""
    from kalman_vs_infoset.experiments.scenario import override_suffix

    ests = "" if args.estimators == seed_estimators() else "-" + "+".join(args.estimators)
    overrides = override_suffix(args.overrides)
    return "fig5" + ests + ("" if args.seed is None else f"-s{args.seed}") + overrides


def run(args) -> dict[str, Any]:
    # here, not at import: declaring the arguments needs none of the runs' libraries
    import pandas as pd
    from kalman_vs_infoset.experiments import figstyle as fs
    from kalman_vs_infoset.experiments import paired, plots
    from kalman_vs_infoset.experiments.intercept_runs import miss_floor_m, run_grid
    from kalman_vs_infoset.experiments.report import summary_markdown, write_tables, write_text
    from kalman_vs_infoset.experiments.scenario import load_scenario, scenario_folder
    from kalman_vs_infoset.experiments.stats import ok_mean

    t0 = time.perf_counter()
    _refuse_variant_overrides(scenario_folder(args.scenarios), args.overrides)
    out = options.out_folder(args.out, Path("results/fig5"))
    frames, rows = [], []
    sc = None
    for fname, variant in VARIANTS:
        sc = load_scenario(scenario_folder(args.scenarios) / fname, args.overrides)
        seed = sc.experiment.seed if args.seed is None else args.seed
        summaries, dfs = run_grid(
            sc, args, args.runs, seed, out / "runs", args.estimators, ("random", "game")
        )
        for summary, df in zip(summaries, dfs, strict=True):
            summary["variant"] = variant
            rows.append(summary)
            frames.append(df.assign(variant=variant))
    assert sc is not None  # VARIANTS is not empty
    stem = _stem(args)
    table = pd.concat(frames, ignore_index=True)
    files = write_tables(table, out / f"{stem}_runs")
    ref = sc.reference
    floor = ok_mean(table, "fuel_perfect_info_mps")  # None when every run failed
    # the paper's single engagements of Fig. 3, and the miss scale the last bearings
    # leave (a scale, not a floor: runs end below it)
    given: dict[str, list[tuple[float | None, str]]] = {
        "miss_m": [
            (ref.miss_random_m, fs.paper_fig3("random")),
            (ref.miss_game_m, fs.paper_fig3("game")),
            (miss_floor_m(sc), fs.MISS_SCALE_MARK),
        ],
        "fuel_mps": [
            (ref.fuel_random_mps, fs.paper_fig3("random")),
            (ref.fuel_game_mps, fs.paper_fig3("game")),
            (floor, fs.PERFECT_INFO_MARK),
        ],
    }
    marks: dict[str, list[tuple[float, str]]] = {
        k: [(v, lab) for v, lab in vals if v is not None] for k, vals in given.items()
    }
    by = ["variant", "noise"] + (["estimator"] if len(args.estimators) > 1 else [])
    fig = plots.cdf_figure(
        table,
        by,
        f"Intercept paper, Fig. 5: {', '.join(fs.words(e) for e in args.estimators)}, "
        f"{args.runs} runs per variant",
        marks,
    )
    files += plots.save(fig, out / f"{stem}_cdf")
    md = summary_markdown(rows, ["variant", "noise", "estimator"])
    fuel = "n/a (no successful run)" if floor is None else f"{floor:.1f} m/s (mean over runs)"
    md += f"\nReferences: perfect-information fuel {fuel}, "
    md += f"bearing-limited miss scale {miss_floor_m(sc):.2f} m (eps times the bearing bound "
    md += "at eps: a scale, not a bound; runs can end below it).\n"
    # the range finder's effect run by run (the variants share truths and seeds)
    compared = paired.variants(table, VARIANTS[0][1])
    md += paired.section(compared)
    files.append(write_text(out / f"{stem}_summary.md", md))
    return {
        "runs": args.runs,
        "variants": rows,
        "fuel_perfect_info_mps": floor,
        "miss_floor_m": miss_floor_m(sc),
        "paired": compared,
        "out": str(out),
        "files": [str(f) for f in files],
        "wall_s": time.perf_counter() - t0,
    }


def render(result: dict[str, Any]) -> str:
    from kalman_vs_infoset.experiments import paired
    from kalman_vs_infoset.experiments.report import summary_markdown

    md = summary_markdown(result["variants"], ["variant", "noise", "estimator"])
    md += paired.section(result.get("paired"))
    return md + "files:\n" + "\n".join("  " + f for f in result["files"])
