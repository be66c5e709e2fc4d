"""``kvi attitude-tightness SCENARIO``: the attitude sets' per-axis intervals against the
exact set of states a run's data allow (docs/attitude.md).

One run of a reaction-wheel scenario (controllers ``pd`` and ``lqr``), of the gyrostat
(``game``) or of the gyrodines' turn (``energy``, ``euler``: Resurs-P) per set
estimator, seeded as run 0 of ``kvi attitude SCENARIO --seed SEED`` (the same truth and
errors), simulated to the last requested time. At each requested
time, after the update, each axis of ``delta = (attitude error about the body axes,
rate)`` relative to the truth: the set's interval (its per-axis hull), the exact one
(:mod:`experiments.attitude_exact`: linear programs over the initial state and the
disturbances, linearised along the true trajectory; an inner reference), ``ratio`` = the
set's width over the exact one (an upper bound of the set's excess) and
``exact_inside`` (the exact interval within the set's, to :func:`inside_rel_tol` of its
width: the linearisation's order).
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from kalman_vs_infoset.experiments import options
from kalman_vs_infoset.experiments.errors import InputError, stat_text
from kalman_vs_infoset.experiments.progress import step_progress, steps_shown

#: the attitude runs import the compiled kernels (the command line announces a compilation)
COMPILED_KERNELS = True

#: the set estimators this command compares (a per-axis hull of a set)
SET_FAMILIES = ("box", "zonotope", "ellipsoid")
#: the exact interval may pass a set's side by this share of its width, or by twice the
#: attitude bound in radians if larger: the linearisation's error, second order, is of the
#: perturbation's size in radians relative to the first order (as is the change of frame
#: from the set's reference attitude to the truth's)
INSIDE_REL_TOL = 1e-4


def inside_rel_tol(angle_bound_rad) -> float:
    """The share of a set's width the exact interval may pass its sides by."""
    return max(INSIDE_REL_TOL, 2.0 * float(max(angle_bound_rad)))


AXES = ("attitude_x", "attitude_y", "attitude_z", "rate_x", "rate_y", "rate_z")
#: the loops whose plants the exact reference models: the reaction wheels' controllers, the
#: gyrostat's game law and the gyrodines' laws (their plant is the reaction wheels' rigid
#: body with the delivered torque held over a step: the same equations and RK4)
CONTROLLERS = ("pd", "lqr", "game", "energy", "euler")
#: the gyrodines' controllers
CMG = ("energy", "euler")


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help=options.SCENARIO_HELP)
    p.add_argument("--controller", default=None, choices=CONTROLLERS,
                   help="pd, lqr, game, energy or euler (default: the scenario's "
                   "'controller')")  # fmt: skip
    p.add_argument("--noise", choices=("random", "game", "none"), default="random",
                   help="measurement errors and disturbance (default: %(default)s)")  # fmt: skip
    p.add_argument("--seed", type=options.seed_int, default=0,
                   help="root seed, as for kvi attitude (run 0; default 0)")  # fmt: skip
    options.add_estimators(p, "attitude", list(SET_FAMILIES), ",".join(SET_FAMILIES))
    p.add_argument("--times", type=options.times_s(positive=True), default=[0.1, 1.0, 5.0, 20.0],
                   help="comma-separated times, s, multiples of the control period "
                   "(default 0.1,1,5,20)")  # fmt: skip
    p.add_argument("--out", help="output directory (default: results/attitude_tightness)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress display on stderr (a comparison slower than a few "
                   "seconds shows its linear programs solved)")  # fmt: skip
    options.add_overrides(p, "simulation.control_period_s=0.02")


