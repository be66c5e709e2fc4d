"""``attitude`` command, controllers ``pd`` (SPEC 2.2) and ``lqr`` (SPEC 2.3) on reaction wheels.

``run(source, scenario, controller, noise, runs, seed, estimator)`` validates the scenario,
simulates ``runs`` closed loops as one batch (the plant of
:mod:`guidance.attitude.wheels`: RK4, controller sampled every ``control_period_s``
with the torque held) and returns the JSON of SPEC 3.1.

The controller sees only an estimator's belief (``perfect``, ``ukf`` or ``box``,
:mod:`experiments.attitude_est`; one belief carries the batch of runs), updated every
sample with the measurement; the law is evaluated at ``(q, w)`` of ``belief.centre()``
and the wheel momentum (known on board).

Noise mapping: ``none`` = exact measurements, no disturbance; ``random`` = attitude
(small body-frame rotation, per axis) and rate errors uniform within ``+-sqrt(3)
sigma`` (the scenario's 1-sigma values, same variance), plus a constant disturbance
torque per run uniform in ``[-d, d]`` per axis; ``game`` = the same measurement
errors and a bounded disturbance ``-d sign(M_u)`` that opposes the control every
sample. Random initial attitudes (``maneuver.random_attitude``)
are drawn for every noise setting, from the run's own seed.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

from estim.attitude_model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    draw_measurement,
)
from estim.base import PointBelief
from experiments.attitude_est import EstimatorLoop
from experiments.errors import InputError
from experiments.schema import Bool, Choice, Num, Str, Vec, validate_table
from experiments.stats import summary_stats
from guidance.attitude.lqr import LQRController
from guidance.attitude.pd import QuaternionPD, angle_and_rate_deg, regime_boundaries, settle_time
from guidance.attitude.plant import RigidBody
from guidance.attitude.wheels import ReactionWheels, simulate_closed_loop

CONTROLLERS = ("pd", "lqr")
NOISES = ("none", "random", "game")
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
    man = out["maneuver"]
    if np.linalg.norm(man["axis"]) == 0:
        raise InputError(f"{source}: field 'maneuver.axis' must be a non-zero vector")
    if abs(np.linalg.norm(man["target_quaternion"]) - 1.0) > 1e-6:
        raise InputError(f"{source}: field 'maneuver.target_quaternion' must be a unit quaternion")
    return out


def body_of(tables: Mapping[str, Any]) -> tuple[RigidBody, np.ndarray, np.ndarray]:
    """``J = W diag(J_diag) W^T`` with ``W`` from ``axes_rotvec_deg``; returns (body, J_diag, W)."""
    jd = np.asarray(tables["body"]["inertia_kgm2"], dtype=float)
    w = Rotation.from_rotvec(np.radians(tables["body"]["axes_rotvec_deg"])).as_matrix()
    return RigidBody(w @ np.diag(jd) @ w.T), jd, w


def make_controller(controller: str, tables: Mapping[str, Any]) -> QuaternionPD | LQRController:
    body, jd, w = body_of(tables)
    q_t = tuple(np.asarray(tables["maneuver"]["target_quaternion"]) / 1.0)
    if controller == "pd":
        p = tables["pd"]
        return QuaternionPD(body, p["k_q"], p["k_w"], p["quaternion_term"], q_target=q_t)
    p = tables["lqr"]
    return LQRController(
        body.inertia_kgm2,
        p["q"],
        p["r"],
        enforce_constraint=p["enforce_constraint"],
        q_target=q_t,
        shortest=p["shortest"],
        axes=w,
    )


def initial_states(tables: Mapping[str, Any], rngs: list[np.random.Generator]) -> np.ndarray:
    """Initial plant states ``(runs, 10)``: the maneuver's turn, or random attitudes/rates."""
    man = tables["maneuver"]
    q_t = Rotation.from_quat(man["target_quaternion"])
    axis = np.asarray(man["axis"]) / np.linalg.norm(man["axis"])
    x = np.zeros((len(rngs), 10))
    for k, rng in enumerate(rngs):
        if man["random_attitude"]:
            rot = Rotation.random(rng=rng)
        else:
            rot = q_t * Rotation.from_rotvec(np.radians(man["angle_deg"]) * axis)
        x[k, 0:4] = rot.as_quat()
        x[k, 4:7] = np.radians(man["initial_rate_degps"]) + np.radians(
            man["random_rate_degps"]
        ) * rng.uniform(-1.0, 1.0, 3)
    return x


