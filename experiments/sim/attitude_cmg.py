"""Resurs-P turn with six gyrodines: the energy-saving law and the Euler-axis baseline.

Seed 000 (docs/models.md §2.1). :func:`simulate_turn` runs one turn from a :class:`TurnSetup`
(built from the typed scenario :class:`experiments.sim.attitude_cmg_config.CmgScenario`
by :meth:`TurnSetup.from_config`);
:func:`one_run` is its row of the runner's table.

Closed loop, each step of ``dt``: the truth ``(q, w, h)`` is measured (noise
``random``/``game``: a body-frame error rotation and a rate error, uniform within
``+-sqrt(3)`` times the seed's standard deviations), passed through an estimator
(any registered attitude estimator, :mod:`kalman_vs_infoset.estim.registry`), the controller reads
``X = (rotvec(R_target^-1 R), w)`` at the belief's centre and asks for a torque, the
gyrodine cluster produces it (``cmg.CmgCluster.step``) and the common plant is advanced
by a fixed-step RK4 with the delivered torque; the plant's ``h`` equals the cluster
momentum at the step ends.

Reading followed for the seed's angles: ``(phi1, phi2, phi3)`` is the rotation vector
of the body relative to the final attitude. The auxiliary system moves along a straight
line in these coordinates (its C_i acts identically on the three axes), i.e. about
a fixed axis, for which ``d(rotvec)/dt = w`` holds exactly, so the seed's linear
kinematics ``phi' = w`` is exact along the reference motion.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    draw_measurement,
)
from kalman_vs_infoset.experiments.sim.estimator_loop import EstimatorLoop
from kalman_vs_infoset.experiments.sim.turn_setup import SQRT3, TurnSetup
from kalman_vs_infoset.guidance.attitude.cmg import rk4_step
from kalman_vs_infoset.guidance.attitude.energy import (
    EnergySavingController,
    EnergySavingState,
    given_system,
)
from kalman_vs_infoset.guidance.attitude.euler_turn import EulerTurnTracker
from kalman_vs_infoset.guidance.attitude.min_energy import min_energy_turn
from kalman_vs_infoset.guidance.attitude.plant import advance_checked
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from kalman_vs_infoset.numerics.rotations import qlog

CONTROLLERS = ("energy", "euler")
#: Seed 000, section 5: accumulated index Z (N^2 m^2 s) of the two turns.
SEED_ENERGY_N2M2S = {"energy": 2150.0, "euler": 11200.0}
OSCILLATION_WINDOW_S = 30.0
#: a row's values of the turn's end (NaN for a turn whose loop diverged)
PERFORMANCE = (
    "settle_time_s", "energy_N2m2s", "energy_horizon", "final_angle_deg", "axis",
    "final_rate_degps", "max_torque_Nm", "h_end", "h_peak", "osc", "tr_inc", "tr_dec", "manip",
    "singular",
)  # fmt: skip


@dataclass(frozen=True)
class TurnResult:
    """Histories of one simulated turn (``n`` steps, states at ``n + 1`` instants)."""

    controller: str
    dt_s: float
    n_turn_steps: int
    error_rotvec_deg: NDArray[np.float64]  # (n+1, 3), truth
    rate_degps: NDArray[np.float64]  # (n+1, 3), truth
    gyro_momentum_Nms: NDArray[np.float64]  # (n+1, 3)
    command_Nm: NDArray[np.float64]  # (n, 3), asked of the gyrodines
    torque_Nm: NDArray[np.float64]  # (n, 3), delivered by the gyrodines
    trace_k_u: NDArray[np.float64]  # (n+1,) energy law only, else empty
    trace_increment: NDArray[np.float64]  # (n,) eq. (2.6), energy law only
    min_manipulability: float
    singular_steps: int
    angle_tol_deg: float
    rate_tol_degps: float
    truth_outside: int = 0
    empty_steps: int = 0
    unbounded_steps: int = 0  # predictions whose set was the whole space
    mean_knowledge_bound_deg: float = 0.0
    #: when the loop diverged (:mod:`experiments.sim.divergence`; the histories are NaN
    #: after it), inf if it did not (as a settle time: never)
    diverged_time_s: float = np.inf

    @property
    def angle_deg(self) -> NDArray[np.float64]:
        """Principal error angle (deg) at every instant."""
        return np.linalg.norm(self.error_rotvec_deg, axis=1)

    @property
    def rate_norm_degps(self) -> NDArray[np.float64]:
        return np.linalg.norm(self.rate_degps, axis=1)

    def energy_N2m2s(self, n_steps: int | None = None) -> float:
        """Seed eq. (5.1): ``Z = sum_{i<N} M_i^T M_i dt`` with the delivered torques."""
        n = self.n_turn_steps if n_steps is None else n_steps
        return float(np.sum(self.torque_Nm[:n] ** 2) * self.dt_s)

    def settle_time_s(self) -> float:
        """First time after which angle and rate errors stay within tolerance (``inf`` if
        never, as the other attitude loops report it)."""
        ok = (self.angle_deg <= self.angle_tol_deg) & (self.rate_norm_degps <= self.rate_tol_degps)
        if not ok[-1]:
            return float("inf")
        bad = np.flatnonzero(~ok)
        return float(0.0 if bad.size == 0 else (bad[-1] + 1) * self.dt_s)

    def initial_oscillation_Nm(self, window_s: float = OSCILLATION_WINDOW_S) -> float:
        """Excess total variation of the commanded torque over the first ``window_s``.

        ``sum_axes (sum_i |U_{i+1} - U_i| - |U_m - U_0|)``: zero for a monotone command,
        growing with every swing back and forth (the seed's "initial oscillation").
        """
        m = max(2, int(round(window_s / self.dt_s)))
        u = self.command_Nm[:m]
        return float(np.sum(np.abs(np.diff(u, axis=0)).sum(axis=0) - np.abs(u[-1] - u[0])))


def _measure(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``X = (rotvec of body relative to target, w)``; the target is the identity."""
    return np.concatenate([Rotation.from_quat(x[0:4]).as_rotvec(), x[4:7]])


def estimator_model(setup: TurnSetup, noise: str = "random") -> AttitudeModel:
    """Bounds known to the estimators: errors uniform in ``+-sqrt(3) std`` (the seed's K_eps
    variances), disturbance ``+-sqrt(3) std`` (random) or the game bound."""
    d = setup.game_disturbance_Nm if noise == "game" else SQRT3 * setup.disturbance_std_Nm
    return AttitudeModel(
        setup.inertia_kgm2,
        d,
        max(SQRT3 * setup.angle_std_rad, 1e-12),
        max(SQRT3 * setup.rate_std_radps, 1e-12),
    )


def estimator_loop(setup: TurnSetup, noise: str, estimator: str | None) -> EstimatorLoop:
    """The runs' estimator: ``estimator`` (None: the exact one) on :func:`estimator_model`,
    with the set-up's options tables."""
    return EstimatorLoop(estimator, estimator_model(setup, noise), setup.estimator_options)


def simulate_turn(
    setup: TurnSetup,
    controller: str,
    rng: np.random.Generator | None = None,
    estimator: str | None = None,
    noise: str | None = None,
    record: dict | None = None,
    steps: int | None = None,
) -> TurnResult:
    """One closed-loop turn; noise is drawn from ``rng`` (None: perfect measurements).

    ``steps``: simulate only the turn's first ``steps`` steps (the loop is causal: the
    same steps as the whole turn's, the laws still planning the whole turn); the
    histories after them are NaN, as after a divergence. None: the whole horizon.

    Each step ``X`` is read from the estimator's belief centre ``(rotvec(q), w)``. With
    ``rng`` the attitude/rate errors are uniform within ``+-sqrt(3) std`` (a body-frame
    error rotation, the seed's variances) and the disturbance torque uniform within
    ``+-sqrt(3) disturbance_std`` per step (``noise="random"``) or, ``noise="game"``,
    ``-D sign(M)`` with ``D = game_disturbance_Nm`` (opposes the delivered torque).

    ``record`` (a dict, filled when given; observing only) receives per instant
    ``estimate`` (the belief's ``X``, rad and rad/s, ``(n+1, 6)``), ``knowledge_bound_rad``
    and ``truth_inside`` (``(n+1,)``) and, for the energy law, the auxiliary state
    ``xi`` (``(n+1, 6)``); and what :mod:`experiments.attitude_exact` needs: the true
    ``states`` ``(n+1, 10)``, the measurements ``meas_quat`` ``(n+1, 4)`` and
    ``meas_rate_radps`` ``(n+1, 3)``, the belief's per-axis ``hull`` (a list of ``n+1``
    :meth:`EstimatorLoop.axis_hull` values) and per step the delivered ``torque_Nm`` and
    the disturbance ``disturbance_Nm`` ``(n, 3)`` (both held over the step). A turn
    that diverged records the instants before it.
    """
    if controller not in CONTROLLERS:
        raise ValueError(f"controller must be one of {CONTROLLERS}, got {controller!r}")
    noise = noise or ("random" if rng is not None else "none")
    n, dt = setup.n_steps, setup.dt_s
    body, cluster = setup.body, setup.cluster
    j, j_inv = body.inertia_kgm2, body.inertia_inv
    noisy = rng is not None
    loop = estimator_loop(setup, noise, estimator)
    model = loop.model
    d_bound = model.disturbance_bound_Nm

    beta = setup.beta0_rad.copy()
    q0 = Rotation.from_rotvec(setup.initial_error_rad).as_quat()
    x = np.concatenate([q0, np.zeros(3), cluster.momentum_Nms(beta)])

    def measured(xx: NDArray[np.float64]) -> AttitudeMeasurement:
        if noisy:
            return draw_measurement(xx, model, rng)
        return AttitudeMeasurement(xx[0:4], xx[4:7])

    def estimate(b) -> NDArray[np.float64]:
        c = loop.centre(b)[0]
        return np.concatenate([qlog(c[0:4]), c[4:7]])

    truth = _measure(x)
    meas = measured(x)
    belief = loop.start(meas)
    outside = int(np.sum(~loop.inside(belief, x[None])))
    bound_sum = 0.0

    # NaN after a turn that diverged (no instant is left unwritten otherwise)
    err, rate, hist_h = (np.full((n + 1, 3), np.nan) for _ in range(3))
    cmd, delivered = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
    trace_k_u = np.full(n + 1, np.nan) if controller == "energy" else np.empty(0)
    trace_inc = np.full(n, np.nan) if controller == "energy" else np.empty(0)
    n_run = n if steps is None else max(0, min(int(steps), n))
    diverged_s, n_done = np.inf, n_run  # n_done: the steps the belief was updated
    min_manip, n_singular = np.inf, 0

    if controller == "energy":
        law = EnergySavingController(setup.energy)
        ctrl = EnergySavingState.initial(setup.energy, estimate(belief))
        trace_k_u[0] = np.trace(ctrl.k_u)
    else:
        eu = setup.euler
        tracker = EulerTurnTracker(
            j,
            setup.initial_error_rad,
            setup.duration_s,
            eu.accel_time_s,
            eu.jerk_time_s,
            eu.natural_freq_radps,
            eu.damping,
        )
        ref_rot, ref_w, ref_dw = tracker.reference(np.arange(n) * dt)

    xm = estimate(belief)
    rec: dict[str, list[Any]] | None = None
    if record is not None:
        rec = {"estimate": [xm], "knowledge_bound_rad": [float(loop.attitude_bound_rad(belief)[0])],
               "truth_inside": [bool(loop.inside(belief, x[None])[0])], "xi": [],
               "states": [x], "torque_Nm": [], "disturbance_Nm": [],
               "meas_quat": [meas.quat], "meas_rate_radps": [meas.rate_radps]}  # fmt: skip
        hulls = [loop.axis_hull(belief)]  # tuples of arrays: a list, not an array
        if controller == "energy":
            rec["xi"].append(ctrl.xi)
    for i in range(n_run):
        err[i], rate[i], hist_h[i] = truth[:3], x[4:7], x[7:10]
        h_gyro = cluster.momentum_Nms(beta)  # known on board from the precession angles
        if controller == "energy":
            a_i, b_i = given_system(j_inv, j @ xm[3:] + h_gyro, dt)
            command = ctrl.u_Nm
        else:
            ref = (ref_rot[i], ref_w[i], ref_dw[i])
            command = tracker.torque_from_reference(ref, xm[:3], xm[3:], h_gyro)
        min_manip = min(min_manip, cluster.manipulability(beta))
        h_before = x[7:10].copy()
        beta, torque, singular = cluster.step(beta, command, dt)
        n_singular += int(singular)
        cmd[i], delivered[i] = command, torque
        ext = None
        if noisy and noise == "game":
            ext = -d_bound * np.sign(torque)
        elif rng is not None:  # noisy
            ext = rng.uniform(-1.0, 1.0, 3) * d_bound
        x_next, bad = advance_checked(rk4_step, body, x, (torque, dt, ext), 1, dt, slice(4, 7))
        if bad:
            # the turn ends here (experiments.sim.divergence); x stays the last resolved
            diverged_s, n_done = (i + 1) * dt, i
            break
        x = x_next
        truth = _measure(x)
        known = AttitudeControl.held(torque, h_before, dt)
        meas = measured(x)
        belief = loop.step(belief, known, dt, meas)
        outside += int(np.sum(~loop.inside(belief, x[None])))
        bound_sum += float(loop.attitude_bound_rad(belief)[0])
        xm = estimate(belief)
        if controller == "energy":
            ctrl, diag = law.update(ctrl, a_i, b_i, xm)
            trace_k_u[i + 1], trace_inc[i] = diag.trace_k_u, diag.trace_increment
        if rec is not None:
            rec["states"].append(x)
            rec["torque_Nm"].append(torque)
            rec["disturbance_Nm"].append(np.zeros(3) if ext is None else ext)
            rec["meas_quat"].append(meas.quat)
            rec["meas_rate_radps"].append(meas.rate_radps)
            hulls.append(loop.axis_hull(belief))
            rec["estimate"].append(xm)
            rec["knowledge_bound_rad"].append(float(loop.attitude_bound_rad(belief)[0]))
            rec["truth_inside"].append(bool(loop.inside(belief, x[None])[0]))
            if controller == "energy":
                rec["xi"].append(ctrl.xi)
    if rec is not None and record is not None:  # rec exists only when record was given
        record.update({k: np.array(v) for k, v in rec.items()})
        # (a measurement of one instant, batched as one run: (1, 4), (1, 3))
        record["meas_quat"] = record["meas_quat"].reshape(-1, 4)
        record["meas_rate_radps"] = record["meas_rate_radps"].reshape(-1, 3)
        record["hull"] = hulls
    if n_done == n_run:
        err[n_run], rate[n_run], hist_h[n_run] = truth[:3], x[4:7], x[7:10]
    return TurnResult(
        controller=controller,
        dt_s=dt,
        n_turn_steps=setup.n_turn_steps,
        error_rotvec_deg=np.degrees(err),
        rate_degps=np.degrees(rate),
        gyro_momentum_Nms=hist_h,
        command_Nm=cmd,
        torque_Nm=delivered,
        trace_k_u=trace_k_u,
        trace_increment=trace_inc,
        min_manipulability=float(min_manip),
        singular_steps=n_singular,
        angle_tol_deg=setup.angle_tol_deg,
        rate_tol_degps=setup.rate_tol_degps,
        truth_outside=outside,
        empty_steps=int(np.sum(loop.empty_steps(belief))),
        unbounded_steps=int(np.sum(loop.unbounded_steps(belief))),
        mean_knowledge_bound_deg=float(np.degrees(bound_sum / n_done)) if n_done else np.nan,
        diverged_time_s=diverged_s,
    )


def lower_bound_energy_N2m2s(setup: TurnSetup) -> float:
    """Open-loop minimum-energy index of the linear model (3.9) over the turn time."""
    h0 = setup.cluster.momentum_Nms(setup.beta0_rad)
    a, b = given_system(setup.body.inertia_inv, h0, setup.dt_s)  # w0 = 0: K = h0
    x0 = np.concatenate([setup.initial_error_rad, np.zeros(3)])
    return min_energy_turn(a, b, x0, setup.n_turn_steps, setup.dt_s).energy_N2m2s


def one_run(setup: TurnSetup, controller: str, noise: str, child, estimator: str):
    """One turn and its row (module level: picklable for a process pool)."""
    rng = np.random.default_rng(child) if noise != "none" else None
    res = simulate_turn(setup, controller, rng, estimator, noise)
    k = setup.n_turn_steps
    counts = {
        "truth_outside": res.truth_outside,
        "empty_steps": res.empty_steps,
        "unbounded_steps": res.unbounded_steps,
        "mean_knowledge_bound_deg": res.mean_knowledge_bound_deg,
        "diverged": int(np.isfinite(res.diverged_time_s)),
        "diverged_time_s": res.diverged_time_s,
    }
    if counts["diverged"]:  # no value for the turn's end (experiments.sim.divergence)
        return dict.fromkeys(PERFORMANCE, np.nan) | {"tr_dec": None} | counts
    return {
        "settle_time_s": res.settle_time_s(),
        "energy_N2m2s": res.energy_N2m2s(),
        "energy_horizon": res.energy_N2m2s(setup.n_steps),
        "final_angle_deg": float(res.angle_deg[k]),
        "axis": float(np.abs(res.error_rotvec_deg[k]).max()),
        "final_rate_degps": float(res.rate_norm_degps[k]),
        "max_torque_Nm": float(np.abs(res.torque_Nm).max()),
        "h_end": float(np.linalg.norm(res.gyro_momentum_Nms[k])),
        "h_peak": float(np.linalg.norm(res.gyro_momentum_Nms, axis=1).max()),
        "osc": res.initial_oscillation_Nm(),
        "tr_inc": float(res.trace_increment.max()) if res.trace_increment.size else np.nan,
        "tr_dec": bool(np.all(np.diff(res.trace_k_u) < 0)) if res.trace_k_u.size else None,
        "manip": res.min_manipulability,
        "singular": res.singular_steps,
        **counts,
    }
