"""Reaction-wheel attitude loops, controllers ``pd`` (docs/models.md §2.2) and ``lqr``
(docs/models.md §2.3).

:func:`simulate_runs` simulates a batch of runs as one closed loop (the plant of
:mod:`kalman_vs_infoset.guidance.attitude.wheels`: the shared RK4, controller sampled every
``control_period_s`` with the torque held). The controller sees only an estimator's
belief (any registered attitude estimator, :mod:`estim.registry`; one belief carries
the batch), updated every sample with the measurement; the law is evaluated at
``(q, w)`` of ``belief.centre()`` and the wheel momentum (known on board).

Noise: ``none`` = exact measurements, no disturbance; ``random`` = attitude (small
body-frame rotation, per axis) and rate errors uniform within ``+-sqrt(3) sigma`` (the
scenario's 1-sigma values, same variance), plus a constant disturbance torque per run
uniform in ``[-d, d]`` per axis; ``game`` = the same measurement errors and a bounded
disturbance ``-d sign(M_u)`` that opposes the control every sample. Random initial
attitudes (``maneuver.random_attitude``) are drawn for every noise setting, from the
run's own generator. ``config`` is the typed scenario
(:class:`kalman_vs_infoset.experiments.sim.attitude_rw_config.RwScenario`).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    draw_measurement,
)
from kalman_vs_infoset.estim.base import PointBelief
from kalman_vs_infoset.experiments.sim.attitude_rw_config import LqrTable, RwScenario
from kalman_vs_infoset.experiments.sim.divergence import diverged_rows
from kalman_vs_infoset.experiments.sim.estimator_loop import EstimatorLoop
from kalman_vs_infoset.guidance.attitude.lqr import LQRController
from kalman_vs_infoset.guidance.attitude.pd import QuaternionPD, angle_and_rate_deg, settle_time
from kalman_vs_infoset.guidance.attitude.plant import LoopDiverged, RigidBody
from kalman_vs_infoset.guidance.attitude.wheels import (
    ReactionWheels,
    Trajectory,
    simulate_closed_loop,
)
from scipy.spatial.transform import Rotation

#: the metrics of a turn's end: no value for a run whose loop diverged before it
PERFORMANCE = (
    "settle_time_s", "energy_N2m2s", "final_angle_deg", "final_rate_degps", "max_torque_Nm",
)  # fmt: skip


def body_of(config: RwScenario) -> tuple[RigidBody, np.ndarray, np.ndarray]:
    """``J = W diag(J_diag) W^T`` with ``W`` from ``axes_rotvec_deg``.

    Returns
    -------
    body : RigidBody
    j_diag_kgm2 : ndarray (3,)
    axes : ndarray (3, 3)
        ``W``, whose columns are the principal axes.
    """
    jd = np.asarray(config.body.inertia_kgm2, dtype=float)
    w = Rotation.from_rotvec(np.radians(config.body.axes_rotvec_deg)).as_matrix()
    return RigidBody(w @ np.diag(jd) @ w.T), jd, w


def make_controller(controller: str, config: RwScenario) -> QuaternionPD | LQRController:
    """The law ``controller`` (``pd`` or ``lqr``) of the scenario (``ValueError`` if its
    table is missing or describes no valid law)."""
    body, jd, w = body_of(config)
    q_t = tuple(np.asarray(config.maneuver.target_quaternion) / 1.0)
    if controller == "pd":
        pd = config.law_table("pd")
        return QuaternionPD(body, pd.k_q, pd.k_w, pd.quaternion_term, q_target=q_t)
    p = config.law_table(controller)
    if not isinstance(p, LqrTable):  # a "pd" table was handled above
        raise TypeError(f"controller '{controller}' has no LQR table")
    return LQRController(
        body.inertia_kgm2,
        p.q,
        p.r,
        enforce_constraint=p.enforce_constraint,
        q_target=q_t,
        shortest=p.shortest,
        axes=w,
    )


def initial_states(config: RwScenario, rngs: list[np.random.Generator]) -> np.ndarray:
    """Initial plant states ``(runs, 10)``: the maneuver's turn, or random attitudes/rates."""
    man = config.maneuver
    q_t = Rotation.from_quat(man.target_quaternion)
    axis = np.asarray(man.axis) / np.linalg.norm(man.axis)
    x = np.zeros((len(rngs), 10))
    for k, rng in enumerate(rngs):
        if man.random_attitude:
            rot = Rotation.random(rng=rng)
        else:
            rot = q_t * Rotation.from_rotvec(np.radians(man.angle_deg) * axis)
        x[k, 0:4] = rot.as_quat()
        x[k, 4:7] = np.radians(man.initial_rate_degps) + np.radians(
            man.random_rate_degps
        ) * rng.uniform(-1.0, 1.0, 3)
    return x


