"""The exact set of an attitude run's states along each axis, as linear programs.

Every state a run's data allow is the truth ``x_k`` moved by a perturbation ``delta_k =
(da, dw)`` (body-frame rotation vector ``log(q_k^-1 q)``, rate), reached from some
initial perturbation under disturbances within their bound, with every measurement error
within its bound. The perturbations are of the order of the measurement bounds, so one
control period maps them linearly to first order (docs/attitude.md):

.. math:: \\delta_{k+1} = A_k \\delta_k + B_k e_k,

``e_k`` the disturbance's offset from the truth's over period ``k`` (held over the
period, as the loops hold the truth's), ``A_k, B_k`` central differences of the plant's
own integration (``substeps`` steps of its RK4, :class:`Plant`) along the true
trajectory. The reaction wheels' momentum follows the known torque and is not perturbed;
the gyrostat's rotor rates are states measured with bounded errors, perturbed and
bounded like the rates (``Plant.extra``).
The measurement of sample ``k`` bounds ``delta_k`` axis by axis: ``|log(q_k^-1 q_m) - da|
<= b_a`` and ``|w_m - w_k - dw| <= b_w`` (first order). The extremes of ``delta_k`` along
each axis are then linear programs (scipy ``linprog``, HiGHS, sparse: the variables
``delta_0 .. delta_k`` and ``e_0 .. e_{k-1}``, the dynamics as equalities), tried again by
another method where HiGHS reports numerical difficulties
(:func:`kalman_vs_infoset.numerics.lp.linprog_highs`).

A disturbance that varies within a period can only add states, so the LP's interval
lies inside the exact one (to the linearisation's order): a set that holds it is sound
against it, and a set's width over it bounds the set's excess from above.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from kalman_vs_infoset.numerics.lp import LinearProgramFailed, linprog_highs
from kalman_vs_infoset.numerics.rotations import qexp, qinv, qlog, qmul

#: finite-difference step of the Jacobians (central differences: error ~ step^2), in the
#: perturbation's units (rad, rad/s)
FD_STEP = 1e-7


@dataclass(frozen=True)
class Plant:
    """What the reference needs of a loop's plant.

    Attributes
    ----------
    advance : callable
        ``advance(states (n, 10), torque (n, 3), disturbance (n, 3), dt_s)``: one RK4 step
        of the plant with both held (the loop's own).
    inertia_min_kgm2 : float
        The smallest moment of inertia the disturbance acts on (its finite-difference step).
    extra : slice or None
        State components measured with bounded errors besides the attitude and the rate
        (the gyrostat's rotor rates), perturbed additively; None: none.
    """

    advance: Callable[[np.ndarray, np.ndarray, np.ndarray, float], np.ndarray]
    inertia_min_kgm2: float
    extra: slice | None = None

    @property
    def dim(self) -> int:
        """The perturbation's dimension: attitude, rate and the extra components."""
        return 6 + (0 if self.extra is None else self.extra.stop - self.extra.start)


def wheels_plant(body) -> Plant:
    """The reaction-wheel plant of ``body`` (:func:`guidance.attitude.wheels.rk4_step`)."""
    from kalman_vs_infoset.guidance.attitude.wheels import rk4_step

    return Plant(
        lambda y, u, d, dt: rk4_step(body, y, u, dt, d),
        float(np.min(np.diag(body.inertia_kgm2))),
    )


def gyrostat_plant(gyro) -> Plant:
    """The gyrostat (:func:`guidance.attitude.gyrostat.rk4_step`): the body moments
    ``A - J`` take the disturbance; the rotor rates are measured (``extra``)."""
    from kalman_vs_infoset.guidance.attitude.gyrostat import PHI, rk4_step

    return Plant(
        lambda y, u, d, dt: rk4_step(gyro, y, u, d, dt),
        float(np.min(gyro.body_moments_kgm2)),
        PHI,
    )


@dataclass(frozen=True)
class ExactAxes:
    """The LP's interval of ``delta_k`` per axis at one sample, with the trajectory that
    attains each end (a witness: the initial perturbation and the disturbances).

    Attributes
    ----------
    lo, hi : ndarray (6,)
        The ends of ``delta_k`` (rad, rad/s).
    delta0 : ndarray (12, p)
        Per end (axis 0 low, axis 0 high, axis 1 low, ...), the initial perturbation
        (``p = Plant.dim``: the extra components after the rate's).
    disturbance_Nm : ndarray (12, k, 3)
        Per end, the disturbance held over each period (the truth's plus the LP's offset).
    """

    lo: np.ndarray
    hi: np.ndarray
    delta0: np.ndarray
    disturbance_Nm: np.ndarray


def model_bounds(model, extra: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """The bounds (3,) of :func:`exact_intervals` from the estimators' model
    (:class:`estim.attitude.model.AttitudeModel`: the same premise as the sets'), with
    ``extra`` those of the plant's extra components if it has some."""
    out = {
        "angle_rad": np.broadcast_to(model.meas_angle_bound_rad, 3),
        "rate_radps": np.broadcast_to(model.meas_rate_bound_radps, 3),
        "disturbance_Nm": np.broadcast_to(model.disturbance_bound_Nm, 3),
    }
    if extra is not None:
        out["extra"] = np.broadcast_to(extra, 3)
    return out


def delta_of(truth: np.ndarray, x: np.ndarray, extra: slice | None = None) -> np.ndarray:
    """``(da, dw[, extra])`` ``(n, p)`` of states ``x`` ``(n, >=7)`` relative to ``truth``."""
    qt = np.broadcast_to(truth[0:4], x[:, 0:4].shape)
    parts = [qlog(qmul(qinv(qt), x[:, 0:4])), x[:, 4:7] - truth[4:7]]
    if extra is not None:
        parts.append(x[:, extra] - truth[extra])
    return np.concatenate(parts, axis=1)


def _moved(truth: np.ndarray, d: np.ndarray, extra: slice | None = None) -> np.ndarray:
    """The states ``truth (+) d`` for perturbations ``d`` ``(n, p)``."""
    x = np.repeat(truth[None], len(d), axis=0)
    x[:, 0:4] = qmul(x[:, 0:4], qexp(d[:, 0:3]))
    x[:, 4:7] += d[:, 3:6]
    if extra is not None:
        x[:, extra] += d[:, 6:]
    return x


def period_jacobians(
    plant: Plant, x: np.ndarray, x_next: np.ndarray, u: np.ndarray, dist: np.ndarray,
    period_s: float, substeps: int,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """``(A, B)`` ``(p, p), (p, 3)`` of one control period at the truth ``x`` (10,), its
    torque ``u`` and disturbance ``dist`` held (central differences, ``2 p + 6`` states in
    one batch); ``x_next`` is the truth at the period's end."""
    p = plant.dim
    # a disturbance step that moves the rate by about FD_STEP over the period: one the
    # size of the disturbance bound moved the attitude by less than its rounding
    h_d = FD_STEP * plant.inertia_min_kgm2 / period_s
    steps = FD_STEP * np.eye(p)
    pert = np.concatenate(
        [_moved(x, steps, plant.extra), _moved(x, -steps, plant.extra),
         np.repeat(x[None], 6, axis=0)]
    )  # fmt: skip
    n = len(pert)
    d = np.tile(dist, (n, 1))
    for i in range(3):
        d[2 * p + i, i] += h_d
        d[2 * p + 3 + i, i] -= h_d
    dt = period_s / substeps
    y = pert
    for _ in range(substeps):
        y = plant.advance(y, np.tile(u, (n, 1)), d, dt)
    dy = delta_of(x_next, y, plant.extra)
    a = (dy[0:p] - dy[p : 2 * p]).T / (2 * FD_STEP)
    b = (dy[2 * p : 2 * p + 3] - dy[2 * p + 3 : 2 * p + 6]).T / (2 * h_d)
    return a, b


def exact_intervals(
    plant: Plant, rec: dict[str, Any], bounds: dict[str, np.ndarray], period_s: float,
    substeps: int, samples: list[int], run: int = 0, solved: Callable[[], None] | None = None,
) -> dict[int, ExactAxes]:  # fmt: skip
    """The LP's interval of ``delta_k`` per axis at each sample ``k`` of ``samples``.

    Parameters
    ----------
    plant : Plant
        The loop's plant (:func:`wheels_plant`, :func:`gyrostat_plant`).
    rec : dict
        A run's record as the reaction-wheel loop writes it
        (:func:`experiments.sim.attitude_rw.simulate_runs`: ``states``, ``torque_Nm``,
        ``disturbance_Nm``, ``meas_quat``, ``meas_rate_radps``, samples first), with
        ``meas_extra`` for the plant's extra components.
    bounds : dict
        ``angle_rad``, ``rate_radps``, ``disturbance_Nm`` (and ``extra`` with extra
        components): the bounds (3,) the estimators assume (their model's).
    period_s, substeps : float, int
        The control period and its integration steps.
    samples : list of int
        Control samples (the measurement ``k`` taken at ``k * period_s``).
    run : int
        The run of the record.
    solved : callable, optional
        Called after each of the ``12 len(samples)`` programs (a progress display).

    Returns
    -------
    dict of int to ExactAxes
        Per sample, the ends of ``delta_k`` and their witnesses.
    """
    from scipy import sparse

    p = plant.dim
    x = rec["states"][:, run]
    u = rec["torque_Nm"][:, run]
    dist = rec["disturbance_Nm"][:, run]
    parts = [bounds["angle_rad"], bounds["rate_radps"]]
    seen = [rec["meas_quat"], rec["meas_rate_radps"]]
    if plant.extra is not None:
        parts.append(bounds["extra"])
        seen.append(rec["meas_extra"])
    meas_bound = np.concatenate(parts)
    dmax = np.asarray(bounds["disturbance_Nm"], dtype=float)
    last = max(samples)
    jac = [
        period_jacobians(plant, x[k], x[k + 1], u[k], dist[k], period_s, substeps)
        for k in range(last)
    ]
    # each measurement as a perturbation of the truth it measured
    xs = x[: last + 1]
    got = [v[: last + 1, run] for v in seen]
    offsets = [qlog(qmul(qinv(xs[:, 0:4]), got[0])), got[1] - xs[:, 4:7]]
    if plant.extra is not None:
        offsets.append(got[2] - xs[:, plant.extra])
    meas = np.concatenate(offsets, axis=1)
    # the variables in units of their bounds (HiGHS's feasibility tolerance, 1e-7, is
    # absolute: on perturbations of 1e-7 rad/s it let the dynamics slip by their size)
    d_scale = meas_bound
    e_scale = np.where(dmax > 0, dmax, 1.0)
    a_all = np.array([j[0] for j in jac]).reshape(-1, p, p) * d_scale[None, None, :]
    a_all = a_all / d_scale[None, :, None]
    b_all = np.array([j[1] for j in jac]).reshape(-1, p, 3) * e_scale[None, None, :]
    b_all = b_all / d_scale[None, :, None]
    lim_d = np.stack([meas / d_scale - 1.0, meas / d_scale + 1.0], axis=-1).reshape(-1, 2)
    lim_e = np.stack([(-dmax - dist[:last]) / e_scale, (dmax - dist[:last]) / e_scale], axis=-1)
    lim_e = lim_e.reshape(-1, 2)
    out = {}
    for s in samples:
        n_d, n_e = p * (s + 1), 3 * s
        # y_{k+1} - A_k y_k - B_k f_k = 0, k = 0 .. s-1 (scaled), as one sparse matrix:
        # row p k + i holds -A_k[i] at y_k, 1 at y_{k+1}[i], -B_k[i] at f_k
        k, i, j = np.meshgrid(np.arange(s), np.arange(p), np.arange(p), indexing="ij")
        rows = np.concatenate([(p * k + i).ravel(), np.arange(p * s), (p * k + i)[..., :3].ravel()])
        cols = np.concatenate(
            [(p * k + j).ravel(), p + np.arange(p * s), (n_d + 3 * k + j)[..., :3].ravel()]
        )
        vals = np.concatenate([-a_all[:s].ravel(), np.ones(p * s), -b_all[:s].ravel()])
        a_eq = sparse.csr_matrix((vals, (rows, cols)), shape=(p * s, n_d + n_e)) if s else None
        limits = np.concatenate([lim_d[:n_d], lim_e[:n_e]])
        lo, hi = np.empty(6), np.empty(6)
        witness = np.empty((12, n_d + n_e))
        for axis in range(6):
            cost = np.zeros(n_d + n_e)
            cost[p * s + axis] = 1.0
            for sign, store in ((1.0, lo), (-1.0, hi)):
                # the truth (all zeros) is feasible and the box bounds the program:
                # any status but optimal is the method's, and the next one is tried
                res = linprog_highs(sign * cost, A_eq=a_eq,
                                    b_eq=np.zeros(p * s) if s else None, bounds=limits,
                                    retry=(1, 2, 3, 4))  # fmt: skip
                if res.status != 0:
                    raise LinearProgramFailed(
                        f"the exact reference's linear program at sample {s} (t = "
                        f"{s * period_s:g} s) failed by every method tried: {res.message}"
                    )
                store[axis] = sign * res.fun * d_scale[axis]
                if solved is not None:
                    solved()
                witness[2 * axis + (sign < 0)] = res.x
        out[s] = ExactAxes(
            lo, hi, witness[:, :p] * d_scale,
            dist[:s] + witness[:, n_d:].reshape(12, s, 3) * e_scale,
        )  # fmt: skip
    return out


def belief_intervals(truth: np.ndarray, hull, run: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A belief's per-axis interval ``(lo, hi)`` ``(6,)`` of ``delta`` relative to the
    truth (10,): its hull ``(q_ref, c, r)`` (:meth:`EstimatorLoop.axis_hull`, run
    ``run``) moved from its reference to the truth's frame (first order: the centre's
    offset, the same radii)."""
    q_ref, c, r = (np.asarray(v)[run] for v in hull)
    centre = qmul(q_ref[None], qexp(c[None, 0:3]))
    cd = np.concatenate([qlog(qmul(qinv(truth[None, 0:4]), centre))[0], c[3:6] - truth[4:7]])
    return cd - r, cd + r
