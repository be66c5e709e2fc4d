"""``attitude`` command, controllers ``pd`` (docs/models.md §2.2) and ``lqr`` (docs/models.md §2.3)
on reaction wheels.

The scenario's typed tables (:class:`experiments.sim.attitude_rw_config.RwScenario`,
read by :func:`prepare`), the runner's task over a chunk of runs (:func:`task`, the
loop itself is :func:`kalman_vs_infoset.experiments.sim.attitude_rw.simulate_runs`) and the JSON of
docs/models.md §3.1 from the runs' rows (:func:`summarise`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments.attitude_est import rows_of, run_here
from kalman_vs_infoset.experiments.attitude_loops import AttitudeLoop
from kalman_vs_infoset.experiments.attitude_traces import trace_rw
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.scenario import validate
from kalman_vs_infoset.experiments.sim.attitude_rw import (
    PERFORMANCE,
    estimator_loop,
    make_controller,
    simulate_runs,
)
from kalman_vs_infoset.experiments.sim.attitude_rw_config import RwScenario
from kalman_vs_infoset.experiments.sim.divergence import diverged_runs, resolved
from kalman_vs_infoset.experiments.sim.estimator_loop import NOISES
from kalman_vs_infoset.experiments.stats import estimator_counts, not_settled, summary_stats
from kalman_vs_infoset.guidance.attitude.lqr import LQRController
from kalman_vs_infoset.guidance.attitude.pd import regime_boundaries

CONTROLLERS = ("pd", "lqr")
#: runs per task: the loop is vectorised over the runs of a chunk
CHUNK = 8


def parse_scenario(source: str, scenario: Mapping[str, Any]) -> RwScenario:
    """The typed scenario (``InputError`` of one line naming ``source`` and the field)."""
    return validate(RwScenario, dict(scenario), source)


def prepare(source: str, scenario: Mapping[str, Any], controller: str, noise: str) -> RwScenario:
    """The validated scenario, with the table of ``controller`` and a valid law
    (``InputError`` naming the file and the field)."""
    if controller not in CONTROLLERS:
        raise InputError(f"{source}: controller '{controller}' is not handled here (use pd or lqr)")
    if noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{noise}'")
    config = parse_scenario(source, scenario)
    try:
        config.law_table(controller)
    except ValueError as exc:
        raise InputError(f"{source}: {exc}") from None
    try:
        make_controller(controller, config)
    except ValueError as exc:
        raise InputError(f"{source}: table '{controller}': {exc}") from None
    return config


def task(
    config: RwScenario, controller: str, noise: str, estimator: str, seeds
) -> list[dict[str, float | int]]:
    """The rows of a batch of runs (one per seed), simulated as one loop."""
    metrics = simulate_runs(
        config, controller, noise, [np.random.default_rng(s) for s in seeds], estimator
    )
    return rows_of(metrics, len(seeds))


def summarise(
    config: RwScenario,
    controller: str,
    noise: str,
    estimator: str,
    runs: int,
    seed: int,
    ok,
    failures: int,
) -> dict[str, Any]:
    """The ``attitude`` JSON of docs/models.md §3.1 for ``pd`` and ``lqr`` from the runs' rows."""

    done = resolved(ok)  # a diverged run has no turn to measure: counted apart

    def col(key: str):
        return done[key].to_numpy(dtype=float) if key in done else np.zeros(0)

    settle = col("settle_time_s")

    result: dict[str, Any] = {
        "scenario": config.name,
        "controller": controller,
        "noise": noise,
        "runs": runs,
        "seed": seed,
        "settle_time_s": summary_stats(settle, finite_only=False),
        "energy_N2m2s": summary_stats(col("energy_N2m2s"), finite_only=False),
        "final_angle_deg": summary_stats(col("final_angle_deg"), finite_only=False),
        "final_rate_degps": summary_stats(col("final_rate_degps"), finite_only=False),
        "max_torque_Nm": float(np.max(col("max_torque_Nm"))) if len(done) else None,
        "failures": failures,
        "diverged": diverged_runs(ok),
        "estimator": estimator,
        **estimator_counts(ok),
        "not_settled": not_settled(settle),
    }
    jd = config.body.inertia_kgm2
    if controller == "pd":
        wh, p = config.wheels, config.law_table("pd")
        if np.isfinite(wh.torque_max_Nm) and np.isfinite(wh.momentum_max_Nms):
            axis = np.abs(np.asarray(config.maneuver.axis, dtype=float))
            j_axis = float(jd[int(np.argmax(axis))])
            phi10, phi20 = regime_boundaries(
                p.k_q, p.k_w, j_axis, wh.torque_max_Nm, wh.momentum_max_Nms, p.quaternion_term
            )
            result["regime_boundaries_deg"] = {
                "phi10": np.degrees(phi10),
                "phi20": np.degrees(phi20),
            }
        result["seed_reference"] = {
            "settle_time_s": 35.6,
            "source": "seed 001, Fig. 12 (J not given)",
        }
    else:
        law = make_controller(controller, config)
        assert isinstance(law, LQRController)
        result["constraint_residual"] = law.constraint
        result["gains"] = {"k_w": law.k_w.tolist(), "y": law.y.tolist(), "q_used": list(law.q)}
        if "lyapunov_max_increase" in done and len(done):
            result["lyapunov_max_increase"] = float(np.max(col("lyapunov_max_increase")))
    return result


def run(source, scenario, controller, noise, runs, seed, estimator=None) -> dict[str, Any]:
    """The attitude JSON of these controllers, computed in this process without files."""
    if estimator is None:  # the loops' default: the measurement read as the state
        estimator = registry.first_with_role("attitude", "exact").name
    return run_here(LOOP, source, scenario, controller, noise, runs, seed, estimator)


def build_estimator(config: RwScenario, noise: str, estimator: str):
    """The runs' estimator (every noise's alike)."""
    return estimator_loop(config, estimator)


LOOP = AttitudeLoop(
    name="reaction wheels",
    controllers=CONTROLLERS,
    chunk=CHUNK,
    prepare=prepare,
    task=task,
    summarise=summarise,
    trace=trace_rw,
    estimator=build_estimator,
    performance=PERFORMANCE,
    controller_columns={"lqr": ("lyapunov_max_increase",)},
)
