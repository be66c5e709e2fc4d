"""Gyrostat game law (seed 004, docs/models.md §2.4) closed through an attitude estimator
(docs/models.md §2.5).

The sampled loop of the seed: every control period ``h`` the law reads ``(q, x)`` from
an estimator's belief (any registered attitude estimator, :mod:`kalman_vs_infoset.estim.registry`:
``perfect``, ``ukf``, ``box``, ...) and the rotor rates from their tachometers,
computes the auxiliary controls ``u*`` (:class:`guidance.attitude.game.GameLaw`, exact
discrete switching) and the rotor torques ``u`` of seed eq. (2.1); ``u`` and the
disturbance ``v`` are held over the period while the plant (1.1)-(1.2) is integrated by
``substeps`` steps of the shared RK4. Runs are batched over a leading axis.

Disturbance kinds (``|v_i| <= beta_i`` always):

* ``"none"``: ``v = 0``;
* ``"random"``: uniform in the box, redrawn every period;
* ``"constant"``: a vertex of the box (random signs per run), body-fixed, whole run;
* ``"adversarial"``: each period the vertex that most delays arrival
  (:func:`guidance.attitude.game.adversarial_disturbance_Nm`, chosen from the true state).

For the estimators the gyrostat is the rigid body of :mod:`estim.attitude.model` with
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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    draw_measurement,
)
from kalman_vs_infoset.experiments.sim.estimator_loop import EstimatorLoop
from kalman_vs_infoset.guidance.attitude.game import GameLaw, adversarial_disturbance_Nm
from kalman_vs_infoset.guidance.attitude.gyrostat import (
    PHI,
    STATE_DIM,
    Gyrostat,
    Q,
    X,
    eta_v_rate,
    linearising_torque,
    rk4_step,
)
from kalman_vs_infoset.guidance.attitude.plant import LoopDiverged, advance_checked
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.rotations import error_angle_rad, error_quaternion

Array = NDArray[np.float64]
DISTURBANCES = ("none", "random", "constant", "adversarial")


@dataclass(frozen=True)
class LoopConfig:
    """Sampling, integration and settle criterion of the closed loop, and the
    estimators' options."""

    period_s: float = 0.05
    substeps: int = 1
    horizon_s: float = 100.0
    settle_angle_rad: float = np.radians(0.05)
    settle_rate_radps: float = np.radians(0.005)
    meas_angle_rad: float = 0.0
    meas_rate_radps: float = 0.0
    meas_rotor_radps: float = 0.0
    #: the scenario's ``[estimator_options.<name>]`` tables (the loop's estimator takes its own)
    estimator_options: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)

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
    truth_outside: Array  # steps with the truth outside the estimator's belief
    empty_steps: Array  # updates that contradicted the model
    unbounded_steps: Array  # predictions whose set was the whole space
    mean_knowledge_bound_deg: Array
    #: when the loop diverged (:mod:`experiments.sim.divergence`), inf if it did not;
    #: the other values of such a run are as of then (its turn's end is not reached)
    diverged_time_s: Array
    time_s: Array | None = None
    states: Array | None = None  # (R, n+1, 10) true states
    torques_Nm: Array | None = None  # (R, n, 3)
    u_star: Array | None = None  # (R, n, 3)
    disturbance_Nm: Array | None = None  # (R, n, 3)
    knowledge_bound_rad: Array | None = None  # (R, n+1) the belief's attitude bound
    truth_inside: Array | None = None  # (R, n+1) the truth in the belief
    estimate_quat: Array | None = None  # (R, n+1, 4) the belief's centre attitude
    #: the measurements (R, n+1, 4 / 3 / 3) and the belief's per-axis hull at each sample
    #: (EstimatorLoop.axis_hull): what experiments.attitude_exact needs
    meas_quat: Array | None = None
    meas_rate_radps: Array | None = None
    meas_rotor_radps: Array | None = None
    hull: list | None = None


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


def gyrostat_model(gyro: Gyrostat, beta_Nm: ArrayLike, cfg: LoopConfig) -> AttitudeModel:
    """The estimators' model of the gyrostat (see the module docstring)."""
    return AttitudeModel(
        np.diag(gyro.A_kgm2),
        np.asarray(beta_Nm, dtype=float),
        max(cfg.meas_angle_rad, 1e-12),
        max(cfg.meas_rate_radps, 1e-12),
        effective_inertia_kgm2=np.diag(gyro.body_moments_kgm2),
    )


def estimator_loop(gyro: Gyrostat, beta_Nm: ArrayLike, cfg: LoopConfig, estimator: str | None):
    """The runs' estimator: ``estimator`` (None: the exact one) on :func:`gyrostat_model`,
    with the loop's options tables."""
    return EstimatorLoop(estimator, gyrostat_model(gyro, beta_Nm, cfg), cfg.estimator_options)


