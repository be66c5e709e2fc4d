"""``attitude`` command, controllers ``pd`` (SPEC 2.2) and ``lqr`` (SPEC 2.3) on reaction wheels.

The scenario's tables (validated here: :func:`prepare`), the runner's task over a chunk
of runs (:func:`task`, the loop itself is :func:`experiments.sim.attitude_rw.simulate_runs`)
and the JSON of SPEC 3.1 from the runs' rows (:func:`summarise`).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from typing import Any

import numpy as np

from experiments.attitude_est import run_here
from experiments.errors import InputError
from experiments.schema import Bool, Choice, Num, Str, Vec, validate_table
from experiments.sim.attitude_rw import make_controller, simulate_runs
from experiments.sim.estimator_loop import NOISES
from experiments.stats import summary_stats
from guidance.attitude.lqr import LQRController
from guidance.attitude.pd import regime_boundaries

CONTROLLERS = ("pd", "lqr")
POS = Num(0.0, open_lo=True)
ANY = Num(-1e9, 1e9)
RULES: dict[str, dict[str, Any]] = {
    "body": {"inertia_kgm2": Vec(POS, 3), "axes_rotvec_deg": Vec(Num(-360.0, 360.0), 3)},
    "wheels": {"torque_max_Nm": POS, "momentum_max_Nms": POS},
    "maneuver": {
        "axis": Vec(ANY, 3),
        "angle_deg": Num(0.0, 180.0),
        "initial_rate_degps": Vec(Num(-100.0, 100.0), 3),
        "target_quaternion": Vec(Num(-1.0, 1.0), 4),
        "random_attitude": Bool(),
        "random_rate_degps": Num(0.0, 100.0),
    },
    "simulation": {
        "duration_s": Num(1.0, 1e5),
        "control_period_s": Num(1e-4, 1.0),
        "substeps": Num(1, 100, integer=True),
        "settle_angle_deg": POS,
        "settle_rate_degps": POS,
    },
    "pd": {"k_q": POS, "k_w": POS, "quaternion_term": Choice(("vector", "twice"))},
    "lqr": {
        "q": Vec(POS, 6),
        "r": Vec(POS, 3),
        "enforce_constraint": Bool(),
        "shortest": Bool(),
    },
    "noise": {
        "meas_angle_deg": Num(0.0, 10.0),
        "meas_rate_degps": Num(0.0, 10.0),
        "disturbance_Nm": Num(0.0, 10.0),
    },
}
DEFAULTS: dict[str, dict[str, Any]] = {
    "body": {"axes_rotvec_deg": (0.0, 0.0, 0.0)},
    "wheels": {"torque_max_Nm": np.inf, "momentum_max_Nms": np.inf},
    "maneuver": {
        "axis": (0.0, 0.0, 1.0),
        "angle_deg": 0.0,
        "initial_rate_degps": (0.0, 0.0, 0.0),
        "target_quaternion": (0.0, 0.0, 0.0, 1.0),
        "random_attitude": False,
        "random_rate_degps": 0.0,
    },
    "simulation": {
        "control_period_s": 0.05,
        "substeps": 1,
        "settle_angle_deg": 0.01,
        "settle_rate_degps": 0.01,
    },
    "pd": {"quaternion_term": "vector"},
    "lqr": {"enforce_constraint": True, "shortest": False},
    "noise": {"meas_angle_deg": 0.002, "meas_rate_degps": 0.0005, "disturbance_Nm": 0.0},
}
REQUIRED = {
    "body": ("inertia_kgm2",),
    "simulation": ("duration_s",),
    "pd": ("k_q", "k_w"),
    "lqr": ("q", "r"),
}
TOP = {"name": Str(), "description": Str(), "controller": Str()}


def parse_scenario(source: str, scenario: Mapping[str, Any], controller: str) -> dict[str, Any]:
    """Validate every field (unknown keys are errors); return the checked tables."""
    unknown = sorted(set(scenario) - set(TOP) - set(RULES))
    if unknown:
        allowed = ", ".join(sorted((*TOP, *RULES)))
        raise InputError(f"{source}: unknown key '{unknown[0]}' (allowed: {allowed})")
    validate_table(source, {k: v for k, v in scenario.items() if k in TOP}, TOP)
    needed = {"body", "simulation", controller}
    out: dict[str, Any] = {}
    for key, rules in RULES.items():
        if key not in scenario and key in needed:
            raise InputError(f"{source}: missing table '[{key}]'")
        out[key] = validate_table(
            source,
            scenario.get(key, {}),
            rules,
            DEFAULTS.get(key),
            prefix=f"{key}.",
            required=REQUIRED.get(key, ()) if key in needed else (),
        )
    out["name"] = scenario.get("name", "")
    man = out["maneuver"]
    if np.linalg.norm(man["axis"]) == 0:
        raise InputError(f"{source}: field 'maneuver.axis' must be a non-zero vector")
    if abs(np.linalg.norm(man["target_quaternion"]) - 1.0) > 1e-6:
        raise InputError(f"{source}: field 'maneuver.target_quaternion' must be a unit quaternion")
    return out


#: runs per task: the loop is vectorised over the runs of a chunk
CHUNK = 8
#: most control steps (and RK4 steps) a run may take: the loop keeps the trajectory
MAX_STEPS = 100_000


def prepare(source: str, scenario: Mapping[str, Any], controller: str, noise: str) -> dict:
    """The validated tables (InputError naming the file and the field)."""
    if controller not in CONTROLLERS:
        raise InputError(f"{source}: controller '{controller}' is not handled here (use pd or lqr)")
    if noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{noise}'")
    tables = parse_scenario(source, scenario, controller)
    try:
        make_controller(controller, tables)
    except ValueError as exc:
        raise InputError(f"{source}: table '{controller}': {exc}") from None
    sim = tables["simulation"]
    steps = int(round(sim["duration_s"] / sim["control_period_s"]))
    if steps * sim["substeps"] > MAX_STEPS:
        raise InputError(
            f"{source}: field 'simulation.duration_s' {sim['duration_s']} s at "
            f"'simulation.control_period_s' {sim['control_period_s']} s x {sim['substeps']} "
            f"substeps is {steps * sim['substeps']} steps a run; the limit is {MAX_STEPS}"
        )
    return tables


def task(tables, controller: str, noise: str, estimator: str, seeds) -> list[dict[str, float]]:
    """The rows of a batch of runs (one per seed), simulated as one loop."""
    metrics = simulate_runs(
        tables, controller, noise, [np.random.default_rng(s) for s in seeds], estimator
    )
    keys = [k for k, v in metrics.items() if np.ndim(v) == 1]
    return [{k: float(metrics[k][i]) for k in keys} for i in range(len(seeds))]


def summarise(
    tables, controller: str, noise: str, estimator: str, runs: int, seed: int, ok, failures: int
) -> dict[str, Any]:
    """The ``attitude`` JSON of SPEC 3.1 for ``pd`` and ``lqr`` from the runs' rows."""

    def col(key: str):
        return ok[key].to_numpy(dtype=float) if key in ok else np.zeros(0)

    settle = col("settle_time_s")

    result: dict[str, Any] = {
        "scenario": tables["name"],
        "controller": controller,
        "noise": noise,
        "runs": runs,
        "seed": seed,
        "settle_time_s": summary_stats(settle, finite_only=False),
        "energy_N2m2s": summary_stats(col("energy_N2m2s"), finite_only=False),
        "final_angle_deg": summary_stats(col("final_angle_deg"), finite_only=False),
        "final_rate_degps": summary_stats(col("final_rate_degps"), finite_only=False),
        "max_torque_Nm": float(np.max(col("max_torque_Nm"))) if len(ok) else None,
        "failures": failures,
        "estimator": estimator,
        "truth_outside": int(np.sum(col("truth_outside"))),
        "empty_steps": int(np.sum(col("empty_steps"))),
        "not_settled": int(np.sum(~np.isfinite(settle))),
    }
    jd = tables["body"]["inertia_kgm2"]
    if controller == "pd":
        wh, p = tables["wheels"], tables["pd"]
        if np.isfinite(wh["torque_max_Nm"]) and np.isfinite(wh["momentum_max_Nms"]):
            axis = np.abs(np.asarray(tables["maneuver"]["axis"], dtype=float))
            j_axis = float(jd[int(np.argmax(axis))])
            phi10, phi20 = regime_boundaries(
                p["k_q"], p["k_w"], j_axis, wh["torque_max_Nm"], wh["momentum_max_Nms"],
                p["quaternion_term"],
            )  # fmt: skip
            result["regime_boundaries_deg"] = {
                "phi10": np.degrees(phi10),
                "phi20": np.degrees(phi20),
            }
        result["seed_reference"] = {
            "settle_time_s": 35.6,
            "source": "seed 001, Fig. 12 (J not given)",
        }
    else:
        law = make_controller(controller, tables)
        assert isinstance(law, LQRController)
        result["constraint_residual"] = law.constraint
        result["gains"] = {"k_w": law.k_w.tolist(), "y": law.y.tolist(), "q_used": list(law.q)}
        if "lyapunov_max_increase" in ok:
            result["lyapunov_max_increase"] = float(np.max(col("lyapunov_max_increase")))
    return result


def run(source, scenario, controller, noise, runs, seed, estimator="perfect") -> dict[str, Any]:
    """The attitude JSON of these controllers, computed in this process without files."""
    return run_here(
        sys.modules[__name__], source, scenario, controller, noise, runs, seed, estimator
    )
