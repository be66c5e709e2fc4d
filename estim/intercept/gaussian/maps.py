"""The Kalman filters' model pieces in their coordinates ``(alpha, r, x)``, and the
moments of a uniform box (docs/models.md §1.3; the choice of ``r`` is explained in
:mod:`kalman_vs_infoset.estim.intercept.gaussian.estimator`)."""

from __future__ import annotations

import math

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter
from kalman_vs_infoset.estim.intercept.model import ChannelModel
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def inv_moment(a: float, b: float, k: int) -> float:
    """``E[x^-k]`` for ``x`` uniform in ``[a, b]``, ``0 < a <= b``."""
    if b - a <= 1e-9 * b:
        return (0.5 * (a + b)) ** -k
    if k == 1:
        return math.log(b / a) / (b - a)
    return (a ** (1 - k) - b ** (1 - k)) / ((k - 1) * (b - a))


def uniform_moments(lo: float, hi: float) -> tuple[float, float]:
    """Mean and second raw moment of a uniform variable on ``[lo, hi]``."""
    mean = 0.5 * (lo + hi)
    return mean, mean**2 + (hi - lo) ** 2 / 12.0


def project_on_bound(mean, cov, k: int, bound: float) -> FloatArray:
    """Estimate projection of ``mean`` onto ``{m : m[k] = bound}`` in the ``cov^-1`` metric.

    The minimiser of ``(m - mean)^T cov^-1 (m - mean)`` subject to ``m[k] = bound``
    (Simon 2010, estimate projection with ``W = P^-1``, one equality row ``D = e_k``):
    ``mean + cov[:, k]/cov[k, k] (bound - mean[k])``. A zero ``cov[k, k]`` (an exactly
    known component, hence uncorrelated: ``cov[:, k] = 0``) moves ``mean[k]`` alone.

    Parameters
    ----------
    mean : array (n,)
        Unconstrained mean.
    cov : array (n, n)
        Its covariance (positive semi-definite).
    k : int
        Index of the constrained component.
    bound : float
        Value the component is projected onto (the active bound).

    Returns
    -------
    array (n,)
        The projected mean (a new array).
    """
    mean = np.array(mean, dtype=float)
    cov = np.asarray(cov, dtype=float)
    if cov[k, k] > 0.0:
        return mean + cov[:, k] / cov[k, k] * (bound - mean[k])
    mean[k] = bound
    return mean


def box_moments(
    lateral_m: tuple[float, float],
    lateral_vel_mps: tuple[float, float],
    x_m: tuple[float, float],
    closing_mps: tuple[float, float],
    e: float,
    coords: str,
) -> tuple[FloatArray, FloatArray]:
    """Mean and covariance of ``(alpha, r, x)`` for ``y``, ``Vy``, ``x`` and the closing
    speed ``c`` independent and uniform in their boxes: ``alpha = y/x``, ``r = omega =
    Vy/x + c y/x^2`` (``coords="rate"``) or ``r = w = (Vy x + c y)/e`` (``"zem"``)."""
    (y0, y1), (v0, v1), (xa, xb), (c0, c1) = lateral_m, lateral_vel_mps, x_m, closing_mps
    ey, ey2 = uniform_moments(y0, y1)
    ev, ev2 = uniform_moments(v0, v1)
    ec, ec2 = uniform_moments(c0, c1)
    ex, ex2 = uniform_moments(xa, xb)
    r1, r2, r3, r4 = (inv_moment(xa, xb, k) for k in (1, 2, 3, 4))
    m_a, e_aa, e_ax = ey * r1, ey2 * r2, ey  # alpha = y r, r = 1/x
    if coords == "rate":  # omega = Vy r + c y r^2
        m_r = ev * r1 + ec * ey * r2
        e_rr = ev2 * r2 + 2.0 * ev * ey * ec * r3 + ec2 * ey2 * r4
        e_ar = ey * ev * r2 + ec * ey2 * r3
        e_rx = ev + ec * ey * r1
    else:  # w = (Vy x + c y) / e
        m_r = (ev * ex + ec * ey) / e
        e_rr = (ev2 * ex2 + 2.0 * ev * ex * ec * ey + ec2 * ey2) / e**2
        e_ar = (ey * ev + ec * ey2 * r1) / e
        e_rx = (ev * ex2 + ec * ey * ex) / e
    mean = np.array([m_a, m_r, ex])
    second = np.array([[e_aa, e_ar, e_ax], [e_ar, e_rr, e_rx], [e_ax, e_rx, ex2]])
    cov = second - np.outer(mean, mean)
    cov[2, 2] = (xb - xa) ** 2 / 12.0
    # raw moments minus squared means cancel: a variance below the rounding of
    # its second moment is an exactly known coordinate (degenerate box)
    known = np.diag(cov) <= 1e-12 * np.diag(second)
    cov[known, :] = 0.0
    cov[:, known] = 0.0
    return mean, cov