def simulate_turn(
    gyro: Gyrostat,
    law: GameLaw,
    q0: ArrayLike,
    q_target: ArrayLike,
    beta_Nm: ArrayLike,
    disturbance: str,
    rngs: Sequence[np.random.Generator],
    cfg: LoopConfig,
    estimator: str | None = None,
    record: bool = False,
) -> LoopResult:
    """``len(rngs)`` rest-to-rest turns from ``q0`` (4,) or (R, 4) to ``q_target``, batched.

    Rotors start at rest relative to the body (seed: ``phi'(t0) = 0``). Run ``r`` draws
    all its randomness (disturbance, measurement noise) from ``rngs[r]``. With
    ``record`` the result holds the trajectories.
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
    loop = estimator_loop(gyro, beta, cfg, estimator)
    model = loop.model
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
    inside = loop.inside(belief, state)
    outside = (~inside).astype(int)
    bound_sum = np.zeros(runs)
    last_out, energy = np.zeros(runs), np.zeros(runs)
    max_u, max_rotor = np.zeros((runs, 3)), np.zeros(runs)
    if record:
        # NaN after a run that diverged (no instant is left unwritten otherwise)
        states = np.full((runs, n + 1, STATE_DIM), np.nan)
        states[:, 0] = state
        rec_u, rec_us, rec_v = (np.full((runs, n, 3), np.nan) for _ in range(3))
        rec_b, rec_in = np.full((runs, n + 1), np.nan), np.zeros((runs, n + 1), dtype=bool)
        rec_b[:, 0], rec_in[:, 0] = loop.attitude_bound_rad(belief), inside
        rec_e = np.full((runs, n + 1, 4), np.nan)
        rec_e[:, 0] = loop.centre(belief)[:, 0:4]
        rec_q, rec_w, rec_r = (np.full((runs, n + 1, m), np.nan) for m in (4, 3, 3))
        rec_q[:, 0], rec_w[:, 0], rec_r[:, 0] = meas.quat, meas.rate_radps, phid
        hulls = [loop.axis_hull(belief)]

    diverged_s, taken = np.full(runs, np.inf), n  # taken: the steps the belief was updated
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
        before = state
        state, bad = advance_checked(rk4_step, gyro, state, (u, v, dt), cfg.substeps, dt, X)
        if np.any(bad):
            if runs > 1:  # the runner simulates each run of the batch alone
                raise LoopDiverged.of(bad, state[:, X], (k + 1) * h, dt)
            # the run ends at its last resolved state (the values below are of it)
            diverged_s[:], taken, state = (k + 1) * h, k, before
            break
        meas, phid = measure(state)
        belief = loop.step(belief, known, h, meas)
        inside = loop.inside(belief, state)
        outside += ~inside
        bound = loop.attitude_bound_rad(belief)
        bound_sum += bound
        energy += np.sum(u * u, axis=-1) * h
        np.maximum(max_u, np.abs(u), out=max_u)
        np.maximum(max_rotor, np.max(np.abs(state[:, PHI]), axis=-1), out=max_rotor)
        last_out = settle_update(state, q_t, cfg, last_out, (k + 1) * h)
        if record:
            states[:, k + 1] = state
            rec_u[:, k], rec_us[:, k], rec_v[:, k] = u, u_star, v
            rec_b[:, k + 1], rec_in[:, k + 1] = bound, inside
            rec_e[:, k + 1] = loop.centre(belief)[:, 0:4]
            rec_q[:, k + 1], rec_w[:, k + 1], rec_r[:, k + 1] = meas.quat, meas.rate_radps, phid
            hulls.append(loop.axis_hull(belief))

    settled = last_out < n * h
    eta = error_quaternion(state[:, Q], q_t)
    extra: dict[str, Any] = {}
    if record:
        extra = dict(
            time_s=np.arange(n + 1) * h,
            states=states,
            torques_Nm=rec_u,
            u_star=rec_us,
            disturbance_Nm=rec_v,
            knowledge_bound_rad=rec_b,
            truth_inside=rec_in,
            estimate_quat=rec_e,
            meas_quat=rec_q,
            meas_rate_radps=rec_w,
            meas_rotor_radps=rec_r,
            hull=hulls,
        )
    return LoopResult(
        diverged_time_s=diverged_s,
        settle_time_s=np.where(settled, last_out + h, np.inf),
        energy_N2m2s=energy,
        final_angle_rad=error_angle_rad(eta),
        final_rate_radps=np.linalg.norm(state[:, X], axis=-1),
        max_abs_torque_Nm=max_u,
        max_rotor_rate_radps=max_rotor,
        truth_outside=outside,
        empty_steps=loop.empty_steps(belief),
        unbounded_steps=loop.unbounded_steps(belief),
        mean_knowledge_bound_deg=np.degrees(bound_sum / taken) if taken else bound_sum + np.nan,
        **extra,
    )