def _setup(args) -> tuple[Any, str, str]:
    """The typed scenario simulated to the last time, its controller and name
    (``InputError`` of one line for another loop or a time off the period)."""
    from kalman_vs_infoset.experiments.attitude_request import request

    others = [e for e in args.estimators if e not in SET_FAMILIES]
    if others:
        raise InputError(
            f"--estimators: {', '.join(others)} keeps no set to compare; attitude-tightness "
            f"compares the set estimators {', '.join(SET_FAMILIES)}"
        )
    req = request(argparse.Namespace(
        scenario=args.scenario, overrides=args.overrides, controller=args.controller,
        noise=[args.noise], estimators=None, runs=1, seed=args.seed, out=None,
    ))  # fmt: skip
    if req.controller not in CONTROLLERS:  # (a controller a later loop adds)
        raise InputError(
            f"{req.source}: controller {req.controller!r}: the exact reference models the "
            f"loops of {', '.join(CONTROLLERS)}"
        )
    data = json.loads(json.dumps(dict(req.scenario), default=str))  # a deep copy
    setup = req.loop.prepare(req.source, data, req.controller, args.noise)
    if req.controller == "game":
        period, duration = setup.cfg.period_s, setup.cfg.horizon_s
    elif req.controller in CMG:
        period, duration = setup.dt_s, setup.horizon_s
    else:
        period, duration = setup.simulation.control_period_s, setup.simulation.duration_s
    for t in args.times:
        if abs(round(t / period) * period - t) > 1e-9 * max(t, 1.0):
            raise InputError(
                f"--times: {t:g} s is not a multiple of the control period {period:g} s"
            )
        if t > duration - period + 1e-9:
            raise InputError(
                f"--times: {t:g} s is not before the run's end ({duration:g} s, the last "
                f"control sample at {duration - period:g} s)"
            )
    if req.controller in CMG:  # the turn's laws plan its duration: cut by steps (_cmg_run)
        return setup, req.controller, req.name
    # the loop is causal: a run cut after the last time has the same beliefs up to it
    # (at least the shortest duration a scenario may have, and at most its own)
    cut = min(max(max(args.times) + period, 1.0), duration)
    if req.controller == "game":
        cfg = dataclasses.replace(setup.cfg, horizon_s=cut)
        return dataclasses.replace(setup, cfg=cfg), req.controller, req.name
    data["simulation"] = {**data.get("simulation", {}), "duration_s": cut}
    return req.loop.prepare(req.source, data, req.controller, args.noise), req.controller, req.name


def compare(setup, controller: str, noise: str, estimator: str, seed: int, times: list[float],
            solved: Callable[[], None] | None = None) -> dict[str, Any]:  # fmt: skip
    """One run of ``estimator`` and the exact intervals at ``times``: the record of
    :func:`run`'s ``estimators`` entry (``solved``: called after each linear program)."""
    import numpy as np
    from kalman_vs_infoset.experiments import attitude_exact

    rng = np.random.default_rng(_run_seed(seed))
    if controller == "game":
        rec, diverged_s, period, substeps, bounds, plant = _gyrostat_run(setup, estimator, rng)
    elif controller in CMG:
        rec, diverged_s, period, substeps, bounds, plant = _cmg_run(
            setup, controller, noise, estimator, rng, times
        )
    else:
        rec, diverged_s, period, substeps, bounds, plant = _wheels_run(
            setup, controller, noise, estimator, rng
        )
    if np.isfinite(diverged_s):  # a counted outcome: nothing to compare after it
        return {"times": [], "max_ratio_attitude": None, "max_ratio_rate": None,
                "exact_inside": None, "diverged_time_s": float(diverged_s)}  # fmt: skip
    samples = [int(round(t / period)) for t in times]
    t0 = time.process_time()
    exact = attitude_exact.exact_intervals(
        plant, rec, bounds, period, substeps, samples, solved=solved
    )
    lp_cpu_s = time.process_time() - t0
    rows = []
    for t, k in zip(times, samples, strict=True):
        lo, hi = exact[k].lo, exact[k].hi
        s_lo, s_hi = attitude_exact.belief_intervals(rec["states"][k, 0], rec["hull"][k])
        width = hi - lo
        tol = inside_rel_tol(bounds["angle_rad"]) * (s_hi - s_lo)
        inside = bool(np.all(s_lo <= lo + tol) and np.all(s_hi >= hi - tol))
        deg = np.degrees  # the intervals in deg and deg/s, per axis
        rows.append({
            "time_s": t, "sample": k,
            "set_lo_deg": deg(s_lo).tolist(), "set_hi_deg": deg(s_hi).tolist(),
            "exact_lo_deg": deg(lo).tolist(), "exact_hi_deg": deg(hi).tolist(),
            # (None where the exact interval is a point: no ratio to a zero width)
            "ratio": [float(a / b) if b > 0 else None
                      for a, b in zip(s_hi - s_lo, width, strict=True)],
            "exact_inside": inside,
            "truth_inside": bool(rec["truth_inside"][k, 0]),
        })  # fmt: skip
    ratios = np.array([[np.nan if v is None else v for v in r["ratio"]] for r in rows])

    def top(cols: slice) -> float | None:
        finite = ratios[:, cols][np.isfinite(ratios[:, cols])]
        return float(finite.max()) if finite.size else None

    return {
        "inside_rel_tol": inside_rel_tol(bounds["angle_rad"]),
        "times": rows,
        "max_ratio_attitude": top(slice(0, 3)),
        "max_ratio_rate": top(slice(3, 6)),
        "exact_inside": all(r["exact_inside"] for r in rows),
        "lp_cpu_s": lp_cpu_s,
        "diverged_time_s": None,
    }