def estimator_model(tables: Mapping[str, Any]) -> AttitudeModel:
    """What the estimators know: J, the disturbance bound and the measurement bounds.

    The scenario's ``meas_*`` values are 1-sigma; the errors are drawn uniform within
    ``+-sqrt(3) sigma`` (same variance, bounded: admissible for the box estimator).
    """
    body, _, _ = body_of(tables)
    nz = tables["noise"]
    return AttitudeModel(
        body.inertia_kgm2,
        nz["disturbance_Nm"],
        max(np.sqrt(3.0) * np.radians(nz["meas_angle_deg"]), 1e-12),
        max(np.sqrt(3.0) * np.radians(nz["meas_rate_degps"]), 1e-12),
    )


def simulate_runs(
    tables: Mapping[str, Any],
    controller: str,
    noise: str,
    rngs: list[np.random.Generator],
    estimator: str = "perfect",
) -> dict[str, np.ndarray]:
    """Simulate the runs as one batch; per-run metrics.

    The controller reads ``(q, w)`` from the estimator's belief (plus the wheel
    momentum, known on board). Noise ``random``: constant disturbance per run uniform
    in ``[-d, d]``; ``game``: ``-d sign(M_u)`` (opposes the control); both with
    measurement errors uniform within the bounds; ``none``: exact measurements.
    """
    body, _, _ = body_of(tables)
    law = make_controller(controller, tables)
    wh = tables["wheels"]
    wheels = ReactionWheels(wh["torque_max_Nm"], wh["momentum_max_Nms"])
    sim, nz = tables["simulation"], tables["noise"]
    period = sim["control_period_s"]
    x0 = initial_states(tables, rngs)
    n = len(rngs)
    model = estimator_model(tables)
    loop = EstimatorLoop(estimator, model)
    d = nz["disturbance_Nm"]
    const_dist = (
        np.stack([r.uniform(-d, d, 3) for r in rngs]) if noise == "random" else np.zeros((n, 3))
    )
    state: dict[str, Any] = {"belief": None, "ctrl": None, "outside": np.zeros(n, dtype=int)}
    bounds = []

    def measure(x: np.ndarray) -> AttitudeMeasurement:
        if noise == "none":
            return AttitudeMeasurement(x[:, 0:4], x[:, 4:7])
        return draw_measurement(x, model, rngs)

    def control(_t: float, x: np.ndarray) -> np.ndarray:
        meas = measure(x)
        if state["belief"] is None:
            belief = loop.start(meas)
        else:
            belief = loop.step(state["belief"], state["ctrl"], period, meas)
        state["outside"] += ~loop.inside(belief, x)
        bounds.append(loop.attitude_bound_rad(belief))
        x_est = np.concatenate([loop.centre(belief), x[:, 7:10]], axis=-1)
        u = wheels.limit(law.from_belief(PointBelief(x_est)), x[:, 7:10], period)
        state["belief"], state["ctrl"] = belief, AttitudeControl.held(u, x[:, 7:10], period)
        return u

    def disturbance(_t: float, _x: np.ndarray, u: np.ndarray) -> np.ndarray:
        if noise == "game":
            return -d * np.sign(u)
        return const_dist

    traj = simulate_closed_loop(
        body, wheels, control, x0, sim["duration_s"], period, sim["substeps"], disturbance
    )
    angle, rate = angle_and_rate_deg(traj.x, law.q_target)
    settle = np.array(
        [
            settle_time(
                traj.time_s,
                angle[:, k],
                rate[:, k],
                sim["settle_angle_deg"],
                sim["settle_rate_degps"],
            )
            for k in range(n)
        ]
    )
    u = traj.torque_Nm[:-1]
    out = {
        "settle_time_s": settle,
        "energy_N2m2s": np.sum(u**2, axis=(0, 2)) * period,
        "final_angle_deg": angle[-1],
        "final_rate_degps": rate[-1],
        "max_torque_Nm": np.max(np.abs(u), axis=(0, 2)),
        "truth_outside": state["outside"],
        "empty_steps": loop.empty_steps(state["belief"]),
        "mean_knowledge_bound_deg": np.degrees(np.mean(bounds, axis=0)),
    }
    if isinstance(law, LQRController):
        v = law.lyapunov(traj.x)
        out["lyapunov_max_increase"] = np.max(np.diff(v, axis=0), axis=0)
    return out


