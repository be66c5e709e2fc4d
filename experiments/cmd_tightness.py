"""``kvi tightness SCENARIO.toml``: a set's interval of the miss
against the exact one.

One lateral channel of the scenario in the auxiliary model of seed 003 (the model the
exact reference solves, :mod:`kalman_vs_infoset.estim.intercept.exact_reference`), run by
the simulation layer (:mod:`kalman_vs_infoset.experiments.sim.channel`: truth, noise
kinds, guidance).

The estimator under test gets the same measurements; with ``--guided`` the seed's law
issues impulses from it, which the truth and the reference receive too.

At each requested time (after the bearing, before the impulse): the estimator's interval of ``w =
omega x^2 / e_nom``, the exact one (inner values attained by consistent trajectories; the outer
certificate beside them), ``ratio`` = estimator width / exact inner width (an upper bound of the
true ratio; ``ratio_outer`` uses the outer width, a lower bound), ``exact_inside`` (the
exact inner interval within the estimator's, to 1e-6 of its width and 4 ulps of the
values, each side rounded apart: false means the estimator misses a consistent state),
``exact_outer_inside`` (the outer certificate within it too: true proves that no
consistent state is missed; where only the inner interval is inside, an estimator's
end lies in the reference's own gap, at most its tolerance wide), ``exact_converged``
(that gap within ``max(0.01 m, 1e-4 of the width)`` on both sides; false: the
reference spent its LP budget first) and the truth's ``w``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.estim.intercept.costs import ZeroEffortMiss
from kalman_vs_infoset.experiments.errors import InputError, stat_text
from kalman_vs_infoset.experiments.files import atomic_write
from kalman_vs_infoset.experiments.noise import NOISE_KINDS
from kalman_vs_infoset.experiments.options import (
    SCENARIO_HELP,
    add_estimators,
    out_folder,
    seed_int,
    times_s,
)

if TYPE_CHECKING:
    from kalman_vs_infoset.estim.intercept.exact_reference import PriorBox

# the exact reference (scipy's LP), the scenario and the channel loop (the compiled
# kernels) are imported by the functions that use them: parsing needs none of them

#: the sets run the compiled kernels (the command line announces their compilation)
COMPILED_KERNELS = True

INSIDE_REL_TOL = 1e-6
#: the exact reference's gap between its inner and outer ends (of the inner width, m)
EXACT_REL_TOL, EXACT_ABS_TOL_M = 1e-4, 0.01
#: ulps of the values by which two ends computed apart may differ and still agree
ULPS_APART = 4
FIELDS = ("set_lo_m", "set_hi_m", "exact_lo_m", "exact_hi_m", "exact_outer_lo_m",
          "exact_outer_hi_m", "truth_w_m", "ratio", "ratio_outer", "exact_inside",
          "exact_outer_inside", "exact_converged", "exact_x0_lo_m", "exact_x0_hi_m", "lp_s", "n_lp",
          "n_simplified", "reason")  # fmt: skip


#: the switch noise's default switch time (s)
DEFAULT_SWITCH_S = 50.0


def switch_s(args) -> float:
    """The switch time of ``--noise switch`` (:data:`DEFAULT_SWITCH_S` unless given);
    ``--switch-s`` with another noise, or after the last requested time (the noise
    would never switch), is refused in one line."""
    if args.switch_s is None:
        return DEFAULT_SWITCH_S
    if args.noise != "switch":
        raise InputError(f"--switch-s applies to --noise switch only (got --noise {args.noise})")
    if args.switch_s >= max(args.times):
        raise InputError(
            f"--switch-s {args.switch_s:g} s is not before the last time {max(args.times):g} s: "
            "the errors would never switch"
        )
    return args.switch_s


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a non-negative time in s, got {text!r}")
    return value


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help=SCENARIO_HELP)
    add = p.add_argument
    add(
        "--noise",
        choices=NOISE_KINDS,
        default="random",
        help="bearing errors (default: %(default)s)",
    )
    add("--seed", type=seed_int, help="seed (default: the scenario's)")
    add("--times", type=times_s(positive=False), default=[10.0, 30.0, 60.0, 90.0, 95.0],
        help="comma-separated times, s (default 10,30,60,90,95)")  # fmt: skip
    add("--guided", action="store_true", help="the paper's guidance law issues impulses")
    reference = registry.reference("intercept").name
    add_estimators(p, "intercept", [reference], f"{reference}; one estimator under test", most=1)
    add("--switch-s", type=_positive, default=None,
        help=f"--noise switch only: time of the switch from +a to -a, s (default "
        f"{DEFAULT_SWITCH_S:g}; another time is in the JSON and the file names)")  # fmt: skip
    add("--kinematic-margin", action="store_true",
        help="keep the set's kinematic margin (off by default: the truth here is the "
        "auxiliary model, which has no kinematic term; with it on, the set models the "
        "nonlinear motion, widens a prior box wide against its range by the Cartesian "
        "states' exact map, spreads an impulse k by its geometry, k cos^2 of the "
        "bearing, and may leave out auxiliary-model states)")  # fmt: skip
    add("--out", help="output directory (default: results/tightness)")
    add("--set", action="append", default=[], metavar="TABLE.KEY=VALUE", dest="overrides",
        help="override a scenario field (as for intercept)")  # fmt: skip


def _prior(sc) -> PriorBox:
    from kalman_vs_infoset.estim.intercept.exact_reference import PriorBox

    e = sc.estimator

    def metres(km: tuple[float, float]) -> tuple[float, float]:
        return km[0] * 1e3, km[1] * 1e3

    return PriorBox(
        metres(e.y_km), metres(e.vy_kmps), metres(e.x_km), metres(sc.closing_speed_kmps)
    )


def simulate(sc, args, seed: int, switch: float) -> tuple[list[dict[str, Any]], float]:
    """Run the channel to the last requested time: one record per requested time, and
    the fuel spent (m/s)."""
    from kalman_vs_infoset.experiments.sim.channel import run_channel

    model, dt = sc.channel_model(), sc.model.dt_s
    steps = [round(t / dt) for t in args.times]
    off = [t for t, k in zip(args.times, steps, strict=True) if abs(k * dt - t) > 1e-9]
    if off:
        raise InputError(f"--times: {off[0]:g} s is not a multiple of the step {dt:g} s")
    slowest_mps = -max(sc.truth.vx_kmps) * 1e3  # the truth closes at -vx
    last_s = (sc.truth.x_km[1] * 1e3 - model.eps_m) / slowest_mps if slowest_mps > 0 else math.inf
    if min(args.times) > last_s + dt:  # nothing to record: an empty table and figure
        raise InputError(
            f"--times: {min(args.times):g} s and later are after the end of every run (the "
            f"range reaches model.eps_km by {last_s:.1f} s at the latest)"
        )
    prior = _prior(sc)

    def observe(belief, est, hist, truth_w):
        return _evaluate(model, prior, est, belief, hist, truth_w)

    records, fuel = run_channel(
        sc, args.estimators[0], args.noise, seed, steps, observe, args.guided, switch
    )
    return [
        records.get(k, {"truth_w_m": None, "reason": "truth under eps"}) | {"time_s": t}
        for t, k in zip(args.times, steps, strict=True)
    ], fuel


def _evaluate(model, prior, est, belief, hist, truth_w) -> dict[str, Any]:
    from kalman_vs_infoset.estim.intercept.exact_reference import (
        ExactChannelSet,
        History,
        InconsistentHistory,
    )

    rec: dict[str, Any] = {"truth_w_m": truth_w, "reason": ""}
    # slices the set outer-simplified so far (sound, slightly wider than exact)
    rec["n_simplified"] = int(getattr(belief, "n_simplified", 0))
    if belief.is_empty:
        rec["reason"] = f"estimator's set {getattr(belief, 'status', 'empty')}"
        return rec
    ext = belief.extremes(ZeroEffortMiss(model))
    history = History(
        np.array(hist["t"]), np.array(hist["a"]), np.array([*hist["k"], 0.0]), np.array(hist["d"])
    )
    try:
        ref = ExactChannelSet(model, prior, history).extremes(
            rel_tol=EXACT_REL_TOL, abs_tol=EXACT_ABS_TOL_M
        )
    except InconsistentHistory:
        rec["reason"] = "exact set empty (the data contradict the model)"
        return rec
    except ValueError as exc:  # a scenario outside the reference's model
        raise InputError(f"exact reference: {exc}") from None
    set_w, inner, outer = (
        ext.max_value - ext.min_value,
        ref.inner_hi - ref.inner_lo,
        ref.outer_hi - ref.outer_lo,
    )
    # both intervals are rounded, apart: a set of zero width (a point prior) read 1 ulp
    # inside an exact end it holds (the rule of the sets' own ``contains``)
    ends = (ext.min_value, ext.max_value, ref.inner_lo, ref.inner_hi)
    tol = INSIDE_REL_TOL * set_w + ULPS_APART * float(np.spacing(max(map(abs, ends))))

    def within(lo: float, hi: float) -> bool:
        return lo >= ext.min_value - tol and hi <= ext.max_value + tol

    inside = within(ref.inner_lo, ref.inner_hi)
    # the outer certificate inside too: a proof that no consistent state is missed
    proven = within(ref.outer_lo, ref.outer_hi)
    # the reference closed its gap on both sides (else it spent its LP budget first)
    gap = max(EXACT_ABS_TOL_M, EXACT_REL_TOL * inner)
    closed = ref.outer_hi - ref.inner_hi <= gap and ref.inner_lo - ref.outer_lo <= gap
    rec.update(
        set_lo_m=ext.min_value, set_hi_m=ext.max_value, exact_lo_m=ref.inner_lo,
        exact_hi_m=ref.inner_hi, exact_outer_lo_m=ref.outer_lo, exact_outer_hi_m=ref.outer_hi,
        ratio=set_w / inner if inner > 0 else None,
        ratio_outer=set_w / outer if outer > 0 else None,
        exact_inside=bool(inside),
        exact_outer_inside=bool(proven),
        exact_converged=bool(closed),
        exact_x0_lo_m=ref.x0_interval_m[0], exact_x0_hi_m=ref.x0_interval_m[1],
        lp_s=ref.wall_s, n_lp=ref.n_lp,
    )  # fmt: skip
    return rec


def run(args) -> dict[str, Any]:
    from kalman_vs_infoset.experiments.scenario import load_scenario
    from kalman_vs_infoset.experiments.sim.channel import auxiliary_model_options

    sc = auxiliary_model_options(
        load_scenario(args.scenario, args.overrides, auxiliary_truth=True), args.kinematic_margin,
        names=sorted({registry.reference("intercept").name, args.estimators[0]}),
    )  # fmt: skip
    seed = sc.experiment.seed if args.seed is None else args.seed
    out = out_folder(args.out, Path("results") / "tightness")
    switch = switch_s(args)  # checked before any run
    t0 = time.perf_counter()
    recs, fuel = simulate(sc, args, seed, switch)
    ratios = [r["ratio"] for r in recs if r.get("ratio") is not None]
    result: dict[str, Any] = {
        "scenario": sc.name,
        "noise": args.noise,
        "seed": seed,
        "estimator": args.estimators[0],
        "guided": bool(args.guided),
        "kinematic_margin": bool(args.kinematic_margin),
        **({"switch_s": switch} if args.noise == "switch" else {}),
        "times_s": [r["time_s"] for r in recs],
        **{f: [r.get(f) for r in recs] for f in FIELDS},
        "max_ratio": max(ratios) if ratios else None,
        "fuel_mps": fuel,
    }
    stem = out / (
        f"{sc.name}-tightness-{args.estimators[0]}-{args.noise}-seed{seed}"
        + ("-guided" if args.guided else "")
        # the set with its kinematic margin is another set: its own files
        + ("-margin" if args.kinematic_margin else "")
        # another switch time is another experiment: its own files (the default's keep
        # their names)
        + (f"-switch{switch:g}s" if switch != DEFAULT_SWITCH_S else "")
    )
    result["files"] = [str(p) for p in _write(result, stem)]
    result["wall_s"] = time.perf_counter() - t0
    return result


#: the width ratio the node set keeps with bearings only, drawn as a reference line
TARGET_RATIO = 1.03


def _write(result: dict[str, Any], stem: Path) -> list[Path]:
    from kalman_vs_infoset.experiments import figstyle
    from kalman_vs_infoset.experiments.plots import plt  # Agg backend

    fig, (ax, ax_r) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    cols = ("times_s", "set_lo_m", "set_hi_m", "exact_lo_m", "exact_hi_m", "truth_w_m", "ratio")
    rows = [r for r in zip(*(result[c] for c in cols), strict=True) if r[-1] is not None]
    if rows:
        t, slo, shi, elo, ehi, w, ratio = (np.array(c, float) for c in zip(*rows, strict=True))
        dx = 0.012 * (np.ptp(t) + 10.0)  # the two bars side by side
        colour = figstyle.estimator_colour(result["estimator"])
        label = figstyle.words(result["estimator"])
        ax.vlines(t - dx, slo - w, shi - w, lw=6, color=colour, alpha=0.7, label=f"{label}: set")
        ax.vlines(t + dx, elo - w, ehi - w, lw=6, color=figstyle.REFERENCE, alpha=0.8,
                  label="exact set (LP)")  # fmt: skip
        ax.plot(t, 0 * t, "_", color=figstyle.TRUTH, ms=14, label="truth")
        ax.set_yscale("symlog", linthresh=10.0)
        ax_r.plot(t, ratio, "o-", color=colour, label=f"{label} / exact width")
        ax_r.axhline(1.0, color=figstyle.TRUTH, lw=0.8)
        # the node set's bound on unseen seeds with bearings only (docs/infoset.md)
        ax_r.axhline(TARGET_RATIO, color=figstyle.REFERENCE, ls="--", lw=0.8,
                     label=f"{TARGET_RATIO:g}: the node set's target")  # fmt: skip
    ax.set_xlabel("time, s")
    ax.set_ylabel("zero-effort miss w minus the truth's, m")
    ax_r.set_xlabel("time, s")
    ax_r.set_ylabel("width ratio (estimator / exact), -")
    for a in (ax, ax_r):
        a.grid(True, alpha=0.3)
        if rows:  # (no time with a ratio: nothing drawn, no legend to warn about)
            a.legend(fontsize=8, loc="best")
    fig.suptitle(  # the estimator and the noise in words, as the legends name them
        f"{result['scenario']}: {figstyle.words(result['estimator'])} against the exact "
        f"set, {figstyle.NOISE_WORDS.get(result['noise'], result['noise'])}, seed "
        f"{result['seed']}" + (", guided" if result["guided"] else ""),
        fontsize=10,
    )
    paths = figstyle.save(fig, stem, dpi=130)
    paths.append(stem.parent / f"{stem.name}.json")
    body = json.dumps({k: v for k, v in result.items() if k != "files"}, default=float)
    atomic_write(paths[2], lambda tmp: Path(tmp).write_text(body + "\n"))
    return paths


def render(result: dict[str, Any]) -> str:
    head = (
        f"{result['scenario']}: {result['estimator']} vs exact set, {result['noise']} noise, "
        f"seed {result['seed']}{', guided' if result['guided'] else ''}"
    )
    lines = [head, "  t, s | estimator w, m        | exact w, m            | truth w, m "
             "| ratio | inside | LP, s"]  # fmt: skip
    for i, t in enumerate(result["times_s"]):
        if result["set_lo_m"][i] is None:
            lines.append(f"{t:6.1f} | {result['reason'][i]}")
            continue
        lines.append(
            f"{t:6.1f} | {result['set_lo_m'][i]:10.2f} {result['set_hi_m'][i]:10.2f} | "
            f"{result['exact_lo_m'][i]:10.2f} {result['exact_hi_m'][i]:10.2f} | "
            # (no ratio when the exact interval has no width: "-")
            f"{result['truth_w_m'][i]:10.2f} | {stat_text(result['ratio'][i], '5.3f'):>5s} | "
            f"{str(result['exact_inside'][i]):6s} | {result['lp_s'][i]:5.1f}"
        )
    top = stat_text(result["max_ratio"], ".4f")  # "-": no time compared
    lines.append(f"  max ratio {top}; files: " + ", ".join(result["files"]))
    lines.append(f"  ({result['wall_s']:.1f} s)")
    return "\n".join(lines)
