"""Gyrostat game law (seed 004, SPEC 2.4) closed through an attitude estimator (SPEC 2.5).

The same sampled loop as :func:`guidance.attitude.gyrostat_loop.simulate_turn` (law
sampled every ``h``, torques held, fixed-step RK4 of the plant (1.1)-(1.2)), except
that the law reads ``(q, x)`` from an estimator's belief (``perfect``, ``ukf`` or
``box``, :mod:`experiments.attitude_est`) and the rotor rates from their tachometers.

For the estimators the gyrostat is the rigid body of :mod:`estim.attitude_model` with
``J_g = diag(A)``, ``J_b = diag(A - J)``, body torque ``M_u = -u``, disturbance ``v``
(``|v_i| <= beta_i``) and relative rotor momentum ``h = J phi'``: from ``J (phi'' + x')
= u``, ``(A - J) x' = K x x - u + v`` with ``K = A x + J phi'`` is
``J_b x' = M_u + v - x x (J_g x + h)``. ``h`` over a period is enclosed by
``J phi'_meas +- (J b_rotor + h max|u - J x'|)`` with ``|J x'|`` bounded by
``2 J (|K| |x| + |u| + beta)/(A - J)`` (estimates, factor 2 margin).

Measurements (``noisy``): a body-frame error rotation, a rate error and rotor-rate
errors, uniform within ``meas_angle``, ``meas_rate``, ``meas_rotor`` per axis.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from estim.attitude_model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    draw_measurement,
)
from experiments.attitude_est import EstimatorLoop
from guidance.attitude.game import GameLaw
from guidance.attitude.gyrostat import (
    PHI,
    STATE_DIM,
    Gyrostat,
    Q,
    X,
    error_angle_rad,
    error_quaternion,
    rk4_step,
)
from guidance.attitude.gyrostat_loop import (
    DISTURBANCES,
    LoopConfig,
    LoopResult,
    disturbance_at,
    disturbance_draws,
    game_torques,
    settle_update,
)

Array = NDArray[np.float64]


def gyrostat_model(gyro: Gyrostat, beta_Nm: ArrayLike, cfg: LoopConfig) -> AttitudeModel:
    """The estimators' model of the gyrostat (see the module docstring)."""
    return AttitudeModel(
        np.diag(gyro.A_kgm2),
        beta_Nm,
        max(cfg.meas_angle_rad, 1e-12),
        max(cfg.meas_rate_radps, 1e-12),
        effective_inertia_kgm2=np.diag(gyro.body_moments_kgm2),
    )


def simulate_turn_est(
    gyro: Gyrostat,
    law: GameLaw,
    q0: ArrayLike,
    q_target: ArrayLike,
    beta_Nm: ArrayLike,
    disturbance: str,
    rngs: Sequence[np.random.Generator],
    cfg: LoopConfig,
    estimator: str = "perfect",
) -> tuple[LoopResult, dict[str, Array]]:
    """``len(rngs)`` rest-to-rest turns batched; returns the result and estimator counts."""
    if disturbance not in DISTURBANCES:
        raise ValueError(f"disturbance must be one of {DISTURBANCES}")
    runs = len(rngs)
    beta = np.asarray(beta_Nm, dtype=float)
    q_t = np.asarray(q_target, dtype=float) / np.linalg.norm(q_target)
    n = int(np.ceil(cfg.horizon_s / cfg.period_s))
    h, dt = cfg.period_s, cfg.period_s / cfg.substeps
    model = gyrostat_model(gyro, beta, cfg)
    loop = EstimatorLoop(estimator, model)
    noisy = max(cfg.meas_angle_rad, cfg.meas_rate_radps, cfg.meas_rotor_radps) > 0
    a_mom, j_rot, b_mom = gyro.A_kgm2, gyro.rotor_J_kgm2, gyro.body_moments_kgm2

    state = np.zeros((runs, STATE_DIM))
    state[:, Q] = np.broadcast_to(np.asarray(q0, dtype=float), (runs, 4))
    state[:, Q] /= np.linalg.norm(state[:, Q], axis=-1, keepdims=True)
    draws = disturbance_draws(disturbance, rngs, n, beta)

    def measure(s: Array) -> tuple[AttitudeMeasurement, Array]:
        if not noisy:
            return AttitudeMeasurement(s[:, Q], s[:, X]), s[:, PHI].copy()
        meas = draw_measurement(s[:, 0:7], model, list(rngs))
        rot = np.stack([g.uniform(-1.0, 1.0, 3) for g in rngs]) * cfg.meas_rotor_radps
        return meas, s[:, PHI] + rot

    meas, phid = measure(state)
    belief = loop.start(meas)
    outside = (~loop.inside(belief, state)).astype(int)
    bound_sum = np.zeros(runs)
    last_out, energy = np.zeros(runs), np.zeros(runs)
    max_u, max_rotor = np.zeros((runs, 3)), np.zeros(runs)

    for k in range(n):
        est = loop.centre(belief)
        u_star, u = game_torques(gyro, law, est[:, 0:4], est[:, 4:7], phid, q_t)
        v = disturbance_at(disturbance, k, draws, gyro, state, q_t, u_star, law, beta)
        # known inputs for the estimator: M_u = -u, h = J phi' enclosed over the period
        k_est = a_mom * est[:, 4:7] + j_rot * phid
        wn = np.linalg.norm(est[:, 4:7], axis=-1, keepdims=True)
        jxd = 2.0 * j_rot * (np.linalg.norm(k_est, axis=-1, keepdims=True) * wn + np.abs(u) + beta)
        h_err = j_rot * cfg.meas_rotor_radps + h * (np.abs(u) + jxd / b_mom + 1e-12)
        h_mid = j_rot * phid
        known = AttitudeControl(-u, h_mid - h_err, h_mid + h_err)
        for _ in range(cfg.substeps):
            state = rk4_step(gyro, state, u, v, dt)
        if not np.all(np.isfinite(state)):
            raise FloatingPointError("gyrostat state became non-finite")
        meas, phid = measure(state)
        belief = loop.step(belief, known, h, meas)
        outside += ~loop.inside(belief, state)
        bound_sum += loop.attitude_bound_rad(belief)
        energy += np.sum(u * u, axis=-1) * h
        np.maximum(max_u, np.abs(u), out=max_u)
        np.maximum(max_rotor, np.max(np.abs(state[:, PHI]), axis=-1), out=max_rotor)
        last_out = settle_update(state, q_t, cfg, last_out, (k + 1) * h)

    settled = last_out < n * h
    eta = error_quaternion(state[:, Q], q_t)
    result = LoopResult(
        settle_time_s=np.where(settled, last_out + h, np.inf),
        energy_N2m2s=energy,
        final_angle_rad=error_angle_rad(eta),
        final_rate_radps=np.linalg.norm(state[:, X], axis=-1),
        max_abs_torque_Nm=max_u,
        max_rotor_rate_radps=max_rotor,
    )
    counts = {
        "truth_outside": outside,
        "empty_steps": loop.empty_steps(belief),
        "mean_knowledge_bound_deg": np.degrees(bound_sum / n),
    }
    return result, counts
