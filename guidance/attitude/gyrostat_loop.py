"""Closed loop of the gyrostat game law (seed 004, SPEC 2.4): sampled controller, fixed-step RK4.

Each control period ``h``: the estimator (a :class:`estim.PerfectEstimator` fed the
measurement, noisy or not) gives the belief, the controller reads ``belief.centre()``,
computes the auxiliary controls ``u*`` (:class:`guidance.attitude.game.GameLaw`, exact
discrete switching) and the rotor torques ``u`` of seed eq. (2.1); ``u`` and the
disturbance ``v`` are held over the period while the plant (1.1)-(1.2) is integrated by
``substeps`` classical RK4 steps. Runs are batched over a leading axis.

Disturbance kinds (``|v_i| <= beta_i`` always):

* ``"none"``: ``v = 0``;
* ``"random"``: uniform in the box, redrawn every period;
* ``"constant"``: a vertex of the box (random signs per run), body-fixed, whole run;
* ``"adversarial"``: each period the vertex that most delays arrival
  (:func:`guidance.attitude.game.adversarial_disturbance_Nm`, chosen from the true state).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from estim import PerfectEstimator, PointBelief
from guidance.attitude.game import GameLaw, adversarial_disturbance_Nm
from guidance.attitude.gyrostat import (
    PHI,
    STATE_DIM,
    Gyrostat,
    Q,
    X,
    error_angle_rad,
    error_quaternion,
    eta_v_rate,
    linearising_torque,
    quat_mul,
    rk4_step,
)

Array = NDArray[np.float64]
DISTURBANCES = ("none", "random", "constant", "adversarial")


@dataclass(frozen=True)
class LoopConfig:
    """Sampling, integration and settle criterion of the closed loop."""

    period_s: float = 0.05
    substeps: int = 1
    horizon_s: float = 100.0
    settle_angle_rad: float = np.radians(0.05)
    settle_rate_radps: float = np.radians(0.005)
    meas_angle_rad: float = 0.0
    meas_rate_radps: float = 0.0
    meas_rotor_radps: float = 0.0

    def __post_init__(self) -> None:
        if not self.period_s > 0 or not self.horizon_s > self.period_s:
            raise ValueError("need 0 < period_s < horizon_s")
        if self.substeps < 1:
            raise ValueError("substeps must be >= 1")
        if not (self.settle_angle_rad > 0 and self.settle_rate_radps > 0):
            raise ValueError("settle tolerances must be positive")
        if min(self.meas_angle_rad, self.meas_rate_radps, self.meas_rotor_radps) < 0:
            raise ValueError("measurement-noise bounds must be >= 0")


@dataclass(frozen=True)
class LoopResult:
    """Per-run outcomes (arrays over runs) and, if recorded, the trajectories."""

    settle_time_s: Array  # inf when not settled by the horizon
    energy_N2m2s: Array  # sum u^T u h
    final_angle_rad: Array
    final_rate_radps: Array
    max_abs_torque_Nm: Array  # (R, 3)
    max_rotor_rate_radps: Array
    time_s: Array | None = None
    states: Array | None = None  # (R, n+1, 10) true states
    torques_Nm: Array | None = None  # (R, n, 3)
    u_star: Array | None = None  # (R, n, 3)
    disturbance_Nm: Array | None = None  # (R, n, 3)


def _measurement_noise(rng: np.random.Generator, n: int, cfg: LoopConfig) -> Array:
    """Bounded uniform measurement errors: rotation vector, body rate, rotor rate; (n, 9)."""
    bounds = np.repeat([cfg.meas_angle_rad, cfg.meas_rate_radps, cfg.meas_rotor_radps], 3)
    return rng.uniform(-1.0, 1.0, size=(n, 9)) * bounds


def disturbance_draws(disturbance: str, rngs, n: int, beta: NDArray) -> dict[str, NDArray]:
    """Per-run disturbance draws: a sequence (``random``) or a vertex (``constant``)."""
    if disturbance == "random":
        return {"seq": np.stack([g.uniform(-1.0, 1.0, size=(n, 3)) for g in rngs]) * beta}
    if disturbance == "constant":
        return {"const": np.stack([g.choice([-1.0, 1.0], size=3) for g in rngs]) * beta}
    return {}


def disturbance_at(
    disturbance: str, k: int, draws: dict[str, NDArray], gyro: Gyrostat, state: NDArray,
    q_t: NDArray, u_star: NDArray, law: GameLaw, beta: NDArray,
) -> NDArray:  # fmt: skip
    """The disturbance torque of step ``k`` (the adversary reads the true state)."""
    if disturbance == "none":
        return np.zeros((state.shape[0], 3))
    if disturbance == "random":
        return draws["seq"][:, k]
    if disturbance == "constant":
        return draws["const"]
    eta = error_quaternion(state[:, Q], q_t)
    return adversarial_disturbance_Nm(gyro, eta, eta_v_rate(eta, state[:, X]), u_star, law, beta)


def game_torques(
    gyro: Gyrostat, law: GameLaw, q_hat: NDArray, x_hat: NDArray, phid_hat: NDArray, q_t: NDArray
) -> tuple[NDArray, NDArray]:
    """``(u*, u)`` from an estimated state: the game law and the linearising torques (2.1)."""
    eta_hat = error_quaternion(q_hat, q_t)
    u_star = law.u_star(eta_hat[:, :3], eta_v_rate(eta_hat, x_hat))
    return u_star, linearising_torque(gyro, eta_hat, x_hat, phid_hat, u_star)


def settle_update(
    state: NDArray, q_t: NDArray, cfg: LoopConfig, last_out: NDArray, t_s: float
) -> NDArray:
    """Time of the last sample outside the settle tolerances (per run)."""
    eta = error_quaternion(state[:, Q], q_t)
    inside = (error_angle_rad(eta) <= cfg.settle_angle_rad) & (
        np.linalg.norm(state[:, X], axis=-1) <= cfg.settle_rate_radps
    )
    return np.where(inside, last_out, t_s)


def simulate_turn(
    gyro: Gyrostat,
    law: GameLaw,
    q0: ArrayLike,
    q_target: ArrayLike,
    beta_Nm: ArrayLike,
    disturbance: str,
    rngs: Sequence[np.random.Generator],
    cfg: LoopConfig,
    record: bool = False,
) -> LoopResult:
    """Simulate ``len(rngs)`` rest-to-rest turns from ``q0`` (4,) or (R, 4) to ``q_target``.

    Rotors start at rest relative to the body (seed: ``phi'(t0) = 0``). Run ``r`` draws
    all its randomness (disturbance, measurement noise) from ``rngs[r]``.
    """
    if disturbance not in DISTURBANCES:
        raise ValueError(f"disturbance must be one of {DISTURBANCES}")
    if abs(law.period_s - cfg.period_s) > 1e-12:
        raise ValueError("the law's period must equal the loop's control period")
    runs = len(rngs)
    beta = np.asarray(beta_Nm, dtype=float)
    q_t = np.asarray(q_target, dtype=float) / np.linalg.norm(q_target)
    n = int(np.ceil(cfg.horizon_s / cfg.period_s))
    h, dt = cfg.period_s, cfg.period_s / cfg.substeps

    state = np.zeros((runs, STATE_DIM))
    state[:, Q] = np.broadcast_to(np.asarray(q0, dtype=float), (runs, 4))
    state[:, Q] /= np.linalg.norm(state[:, Q], axis=-1, keepdims=True)

    noisy = max(cfg.meas_angle_rad, cfg.meas_rate_radps, cfg.meas_rotor_radps) > 0
    noise = np.stack([_measurement_noise(g, n, cfg) for g in rngs]) if noisy else None
    if noise is not None:  # attitude error as a small body-frame rotation, precomputed
        noise_q = Rotation.from_rotvec(noise[..., 0:3].reshape(-1, 3)).as_quat()
        noise_q = noise_q.reshape(runs, n, 4)
    draws = disturbance_draws(disturbance, rngs, n, beta)

    estimator = PerfectEstimator()
    belief = PointBelief(state)
    last_out = np.zeros(runs)
    energy = np.zeros(runs)
    max_u = np.zeros((runs, 3))
    max_rotor = np.zeros(runs)
    if record:
        states = np.empty((runs, n + 1, STATE_DIM))
        states[:, 0] = state
        rec_u, rec_us, rec_v = (np.empty((runs, n, 3)) for _ in range(3))

    for k in range(n):
        meas = state.copy()
        if noise is not None:
            meas[:, Q] = quat_mul(state[:, Q], noise_q[:, k])
            meas[:, X] += noise[:, k, 3:6]
            meas[:, PHI] += noise[:, k, 6:9]
        belief = estimator.update(belief, meas)
        est = belief.centre()
        u_star, u = game_torques(gyro, law, est[:, Q], est[:, X], est[:, PHI], q_t)
        v = disturbance_at(disturbance, k, draws, gyro, state, q_t, u_star, law, beta)

        for _ in range(cfg.substeps):
            state = rk4_step(gyro, state, u, v, dt)
        if not np.all(np.isfinite(state)):
            raise FloatingPointError("gyrostat state became non-finite")
        energy += np.sum(u * u, axis=-1) * h
        np.maximum(max_u, np.abs(u), out=max_u)
        np.maximum(max_rotor, np.max(np.abs(state[:, PHI]), axis=-1), out=max_rotor)
        last_out = settle_update(state, q_t, cfg, last_out, (k + 1) * h)
        if record:
            states[:, k + 1] = state
            rec_u[:, k], rec_us[:, k], rec_v[:, k] = u, u_star, v

    settled = last_out < n * h
    eta = error_quaternion(state[:, Q], q_t)
    extra = {}
    if record:
        extra = dict(
            time_s=np.arange(n + 1) * h,
            states=states,
            torques_Nm=rec_u,
            u_star=rec_us,
            disturbance_Nm=rec_v,
        )
    return LoopResult(
        settle_time_s=np.where(settled, last_out + h, np.inf),
        energy_N2m2s=energy,
        final_angle_rad=error_angle_rad(eta),
        final_rate_radps=np.linalg.norm(state[:, X], axis=-1),
        max_abs_torque_Nm=max_u,
        max_rotor_rate_radps=max_rotor,
        **extra,
    )