def per_run_rows(metrics: Mapping[str, np.ndarray], children) -> list[dict[str, Any]]:
    """One row per run (metrics as plain floats) for the Parquet table."""
    keys = [k for k, v in metrics.items() if np.ndim(v) == 1]
    n = len(metrics["settle_time_s"])
    return [{"run": j, **{k: float(metrics[k][j]) for k in keys}} for j in range(n)]


def run(
    source: str,
    scenario: Mapping[str, Any],
    controller: str,
    noise: str,
    runs: int,
    seed: int,
    estimator: str = "perfect",
) -> dict[str, Any]:
    """The ``attitude`` command for ``pd`` and ``lqr`` (JSON of SPEC 3.1)."""
    if controller not in CONTROLLERS:
        raise InputError(f"{source}: controller '{controller}' is not handled here (use pd or lqr)")
    if noise not in NOISES:
        raise InputError(f"--noise must be one of {', '.join(NOISES)}, got '{noise}'")
    if not isinstance(runs, int) or runs < 1:
        raise InputError(f"--runs must be an integer >= 1, got {runs}")
    tables = parse_scenario(source, scenario, controller)
    try:
        make_controller(controller, tables)
    except ValueError as exc:
        raise InputError(f"{source}: table '{controller}': {exc}") from None
    t0 = time.perf_counter()
    children = np.random.SeedSequence(seed).spawn(runs)
    rngs = [np.random.default_rng(c) for c in children]
    failures = 0
    try:
        metrics = simulate_runs(tables, controller, noise, rngs, estimator)
    except Exception:  # noqa: BLE001 - rerun one by one and count the runs that raise
        parts = []
        for c in children:
            try:
                rng = [np.random.default_rng(c)]
                parts.append(simulate_runs(tables, controller, noise, rng, estimator))
            except Exception:  # noqa: BLE001
                failures += 1
        keys = parts[0].keys() if parts else ("settle_time_s",)
        metrics = {k: np.concatenate([p[k] for p in parts]) if parts else np.zeros(0) for k in keys}
    settle = metrics["settle_time_s"]
    result: dict[str, Any] = {
        "scenario": scenario.get("name", str(source)),
        "controller": controller,
        "noise": noise,
        "runs": runs,
        "seed": seed,
        "settle_time_s": summary_stats(settle, finite_only=False),
        "energy_N2m2s": summary_stats(metrics.get("energy_N2m2s", np.zeros(0)), finite_only=False),
        "final_angle_deg": summary_stats(
            metrics.get("final_angle_deg", np.zeros(0)), finite_only=False
        ),
        "final_rate_degps": summary_stats(
            metrics.get("final_rate_degps", np.zeros(0)), finite_only=False
        ),
        "max_torque_Nm": float(np.max(metrics["max_torque_Nm"])) if failures < runs else None,
        "failures": failures,
        "estimator": estimator,
        "truth_outside": int(np.sum(metrics.get("truth_outside", 0))),
        "empty_steps": int(np.sum(metrics.get("empty_steps", 0))),
        "not_settled": int(np.sum(~np.isfinite(settle))),
        "wall_s": time.perf_counter() - t0,
    }
    result["_rows"] = per_run_rows(metrics, children if not failures else [])
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
        if "lyapunov_max_increase" in metrics:
            result["lyapunov_max_increase"] = float(np.max(metrics["lyapunov_max_increase"]))
    return result