def _run_seed(seed: int):
    from kalman_vs_infoset.experiments.runner import run_seed

    return run_seed(seed, 0)


def _wheels_run(setup, controller: str, noise: str, estimator: str, rng):
    """One reaction-wheel run recorded: ``(record, diverged time or inf, period,
    substeps, bounds, plant)``."""
    from kalman_vs_infoset.experiments import attitude_exact
    from kalman_vs_infoset.experiments.sim.attitude_rw import (
        body_of,
        estimator_model,
        simulate_runs,
    )

    rec: dict[str, Any] = {}
    out = simulate_runs(setup, controller, noise, [rng], estimator, rec)
    bounds = attitude_exact.model_bounds(estimator_model(setup))
    sim = setup.simulation
    plant = attitude_exact.wheels_plant(body_of(setup)[0])
    return rec, out["diverged_time_s"][0], sim.control_period_s, sim.substeps, bounds, plant


def _gyrostat_run(setup, estimator: str, rng):
    """One gyrostat turn recorded (its rotor rates measured: the plant's extra
    components), in the reaction-wheel record's layout (samples first)."""
    import numpy as np
    from kalman_vs_infoset.experiments import attitude_exact
    from kalman_vs_infoset.experiments.sim.gyrostat import gyrostat_model, simulate_turn

    s, cfg = setup, setup.cfg
    r = simulate_turn(s.gyro, s.law, s.q0, s.q_target, s.beta_Nm, s.disturbance, [rng], cfg,
                      estimator, record=True)  # fmt: skip
    # (the rotor rates' bound floored as the estimators' bounds are: exact ones still bound)
    bounds = attitude_exact.model_bounds(
        gyrostat_model(s.gyro, s.beta_Nm, cfg), extra=np.full(3, max(cfg.meas_rotor_radps, 1e-12))
    )

    def samples_first(a: np.ndarray | None) -> np.ndarray:
        assert a is not None  # recorded
        return np.swapaxes(a, 0, 1)

    rec = {
        "states": samples_first(r.states), "torque_Nm": samples_first(r.torques_Nm),
        "disturbance_Nm": samples_first(r.disturbance_Nm),
        "meas_quat": samples_first(r.meas_quat),
        "meas_rate_radps": samples_first(r.meas_rate_radps),
        "meas_extra": samples_first(r.meas_rotor_radps),
        "hull": r.hull, "truth_inside": samples_first(r.truth_inside),
    }  # fmt: skip
    plant = attitude_exact.gyrostat_plant(s.gyro)
    return rec, r.diverged_time_s[0], cfg.period_s, cfg.substeps, bounds, plant


def _cmg_run(setup, controller: str, noise: str, estimator: str, rng, times: list[float]):
    """One gyrodine turn recorded (seeded as ``kvi attitude``'s run: no generator for
    ``none``), in the reaction-wheel record's layout (samples first, one run); its plant
    is the reaction wheels' rigid body (:func:`guidance.attitude.cmg.rk4_step` integrates
    the same equations by the same RK4, with the delivered torque held over a step)."""
    from kalman_vs_infoset.experiments import attitude_exact
    from kalman_vs_infoset.experiments.sim.attitude_cmg import estimator_model, simulate_turn

    r: dict[str, Any] = {}
    gen = None if noise == "none" else rng
    steps = int(round(max(times) / setup.dt_s)) + 1  # the samples asked for and one more
    res = simulate_turn(setup, controller, gen, estimator, noise, r, steps=steps)
    bounds = attitude_exact.model_bounds(estimator_model(setup, noise))
    keys = ("states", "torque_Nm", "disturbance_Nm", "meas_quat", "meas_rate_radps")
    rec = {k: r[k][:, None] for k in keys}
    rec["truth_inside"] = r["truth_inside"][:, None]
    rec["hull"] = r["hull"]
    plant = attitude_exact.wheels_plant(setup.body)
    return rec, res.diverged_time_s, setup.dt_s, 1, bounds, plant


