"""Unscented Kalman filter of attitude and rate with a multiplicative error state (docs/models.md
§2.5).

State. The belief of each run is a reference quaternion ``q_ref`` and a Gaussian on the
9-dimensional error state ``x = (a, w, d)``: ``a`` the body-frame rotation vector with
``q = q_ref exp(a)``, ``w`` the body rate and ``d`` the disturbance torque (a slowly
varying bias: without it a constant disturbance biases the rate and the filter
becomes overconfident; measured on the RW scenario, 99 % of steps outside the gate).
The quaternion is never averaged or perturbed additively; the manifold enters
through three functions (filterpy's hooks):

* ``residual_x(x1, x2) = (log(exp(a2)^-1 exp(a1)), w1 - w2)`` (on-manifold difference);
* ``state_add(x, dx) = (log(exp(a) exp(da)), w + dw)`` (on-manifold sum);
* ``x_mean_fn(sigmas, Wm)``: the weighted mean in the tangent space at the reference,
  which the prediction moves to the propagated mean point (so the sigma points are
  close to it and the tangent-space mean is the usual first-order Karcher mean).

Prediction: sigma points (Van der Merwe, ``alpha = 1, beta = 2, kappa = 0``, filterpy's
:class:`MerweScaledSigmaPoints`) are mapped to full states ``(q_ref exp(a_i), w_i)``,
propagated by RK4 through the rigid-body model of :mod:`kalman_vs_infoset.estim.attitude.model` with
the known torque and the midpoint of the momentum interval, and expressed relative
to the propagated mean point (torque ``M_u + d_i``). Process noise: a white torque of
variance ``D^2/3`` (a uniform in ``[-D, D]``) held over the step, ``G diag(D^2/3)
G^T``, ``G = (dt^2/2 J_b^-1; dt J_b^-1)``, a small floor, and a random walk of ``d``
(variance ``D^2/3`` per ``tau_d = 60 s``).
Update: ``z = (log(q_ref^-1 q_m), w_m)``, ``h(x) = x``, ``R = diag(b_a^2/3, b_w^2/3)``
(the variance of a uniform error within the bounds, each bound at least
``MEAS_FLOOR``). After each step the mean
attitude error is folded into the reference (``q_ref <- q_ref exp(a)``, ``a <- 0``);
the covariance is kept (its transport by the small reset rotation is neglected, as
in the usual multiplicative EKF/UKF).

Two implementations of the same filter: :meth:`UkfAttitudeEstimator.predict` /
``update`` run all runs and all sigma points as one numpy batch (the Monte Carlo
path); :meth:`predict_filterpy` / :meth:`update_filterpy` build a fresh filterpy
:class:`UnscentedKalmanFilter` from one run's belief (never stored) with the hooks
above. The tests check that both give the same belief.

The belief is read as its ``gate``-ellipsoid (``chi2`` quantile ``gate_prob`` in 6
dimensions): ``contains`` by Mahalanobis distance, ``extremes`` over points of it.
That is a probabilistic region, not a guarantee.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter
from kalman_vs_infoset.estim.attitude.model import (
    AttitudeControl,
    AttitudeMeasurement,
    AttitudeModel,
    AttitudePrior,
    NeverEmptyBelief,
    check_runs,
    check_step,
    rate_component,
    rk4_attitude,
    run_states,
)
from kalman_vs_infoset.estim.attitude.ukf.options import DEFAULTS
from kalman_vs_infoset.estim.base import Estimator, Extremes, StateFunction, Status
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from kalman_vs_infoset.numerics.arrays import readonly
from kalman_vs_infoset.numerics.rotations import qexp, qinv, qlog, qmul

FloatArray = NDArray[np.float64]
DIM = 9  # (a, w, d): attitude error, rate, disturbance torque
DIM_Z = 6
#: least measurement error bound the filter assumes (rad for the angle, rad/s for the
#: rate): far under any sensor's, far over rounding of the covariance (~1e-16 relative)
MEAS_FLOOR = 1e-8
TAU_D_S = 60.0


def residual_x(x1: FloatArray, x2: FloatArray) -> FloatArray:
    """On-manifold difference of error states or measurements (batched over leading axes).

    ``log(exp(a2)^-1 exp(a1))``; when every ``|a2| < 1e-15`` this is ``a1 - a2`` to
    ``|a1| |a2|/2 < 1e-15 |a1|`` (BCH) and is computed so (the reset makes ``a2 = 0``).
    """
    if not np.any(np.abs(x2[..., 0:3]) >= 1e-15):
        return x1 - x2
    a = qlog(qmul(qinv(qexp(x2[..., 0:3])), qexp(x1[..., 0:3])))
    return np.concatenate([a, x1[..., 3:] - x2[..., 3:]], axis=-1)


def state_add(x: FloatArray, dx: FloatArray) -> FloatArray:
    """On-manifold sum of an error state and a correction (batched); ``a = 0``: ``da``."""
    if not np.any(x[..., 0:3]):
        return x + dx
    a = qlog(qmul(qexp(x[..., 0:3]), qexp(dx[..., 0:3])))
    return np.concatenate([a, x[..., 3:] + dx[..., 3:]], axis=-1)


def tangent_mean(sigmas: FloatArray, wm: FloatArray) -> FloatArray:
    """Weighted mean of sigma points ``(..., S, 6)`` in the tangent space at the reference."""
    return np.einsum("s,...si->...i", wm, sigmas)


@dataclass(frozen=True, eq=False)
class UkfAttitudeBelief(NeverEmptyBelief):
    """Reference quaternions ``(R, 4)``, error-state means ``(R, 9)``, covariances ``(R, 9, 9)``."""

    q_ref: FloatArray
    mean: FloatArray
    cov: FloatArray
    gate: float = float(np.sqrt(chi2.ppf(0.997, DIM_Z)))
    #: a Kalman update is never contradicted (outliers are kept, not rejected)
    status: Status = Status.OK
    contradictions: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "q_ref", readonly(np.atleast_2d(self.q_ref)))
        object.__setattr__(self, "mean", readonly(np.atleast_2d(self.mean)))
        cov = np.array(self.cov, dtype=float)
        if cov.ndim == 2:
            cov = cov[None]
        object.__setattr__(self, "cov", readonly(cov))
        if self.mean.shape[-1] != DIM or self.cov.shape[-2:] != (DIM, DIM):
            raise ValueError("mean must be (R, 9) and cov (R, 9, 9)")

    @property
    def runs(self) -> int:
        return self.q_ref.shape[0]

    def centre(self) -> FloatArray:
        """``(q, w)`` of the mean, ``(R, 7)``."""
        q = qmul(self.q_ref, qexp(self.mean[:, 0:3]))
        return np.concatenate([q, self.mean[:, 3:6]], axis=-1)

    def error_of(self, state: ArrayLike) -> FloatArray:
        """``(a, w)`` of true states ``(q, w, ...)`` in this belief's coordinates."""
        x = np.atleast_2d(np.asarray(state, dtype=float))
        return np.concatenate([qlog(qmul(qinv(self.q_ref), x[:, 0:4])), x[:, 4:7]], axis=-1)

    def mahalanobis(self, state: ArrayLike) -> FloatArray:
        """Mahalanobis distance of ``(q, w)`` in the ``(a, w)`` marginal."""
        r = residual_x(self.error_of(state), self.mean[:, 0:DIM_Z])
        sol = np.linalg.solve(self.cov[:, 0:DIM_Z, 0:DIM_Z], r[..., None])[..., 0]
        return np.sqrt(np.maximum(np.sum(r * sol, axis=-1), 0.0))

    def inside(self, state: ArrayLike) -> NDArray[np.bool_]:
        return self.mahalanobis(run_states(state, self.runs)) <= self.gate

    def contains(self, state: ArrayLike) -> bool:
        return bool(np.all(self.inside(state)))

    def attitude_bound_rad(self) -> FloatArray:
        """``gate`` times the largest attitude standard deviation (not guaranteed)."""
        return self.gate * np.sqrt(np.linalg.eigvalsh(self.cov[:, 0:3, 0:3])[:, -1])

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of a :class:`RateComponent` over run 0's gate ellipsoid, in
        closed form: ``w_i = m_i +- gate sqrt(P_ii)``, attained at ``m +- gate P e_i /
        sqrt(P_ii)`` (``m``, ``P``: the error state's mean and covariance, rate
        coordinates ``3..5``); any other function is refused with ``TypeError``."""
        fn = rate_component(fn, "the UKF's gate ellipsoid")
        k = 3 + fn.axis
        cov = self.cov[0, 0:DIM_Z, 0:DIM_Z]
        step = self.gate * cov[:, k] / np.sqrt(cov[k, k])
        pts_err = self.mean[0, 0:DIM_Z] + np.stack([-step, step])
        q = qmul(np.broadcast_to(self.q_ref[0], (2, 4)), qexp(pts_err[:, 0:3]))
        pts = np.concatenate([q, pts_err[:, 3:6]], axis=-1)
        vals = fn(pts)
        return Extremes(float(vals[0]), pts[0], float(vals[1]), pts[1])


def _with(belief: UkfAttitudeBelief, **changes: Any) -> UkfAttitudeBelief:
    new = object.__new__(UkfAttitudeBelief)
    for name in UkfAttitudeBelief.__dataclass_fields__:
        value = changes.get(name, getattr(belief, name))
        if isinstance(value, np.ndarray) and value.flags.writeable:
            value.setflags(write=False)
        object.__setattr__(new, name, value)
    return new


@dataclass(frozen=True)
class UkfAttitudeEstimator(Estimator[UkfAttitudeBelief, AttitudePrior]):
    """UKF on the multiplicative error state (see the module docstring)."""

    model: AttitudeModel
    gate_prob: float = DEFAULTS.gate_prob
    floor_accel_radps2: float = 1e-9
    substeps: int = 1
    points: MerweScaledSigmaPoints = field(init=False, repr=False)
    r_cov: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not 0 < self.gate_prob < 1:
            raise ValueError("gate_prob must be in (0, 1)")
        if self.substeps < 1:
            raise ValueError("substeps must be >= 1")
        object.__setattr__(self, "points", MerweScaledSigmaPoints(DIM, 1.0, 2.0, 0.0))
        bound = np.concatenate([self.model.meas_angle_bound_rad, self.model.meas_rate_bound_radps])
        # measurement noise R (6 x 6), its bounds floored: error-free measurements (the
        # loops' noise "none" passes bounds of 1e-12) made R ~ 1e-24 and the updated
        # covariance lost definiteness to rounding (LinAlgError in the next Cholesky)
        bound = np.maximum(bound, MEAS_FLOOR)
        object.__setattr__(self, "r_cov", readonly(np.diag(bound**2 / 3.0)))

    @property
    def gate(self) -> float:
        return float(np.sqrt(chi2.ppf(self.gate_prob, DIM_Z)))

    def process_noise(self, dt_s: float) -> FloatArray:
        """``Q``: a white torque of variance ``D^2/3`` through ``G = (dt^2/2 J_b^-1; dt J_b^-1)``,
        a floor, and a random walk of the disturbance state, variance ``D^2/3 dt/tau_d``."""
        jinv = self.model.j_b_inv
        var_d = self._var_d
        g = np.vstack([0.5 * dt_s**2 * jinv, dt_s * jinv])
        q = np.zeros((DIM, DIM))
        q[0:6, 0:6] = g @ np.diag(var_d) @ g.T
        gf = np.concatenate([0.5 * dt_s**2 * np.ones(3), dt_s * np.ones(3)])
        q[0:6, 0:6] += np.diag(gf**2) * self.floor_accel_radps2**2
        q[6:9, 6:9] = np.diag(var_d * dt_s / TAU_D_S)
        return q

    @property
    def _var_d(self) -> FloatArray:
        """Variance of a uniform disturbance in ``[-D, D]`` (floored: keeps P definite)."""
        j_b = self.model.effective_inertia_kgm2
        assert j_b is not None  # AttitudeModel.__post_init__ always sets J_b
        floor = self.floor_accel_radps2 * np.diag(j_b)
        return np.maximum(self.model.disturbance_bound_Nm, floor) ** 2 / 3.0

    def initial(self, prior: AttitudePrior) -> UkfAttitudeBelief:
        """Mean at the first measurement, its error covariance; disturbance at zero."""
        meas = prior.measurement
        runs = meas.quat.shape[0]
        mean = np.concatenate([np.zeros((runs, 3)), meas.rate_radps, np.zeros((runs, 3))], -1)
        cov0 = np.zeros((DIM, DIM))
        cov0[0:6, 0:6] = self.r_cov
        cov0[6:9, 6:9] = np.diag(self._var_d)
        cov = np.broadcast_to(cov0, (runs, DIM, DIM)).copy()
        return UkfAttitudeBelief(meas.quat, mean, cov, gate=self.gate)

    # -- shared pieces -------------------------------------------------------------------
    def _sigma_points(self, mean: FloatArray, cov: FloatArray) -> FloatArray:
        """Van der Merwe points ``(R, 13, 6)``: ``x, x + U_k, x - U_k`` (U = chol upper)."""
        lam = self.points.alpha**2 * (DIM + self.points.kappa) - DIM
        try:
            lower = np.linalg.cholesky((DIM + lam) * cov)
        except np.linalg.LinAlgError:  # numpy's words name neither the filter nor why
            raise np.linalg.LinAlgError(
                "the UKF diverged: its covariance is no longer positive definite"
            ) from None
        rows = np.swapaxes(lower, -1, -2)
        x = mean[:, None, :]
        return np.concatenate([x, x + rows, x - rows], axis=1)

    @staticmethod
    def _control(belief, control: AttitudeControl | None) -> AttitudeControl:
        if control is None:
            return AttitudeControl.zero(belief.runs)
        if not isinstance(control, AttitudeControl):
            raise TypeError("control must be an AttitudeControl")
        check_runs(belief.runs, control.runs, "control")
        return control

    def _propagate(self, belief, sigmas, dt_s, ctrl: AttitudeControl):
        """Full-state propagation of error-state points ``(R, S, 6)`` -> quats, rates,
        under the known inputs ``ctrl`` held over the step."""
        q = qmul(belief.q_ref[:, None, :], qexp(sigmas[..., 0:3]))
        h_mid = 0.5 * (ctrl.h_lo_Nms + ctrl.h_hi_Nms)
        return rk4_attitude(
            self.model,
            q,
            sigmas[..., 3:6],
            ctrl.torque_Nm[:, None, :] + sigmas[..., 6:9],
            h_mid[:, None, :],
            dt_s,
            self.substeps,
        )

    def _reset(self, belief, q_ref, mean, cov) -> UkfAttitudeBelief:
        q_new = qmul(q_ref, qexp(mean[:, 0:3]))
        mean = np.concatenate([np.zeros_like(mean[:, 0:3]), mean[:, 3:]], axis=-1)
        cov = 0.5 * (cov + np.swapaxes(cov, -1, -2))
        return _with(belief, q_ref=q_new, mean=mean, cov=cov)

    # -- batched filter ------------------------------------------------------------------
    def predict(
        self, belief: UkfAttitudeBelief, dt_s: float, control: AttitudeControl | None = None
    ) -> UkfAttitudeBelief:
        """Sigma points through the model under the known inputs ``control`` held over
        the step (None: no torque, no momentum)."""
        check_step(dt_s)
        ctrl = self._control(belief, control)
        sig = self._sigma_points(belief.mean, belief.cov)
        q1, w1 = self._propagate(belief, sig, dt_s, ctrl)
        q_ref = q1[:, 0]  # the propagated mean point (sigma point 0 is the mean)
        chi = np.concatenate([qlog(qmul(qinv(q_ref)[:, None, :], q1)), w1, sig[..., 6:9]], -1)
        wm, wc = self.points.Wm, self.points.Wc
        mean = tangent_mean(chi, wm)
        res = residual_x(chi, mean[:, None, :])
        cov = np.einsum("s,rsi,rsj->rij", wc, res, res) + self.process_noise(dt_s)
        return self._reset(belief, q_ref, mean, cov)

    def update(self, belief: UkfAttitudeBelief, measurement: Any) -> UkfAttitudeBelief:
        if not isinstance(measurement, AttitudeMeasurement):
            raise TypeError("measurement must be an AttitudeMeasurement")
        check_runs(belief.runs, measurement.runs, "measurement")
        z = np.concatenate(
            [qlog(qmul(qinv(belief.q_ref), measurement.quat)), measurement.rate_radps], axis=-1
        )
        sig = self._sigma_points(belief.mean, belief.cov)
        wm, wc = self.points.Wm, self.points.Wc
        sig_z = sig[..., 0:DIM_Z]  # h(x) = (a, w)
        zp = tangent_mean(sig_z, wm)
        rz = residual_x(sig_z, zp[:, None, :])
        rx = residual_x(sig, belief.mean[:, None, :])
        s = np.einsum("s,rsi,rsj->rij", wc, rz, rz) + self.r_cov
        pxz = np.einsum("s,rsi,rsj->rij", wc, rx, rz)
        k = np.swapaxes(np.linalg.solve(s, np.swapaxes(pxz, -1, -2)), -1, -2)
        y = residual_x(z, zp)
        mean = state_add(belief.mean, np.einsum("rij,rj->ri", k, y))
        cov = belief.cov - k @ s @ np.swapaxes(k, -1, -2)
        return self._reset(belief, belief.q_ref, mean, cov)

    # -- the same filter through filterpy (one run; used to check the batch) -------------
    def _filterpy(self, belief: UkfAttitudeBelief, fx, dt_s: float) -> UnscentedKalmanFilter:
        if belief.runs != 1:
            raise ValueError("the filterpy path takes one run")
        ukf = UnscentedKalmanFilter(
            dim_x=DIM,
            dim_z=DIM_Z,
            dt=dt_s,
            hx=lambda s: np.array(s[0:DIM_Z], dtype=float),
            fx=fx,
            points=MerweScaledSigmaPoints(DIM, 1.0, 2.0, 0.0),
            x_mean_fn=tangent_mean,
            z_mean_fn=tangent_mean,
            residual_x=residual_x,
            residual_z=residual_x,
            state_add=state_add,
        )
        ukf.x = np.array(belief.mean[0])
        ukf.P = np.array(belief.cov[0])
        return ukf

    def predict_filterpy(
        self, belief: UkfAttitudeBelief, dt_s: float, control: AttitudeControl | None = None
    ) -> UkfAttitudeBelief:
        ctrl = self._control(belief, control)
        mean_pt = belief.mean[:, None, :]
        q1, _ = self._propagate(belief, mean_pt, dt_s, ctrl)
        q_ref = q1[:, 0]

        def fx(s, dt):
            qs, ws = self._propagate(belief, np.asarray(s, float)[None, None, :], dt, ctrl)
            return np.concatenate([qlog(qmul(qinv(q_ref), qs[:, 0]))[0], ws[0, 0], s[6:9]])

        ukf = self._filterpy(belief, fx, dt_s)
        ukf.Q = self.process_noise(dt_s)
        ukf.predict()
        return self._reset(belief, q_ref, ukf.x[None], ukf.P[None])

    def update_filterpy(self, belief: UkfAttitudeBelief, meas: AttitudeMeasurement):
        ukf = self._filterpy(belief, lambda s, dt: s, 1.0)
        ukf.R = np.array(self.r_cov)
        ukf.sigmas_f = ukf.points_fn.sigma_points(ukf.x, ukf.P)
        z = np.concatenate([qlog(qmul(qinv(belief.q_ref), meas.quat))[0], meas.rate_radps[0]])
        ukf.update(z)
        return self._reset(belief, belief.q_ref, ukf.x[None], ukf.P[None])
