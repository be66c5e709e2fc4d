"""The Gaussian belief of a Kalman filter seen through its n-sigma ellipsoid.

A Kalman filter's belief is a mean ``m`` and a covariance ``P`` of its internal
state ``q = (alpha, r, x)``, where ``r`` is either the bearing rate ``omega``
(``coords="rate"``) or the zero-effort miss ``w = omega x^2 / e`` (``coords="zem"``,
see :mod:`kalman_vs_infoset.estim.intercept.gaussian.estimator` for the choice). To answer the same
questions as the information set (:class:`kalman_vs_infoset.estim.base.Belief`) it is read as the
n-sigma ellipsoid

    E = {q : (q - m)^T P^+ (q - m) <= n^2} = {m + n S u : |u| <= 1},   S S^T = P,

(``n = 3`` by default; a singular ``P`` gives a flat ellipsoid, which is handled),
and every point leaves the belief as a row ``(alpha, omega, x)`` (for ``"zem"``
through ``omega = w e / x^2``: the region is then the image of the ellipsoid).
The square root ``S`` is a Cholesky factor taken in the coordinate order
``(r, x, alpha)``, so that its first two columns span the projection of ``E``
onto the ``(r, x)`` plane (see :meth:`GaussianBelief.extremes`). Cholesky is
invariant under diagonal scaling, so the wildly different units (``alpha`` ~ 1e-3
rad, ``omega`` ~ 1e-5 rad/s, ``x`` ~ 6e6 m) need no explicit rescaling; no
eigen-decomposition of ``P`` (which is not scale invariant) is ever taken.

Unlike the information set, the ellipsoid is *not* guaranteed to contain the
truth: containment is a statistic to count, never an invariant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from kalman_vs_infoset.estim.base import Belief, Extremes, StateFunction, Status, state_values
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import ChannelModel, channel_state
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

#: coordinate order of the stored Cholesky factor: (r, x, alpha)
PERM = np.array([1, 2, 0])
_PERM_IX = np.ix_(PERM, PERM)

#: internal coordinates: (alpha, omega, x) or (alpha, w = omega x^2/e, x)
COORDS = ("rate", "zem")

#: relative pivot below which a direction is taken as exactly degenerate
#: (the share of a variance not explained by the preceding coordinates)
PIVOT_RTOL = 1.0e-13

#: angles sampling the boundary of the projected (omega, x) ellipse
_N_BOUNDARY = 720
_THETA = np.linspace(0.0, 2.0 * np.pi, _N_BOUNDARY, endpoint=False)
_COS, _SIN = np.cos(_THETA), np.sin(_THETA)
_DTHETA = 2.0 * np.pi / _N_BOUNDARY


def _fibonacci_sphere(n: int) -> FloatArray:
    """``n`` nearly uniform unit vectors in 3D (Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    r = np.sqrt(1.0 - z**2)
    phi = np.pi * (3.0 - np.sqrt(5.0)) * i
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


#: unit-ball samples for generic functions: the centre, a half-radius shell and the surface
_SPHERE = _fibonacci_sphere(1024)
_BALL = np.vstack([np.zeros((1, 3)), 0.5 * _fibonacci_sphere(128), _SPHERE])


def psd_cholesky(p: ArrayLike) -> FloatArray:
    """Lower-triangular ``L`` with ``L L^T = P`` for a positive semi-definite ``P``.

    ``numpy.linalg.cholesky`` when ``P`` is positive definite; otherwise the same
    recursion with a zero column wherever the remaining pivot is below
    ``PIVOT_RTOL`` of the diagonal entry (an exactly known direction).
    """
    p = np.asarray(p, dtype=float)
    try:
        return np.linalg.cholesky(p)
    except np.linalg.LinAlgError:
        pass
    n = p.shape[0]
    low = np.zeros_like(p)
    for j in range(n):
        piv = p[j, j] - low[j, :j] @ low[j, :j]
        if piv > PIVOT_RTOL * p[j, j] and piv > 0.0:
            low[j, j] = math.sqrt(piv)
            low[j + 1 :, j] = (p[j + 1 :, j] - low[j + 1 :, :j] @ low[j, :j]) / low[j, j]
    return low


@dataclass(frozen=True, eq=False)
class GaussianBelief(Belief):
    """An immutable ``(mean, covariance)`` of ``(alpha, r, x)`` read as its ellipsoid.

    Parameters
    ----------
    mean : array (3,)
        ``(alpha_rad, omega_radps, x_m)`` (``coords="rate"``) or
        ``(alpha_rad, w_m, x_m)`` (``coords="zem"``).
    cov : array (3, 3)
        Covariance (symmetrised on construction).
    coords : {"rate", "zem"}
        Meaning of the second coordinate.
    closing_speed_mps : float
        ``e`` of the map ``omega = w e / x^2`` (``"zem"`` only).
    n_sigma : float
        Radius of the ellipsoid in standard deviations.
    status : Status
        ``Status.OK``, or ``Status.TERMINAL`` once the mean range has passed under ``eps``
        (the belief is then empty, as the information set after its threshold).
    contradictions : int
        Always 0: a Kalman update cannot be contradicted (kept for the interface).
    innovation_outliers : int
        Number of measurements so far whose innovation exceeded ``n_sigma``
        standard deviations (the Kalman filter's analogue of a contradiction).
    x_bounds_m : (float, float) or None
        A-priori interval ``[lo, hi]`` of the true range ``x`` at this belief's
        time (the initial ``x`` box moved by the closing-speed interval), carried
        for the estimator's optional range constraint; ``None`` when not tracked.
    """

    mean: FloatArray
    cov: FloatArray
    n_sigma: float = 3.0
    coords: str = "rate"
    closing_speed_mps: float = 58.0e3
    status: Status = Status.OK
    contradictions: int = 0
    innovation_outliers: int = 0
    x_bounds_m: tuple[float, float] | None = None
    _root: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        m = np.array(self.mean, dtype=float).reshape(-1)
        p = np.array(self.cov, dtype=float)
        if m.shape != (3,) or p.shape != (3, 3):
            raise ValueError("mean must have shape (3,) and cov shape (3, 3)")
        if not (np.all(np.isfinite(m)) and np.all(np.isfinite(p))):
            raise ValueError("mean and covariance must be finite")
        if not self.n_sigma > 0:
            raise ValueError("n_sigma must be positive")
        if self.coords not in COORDS:
            raise ValueError(f"coords must be one of {COORDS}, got {self.coords!r}")
        if not self.closing_speed_mps > 0:
            raise ValueError("closing_speed_mps must be positive")
        if self.x_bounds_m is not None:
            lo, hi = (float(v) for v in self.x_bounds_m)
            if not lo <= hi:
                raise ValueError("x_bounds_m must be an interval lo <= hi")
            object.__setattr__(self, "x_bounds_m", (lo, hi))
        p = 0.5 * (p + p.T)
        if np.any(np.diag(p) < 0):
            raise ValueError("covariance has a negative variance")
        root = psd_cholesky(p[_PERM_IX])
        for a in (m, p, root):
            a.setflags(write=False)
        object.__setattr__(self, "mean", m)
        object.__setattr__(self, "cov", p)
        object.__setattr__(self, "_root", root)

    # -- Belief interface ------------------------------------------------------------
    @property
    def is_empty(self) -> bool:
        # terminal (every state under eps) or diverged (emptied: reported, not propagated)
        return self.status in (Status.TERMINAL, Status.DIVERGED)

    def trace_fields(self) -> dict[str, float]:
        """The gate (``n_sigma``) and the innovations outside it so far."""
        return {
            "n_sigma": float(self.n_sigma),
            "innovation_outliers": float(self.innovation_outliers),
        }

    def centre(self) -> FloatArray:
        """The mean as a row ``(alpha, omega, x)``."""
        return self.to_rows(self.mean)

    def std(self) -> FloatArray:
        """Standard deviations of the internal coordinates ``(alpha, r, x)``."""
        return np.sqrt(np.diag(self.cov))

    def to_rows(self, q: ArrayLike) -> FloatArray:
        """Internal ``(alpha, r, x)`` rows to ``(alpha, omega, x)`` rows (new array)."""
        out = np.array(q, dtype=float)
        if self.coords == "zem":
            out[..., 1] = out[..., 1] * self.closing_speed_mps / out[..., 2] ** 2
        return out

    def from_rows(self, state: ArrayLike) -> FloatArray:
        """``(alpha, omega, x)`` rows to internal ``(alpha, r, x)`` rows (new array)."""
        out = np.array(state, dtype=float)
        if self.coords == "zem":
            out[..., 1] = out[..., 1] * out[..., 2] ** 2 / self.closing_speed_mps
        return out

    def internal_points(self, u: ArrayLike) -> FloatArray:
        """Internal rows ``m + n S u`` for unit-ball rows ``u`` in ``(r, x, alpha)`` order."""
        d = np.asarray(u, dtype=float) @ (self.n_sigma * self._root).T  # (r, x, alpha)
        out = np.empty_like(d)
        out[..., PERM] = d
        return out + self.mean

    def points(self, u: ArrayLike) -> FloatArray:
        """Rows ``(alpha, omega, x)`` of the ellipsoid points ``m + n S u``."""
        return self.to_rows(self.internal_points(u))

    def mahalanobis(self, state: ArrayLike) -> float:
        """Mahalanobis distance of a row ``(alpha, omega, x)`` from the mean.

        Measured in the internal coordinates; ``inf`` off a flat ellipsoid.
        """
        d = (self.from_rows(np.array(channel_state(state))) - self.mean)[PERM]
        low = self._root
        z = np.zeros(3)
        for i in range(3):
            r = d[i] - low[i, :i] @ z[:i]
            if low[i, i] > 0.0:
                z[i] = r / low[i, i]
            elif abs(r) > 1e-12 * (abs(self.mean[PERM[i]]) + abs(d[i])) + 1e-300:
                return math.inf
        return float(np.sqrt(z @ z))

    def contains(self, state: ArrayLike) -> bool:
        """Whether ``state`` lies in the n-sigma ellipsoid (Mahalanobis distance <= n)."""
        if self.is_empty:
            return False
        return self.mahalanobis(state) <= self.n_sigma * (1.0 + 1e-12)

    def extremes(self, fn: StateFunction) -> Extremes:
        """Min and max of ``fn`` over the n-sigma ellipsoid, with the points.

        The miss forecast ``Pi`` (a :class:`~estim.intercept.costs.MissForecast`, recognised by
        type) takes the exact route of
        :meth:`_forecast_extremes`. Any other function: samples of the ball (the
        centre, a half-radius shell and 1024 surface points), then from the best
        surface samples the fixed-point iteration ``u <- +-grad/|grad|`` on the unit
        sphere (finite-difference gradient in ``u``), kept only when it improves.
        For a linear function ``c.s`` one iteration gives the exact extremes
        ``c.m -+ n sqrt(c^T P c)``; for convex functions the maximum improves
        monotonically; a non-convex function is handled to sampling accuracy.
        """
        if self.is_empty:
            raise ValueError(f"extremes of an empty Gaussian belief (status {self.status})")
        if isinstance(fn, MissForecast):
            return self._forecast_extremes(fn, fn.model)
        return self._generic_extremes(fn)

    # -- extremes ------------------------------------------------------------------
    def _generic_extremes(self, fn: StateFunction) -> Extremes:
        pts = self.points(_BALL)
        vals = state_values(fn, pts)
        i_min, i_max = int(np.argmin(vals)), int(np.argmax(vals))
        best = []
        for sign, i0 in ((-1.0, i_min), (1.0, i_max)):
            u, v = _BALL[i0], vals[i0]
            if np.linalg.norm(u) < 0.99:  # interior optimum: keep the sample
                best.append((u, v))
                continue
            for _ in range(8):
                g = self._u_gradient(fn, u)
                ng = float(np.linalg.norm(g))
                if ng == 0.0:
                    break
                u_new = sign * g / ng
                v_new = float(np.asarray(fn(self.points(u_new[None, :])))[0])
                if sign * (v_new - v) <= 0.0:
                    break
                step = float(np.linalg.norm(u_new - u))
                u, v = u_new, v_new
                if step < 1e-12:
                    break
            best.append((u, v))
        (u_lo, v_lo), (u_hi, v_hi) = best
        p = self.points(np.vstack([u_lo, u_hi]))
        return Extremes(float(v_lo), p[0], float(v_hi), p[1])

    def _u_gradient(self, fn: StateFunction, u: FloatArray, h: float = 1e-3) -> FloatArray:
        steps = np.vstack([u + h * np.eye(3), u - h * np.eye(3)])
        f = np.asarray(fn(self.points(steps)), dtype=float)
        return (f[:3] - f[3:]) / (2.0 * h)

    def _forecast_extremes(self, fn: StateFunction, model: ChannelModel) -> Extremes:
        """Extremes of ``Pi(alpha, omega, x) = omega x^2/e + sign(omega) nu x^2/(2 e^2)``.

        In internal coordinates ``Pi = A r x^2 + B r + C x^2`` with, for ``"rate"``,
        ``A = 1/e, B = 0``, and for ``"zem"`` (``omega = w e_b/x^2``) ``A = 0,
        B = e_b/e``; ``C = sign(r) nu/(2 e^2)``. ``Pi`` does not depend on ``alpha``
        and, for any fixed ``x != 0``, increases with ``r`` (linear on each side of
        ``r = 0`` with a jump up there). Its extremes over ``E`` are therefore its
        extremes over the projection of ``E`` onto the ``(r, x)`` plane, attained on
        the top (max) and bottom (min) of that ellipse, whose boundary is
        ``m + n S (cos t, sin t, 0)`` with ``S`` the Cholesky factor in
        ``(r, x, alpha)`` order; the ``alpha`` of that point is the conditional
        mean, so the returned rows lie on the surface of ``E``.

        The boundary is sampled at 720 angles; each best sample is refined by up to
        three Newton steps on its smooth branch (sign of ``r`` fixed), accepted
        only if they stay on the branch and improve the value. Values are ``fn`` at
        the returned rows.
        """
        m0, m1, m2 = (float(v) for v in self.mean)
        low, n = self._root, self.n_sigma
        e, nu = model.e, model.nu_mps2
        coef_a, coef_b = (
            (1.0 / e, 0.0) if self.coords == "rate" else (0.0, self.closing_speed_mps / e)
        )
        a_r = n * float(low[0, 0])
        b_x, c_x = n * float(low[1, 0]), n * float(low[1, 1])
        b_a, c_a = n * float(low[2, 0]), n * float(low[2, 1])

        def rows(cos, sin):
            q = np.empty((len(cos), 3))
            q[:, 0] = m0 + b_a * cos + c_a * sin
            q[:, 1] = m1 + a_r * cos
            q[:, 2] = m2 + b_x * cos + c_x * sin
            return self.to_rows(q)

        pts = rows(_COS, _SIN)
        vals = np.asarray(fn(pts), dtype=float)
        best = [int(np.argmin(vals)), int(np.argmax(vals))]
        angles = [float(_THETA[i]) for i in best]
        for j, sense in enumerate((-1.0, 1.0)):
            r0 = m1 + a_r * float(_COS[best[j]])
            if r0 == 0.0:  # on the jump itself: keep the sample
                continue
            branch = math.copysign(1.0, r0)
            coef_c = branch * nu / (2.0 * e * e)
            t = angles[j]
            for _ in range(3):
                ct, st = math.cos(t), math.sin(t)
                r, x = m1 + a_r * ct, m2 + b_x * ct + c_x * st
                r1, x1 = -a_r * st, -b_x * st + c_x * ct
                r2, x2 = -a_r * ct, -b_x * ct - c_x * st
                xx1, xx2 = 2.0 * x * x1, 2.0 * (x1 * x1 + x * x2)  # (x^2)', (x^2)''
                f1 = coef_a * (r1 * x * x + r * xx1) + coef_b * r1 + coef_c * xx1
                f2 = coef_a * (r2 * x * x + 2.0 * r1 * xx1 + r * xx2) + coef_b * r2 + coef_c * xx2
                if sense * f2 >= 0.0:  # not locally concave (max) / convex (min)
                    break
                dt = min(max(-f1 / f2, -_DTHETA), _DTHETA)
                t += dt
                if abs(dt) < 1e-14:
                    break
            if math.copysign(1.0, m1 + a_r * math.cos(t)) == branch:
                angles[j] = t
        # refined candidates, evaluated with fn; kept only where they improve the sample
        cand = rows(np.cos(angles), np.sin(angles))
        cval = np.asarray(fn(cand), dtype=float)
        out = []
        for j, sense in enumerate((-1.0, 1.0)):
            if sense * (cval[j] - vals[best[j]]) > 0.0:
                out.append((cand[j], float(cval[j])))
            else:
                out.append((pts[best[j]].copy(), float(vals[best[j]])))
        (p_lo, v_lo), (p_hi, v_hi) = out
        return Extremes(v_lo, p_lo, v_hi, p_hi)