def run(args) -> dict[str, Any]:
    from kalman_vs_infoset.experiments.files import atomic_write

    t0 = time.perf_counter()
    setup, controller, name = _setup(args)
    out = options.out_folder(args.out, Path("results") / "attitude_tightness")
    # a long comparison (the programs grow with the samples) shows how many programs are
    # solved, as a slow run shows its steps: a bar, or log lines when stderr is a file
    programs = 2 * len(AXES) * len(args.times) * len(args.estimators)
    with (
        steps_shown(not args.no_progress),
        step_progress(programs, f"{name} exact set", unit="program") as shown,
    ):
        count = itertools.count(1)

        def solved() -> None:
            shown(next(count))

        result: dict[str, Any] = {
            "scenario": name, "controller": controller, "noise": args.noise, "seed": args.seed,
            "times_s": list(args.times), "axes": list(AXES),
            "estimators": {
                est: compare(setup, controller, args.noise, est, args.seed, list(args.times),
                             solved)
                for est in args.estimators
            },
        }  # fmt: skip
    compared = [r["exact_inside"] for r in result["estimators"].values() if r["times"]]
    result["exact_inside"] = all(compared) if compared else None
    stem = out / f"{name}-{controller}-{args.noise}-seed{args.seed}"
    path = stem.parent / f"{stem.name}.json"
    body = json.dumps(result, default=float, allow_nan=False) + "\n"
    atomic_write(path, lambda tmp: Path(tmp).write_text(body))
    result["files"] = [str(p) for p in (path, *_figure(result, stem))]
    result["wall_s"] = time.perf_counter() - t0
    return result


def _figure(result: dict[str, Any], stem: Path) -> list[Path]:
    """The width ratios against time, the attitude axes and the rates side by side: one
    colour a family, one marker an axis (PNG and SVG beside the JSON)."""
    from kalman_vs_infoset.experiments import figstyle
    from kalman_vs_infoset.experiments.plots import plt  # Agg backend

    fig, panels = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    markers = ("o", "s", "^")
    # families that coincide (the ellipsoid's hull is often the box's) stay visible: the
    # first drawn widest, the next ones narrower and dashed over it
    styles = [("-", 3.0), ("--", 2.0), (":", 1.5)]
    for f, (est, r) in enumerate(result["estimators"].items()):
        ls, lw = styles[f % len(styles)]
        times = [row["time_s"] for row in r["times"]]
        for half, ax in enumerate(panels):
            for i, marker in enumerate(markers):
                axis = 3 * half + i
                ratio = [row["ratio"][axis] for row in r["times"]]
                ratio = [math.nan if v is None else v for v in ratio]
                label = f"{figstyle.words(est)}, {AXES[axis].split('_')[1]} axis"
                colour = figstyle.estimator_colour(est)
                ax.plot(times, ratio, marker=marker, ls=ls, lw=lw, ms=2 + 2 * lw, color=colour,
                        label=label)  # fmt: skip
    compared = any(r["times"] for r in result["estimators"].values())
    for ax, what in zip(panels, ("attitude error", "rate"), strict=True):
        ax.axhline(1.0, color=figstyle.TRUTH, lw=0.8, label="the exact width")
        if compared:  # (every run diverged: no time to draw, and no log axis without one)
            ax.set_xscale("log")
        ax.set_xlabel("time, s")
        ax.set_ylabel(f"{what}: set width / exact width, -")
        ax.set_title(f"{what} about the body axes")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(
        f"{result['scenario']} ({result['controller']}): the attitude sets against the exact "
        f"set, {result['noise']} noise, seed {result['seed']}",
        fontsize=10,
    )
    return figstyle.save(fig, stem, dpi=130)


def render(result: dict[str, Any]) -> str:
    lines = [
        f"{result['scenario']} ({result['controller']}): set / exact width per axis, "
        f"{result['noise']} noise, seed {result['seed']}",
        "  estimator  t, s |" + "".join(f" {a:>10s}" for a in result["axes"]) + " | inside",
    ]
    for est, r in result["estimators"].items():
        if r["diverged_time_s"] is not None:
            lines.append(
                f"  {est:9s} the loop diverged at {r['diverged_time_s']:g} s: not compared"
            )
            continue
        for row in r["times"]:
            ratios = "".join(f" {stat_text(v, '10.3f')}" for v in row["ratio"])
            lines.append(f"  {est:9s} {row['time_s']:5g} |{ratios} | {row['exact_inside']}")
        lines.append(
            f"  {est:9s} max ratio: attitude {stat_text(r['max_ratio_attitude'], '.3f')}, rate "
            f"{stat_text(r['max_ratio_rate'], '.3f')}; exact inside every time: "
            f"{r['exact_inside']}"
        )
    lines.append("  files: " + ", ".join(result["files"]) + f" ({result['wall_s']:.1f} s)")
    return "\n".join(lines)
