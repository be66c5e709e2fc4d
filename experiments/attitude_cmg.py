"""``attitude`` command, controllers ``energy`` and ``euler``: Resurs-P (seed 000, docs/models.md
§2.1).

The scenario (typed tables: :func:`prepare`), the runner's task (one turn a run:
:func:`kalman_vs_infoset.experiments.sim.attitude_cmg.one_run`) and the JSON of docs/models.md §3.1
with
``lower_bound_energy_N2m2s`` and diagnostics from the runs' rows (:func:`summarise`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from kalman_vs_infoset.estim import registry
from kalman_vs_infoset.experiments.attitude_cmg_setup import TurnSetup, setup_from_scenario
from kalman_vs_infoset.experiments.attitude_est import run_here
from kalman_vs_infoset.experiments.attitude_loops import AttitudeLoop
from kalman_vs_infoset.experiments.attitude_traces import trace_cmg
from kalman_vs_infoset.experiments.errors import InputError
from kalman_vs_infoset.experiments.sim.attitude_cmg import (
    CONTROLLERS,
    PERFORMANCE,
    SEED_ENERGY_N2M2S,
    estimator_loop,
    lower_bound_energy_N2m2s,
    one_run,
)
from kalman_vs_infoset.experiments.sim.divergence import diverged_runs, resolved
from kalman_vs_infoset.experiments.stats import estimator_counts, not_settled, summary_stats

#: runs per task (each turn is its own loop)
CHUNK = 1


def prepare(source: str, scenario: Mapping[str, Any], controller: str, noise: str) -> TurnSetup:
    """The validated turn (InputError naming the file and the field)."""
    if controller not in CONTROLLERS:
        raise InputError(f"{source}: controller {controller!r} is not handled here {CONTROLLERS}")
    if noise not in ("none", "random", "game"):
        raise InputError(f"{source}: noise must be one of none, random, game, got {noise!r}")
    setup = setup_from_scenario(source, scenario)
    if noise == "game" and setup.game_disturbance_Nm <= 0:
        raise InputError(
            f"{source}: noise 'game' is not defined for controller '{controller}' while "
            "noise.game_disturbance_Nm = 0 (set the adversary's torque bound, N m)"
        )
    return setup


def task(setup: TurnSetup, controller: str, noise: str, estimator: str, seeds) -> list[dict]:
    """The rows of a chunk of runs (one turn each)."""
    return [one_run(setup, controller, noise, s, estimator) for s in seeds]


def summarise(
    setup: TurnSetup, controller: str, noise: str, estimator: str, runs: int, seed: int, ok,
    failures: int,
) -> dict[str, Any]:  # fmt: skip
    """docs/models.md §3.1 ``attitude`` for the controllers ``energy`` and ``euler`` (seed 000)."""

    done = resolved(ok)  # a diverged run has no turn to measure: counted apart

    def col(key: str) -> list:
        return done[key].tolist() if key in done else []

    settle = col("settle_time_s")
    result: dict[str, Any] = {
        "scenario": setup.name,
        "controller": controller,
        "noise": noise,
        "runs": runs,
        "seed": seed,
        # runs that never settled count (inf), as in the other loops: a mean over the
        # settled runs alone would read shorter than the loop's
        "settle_time_s": summary_stats(settle, finite_only=False),
        "not_settled": not_settled(settle),
        # a value that is not finite enters too (as in the other loops), never dropped
        "energy_N2m2s": summary_stats(col("energy_N2m2s"), finite_only=False),
        "final_angle_deg": summary_stats(col("final_angle_deg"), finite_only=False),
        "final_rate_degps": summary_stats(col("final_rate_degps"), finite_only=False),
        "max_torque_Nm": max(col("max_torque_Nm"), default=None),
        "failures": failures,
        "diverged": diverged_runs(ok),
        "estimator": estimator,
        **estimator_counts(ok),
        "lower_bound_energy_N2m2s": lower_bound_energy_N2m2s(setup),
        "seed_energy_N2m2s": SEED_ENERGY_N2M2S[controller],
        "turn_time_s": setup.duration_s,
        "horizon_s": setup.horizon_s,
        "energy_to_horizon_N2m2s": summary_stats(col("energy_horizon")),
        "final_axis_error_deg": summary_stats(col("axis")),
        "final_gyro_momentum_Nms": summary_stats(col("h_end")),
        "peak_gyro_momentum_Nms": max(col("h_peak"), default=None),
        "initial_oscillation_Nm": summary_stats(col("osc")),
        "min_manipulability": min(col("manip"), default=None),
        "singular_steps": int(sum(col("singular"))),
    }
    if controller == "energy":
        result["trace_k_u_decreasing"] = bool(all(col("tr_dec"))) if len(done) else None
        result["max_trace_increment"] = max(col("tr_inc"), default=None)
    return result


def run(source, scenario, controller, noise, runs, seed, estimator=None) -> dict[str, Any]:
    """The attitude JSON of these controllers, computed in this process without files."""
    if estimator is None:  # the loops' default: the measurement read as the state
        estimator = registry.first_with_role("attitude", "exact").name
    return run_here(LOOP, source, scenario, controller, noise, runs, seed, estimator)


LOOP = AttitudeLoop(
    name="gyrodines (Resurs-P)",
    controllers=tuple(CONTROLLERS),
    chunk=CHUNK,
    prepare=prepare,
    task=task,
    summarise=summarise,
    trace=trace_cmg,
    estimator=estimator_loop,
    performance=PERFORMANCE,
)
