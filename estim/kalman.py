"""EKF and UKF of one intercept guidance channel, built on filterpy (SPEC 1.7).

State choice. Per channel the state is ``s = (alpha, omega, x)``: bearing (rad),
bearing rate (rad/s) and range along the nominal axis (m), the very coordinates
of the auxiliary model (SPEC 1.3, :mod:`estim.model`) and of the information set.
Reasons:

* the bearing measurement is then *linear*, ``h(s) = alpha``, so the update of both
  filters is the exact Kalman update and any difference to the set comes from the
  prediction model and the Gaussian reading of the noise, not from linearising
  the measurement;
* the one-step map (exact for constant ``v``) and the disturbance ``v`` are those
  of the set, so both estimators are run on the same model (a fair comparison),
  and the guidance law receives rows ``(alpha, omega, x)`` from both;
* the miss forecast ``Pi`` is a function of ``(omega, x)`` alone, which makes its
  extremes over the ellipsoid a 1-D problem (:mod:`estim.kalman_belief`).

The Cartesian alternative ``(y, Vy, x, Vx)`` would put the nonlinearity into the
bearing ``atan2(y, x)`` and need its own model of the disturbance. As in the set,
``x`` drifts at the *nominal* closing speed ``e`` with no process noise (the
mismatch of the true closing speed is part of what ``v`` stands for).

Model (SPEC 1.3, :meth:`estim.model.ChannelModel.step`), one step ``Delta``::

    alpha1 = alpha0 + omega0 x0 Delta / x1 + g_alpha v,  g_alpha = Delta^2 / (2 x1)
    omega1 = omega0 x0^2 / x1^2 + g_omega v,             g_omega = Delta (x0 + x1) / (2 x1^2)
    x1     = x0 - e Delta

with ``v`` uniform in ``[-nu, nu]`` and constant over the step: process noise
``Q = G G^T nu^2/3``, ``G = (g_alpha, g_omega, 0)`` at the mean range. The EKF
Jacobian ``F = d s1/d s0`` has ``d alpha1/d omega0 = x0 Delta/x1``,
``d alpha1/d x0 = -omega0 e Delta^2/x1^2``, ``d omega1/d omega0 = x0^2/x1^2``,
``d omega1/d x0 = -2 omega0 x0 e Delta/x1^3``, ``d x1/d x0 = 1``.

Measurements: bearing ``alpha`` with a uniform error of half-width ``a(d)``,
variance ``R = a(x_hat)^2/3``; range ``d = x / cos(alpha)`` (the other channel's
angle neglected: a relative 1e-6) with a uniform error ``|beta| <= b d``,
``R = (b d_hat)^2/3``. Control: an impulse ``k`` maps ``omega -> omega + k/x``
(nonlinear in an uncertain ``x``: the EKF linearises it, the UKF transforms it).

Initial belief: the exact first two moments of ``alpha = y/x``,
``omega = Vy/x + c y/x^2`` (``c = -Vx``; the set's small-angle map with ``c = e``)
for ``y, Vy, x, c`` independent and uniform in their boxes (variance
``width^2/12``), from the closed-form moments of ``1/x^k`` of a uniform ``x``.

filterpy objects are mutable: each call builds a fresh filter from the belief's
``(mean, cov)`` (copies), runs one filterpy step and returns a new
:class:`~estim.kalman_belief.GaussianBelief`; no filter is ever stored. The
EKF's state map is filterpy's documented override point ``predict_x``; the UKF
uses Van der Merwe's scaled sigma points with ``alpha = 1, beta = 2, kappa = 0``
(points at ``+-sqrt(3)`` standard deviations, the edges of a uniform box).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter, MerweScaledSigmaPoints, UnscentedKalmanFilter
from numpy.typing import NDArray

from estim.base import Estimator
from estim.kalman_belief import GaussianBelief, psd_cholesky
from estim.model import Bearing, ChannelModel, Range

FloatArray = NDArray[np.float64]

KINDS = ("ekf", "ukf")
_H_BEARING = np.array([[1.0, 0.0, 0.0]])


class _MappedEKF(ExtendedKalmanFilter):
    """filterpy's EKF whose mean is propagated by an exact nonlinear map ``fx``.

    filterpy's ``predict`` calls ``predict_x`` (documented as the method to
    override when ``F x`` is not the state map) and then ``P = F P F^T + Q``.
    """

    def __init__(self, fx) -> None:
        super().__init__(dim_x=3, dim_z=1)
        self._fx = fx

    def predict_x(self, u=0) -> None:
        self.x = self._fx(self.x)


def _inv_moment(a: float, b: float, k: int) -> float:
    """``E[x^-k]`` for ``x`` uniform in ``[a, b]``, ``0 < a <= b``."""
    if b - a <= 1e-9 * b:
        return (0.5 * (a + b)) ** -k
    if k == 1:
        return math.log(b / a) / (b - a)
    return (a ** (1 - k) - b ** (1 - k)) / ((k - 1) * (b - a))


def _uniform_moments(lo: float, hi: float) -> tuple[float, float]:
    """Mean and second raw moment of a uniform variable on ``[lo, hi]``."""
    mean = 0.5 * (lo + hi)
    return mean, mean**2 + (hi - lo) ** 2 / 12.0


@dataclass(frozen=True)
class KalmanChannelEstimator(Estimator[GaussianBelief]):
    """EKF or UKF of one guidance channel behind the estimator interface.

    Parameters
    ----------
    model : ChannelModel
        Closing speed, disturbance bound ``nu``, measurement bounds, ``eps``.
    kind : {"ekf", "ukf"}
        Filter type.
    n_sigma : float
        Radius (in standard deviations) of the ellipsoid the beliefs answer with.
    ukf_alpha, ukf_beta, ukf_kappa : float
        Van der Merwe sigma-point parameters (UKF only).
    """

    model: ChannelModel = field(default_factory=ChannelModel)
    kind: str = "ekf"
    n_sigma: float = 3.0
    ukf_alpha: float = 1.0
    ukf_beta: float = 2.0
    ukf_kappa: float = 0.0
    _points: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        if not self.n_sigma > 0:
            raise ValueError("n_sigma must be positive")
        if not (self.ukf_alpha > 0 and 3 + self.ukf_kappa > 0):
            raise ValueError("ukf_alpha must be positive and 3 + ukf_kappa positive")
        # the sigma-point generator holds weights only (never mutated by filterpy);
        # the PSD square root accepts an exactly known direction (zero variance)
        points = MerweScaledSigmaPoints(
            3,
            self.ukf_alpha,
            self.ukf_beta,
            self.ukf_kappa,
            sqrt_method=lambda p: psd_cholesky(p).T,
        )
        object.__setattr__(self, "_points", points)

    # -- construction ----------------------------------------------------------------
    def belief(self, mean, cov) -> GaussianBelief:
        """A belief with this estimator's ``n_sigma``."""
        return GaussianBelief(mean, cov, self.n_sigma)

    def initial(
        self,
        lateral_m: tuple[float, float],
        lateral_vel_mps: tuple[float, float],
        x_m: tuple[float, float],
        vx_mps: tuple[float, float] | None = None,
    ) -> GaussianBelief:
        """Moment-matched Gaussian of the a-priori boxes (see module docstring).

        ``alpha = y/x``, ``omega = Vy/x + c y/x^2`` with ``c = -Vx`` uniform in the
        ``vx_mps`` box (``c = e`` when it is not given), ``x`` uniform in ``x_m``.
        """
        (y0, y1), (v0, v1), (xa, xb) = lateral_m, lateral_vel_mps, x_m
        if vx_mps is None:
            c0 = c1 = self.model.e
        else:
            c0, c1 = sorted((-vx_mps[0], -vx_mps[1]))
        if not (y0 <= y1 and v0 <= v1 and 0 < xa <= xb and c0 > 0):
            raise ValueError("boxes must be [lo, hi] with lo <= hi, positive range and closing")
        ey, ey2 = _uniform_moments(y0, y1)
        ev, ev2 = _uniform_moments(v0, v1)
        ec, ec2 = _uniform_moments(c0, c1)
        ex, ex2 = _uniform_moments(xa, xb)
        r1, r2, r3, r4 = (_inv_moment(xa, xb, k) for k in (1, 2, 3, 4))
        m_a = ey * r1
        m_w = ev * r1 + ec * ey * r2
        e_aa = ey2 * r2
        e_ww = ev2 * r2 + 2.0 * ev * ey * ec * r3 + ec2 * ey2 * r4
        e_aw = ey * ev * r2 + ec * ey2 * r3
        e_ax = ey  # E[y/x x]
        e_wx = ev + ec * ey * r1
        mean = np.array([m_a, m_w, ex])
        second = np.array([[e_aa, e_aw, e_ax], [e_aw, e_ww, e_wx], [e_ax, e_wx, ex2]], dtype=float)
        cov = second - np.outer(mean, mean)
        cov[2, 2] = (xb - xa) ** 2 / 12.0
        # raw moments minus squared means cancel: a variance below the rounding of
        # its second moment is an exactly known coordinate (degenerate box)
        known = np.diag(cov) <= 1e-12 * np.diag(second)
        cov[known, :] = 0.0
        cov[:, known] = 0.0
        return self.belief(mean, cov)

    # -- model pieces ------------------------------------------------------------------
    def process_noise(self, x_m: float, dt_s: float) -> FloatArray:
        """``Q = G G^T nu^2/3``, ``G = (g_alpha, g_omega, 0)`` at range ``x_m``."""
        c = self.model.step_coefficients(x_m, dt_s)
        g = np.array([float(c["g_alpha"]), float(c["g_omega"]), 0.0])
        return np.outer(g, g) * self.model.nu_mps2**2 / 3.0

    def step_jacobian(self, state, dt_s: float) -> FloatArray:
        """``F = d step(s)/d s`` at ``s = (alpha, omega, x)`` (module docstring)."""
        _, w, x0 = (float(v) for v in state)
        e = self.model.e
        x1 = x0 - e * dt_s
        return np.array(
            [
                [1.0, x0 * dt_s / x1, -w * e * dt_s**2 / x1**2],
                [0.0, x0**2 / x1**2, -2.0 * w * x0 * e * dt_s / x1**3],
                [0.0, 0.0, 1.0],
            ]
        )

    @staticmethod
    def range_of(state) -> FloatArray:
        """Range ``d = x / cos(alpha)`` of ``(alpha, omega, x)`` (rows)."""
        s = np.asarray(state, dtype=float)
        return s[..., 2] / np.cos(s[..., 0])

    # -- Estimator interface ---------------------------------------------------------
    def predict(self, belief: GaussianBelief, dt_s: float) -> GaussianBelief:
        """Propagate over ``dt_s`` (exact map, ``Q`` of the disturbance).

        When the mean range would pass under ``eps`` the belief becomes empty
        with status ``"terminal"`` (as the set after its threshold): guidance ends.
        """
        if belief.is_empty:
            return belief
        x1 = float(belief.mean[2]) - self.model.e * dt_s
        if x1 < self.model.eps_m:
            return replace(belief, status="terminal")
        q = self.process_noise(float(belief.mean[2]), dt_s)

        def fx(s, dt=dt_s):
            return self.model.step(s, dt)

        if self.kind == "ekf":
            f = _MappedEKF(fx)
            f.x, f.P = belief.mean.copy(), belief.cov.copy()
            f.F, f.Q = self.step_jacobian(belief.mean, dt_s), q
            f.predict()
        else:
            f = self._ukf(belief, fx)
            f.Q = q
            f.predict(dt=dt_s)
        return replace(belief, mean=f.x, cov=f.P)

    def shift(self, belief: GaussianBelief, control: float) -> GaussianBelief:
        """Impulse ``k`` (m/s, relative velocity): ``omega -> omega + k/x``."""
        k = float(control)
        if k == 0.0 or belief.is_empty:
            return belief

        def fx(s, dt=0.0):
            out = np.array(s, dtype=float)
            out[..., 1] = out[..., 1] + k / out[..., 2]
            return out

        if self.kind == "ekf":
            f = _MappedEKF(fx)
            f.x, f.P = belief.mean.copy(), belief.cov.copy()
            jac = np.eye(3)
            jac[1, 2] = -k / float(belief.mean[2]) ** 2
            f.F, f.Q = jac, np.zeros((3, 3))
            f.predict()
        else:
            f = self._ukf(belief, fx)
            f.Q = np.zeros((3, 3))
            f.predict(dt=0.0)
        return replace(belief, mean=f.x, cov=f.P)

    def update(self, belief: GaussianBelief, measurement: Bearing | Range) -> GaussianBelief:
        """Kalman update with a bearing (linear) or a range (nonlinear) measurement."""
        if belief.is_empty:
            return belief
        if isinstance(measurement, Bearing):
            z = float(measurement.alpha_rad)
            a = float(self.model.bearing_bound(abs(float(belief.mean[2]))))
            r = a * a / 3.0

            def hx(s):
                return np.array([s[0]])

            def jac(s):
                return _H_BEARING
        elif isinstance(measurement, Range):
            z = float(measurement.range_m)
            d_hat = float(self.range_of(belief.mean))
            r = (self.model.range_rel_bound * d_hat) ** 2 / 3.0

            def hx(s):
                return np.array([s[2] / math.cos(s[0])])

            def jac(s):
                ca = math.cos(s[0])
                return np.array([[s[2] * math.sin(s[0]) / ca**2, 0.0, 1.0 / ca]])
        else:
            raise TypeError(f"unsupported measurement {type(measurement).__name__}")

        zs = np.array([z])
        if self.kind == "ekf":
            f = ExtendedKalmanFilter(dim_x=3, dim_z=1)
            f.x, f.P = belief.mean.copy(), belief.cov.copy()
            f.update(zs, jac, hx, R=np.array([[r]]))
        else:
            f = self._ukf(belief, lambda s, dt: s, hx)
            f.compute_process_sigmas(0.0, fx=lambda s, dt: s)  # sigmas of the current belief
            f.update(zs, R=np.array([[r]]))
        innovation = float(np.ravel(f.y)[0])
        s_var = float(np.ravel(f.S)[0])
        outlier = innovation**2 > belief.n_sigma**2 * s_var
        return replace(
            belief,
            mean=np.ravel(f.x),
            cov=f.P,
            innovation_outliers=belief.innovation_outliers + int(outlier),
        )

    # -- helpers -----------------------------------------------------------------------
    def _ukf(self, belief: GaussianBelief, fx, hx=None) -> UnscentedKalmanFilter:
        """A fresh filterpy UKF holding copies of the belief's mean and covariance."""
        f = UnscentedKalmanFilter(
            dim_x=3,
            dim_z=1,
            dt=0.0,
            hx=hx if hx is not None else (lambda s: np.array([s[0]])),
            fx=fx,
            points=self._points,
        )
        f.x, f.P = belief.mean.copy(), belief.cov.copy()
        return f
