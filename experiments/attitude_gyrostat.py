"""``attitude`` command, controller ``game``: the three-rotor gyrostat of seed 004 (SPEC 2.4).

:func:`prepare` validates the scenario table and designs a* by the iteration of seed
section 3 (:func:`guidance.attitude.game.design_a_star`); :func:`task` simulates a chunk
of turns batched (:func:`experiments.sim.gyrostat.simulate_turn`); :func:`summarise`
gives the JSON of SPEC 3.1 plus ``guaranteed_time_s`` (seed eq. 2.8).

The law reads ``(q, x)`` from an estimator (``perfect``, ``ukf``, ``box``;
:mod:`experiments.sim.gyrostat`). Noise mapping: ``none`` = perfect measurements,
no disturbance; ``random`` = uniform random disturbance torques and bounded uniform
measurement errors; ``game`` = the adversarial disturbance and the same bounded
measurement errors. ``[simulation] disturbance`` overrides the
disturbance kind (``"constant"`` = a vertex of the box held all run).
"""

from __future__ import annotations

import sys
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from estim.rotations import error_quaternion, qmul
from experiments.attitude_est import run_here
from experiments.errors import InputError
from experiments.schema import Choice, Num, Str, Vec, validate_table
from experiments.sim.estimator_loop import NOISES
from experiments.sim.gyrostat import LoopConfig, simulate_turn
from experiments.stats import summary_stats
from guidance.attitude.game import GameLaw, design_a_star
from guidance.attitude.gyrostat import Gyrostat

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
    return qmul(np.asarray(man["target_quaternion"], float), rel)


#: runs per task: the loop is vectorised over the runs of a chunk
CHUNK = 8
#: most control steps a run may take
MAX_STEPS = 100_000


@dataclass(frozen=True)
class GyrostatSetup:
    """Everything a batch of turns needs (from a validated scenario)."""

    name: str
    gyro: Gyrostat
    law: GameLaw
    q0: np.ndarray
    q_target: np.ndarray
    alpha_Nm: np.ndarray
    beta_Nm: np.ndarray
    design: Any
    disturbance: str
    cfg: LoopConfig
    switching: str


def prepare(source: str, scenario: Mapping[str, Any], controller: str, noise: str) -> GyrostatSetup:
    """The validated turn (InputError naming the file and the field)."""
    if controller != "game":
        raise InputError(f"{source}: controller '{controller}' is not handled here (use 'game')")
    if noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{noise}'")
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
    horizon = max(sim["horizon_factor"] * design.tau_s, 10 * h)
    if horizon / h * sim["substeps"] > MAX_STEPS:
        raise InputError(
            f"{source}: field 'simulation.control_period_s' {h} s makes the "
            f"{horizon:.0f}-s horizon {int(horizon / h * sim['substeps'])} steps a run; "
            f"the limit is {MAX_STEPS}"
        )
    cfg = LoopConfig(
        period_s=h,
        substeps=sim["substeps"],
        horizon_s=horizon,
        settle_angle_rad=np.radians(sim["settle_angle_deg"]),
        settle_rate_radps=np.radians(sim["settle_rate_degps"]),
        meas_angle_rad=np.radians(sim["meas_angle_deg"]) if noisy else 0.0,
        meas_rate_radps=np.radians(sim["meas_rate_degps"]) if noisy else 0.0,
        meas_rotor_radps=sim["meas_rotor_radps"] if noisy else 0.0,
    )
    law = GameLaw(design.a_star, rho, h, mode=sim["switching"])
    name = str(scenario.get("name", source))
    return GyrostatSetup(name, gyro, law, q0, q_t, alpha, beta, design, kind, cfg, sim["switching"])


def task(setup: GyrostatSetup, controller: str, noise: str, estimator: str, seeds) -> list[dict]:
    """The rows of a batch of turns (one per seed), simulated as one loop."""
    rngs = [np.random.default_rng(c) for c in seeds]
    s = setup
    r = simulate_turn(
        s.gyro, s.law, s.q0, s.q_target, s.beta_Nm, s.disturbance, rngs, s.cfg, estimator
    )
    return [
        {
            "settle_time_s": float(r.settle_time_s[i]),
            "energy_N2m2s": float(r.energy_N2m2s[i]),
            "final_angle_deg": float(np.degrees(r.final_angle_rad[i])),
            "final_rate_degps": float(np.degrees(r.final_rate_radps[i])),
            "max_torque_Nm": float(r.max_abs_torque_Nm[i].max()),
            "max_torque_ratio": float((r.max_abs_torque_Nm[i] / s.alpha_Nm).max()),
            "max_rotor_rate_radps": float(r.max_rotor_rate_radps[i]),
            "truth_outside": int(r.truth_outside[i]),
            "empty_steps": int(r.empty_steps[i]),
            "mean_knowledge_bound_deg": float(r.mean_knowledge_bound_deg[i]),
        }
        for i in range(len(seeds))
    ]


def summarise(
    setup: GyrostatSetup, controller: str, noise: str, estimator: str, runs: int, seed: int, ok,
    failures: int,
) -> dict[str, Any]:  # fmt: skip
    """Monte Carlo of the gyrostat game turn: the JSON object of SPEC 3.1."""

    def col(key: str) -> np.ndarray:
        return ok[key].to_numpy(dtype=float) if key in ok else np.empty((0,))

    settle = col("settle_time_s")
    design, alpha = setup.design, setup.alpha_Nm
    tau = design.tau_s
    return {
        "scenario": setup.name,
        "controller": controller,
        "noise": noise,
        "runs": runs,
        "seed": seed,
        "disturbance": setup.disturbance,
        "settle_time_s": summary_stats(settle, finite_only=False),
        "energy_N2m2s": summary_stats(col("energy_N2m2s"), finite_only=False),
        "final_angle_deg": summary_stats(col("final_angle_deg"), finite_only=False),
        "final_rate_degps": summary_stats(col("final_rate_degps"), finite_only=False),
        "max_torque_Nm": float(col("max_torque_Nm").max()) if len(ok) else float("nan"),
        "failures": failures,
        "estimator": estimator,
        "truth_outside": int(col("truth_outside").sum()),
        "empty_steps": int(col("empty_steps").sum()),
        "guaranteed_time_s": tau,
        "late_runs": int(np.sum(settle > tau)),
        "unsettled_runs": int(np.sum(~np.isfinite(settle))),
        "max_torque_ratio": float(col("max_torque_ratio").max()) if len(ok) else float("nan"),
        "alpha_Nm": alpha.tolist(),
        "a_star": design.a_star.tolist(),
        "beta_star": design.beta_star,
        "torque_bound_Nm": design.torque_bound_Nm.tolist(),
        "a_star_iterations": len(design.iterations),
        "max_rotor_rate_radps": float(col("max_rotor_rate_radps").max()) if len(ok) else 0.0,
        "switching": setup.switching,
        "control_period_s": setup.cfg.period_s,
    }


def run(source, scenario, controller, noise, runs, seed, estimator="perfect") -> dict[str, Any]:
    """The attitude JSON of these controllers, computed in this process without files."""
    return run_here(
        sys.modules[__name__], source, scenario, controller, noise, runs, seed, estimator
    )
