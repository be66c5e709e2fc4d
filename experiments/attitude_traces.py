"""Traces of the attitude loops: one run replayed with recording, as long-format rows.

Each loop's ``trace(setup, controller, noise, estimator, seed_seq)`` (its
:class:`experiments.attitude_loops.AttitudeLoop`) returns one row
per (step, axis) (:func:`kalman_vs_infoset.experiments.traces.long_rows`) for the run seeded by
``seed_seq`` (the runner's seed of that run id: the same realisation as its row).
Columns common to every loop (units in the names):

* per axis: ``error_deg`` (rotation vector of the body relative to the target),
  ``rate_degps`` (body rate), ``torque_Nm`` (on the body; NaN after the last step),
  ``momentum_Nms`` (wheels, gyrodines or rotors), ``est_error_deg`` (the belief's
  centre, same coordinates);
* per step: ``angle_deg`` (principal error angle), ``rate_norm_degps``,
  ``energy_N2m2s`` (the index ``sum M^T M dt`` so far), ``knowledge_bound_deg`` (the
  belief's attitude bound), ``truth_inside``;
* loop-specific: reaction wheels ``torque_max_Nm``, ``momentum_max_Nms``; gyrodines
  ``command_Nm``, ``xi_deg``/``xi_rate_degps`` (the energy law's auxiliary system),
  ``trace_k_u_N2m2``; gyrostat ``eta`` and ``eta_rate_per_s`` (vector part of the
  error quaternion and its rate), ``psi`` (the switching function), ``u_star_per_s2``,
  ``torque_limit_Nm`` (``alpha_i``), ``disturbance_Nm``, ``guaranteed_time_s``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from kalman_vs_infoset.experiments.traces import long_rows

from kalman_vs_infoset.numerics.rotations import error_quaternion, qlog


def _error_rotvec_deg(q: np.ndarray, q_target: np.ndarray) -> np.ndarray:
    return np.degrees(qlog(error_quaternion(q, q_target)))


def _energy(torque_Nm: np.ndarray, dt_s: float) -> np.ndarray:
    """``sum_{i<k} M_i^T M_i dt`` at every instant ``k`` (``n + 1`` values)."""
    steps = np.sum(np.nan_to_num(torque_Nm) ** 2, axis=-1) * dt_s
    return np.concatenate([[0.0], np.cumsum(steps)])


def trace_rw(config, controller: str, noise: str, estimator: str, seed_seq) -> pd.DataFrame:
    """Reaction-wheel loops (``pd``, ``lqr``; ``config`` an
    :class:`kalman_vs_infoset.experiments.sim.attitude_rw_config.RwScenario`)."""
    from kalman_vs_infoset.experiments.sim.attitude_rw import simulate_runs

    rec: dict = {}
    simulate_runs(config, controller, noise, [np.random.default_rng(seed_seq)], estimator, rec)
    x = rec["states"][:, 0]
    q_t = rec["q_target"]
    n = len(rec["time_s"])
    period = config.simulation.control_period_s
    torque = rec["torque_Nm"][:-1, 0]
    err = _error_rotvec_deg(x[:, 0:4], q_t)
    est = _error_rotvec_deg(rec["estimate"][:, 0, 0:4], q_t)
    wh = config.wheels
    return long_rows(
        rec["time_s"],
        {
            "error_deg": err,
            "rate_degps": np.degrees(x[:, 4:7]),
            "torque_Nm": torque,
            "momentum_Nms": x[:, 7:10],
            "est_error_deg": est,
        },
        {
            "angle_deg": np.linalg.norm(err, axis=-1),
            "rate_norm_degps": np.degrees(np.linalg.norm(x[:, 4:7], axis=-1)),
            "energy_N2m2s": _energy(torque, period),
            "knowledge_bound_deg": np.degrees(rec["knowledge_bound_rad"][:, 0]),
            "truth_inside": np.concatenate([rec["truth_inside"][:, 0], [True]])[:n],
        },
        torque_max_Nm=float(wh.torque_max_Nm),
        momentum_max_Nms=float(wh.momentum_max_Nms),
    )


def trace_cmg(setup, controller: str, noise: str, estimator: str, seed_seq) -> pd.DataFrame:
    """Gyrodine turns (``energy``, ``euler``; seed 000)."""
    from kalman_vs_infoset.experiments.sim.attitude_cmg import simulate_turn

    rng = np.random.default_rng(seed_seq) if noise != "none" else None
    rec: dict = {}
    res = simulate_turn(setup, controller, rng, estimator, noise, rec)
    n = len(res.error_rotvec_deg)
    time_s = np.arange(n) * res.dt_s
    xi = rec["xi"] if len(rec["xi"]) else np.full((n, 6), np.nan)
    per_step = {
        "angle_deg": res.angle_deg,
        "rate_norm_degps": res.rate_norm_degps,
        "energy_N2m2s": _energy(res.torque_Nm, res.dt_s),
        "knowledge_bound_deg": np.degrees(rec["knowledge_bound_rad"]),
        "truth_inside": rec["truth_inside"],
        "trace_k_u_N2m2": res.trace_k_u if res.trace_k_u.size else np.full(n, np.nan),
    }
    return long_rows(
        time_s,
        {
            "error_deg": res.error_rotvec_deg,
            "rate_degps": res.rate_degps,
            "torque_Nm": res.torque_Nm,
            "command_Nm": res.command_Nm,
            "momentum_Nms": res.gyro_momentum_Nms,
            "est_error_deg": np.degrees(rec["estimate"][:, 0:3]),
            "xi_deg": np.degrees(xi[:, 0:3]),
            "xi_rate_degps": np.degrees(xi[:, 3:6]),
        },
        per_step,
        turn_time_s=float(setup.duration_s),
    )


def trace_gyrostat(setup, controller: str, noise: str, estimator: str, seed_seq) -> pd.DataFrame:
    """The gyrostat game law (seed 004)."""
    from kalman_vs_infoset.experiments.sim.gyrostat import simulate_turn
    from kalman_vs_infoset.guidance.attitude.gyrostat import PHI, Q, X, eta_v_rate

    s = setup
    rng = [np.random.default_rng(seed_seq)]
    r = simulate_turn(
        s.gyro,
        s.law,
        s.q0,
        s.q_target,
        s.beta_Nm,
        s.disturbance,
        rng,
        s.cfg,
        estimator,
        record=True,
    )
    # record=True fills the per-instant traces
    assert r.states is not None and r.torques_Nm is not None and r.time_s is not None
    assert r.u_star is not None and r.disturbance_Nm is not None
    assert r.knowledge_bound_rad is not None and r.truth_inside is not None
    assert r.estimate_quat is not None
    st = r.states[0]
    eta = error_quaternion(st[:, Q], s.q_target)
    deta = eta_v_rate(eta, st[:, X])
    err = _error_rotvec_deg(st[:, Q], s.q_target)
    torque = r.torques_Nm[0]
    return long_rows(
        r.time_s,
        {
            "error_deg": err,
            "rate_degps": np.degrees(st[:, X]),
            "torque_Nm": torque,
            "momentum_Nms": st[:, PHI] * s.gyro.rotor_J_kgm2,
            "est_error_deg": _error_rotvec_deg(r.estimate_quat[0], s.q_target),
            "eta": eta[:, :3],
            "eta_rate_per_s": deta,
            "psi": s.law.psi(eta[:, :3], deta),
            "u_star_per_s2": r.u_star[0],
            "disturbance_Nm": r.disturbance_Nm[0],
            "torque_limit_Nm": np.broadcast_to(s.alpha_Nm, st[:, X].shape),
        },
        {
            "angle_deg": np.linalg.norm(err, axis=-1),
            "rate_norm_degps": np.degrees(np.linalg.norm(st[:, X], axis=-1)),
            "energy_N2m2s": _energy(torque, s.cfg.period_s),
            "knowledge_bound_deg": np.degrees(r.knowledge_bound_rad[0]),
            "truth_inside": r.truth_inside[0],
        },
        guaranteed_time_s=float(s.design.tau_s),
    )
