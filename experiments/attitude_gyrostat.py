"""``attitude`` command, controller ``game``: the three-rotor gyrostat of seed 004 (SPEC 2.4).

``run(source, scenario, controller, noise, runs, seed)`` validates the scenario table,
designs a* by the iteration of seed section 3 (:func:`guidance.attitude.game.design_a_star`),
simulates ``runs`` turns batched (:func:`guidance.attitude.gyrostat_loop.simulate_turn`)
and returns the JSON of SPEC 3.1 plus ``guaranteed_time_s`` (seed eq. 2.8).

The law reads ``(q, x)`` from an estimator (``perfect``, ``ukf``, ``box``;
:mod:`experiments.gyrostat_est_loop`). Noise mapping: ``none`` = perfect measurements,
no disturbance; ``random`` = uniform random disturbance torques and bounded uniform
measurement errors; ``game`` = the adversarial disturbance and the same bounded
measurement errors. ``[simulation] disturbance`` overrides the
disturbance kind (``"constant"`` = a vertex of the box held all run).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np

from experiments.errors import InputError
from experiments.gyrostat_est_loop import simulate_turn_est
from experiments.schema import Choice, Num, Str, Vec, validate_table
from experiments.stats import summary_stats
from guidance.attitude.game import GameLaw, design_a_star
from guidance.attitude.gyrostat import Gyrostat, error_quaternion, quat_mul
from guidance.attitude.gyrostat_loop import LoopConfig, LoopResult

NOISES = ("none", "random", "game")
AUTO_DISTURBANCE = {"none": "none", "random": "random", "game": "adversarial"}

TOP_RULES = {"name": Str(), "description": Str(), "controller": Str()}
TABLES = ("gyrostat", "manoeuvre", "simulation")
POS = Num(0.0, open_lo=True)
GYRO_RULES = {
    "A_kgm2": Vec(POS, 3),
    "rotor_J_kgm2": Vec(POS, 3),
    "alpha_Nm": Vec(POS, 3),
    "beta_Nm": Vec(Num(0.0), 3),
    "rho": Vec(Num(0.0, 1.0, open_lo=True, open_hi=True), 3),
}
MANOEUVRE_RULES = {
    "initial_axis": Vec(Num(-1e6, 1e6), 3),
    "initial_angle_deg": Num(0.0, 180.0, open_hi=True),
    "target_quaternion": Vec(Num(-1.0, 1.0), 4),
}
SIM_RULES = {
    "control_period_s": Num(1e-4, 1.0),
    "substeps": Num(1, 100, integer=True),
    "horizon_factor": Num(1.0, 10.0, open_lo=True),
    "settle_angle_deg": Num(0.0, 10.0, open_lo=True),
    "settle_rate_degps": Num(0.0, 10.0, open_lo=True),
    "disturbance": Choice(("auto", "none", "random", "constant", "adversarial")),
    "switching": Choice(("discrete", "sign")),
    "meas_angle_deg": Num(0.0, 1.0),
    "meas_rate_degps": Num(0.0, 1.0),
    "meas_rotor_radps": Num(0.0, 100.0),
}
SIM_DEFAULTS = {
    "control_period_s": 0.05,
    "substeps": 1,
    "horizon_factor": 1.25,
    "settle_angle_deg": 0.05,
    "settle_rate_degps": 0.01,
    "disturbance": "auto",
    "switching": "discrete",
    "meas_angle_deg": 0.001,
    "meas_rate_degps": 0.0001,
    "meas_rotor_radps": 0.01,
}


def parse_scenario(source: str, scenario: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """Validate the scenario (unknown keys are errors); return the three checked tables."""
    unknown = sorted(set(scenario) - set(TOP_RULES) - set(TABLES))
    if unknown:
        allowed = ", ".join(sorted((*TOP_RULES, *TABLES)))
        raise InputError(f"{source}: unknown key '{unknown[0]}' (allowed: {allowed})")
    validate_table(source, {k: v for k, v in scenario.items() if k in TOP_RULES}, TOP_RULES)
    for key in ("gyrostat", "manoeuvre"):
        if key not in scenario:
            raise InputError(f"{source}: missing table '[{key}]'")
    gyro = validate_table(
        source, scenario["gyrostat"], GYRO_RULES, prefix="gyrostat.", required=tuple(GYRO_RULES)
    )
    man = validate_table(
        source,
        scenario["manoeuvre"],
        MANOEUVRE_RULES,
        defaults={"target_quaternion": (0.0, 0.0, 0.0, 1.0)},
        prefix="manoeuvre.",
        required=("initial_axis", "initial_angle_deg"),
    )
    sim = validate_table(
        source, scenario.get("simulation", {}), SIM_RULES, SIM_DEFAULTS, prefix="simulation."
    )
    if np.linalg.norm(man["initial_axis"]) == 0:
        raise InputError(f"{source}: field 'manoeuvre.initial_axis' must be a non-zero vector")
    if abs(np.linalg.norm(man["target_quaternion"]) - 1.0) > 1e-6:
        raise InputError(
            f"{source}: field 'manoeuvre.target_quaternion' must be a unit quaternion (x, y, z, w)"
        )
    try:
        Gyrostat(gyro["A_kgm2"], gyro["rotor_J_kgm2"])
    except ValueError as exc:
        raise InputError(f"{source}: table 'gyrostat': {exc}") from None
    return {"gyrostat": gyro, "manoeuvre": man, "simulation": sim}


def initial_quaternion(man: Mapping[str, Any]) -> np.ndarray:
    """``q0 = q_target (x) (sin(theta/2) e, cos(theta/2))``: the turn to do is theta about e."""
    axis = np.asarray(man["initial_axis"], float)
    half = 0.5 * np.radians(man["initial_angle_deg"])
    rel = np.concatenate([np.sin(half) * axis / np.linalg.norm(axis), [np.cos(half)]])
    return quat_mul(np.asarray(man["target_quaternion"], float), rel)


def _simulate_all(
    gyro: Gyrostat, law: GameLaw, q0, q_t, beta, kind, children, cfg, estimator="perfect"
) -> tuple[list[tuple[LoopResult, dict]], int]:
    """Batched simulation; if the batch raises, rerun one by one and count failures."""
    rngs = [np.random.default_rng(c) for c in children]
    try:
        return [simulate_turn_est(gyro, law, q0, q_t, beta, kind, rngs, cfg, estimator)], 0
    except Exception:  # SPEC 3.1: a run that raises is a failure
        pass
    results, failures = [], 0
    for child in children:
        try:
            rng = [np.random.default_rng(child)]
            results.append(simulate_turn_est(gyro, law, q0, q_t, beta, kind, rng, cfg, estimator))
        except Exception:
            failures += 1
    return results, failures


def run(
    source: str,
    scenario: Mapping[str, Any],
    controller: str,
    noise: str,
    runs: int,
    seed: int,
    estimator: str = "perfect",
) -> dict[str, Any]:
    """Monte Carlo of the gyrostat game turn; the JSON object of SPEC 3.1."""
    t_wall = time.perf_counter()
    if controller != "game":
        raise InputError(f"{source}: controller '{controller}' is not handled here (use 'game')")
    if noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{noise}'")
    if not isinstance(runs, int) or runs < 1:
        raise InputError(f"--runs must be an integer >= 1, got {runs}")
    tables = parse_scenario(source, scenario)
    g, man, sim = tables["gyrostat"], tables["manoeuvre"], tables["simulation"]
    gyro = Gyrostat(g["A_kgm2"], g["rotor_J_kgm2"])
    alpha, beta, rho = (np.asarray(g[k], float) for k in ("alpha_Nm", "beta_Nm", "rho"))

    q_t = np.asarray(man["target_quaternion"], float)
    q0 = initial_quaternion(man)
    eta0 = error_quaternion(q0, q_t)[:3]
    try:
        design = design_a_star(gyro, eta0, alpha, beta, rho)
    except ValueError as exc:
        raise InputError(f"{source}: infeasible gyrostat design: {exc}") from None
    kind = AUTO_DISTURBANCE[noise] if sim["disturbance"] == "auto" else sim["disturbance"]
    noisy = noise in ("random", "game")
    h = sim["control_period_s"]
    cfg = LoopConfig(
        period_s=h,
        substeps=sim["substeps"],
        horizon_s=max(sim["horizon_factor"] * design.tau_s, 10 * h),
        settle_angle_rad=np.radians(sim["settle_angle_deg"]),
        settle_rate_radps=np.radians(sim["settle_rate_degps"]),
        meas_angle_rad=np.radians(sim["meas_angle_deg"]) if noisy else 0.0,
        meas_rate_radps=np.radians(sim["meas_rate_degps"]) if noisy else 0.0,
        meas_rotor_radps=sim["meas_rotor_radps"] if noisy else 0.0,
    )
    law = GameLaw(design.a_star, rho, h, mode=sim["switching"])
    children = np.random.SeedSequence(seed).spawn(runs)
    pairs, failures = _simulate_all(gyro, law, q0, q_t, beta, kind, children, cfg, estimator)
    results = [r for r, _ in pairs]

    def cat(attr: str) -> np.ndarray:
        parts = [getattr(r, attr) for r in results]
        return np.concatenate(parts) if parts else np.empty((0,))

    def count(key: str) -> np.ndarray:
        parts = [c[key] for _, c in pairs]
        return np.concatenate(parts) if parts else np.empty((0,))

    settle = cat("settle_time_s")
    max_u = np.concatenate([r.max_abs_torque_Nm for r in results]) if results else np.zeros((0, 3))
    rows = [
        {
            "run": i,
            "settle_time_s": float(settle[i]),
            "energy_N2m2s": float(cat("energy_N2m2s")[i]),
            "final_angle_deg": float(np.degrees(cat("final_angle_rad")[i])),
            "final_rate_degps": float(np.degrees(cat("final_rate_radps")[i])),
            "max_torque_Nm": float(max_u[i].max()),
            "truth_outside": int(count("truth_outside")[i]),
            "empty_steps": int(count("empty_steps")[i]),
            "mean_knowledge_bound_deg": float(count("mean_knowledge_bound_deg")[i]),
        }
        for i in range(len(settle))
    ]
    tau = design.tau_s
    return {
        "scenario": str(scenario.get("name", source)),
        "controller": controller,
        "noise": noise,
        "runs": runs,
        "seed": seed,
        "disturbance": kind,
        "settle_time_s": summary_stats(settle, finite_only=False),
        "energy_N2m2s": summary_stats(cat("energy_N2m2s"), finite_only=False),
        "final_angle_deg": summary_stats(np.degrees(cat("final_angle_rad")), finite_only=False),
        "final_rate_degps": summary_stats(np.degrees(cat("final_rate_radps")), finite_only=False),
        "max_torque_Nm": float(max_u.max()) if max_u.size else float("nan"),
        "failures": failures,
        "estimator": estimator,
        "truth_outside": int(count("truth_outside").sum()),
        "empty_steps": int(count("empty_steps").sum()),
        "_rows": rows,
        "wall_s": time.perf_counter() - t_wall,
        "guaranteed_time_s": tau,
        "late_runs": int(np.sum(settle > tau)),
        "unsettled_runs": int(np.sum(~np.isfinite(settle))),
        "max_torque_ratio": float((max_u / alpha).max()) if max_u.size else float("nan"),
        "alpha_Nm": alpha.tolist(),
        "a_star": design.a_star.tolist(),
        "beta_star": design.beta_star,
        "torque_bound_Nm": design.torque_bound_Nm.tolist(),
        "a_star_iterations": len(design.iterations),
        "max_rotor_rate_radps": float(cat("max_rotor_rate_radps").max()) if results else 0.0,
        "switching": sim["switching"],
        "control_period_s": h,
    }