def estimator_model(config: RwScenario) -> AttitudeModel:
    """What the estimators know: J, the disturbance bound and the measurement bounds.

    The scenario's ``meas_*`` values are 1-sigma; the errors are drawn uniform within
    ``+-sqrt(3) sigma`` (same variance, bounded: admissible for the box estimator).
    """
    body, _, _ = body_of(config)
    nz = config.noise
    return AttitudeModel(
        body.inertia_kgm2,
        nz.disturbance_Nm,
        max(np.sqrt(3.0) * np.radians(nz.meas_angle_deg), 1e-12),
        max(np.sqrt(3.0) * np.radians(nz.meas_rate_degps), 1e-12),
    )


def estimator_loop(config: RwScenario, estimator: str | None) -> EstimatorLoop:
    """The runs' estimator: ``estimator`` (None: the exact one) on :func:`estimator_model`,
    with the scenario's options tables."""
    return EstimatorLoop(estimator, estimator_model(config), config.estimator_options)


def simulate_runs(
    config: RwScenario,
    controller: str,
    noise: str,
    rngs: list[np.random.Generator],
    estimator: str | None = None,
    record: dict | None = None,
) -> dict[str, np.ndarray]:
    """Simulate the runs as one batch; per-run metrics.

    Parameters
    ----------
    config : RwScenario
        The typed scenario.
    controller : {"pd", "lqr"}
        The law (its table must be in ``config``).
    noise : {"none", "random", "game"}
        Measurement errors and disturbance (module docstring).
    rngs : list of numpy.random.Generator
        One generator per run: the run's initial state and noise.
    estimator : str or None
        A registered attitude estimator (None: the one with the role ``exact``, the
        measurement read as the state).
    record : dict, optional
        Filled with the trajectories (below).

    Returns
    -------
    dict of str to ndarray
        Per-run metrics ``(runs,)``: ``settle_time_s`` (inf if not settled),
        ``energy_N2m2s``, ``final_angle_deg``, ``final_rate_degps``, ``max_torque_Nm``,
        ``truth_outside``, ``empty_steps``, ``unbounded_steps``,
        ``mean_knowledge_bound_deg``, for the LQR ``lyapunov_max_increase``, and
        ``diverged`` / ``diverged_time_s`` (:mod:`experiments.sim.divergence`: one run
        whose loop diverges ends there, its turn's metrics NaN; in a batch of runs
        :class:`~kalman_vs_infoset.guidance.attitude.plant.LoopDiverged` is raised).

    Notes
    -----
    The controller reads ``(q, w)`` from the estimator's belief (plus the wheel
    momentum, known on board). Noise ``random``: constant disturbance per run uniform
    in ``[-d, d]``; ``game``: ``-d sign(M_u)`` (opposes the control); both with
    measurement errors uniform within the bounds; ``none``: exact measurements.

    ``record`` (a dict, filled when given; observing only) receives the trajectory
    (``time_s`` ``(n+1,)``, ``states`` ``(n+1, runs, 10)``, ``torque_Nm`` ``(n+1, runs,
    3)``, the last held), the target quaternion ``q_target`` and per control sample
    ``estimate`` ``(n, runs, 7)``, ``knowledge_bound_rad`` and ``truth_inside``
    ``(n, runs)``, the measurement ``meas_quat`` ``(n, runs, 4)`` and ``meas_rate_radps``
    ``(n, runs, 3)``, the belief's per-axis ``hull`` (a list of ``n``
    :meth:`EstimatorLoop.axis_hull` values) and the disturbance held over each period,
    ``disturbance_Nm`` ``(n, runs, 3)`` (what :mod:`experiments.attitude_exact` needs).
    """
    body, _, _ = body_of(config)
    law = make_controller(controller, config)
    wh = config.wheels
    wheels = ReactionWheels(wh.torque_max_Nm, wh.momentum_max_Nms)
    sim = config.simulation
    period = sim.control_period_s
    x0 = initial_states(config, rngs)
    n = len(rngs)
    loop = estimator_loop(config, estimator)
    model = loop.model
    d = config.noise.disturbance_Nm
    const_dist = (
        np.stack([r.uniform(-d, d, 3) for r in rngs]) if noise == "random" else np.zeros((n, 3))
    )
    state = SimpleNamespace(belief=None, ctrl=None, outside=np.zeros(n, dtype=int))
    bounds, centres, insides = [], [], []
    seen: dict[str, list] = {"meas_quat": [], "meas_rate_radps": [], "hull": [], "dist": []}

    def measure(x: np.ndarray) -> AttitudeMeasurement:
        if noise == "none":
            return AttitudeMeasurement(x[:, 0:4], x[:, 4:7])
        return draw_measurement(x, model, rngs)

    def control(_t: float, x: np.ndarray) -> np.ndarray:
        meas = measure(x)
        if state.belief is None:
            belief = loop.start(meas)
        else:
            belief = loop.step(state.belief, state.ctrl, period, meas)
        inside = loop.inside(belief, x)
        state.outside += ~inside
        bounds.append(loop.attitude_bound_rad(belief))
        if record is not None:
            centres.append(loop.centre(belief))
            insides.append(inside)
            seen["meas_quat"].append(meas.quat)
            seen["meas_rate_radps"].append(meas.rate_radps)
            seen["hull"].append(loop.axis_hull(belief))
        x_est = np.concatenate([loop.centre(belief), x[:, 7:10]], axis=-1)
        u = wheels.limit(law.from_belief(PointBelief(x_est)), x[:, 7:10], period)
        state.belief, state.ctrl = belief, AttitudeControl.held(u, x[:, 7:10], period)
        return u

    def disturbance(_t: float, _x: np.ndarray, u: np.ndarray) -> np.ndarray:
        m = -d * np.sign(u) if noise == "game" else const_dist
        if record is not None:
            seen["dist"].append(m)
        return m

    try:
        traj = simulate_closed_loop(
            body, wheels, control, x0, sim.duration_s, period, sim.substeps, disturbance
        )
        diverged_s = np.full(n, np.inf)  # never
    except LoopDiverged as exc:
        if n > 1:
            raise  # the runner simulates each run of the batch alone
        assert isinstance(exc.trajectory, Trajectory)  # simulate_closed_loop keeps it
        traj, diverged_s = exc.trajectory, np.array([exc.time_s])
    if record is not None:
        record.update(
            time_s=traj.time_s, states=traj.x, torque_Nm=traj.torque_Nm,
            q_target=np.asarray(law.q_target, dtype=float), estimate=np.array(centres),
            knowledge_bound_rad=np.array(bounds), truth_inside=np.array(insides),
            meas_quat=np.array(seen["meas_quat"]),
            meas_rate_radps=np.array(seen["meas_rate_radps"]),
            disturbance_Nm=np.array(seen["dist"]), hull=seen["hull"],
        )  # fmt: skip
    out = {
        "truth_outside": state.outside,
        "empty_steps": loop.empty_steps(state.belief),
        "unbounded_steps": loop.unbounded_steps(state.belief),
        "mean_knowledge_bound_deg": np.degrees(np.mean(bounds, axis=0)),
    }
    lqr = isinstance(law, LQRController)
    keys = (*PERFORMANCE, "lyapunov_max_increase") if lqr else PERFORMANCE
    if np.isfinite(diverged_s).any():  # one run, ended before the turn did
        return diverged_rows({**out, **dict.fromkeys(keys, np.full(n, np.nan))}, diverged_s, keys)
    angle, rate = angle_and_rate_deg(traj.x, law.q_target)
    settle = np.array(
        [
            settle_time(
                traj.time_s,
                angle[:, k],
                rate[:, k],
                sim.settle_angle_deg,
                sim.settle_rate_degps,
            )
            for k in range(n)
        ]
    )
    u = traj.torque_Nm[:-1]
    out |= {
        "settle_time_s": settle,
        "energy_N2m2s": np.sum(u**2, axis=(0, 2)) * period,
        "final_angle_deg": angle[-1],
        "final_rate_degps": rate[-1],
        "max_torque_Nm": np.max(np.abs(u), axis=(0, 2)),
    }
    if isinstance(law, LQRController):
        v = law.lyapunov(traj.x)
        out["lyapunov_max_increase"] = np.max(np.diff(v, axis=0), axis=0)
    return diverged_rows(out, diverged_s, keys)