class MappedEKF(ExtendedKalmanFilter):
    """filterpy's EKF whose mean is propagated by an exact nonlinear map ``fx``.

    filterpy's ``predict`` calls ``predict_x`` (documented as the method to
    override when ``F x`` is not the state map) and then ``P = F P F^T + Q``.
    """

    x: FloatArray  # filterpy's state (column or row vector; filterpy ships no types)

    def __init__(self, fx) -> None:
        super().__init__(dim_x=3, dim_z=1)
        self._fx = fx

    def predict_x(self, u=0) -> None:
        self.x = self._fx(self.x)


class ChannelMaps:
    """The one-step map, its Jacobian, the process noise, the impulse map and the range
    of internal rows ``(alpha, r, x)``: a mixin of the filter of a channel, which
    holds ``model``, ``coords`` (``"rate"``: ``r = omega``; ``"zem"``: ``r = w``) and
    ``noise_inflation``."""

    # what the mixin uses of the filter (declared there, as dataclass fields)
    model: ChannelModel
    coords: str
    noise_inflation: float

    def step(self, q, dt_s: float) -> FloatArray:
        """Exact one-step map of internal rows ``(alpha, r, x)`` with ``v = 0``."""
        q = np.asarray(q, dtype=float)
        if self.coords == "rate":
            return self.model.step(q, dt_s)
        c = self.model.step_coefficients(q[..., 2], dt_s)
        return np.stack([q[..., 0] + c["a_w"] * q[..., 1], q[..., 1], c["x1"]], axis=-1)

    def process_noise(self, x_m: float, dt_s: float) -> FloatArray:
        """``Q = s G G^T nu^2/3``, ``G = (g_alpha, g_r, 0)`` at range ``x_m``, ``s``
        the noise inflation."""
        c = self.model.step_coefficients(x_m, dt_s)
        g_r = c["g_omega"] if self.coords == "rate" else c["g_w"]
        g = np.array([float(c["g_alpha"]), float(g_r), 0.0])
        return np.outer(g, g) * self.model.nu_mps2**2 / 3.0 * self.noise_inflation

    def step_jacobian(self, q, dt_s: float) -> FloatArray:
        """``F = d step(q)/d q`` at ``q = (alpha, r, x)`` (module docstring)."""
        _, r, x0 = (float(v) for v in q)
        e = self.model.e
        x1 = x0 - e * dt_s
        if self.coords == "rate":
            return np.array(
                [
                    [1.0, x0 * dt_s / x1, -r * e * dt_s**2 / x1**2],
                    [0.0, x0**2 / x1**2, -2.0 * r * x0 * e * dt_s / x1**3],
                    [0.0, 0.0, 1.0],
                ]
            )
        return np.array(
            [
                [1.0, e * dt_s / (x0 * x1), -r * e * dt_s * (x0 + x1) / (x0 * x1) ** 2],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ]
        )

    def shift_map(self, q, k_mps: float) -> FloatArray:
        """Internal rows after an impulse ``k``: ``omega + k/x`` or ``w + k x/e``."""
        out = np.array(q, dtype=float)
        if self.coords == "rate":
            out[..., 1] = out[..., 1] + k_mps / out[..., 2]
        else:
            out[..., 1] = out[..., 1] + k_mps * out[..., 2] / self.model.e
        return out

    def shift_jacobian(self, q, k_mps: float) -> FloatArray:
        jac = np.eye(3)
        x = float(q[2])
        jac[1, 2] = -k_mps / x**2 if self.coords == "rate" else k_mps / self.model.e
        return jac

    @staticmethod
    def range_of(q) -> FloatArray:
        """Range ``d = x / cos(alpha)`` of internal rows ``(alpha, r, x)``."""
        q = np.asarray(q, dtype=float)
        return q[..., 2] / np.cos(q[..., 0])
