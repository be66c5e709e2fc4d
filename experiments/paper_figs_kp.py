"""The figures of seed 003 (Kumkov & Patsko) redrawn from our runs (``paper-figures``).

* ``kp_fig3``: control processes of the Fig. 3 engagement, random | game errors
  (``kp_fig3.toml``, run 0 of its seed), the paper's miss and fuel marked;
* ``kp_fig3_overlay``: ours, not the paper's: the set's, EKF's and UKF's forecast-miss
  intervals on the same realisation (random and game errors side by side);
* ``kp_fig4``: the set at ``t = 1 s`` before and after a bearing and a range
  measurement (``kp_fig3.toml`` with the range finder on, random errors);
* ``kp_fig5``: CDFs of miss and fuel over ``runs`` engagements of the Fig. 5 box, bearings
  only and with the range finder, random and game errors (the paper prints curves
  only; its Fig. 3 single-run numbers are marked, as in ``fig5``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments import figstyle as fs
from kalman_vs_infoset.experiments import plots_intercept, plots_sets
from kalman_vs_infoset.experiments.intercept_runs import miss_floor_m, paper_marks, run_experiment
from kalman_vs_infoset.experiments.scenario import load_scenario
from kalman_vs_infoset.experiments.stats import ok_mean
from kalman_vs_infoset.experiments.traces import intercept_trace

NOISES = ("random", "game")


def _seed_estimator() -> str:
    """The seed's estimator: the registry's reference (the information set)."""
    return registry.reference("intercept").name


def _baselines() -> tuple[str, ...]:
    """The Kalman baselines the set is compared with (the EKF and UKF), by rank."""
    return tuple(r.name for r in registry.with_role("intercept", "baseline"))


def _paper(sc) -> dict[str, tuple[Any, Any]]:
    """The scenario's printed ``(miss_m, fuel_mps)`` per noise (the results file's form)."""
    return {noise: marks[:2] for noise, marks in paper_marks(sc).items()}


def fig3(ctx) -> dict[str, Any]:
    sc = load_scenario(ctx.scenarios / "kp_fig3.toml")
    seed = sc.experiment.seed
    frames = {}
    ref = _seed_estimator()
    for est in (ref, *_baselines()):
        for noise in NOISES:
            frames[est, noise] = intercept_trace(sc, est, noise, seed, [0], sets_every=0)[0]
    steps = pd.concat(frames.values(), ignore_index=True)
    ours = {
        n: (
            float(frames[ref, n]["miss_m"].iloc[0]),
            float(frames[ref, n]["final_fuel_mps"].iloc[0]),
        )
        for n in NOISES
    }
    fig = plots_intercept.control_processes(
        steps[steps["estimator"] == ref], 0, ref, list(NOISES), paper=paper_marks(sc)
    )
    ctx.save(fig, "kp_fig3")
    fig, axes = fs.figure(3, 2, size=(12.0, 8.0), sharex="col")
    for col, noise in enumerate(NOISES):
        plots_intercept.estimator_overlay(steps, 0, noise, axes=axes[:, col])
        axes[0, col].set_title(f"{noise} errors")
    fig.suptitle(
        "kp_fig3 engagement: forecast-miss intervals of the set, EKF and UKF on the "
        "same realisation (interval ends minus the truth's forecast)"
    )
    ctx.save(fig, "kp_fig3_overlay")
    kal = {
        f"{e}_{n}": (
            float(frames[e, n]["miss_m"].iloc[0]),
            float(frames[e, n]["final_fuel_mps"].iloc[0]),
        )
        for e in _baselines()
        for n in NOISES
    }
    return {
        "kp_fig3": {"ours_miss_fuel": ours, "paper_miss_fuel": _paper(sc)},
        "kp_fig3_overlay": {"kalman_miss_fuel": kal},
    }


def fig4(ctx) -> dict[str, Any]:
    sc = load_scenario(ctx.scenarios / "kp_fig3.toml", ["range_finder.enabled=true"])
    steps, sets, _ = intercept_trace(
        sc, _seed_estimator(), "random", sc.experiment.seed, [0], sets_every=1000
    )
    step = int(sets.loc[sets["t_s"] == 1.0, "step"].iloc[0])
    fig = plots_sets.stacked_3d(
        sets,
        0,
        step,
        steps,
        title="kp_fig4: the information set at t = 1 s, bearing and range measured "
        "(node slices; between nodes the set is bounded, not drawn)\n"
        "top: the paper's coordinates (alpha, omega, x); bottom: the same sets in "
        "(alpha, zero-effort miss w = omega x^2 / e, x)",
        closing_speed_mps=float(sc.model.closing_speed_kmps) * 1e3,
    )
    ctx.save(fig, "kp_fig4")
    at = sets[sets["step"] == step]
    return {
        "kp_fig4": {
            "sections_before": int(at[at["phase"] == "prior"]["section"].nunique()),
            "sections_after": int(at[at["phase"] == "posterior"]["section"].nunique()),
            "range_measured_m": float(steps.loc[steps["step"] == step, "range_meas_m"].iloc[0]),
        }
    }


def fig5(ctx) -> dict[str, Any]:
    frames, means = [], {}
    sc = None
    ref = _seed_estimator()
    sc3 = load_scenario(ctx.scenarios / "kp_fig3.toml")
    for fname, variant in (
        ("kp_fig5.toml", "bearings only"),
        ("kp_fig5_range.toml", "bearings + range"),
    ):
        sc = load_scenario(ctx.scenarios / fname)
        for noise in NOISES:
            df = run_experiment(
                sc,
                ref,
                noise,
                ctx.runs,
                sc.experiment.seed,
                ctx.out / "runs",
                workers=1,
                progress=False,
            )
            ok = df[df["status"] == "ok"].assign(variant=variant)
            frames.append(ok)
            means[f"{variant}, {noise}"] = (
                float(ok["miss_m"].mean()),
                float(ok["fuel_mps"].mean()),
            )
    assert sc is not None  # the variants are not empty
    table = pd.concat(frames, ignore_index=True)
    one = _fig3_engagement(ctx)
    fig, axes = fs.figure(1, 2, size=(11.0, 5.8))  # (the legend below the panels)
    panels = (("miss_m", "miss distance, m", 0), ("fuel_mps", "fuel (sum of |impulses|), m/s", 1))
    for col, xlabel, k in panels:
        ax = axes[0, k]
        groups = table.groupby(["variant", "noise"], sort=True)
        for (variant, noise), grp in sorted(groups, key=lambda g: CURVE_NUMBERS[g[0]]):
            v = np.sort(grp[col].to_numpy(dtype=float))
            p = np.arange(1, len(v) + 1) / len(v)
            lw = 1.3 if variant == "bearings only" else 2.8
            number = CURVE_NUMBERS[variant, noise]
            ax.ecdf(
                v,
                **{**fs.line(ref, noise), "lw": lw},
                label=f"{number}: {variant}, {fs.NOISE_WORDS[noise]} (n={len(v)})",
            )
            # each number at its own height (0.2, 0.4, ...): at the medians, close curves'
            # numbers ran into each other ("24")
            mid = min(len(v) - 1, int(len(v) * 0.2 * number))
            ax.annotate(
                str(number),
                (v[mid], p[mid]),
                xytext=(4, -2 if number % 2 else 6),
                textcoords="offset points",
                fontsize=9,
                fontweight="bold",
                color=fs.estimator_colour(ref),
            )
        # the Fig. 3 engagement (one run, kp_fig3.toml), not the Fig. 5 box: above the CDF
        ax.axhline(1.0, color=fs.REFERENCE, lw=0.6, label="CDF = 1; above: one engagement")
        for noise, marker in (("random", "*"), ("game", "D")):
            value = _paper(sc3)[noise][k]
            if value is not None:
                ax.plot(
                    [value], [1.07], marker=marker, ms=9, color=fs.PAPER, ls="none", clip_on=False,
                    label=f"paper Fig. 3 (one engagement), {fs.NOISE_WORDS[noise]}: {value:g}",
                )  # fmt: skip
            ax.plot(
                [one[noise][k]], [1.13], marker=marker, ms=8, mfc="none", ls="none", clip_on=False,
                color=fs.estimator_colour(ref),
                label=f"ours, the same engagement, {fs.NOISE_WORDS[noise]}: {one[noise][k]:.3g}",
            )  # fmt: skip
        if col == "miss_m":
            ax.axvline(
                miss_floor_m(sc),
                color=fs.REFERENCE,
                ls=":",
                lw=1.0,
                label=f"bearing-limited miss scale {miss_floor_m(sc):.2f} m",
            )
            ax.set_xscale("log")
        else:
            floor = ok_mean(table, "fuel_perfect_info_mps")  # None: every run failed
            if floor is not None:
                ax.axvline(
                    floor,
                    color=fs.REFERENCE,
                    ls=":",
                    lw=1.0,
                    label=f"perfect-information fuel (mean) {floor:.1f} m/s",
                )
        ax.set_xlabel(xlabel)
        ax.set_ylabel("fraction of runs (CDF), -")
        ax.set_ylim(0, 1.17)
    # one legend below both panels: inside them it covered curve 3 in (a) and the bottom
    # of the game curves in (b)
    fs.figure_legend(fig, axes[0], fontsize=6.5, ncol=3)
    axes[0, 0].set_title("(a) miss")
    axes[0, 1].set_title("(b) fuel")
    fig.suptitle(
        f"kp_fig5: {ctx.runs} runs per curve, numbered as in the paper\n(thin = bearings "
        "only, thick = with the range finder; solid = random, dashed = game errors)"
    )
    ctx.save(fig, "kp_fig5")
    return {"kp_fig5": {"runs": ctx.runs, "mean_miss_fuel": means, "fig3_engagement": one}}


#: the paper's numbering of the Fig. 5 curves (seed 003, section 6)
CURVE_NUMBERS = {
    ("bearings only", "random"): 1,
    ("bearings + range", "random"): 2,
    ("bearings only", "game"): 3,
    ("bearings + range", "game"): 4,
}


def _fig3_engagement(ctx) -> dict[str, tuple[float, float]]:
    """Our (miss, fuel) of the Fig. 3 engagement (``kp_fig3.toml``, run 0), per noise."""
    sc3 = load_scenario(ctx.scenarios / "kp_fig3.toml")
    out = {}
    for noise in NOISES:
        df = run_experiment(
            sc3, _seed_estimator(), noise, 1, sc3.experiment.seed, ctx.out / "runs", workers=1,
            progress=False,
        )  # fmt: skip
        out[noise] = (float(df["miss_m"].iloc[0]), float(df["fuel_mps"].iloc[0]))
    return out


FIGURES = {
    "kp_fig3": fig3,
    "kp_fig3_overlay": fig3,
    "kp_fig4": fig4,
    "kp_fig5": fig5,
}
