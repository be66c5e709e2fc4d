"""``attitude`` command, controller ``game``: the three-rotor gyrostat of seed 004 (docs/models.md
§2.4).

:func:`prepare` reads the scenario's typed tables
(:class:`kalman_vs_infoset.experiments.sim.gyrostat_config.GyrostatScenario`) and designs a* by the
iteration of seed section 3
(:meth:`kalman_vs_infoset.experiments.sim.gyrostat_config.GyrostatSetup.from_config`); :func:`task`
simulates a chunk of turns batched (:func:`experiments.sim.gyrostat.simulate_turn`);
:func:`summarise` gives the JSON of docs/models.md §3.1 plus ``guaranteed_time_s`` (seed eq. 2.8).

The law reads ``(q, x)`` from an estimator (``perfect``, ``ukf``, ``box``;
:mod:`kalman_vs_infoset.experiments.sim.gyrostat`). Noise mapping: ``none`` = perfect measurements,
no disturbance; ``random`` = uniform random disturbance torques and bounded uniform
measurement errors; ``game`` = the adversarial disturbance and the same bounded
measurement errors. ``[simulation] disturbance`` overrides the
disturbance kind (``"constant"`` = a vertex of the box held all run).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments.attitude_est import rows_of, run_here
from kalman_vs_infoset.experiments.attitude_loops import AttitudeLoop
from kalman_vs_infoset.experiments.attitude_traces import trace_gyrostat
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.scenario import validate
from kalman_vs_infoset.experiments.sim.divergence import diverged_rows, diverged_runs, resolved
from kalman_vs_infoset.experiments.sim.estimator_loop import NOISES
from kalman_vs_infoset.experiments.sim.gyrostat import estimator_loop, simulate_turn
from kalman_vs_infoset.experiments.sim.gyrostat_config import (  # noqa: F401 - initial_quaternion re-exported
    GyrostatScenario,
    GyrostatSetup,
    initial_quaternion,
)
from kalman_vs_infoset.experiments.stats import estimator_counts, not_settled, summary_stats

#: runs per task: the loop is vectorised over the runs of a chunk
CHUNK = 8
#: the values of a turn's end: no value for a run whose loop diverged before it
PERFORMANCE = (
    "settle_time_s", "energy_N2m2s", "final_angle_deg", "final_rate_degps", "max_torque_Nm",
    "max_torque_ratio", "max_rotor_rate_radps",
)  # fmt: skip


def parse_scenario(source: str, scenario: Mapping[str, Any]) -> GyrostatScenario:
    """The typed scenario (``InputError`` of one line naming ``source`` and the field)."""
    return validate(GyrostatScenario, dict(scenario), source)


def prepare(source: str, scenario: Mapping[str, Any], controller: str, noise: str) -> GyrostatSetup:
    """The validated turn with a* designed (InputError naming the file and the field)."""
    if controller != "game":
        raise InputError(f"{source}: controller '{controller}' is not handled here (use 'game')")
    if noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{noise}'")
    config = parse_scenario(source, scenario)
    try:
        return GyrostatSetup.from_config(config, noise, source)
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from None


def task(setup: GyrostatSetup, controller: str, noise: str, estimator: str, seeds) -> list[dict]:
    """The rows of a batch of turns (one per seed), simulated as one loop."""
    rngs = [np.random.default_rng(c) for c in seeds]
    s = setup
    r = simulate_turn(
        s.gyro, s.law, s.q0, s.q_target, s.beta_Nm, s.disturbance, rngs, s.cfg, estimator
    )
    metrics = {
        "settle_time_s": r.settle_time_s,
        "energy_N2m2s": r.energy_N2m2s,
        "final_angle_deg": np.degrees(r.final_angle_rad),
        "final_rate_degps": np.degrees(r.final_rate_radps),
        "max_torque_Nm": r.max_abs_torque_Nm.max(axis=-1),
        "max_torque_ratio": (r.max_abs_torque_Nm / s.alpha_Nm).max(axis=-1),
        "max_rotor_rate_radps": r.max_rotor_rate_radps,
        "truth_outside": np.asarray(r.truth_outside, dtype=int),
        "empty_steps": np.asarray(r.empty_steps, dtype=int),
        "unbounded_steps": np.asarray(r.unbounded_steps, dtype=int),
        "mean_knowledge_bound_deg": r.mean_knowledge_bound_deg,
    }
    # a run whose loop diverged: no value for its turn's end (experiments.sim.divergence)
    return rows_of(diverged_rows(metrics, r.diverged_time_s, PERFORMANCE), len(seeds))


def summarise(
    setup: GyrostatSetup, controller: str, noise: str, estimator: str, runs: int, seed: int, ok,
    failures: int,
) -> dict[str, Any]:  # fmt: skip
    """Monte Carlo of the gyrostat game turn: the JSON object of docs/models.md §3.1."""

    done = resolved(ok)  # a diverged run has no turn to measure: counted apart

    def col(key: str) -> np.ndarray:
        return done[key].to_numpy(dtype=float) if key in done else np.empty((0,))

    settle = col("settle_time_s")
    never = not_settled(settle)
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
        "max_torque_Nm": float(col("max_torque_Nm").max()) if len(done) else float("nan"),
        "failures": failures,
        "diverged": diverged_runs(ok),
        "estimator": estimator,
        **estimator_counts(ok),
        "guaranteed_time_s": tau,
        "late_runs": int(np.sum(settle > tau)),
        "not_settled": never,
        "unsettled_runs": never,  # the same count, by the name of this loop's earlier files
        "max_torque_ratio": float(col("max_torque_ratio").max()) if len(done) else float("nan"),
        "alpha_Nm": alpha.tolist(),
        "a_star": design.a_star.tolist(),
        "beta_star": design.beta_star,
        "torque_bound_Nm": design.torque_bound_Nm.tolist(),
        "a_star_iterations": len(design.iterations),
        "max_rotor_rate_radps": float(col("max_rotor_rate_radps").max()) if len(done) else 0.0,
        "switching": setup.switching,
        "control_period_s": setup.cfg.period_s,
    }


def run(source, scenario, controller, noise, runs, seed, estimator=None) -> dict[str, Any]:
    """The attitude JSON of these controllers, computed in this process without files."""
    if estimator is None:  # the loops' default: the measurement read as the state
        estimator = registry.first_with_role("attitude", "exact").name
    return run_here(LOOP, source, scenario, controller, noise, runs, seed, estimator)


def build_estimator(setup: GyrostatSetup, noise: str, estimator: str):
    """The runs' estimator (every noise's alike)."""
    return estimator_loop(setup.gyro, setup.beta_Nm, setup.cfg, estimator)


LOOP = AttitudeLoop(
    name="three-rotor gyrostat",
    controllers=("game",),
    chunk=CHUNK,
    prepare=prepare,
    task=task,
    summarise=summarise,
    trace=trace_gyrostat,
    estimator=build_estimator,
    performance=PERFORMANCE,
)
