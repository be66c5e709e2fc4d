"""EKF and UKF of one intercept guidance channel, built on filterpy (docs/models.md §1.7).

State choice. Per channel the state is ``(alpha, r, x)``: bearing (rad), a rate
coordinate ``r`` and the range along the nominal axis (m), i.e. the coordinates
of the auxiliary model (docs/models.md §1.3, :mod:`kalman_vs_infoset.estim.intercept.model`) and of
the information set,
whose polygons live in ``(alpha, w)`` at each ``x``. Two choices of ``r``:

* ``coords="zem"`` (default): the zero-effort miss ``w = omega x^2 / e`` (m);
* ``coords="rate"``: the bearing rate ``omega`` (rad/s) itself.

Why not the Cartesian ``(y, Vy, x, Vx)``: it would put a nonlinearity into the
bearing ``atan2(y, x)`` and need its own disturbance model; here the bearing is
*linear*, ``h = alpha``, so the update of both filters is the exact Kalman update,
and the one-step map and the disturbance ``v`` are those of the set (a fair
comparison on the same model). Why ``w`` rather than ``omega``: in ``w`` the model
is as linear as it can be. The prediction of ``w`` is ``w1 = w0 + g_w v``
(independent of the uncertain range), the impulse ``w -> w + k x / e`` is linear,
and ``Pi = w + sign(w) nu x^2/(2 e^2)`` is linear in ``w``; the only nonlinear
term left is the bearing drift ``w e Delta/(x0 x1)``, which is what carries the
range information. In ``omega`` the prediction ``omega x0^2/x1^2`` and the impulse
``k/x`` both multiply the range error and the EKF linearisation fails as soon as
the bearing rate starts revealing the range. Measured on the uncontrolled model
with uniform noise (40 runs, Fig. 3 boxes, mean NEES, 3 expected): the
``omega``-EKF reaches 9.6 at x ~ 2200 km and 1e2-1e3 under 1300 km; the ``w``-EKF
3.5 at 2200 km, 4.8 at 1600 km, 7 at 1000 km; the ``w``-UKF stays under 4.7 down
to 800 km. On Fig. 5 (12 runs, random noise) the ``w`` filters miss by 5-7 m on
average against 70-80 m for the ``omega`` filters; under the game noise the order
reverses (the biased bearings drive the ``w`` filters' range estimate to a few
tens of km, so their threshold ends guidance far too early), which is why both
are kept (``coords``). As in the set, ``x`` drifts at the *nominal* closing speed
``e`` with no process noise (the true closing speed's mismatch is part of what
``v`` stands for). The belief answers in rows
``(alpha, omega, x)`` whatever ``r`` is (:mod:`kalman_vs_infoset.estim.intercept.gaussian.belief`).

Model (docs/models.md §1.3,
:meth:`kalman_vs_infoset.estim.intercept.model.ChannelModel.step_coefficients`), one step
``Delta``, ``x1 = x0 - e Delta``, ``v`` constant over the step::

    alpha1 = alpha0 + w0 e Delta/(x0 x1) + g_alpha v      = alpha0 + omega0 x0 Delta/x1 + g_alpha v
    w1     = w0 + g_w v                                   omega1 = omega0 x0^2/x1^2 + g_omega v

with ``g_alpha = Delta^2/(2 x1)``, ``g_w = Delta (x0 + x1)/(2 e)``,
``g_omega = Delta (x0 + x1)/(2 x1^2)``; ``v`` uniform in ``[-nu, nu]``: process
noise ``Q = G G^T nu^2/3``, ``G = (g_alpha, g_r, 0)`` at the mean range (all noise
variances times ``noise_inflation``, 1 by default). EKF
Jacobians ``F = d q1/d q0`` (besides the unit diagonal and the constant ``dx1/dx0 = 1``):

* zem: ``d alpha1/d w0 = e Delta/(x0 x1)``, ``d alpha1/d x0 = -w0 e Delta (x0 + x1)/(x0 x1)^2``;
* rate: ``d alpha1/d omega0 = x0 Delta/x1``, ``d alpha1/d x0 = -omega0 e Delta^2/x1^2``,
  ``d omega1/d omega0 = x0^2/x1^2``, ``d omega1/d x0 = -2 omega0 x0 e Delta/x1^3``.

Measurements: bearing ``alpha`` with a uniform error of half-width ``a(d)``,
variance ``R = a(x_hat)^2/3``; range ``d = x / cos(alpha)`` (the other channel's
angle neglected: a relative 1e-6) with a uniform error ``|beta| <= b d``,
``R = (b d_hat)^2/3``. Control: an impulse ``k`` (relative velocity) maps
``omega -> omega + k/x`` (rate: nonlinear in ``x``, linearised by the EKF and
transformed by the UKF), i.e. ``w -> w + k x/e`` (zem: exactly linear).

Threshold (the set's ``eps``, docs/models.md §1.4): before each prediction ``x`` is
conditioned on ``x >= eps + e Delta`` (a truncated normal, :meth:`threshold`);
when the whole ellipsoid is below, the belief is empty (status ``Status.TERMINAL``).

Initial belief: the exact first two moments of ``alpha = y/x`` and
``omega = Vy/x + c y/x^2`` or ``w = (Vy x + c y)/e`` (``c = -Vx``; the set's
small-angle map with ``c = e``) for ``y, Vy, x, c`` independent and uniform in
their boxes (variance ``width^2/12``), with the closed-form moments of ``x^-k``.

Range constraint (optional, ``range_constraint=True``; off by default). The
information set knows a priori that the true range lies in the initial ``x`` box
moved by the closing-speed interval ``[e_lo, e_hi]``:
``x(t) in [x_lo - e_hi t, x_hi - e_lo t]``. With the option on the belief carries
that interval (:attr:`~kalman_vs_infoset.estim.intercept.gaussian.belief.GaussianBelief.x_bounds_m`,
set by :meth:`KalmanChannelEstimator.initial`, moved by every prediction) and a mean whose
``x`` leaves it is projected back onto the violated bound in the ``P^-1`` metric
(estimate projection with ``W = P^-1``, Simon & Chia 2002; D. Simon, IET Control
Theory Appl. 2010): the minimiser of ``(m - mu)^T P^-1 (m - mu)`` subject to
``m_x = bound`` is ``mu + P[:, x]/P[x, x] (bound - mu_x)``, so the correlated
``alpha`` and ``r`` move with ``x`` (:func:`project_on_bound`). The covariance is
left unchanged (:meth:`KalmanChannelEstimator.constrain`).

filterpy objects are mutable: each call builds a fresh filter from the belief's
``(mean, cov)`` (copies), runs one filterpy step and returns a new
:class:`~kalman_vs_infoset.estim.intercept.gaussian.belief.GaussianBelief`; no filter is ever
stored. The EKF's state map is filterpy's documented override point ``predict_x``; the UKF
uses Van der Merwe's scaled sigma points with ``alpha = 1, beta = 2, kappa = 0``
(points at ``+-sqrt(3)`` standard deviations, the edges of a uniform box).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from filterpy.kalman import ExtendedKalmanFilter, MerweScaledSigmaPoints, UnscentedKalmanFilter
from kalman_vs_infoset.estim.base import Estimator, Status
from kalman_vs_infoset.estim.intercept.gaussian.belief import COORDS, GaussianBelief, psd_cholesky
from kalman_vs_infoset.estim.intercept.gaussian.maps import (
    ChannelMaps,
    MappedEKF,
    box_moments,
    project_on_bound,
)
from kalman_vs_infoset.estim.intercept.gaussian.options import DEFAULTS
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    Impulse,
    Range,
    check_step,
    impulse_parts,
)
from numpy.typing import NDArray
from scipy import special

FloatArray = NDArray[np.float64]

KINDS = ("ekf", "ukf")
_H_BEARING = np.array([[1.0, 0.0, 0.0]])


def _psd_sqrt(p):
    """The sigma points' matrix square root (upper factor), a module function so that
    the estimator pickles (to a process pool of one's own)."""
    return psd_cholesky(p).T


@dataclass(frozen=True)
class KalmanChannelEstimator(ChannelMaps, Estimator[GaussianBelief, ChannelPrior]):
    """EKF or UKF of one guidance channel behind the estimator interface.

    Parameters
    ----------
    model : ChannelModel
        Closing speed, disturbance bound ``nu``, measurement bounds, ``eps``.
    kind : {"ekf", "ukf"}
        Filter type.
    n_sigma : float
        Radius (in standard deviations) of the ellipsoid the beliefs answer with.
    coords : {"zem", "rate"}
        Second state coordinate: zero-effort miss ``w`` or bearing rate ``omega``.
    ukf_alpha, ukf_beta, ukf_kappa : float
        Van der Merwe sigma-point parameters (UKF only).
    range_constraint : bool
        Project the mean's range onto the a-priori interval of the true range
        (module docstring, :meth:`constrain`); off by default.
    closing_speed_mps : (float, float) or None
        Interval ``[e_lo, e_hi]`` of the true closing speed that moves that interval;
        ``None`` means the nominal ``e`` exactly (as the information set).
    noise_inflation : float
        Factor on every noise variance, ``R`` and ``Q`` (>= 1). 1 is the variance of
        an error uniform within its bound (``a^2/3``); 3 is the largest variance any
        error within the bound can have (``a^2``: all of it at the bound), the
        natural choice when the statistics are unknown; more is hand-tuning.
    """

    model: ChannelModel = field(default_factory=ChannelModel)
    kind: str = "ekf"
    n_sigma: float = DEFAULTS.n_sigma
    coords: str = "zem"
    ukf_alpha: float = 1.0
    ukf_beta: float = 2.0
    ukf_kappa: float = 0.0
    range_constraint: bool = DEFAULTS.range_constraint
    closing_speed_mps: tuple[float, float] | None = None
    noise_inflation: float = DEFAULTS.noise_inflation
    _points: Any = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"kind must be one of {KINDS}, got {self.kind!r}")
        if self.coords not in COORDS:
            raise ValueError(f"coords must be one of {COORDS}, got {self.coords!r}")
        if not self.n_sigma > 0:
            raise ValueError("n_sigma must be positive")
        if not 1.0 <= self.noise_inflation < np.inf:
            raise ValueError("noise_inflation must be a finite number >= 1")
        if not (self.ukf_alpha > 0 and 3 + self.ukf_kappa > 0):
            raise ValueError("ukf_alpha must be positive and 3 + ukf_kappa positive")
        if self.closing_speed_mps is not None:
            lo, hi = self.closing_speed_mps
            if not 0 < lo <= hi:
                raise ValueError("closing_speed_mps must be an interval 0 < lo <= hi")
        # the sigma-point generator holds weights only (never mutated by filterpy);
        # the PSD square root accepts an exactly known direction (zero variance)
        points = MerweScaledSigmaPoints(
            3,
            self.ukf_alpha,
            self.ukf_beta,
            self.ukf_kappa,
            sqrt_method=_psd_sqrt,
        )
        object.__setattr__(self, "_points", points)

    @property
    def speed_interval(self) -> tuple[float, float]:
        """``[e_lo, e_hi]`` of the true closing speed (``[e, e]`` when not given)."""
        if self.closing_speed_mps is None:
            return self.model.e, self.model.e
        return self.closing_speed_mps

    # -- construction ----------------------------------------------------------------
    def belief(self, mean, cov, x_bounds_m=None) -> GaussianBelief:
        """A belief in this estimator's coordinates with its ``n_sigma``."""
        return GaussianBelief(
            mean, cov, self.n_sigma, self.coords, self.model.e, x_bounds_m=x_bounds_m
        )

    def initial(self, prior: ChannelPrior | None = None, **box: Any) -> GaussianBelief:
        """Moment-matched Gaussian of the a-priori box (:meth:`from_boxes`, ``c = -Vx``
        uniform in the prior's closing-speed interval, ``e`` when it has none).

        ``initial(lateral_m=..., lateral_vel_mps=..., x_m=...)`` is short for
        ``initial(ChannelPrior(...))``.
        """
        prior = ChannelPrior(**box) if prior is None else prior
        speed = prior.closing_speed_mps
        vx = None if speed is None else (-speed[1], -speed[0])
        return self.from_boxes(prior.lateral_m, prior.lateral_vel_mps, prior.x_m, vx)

    def from_boxes(
        self,
        lateral_m: tuple[float, float],
        lateral_vel_mps: tuple[float, float],
        x_m: tuple[float, float],
        vx_mps: tuple[float, float] | None = None,
    ) -> GaussianBelief:
        """Moment-matched Gaussian of the a-priori boxes (see module docstring).

        ``alpha = y/x``, ``omega = Vy/x + c y/x^2`` or ``w = (Vy x + c y)/e`` with
        ``c = -Vx`` uniform in the ``vx_mps`` box (``c = e`` when it is not given)
        and ``x`` uniform in ``x_m``; all four independent. With ``range_constraint``
        the belief carries ``x_m`` as the interval of the true range.
        """
        (y0, y1), (v0, v1), (xa, xb) = lateral_m, lateral_vel_mps, x_m
        e = self.model.e
        c0, c1 = (e, e) if vx_mps is None else sorted((-vx_mps[0], -vx_mps[1]))
        if not (y0 <= y1 and v0 <= v1 and 0 < xa <= xb and c0 > 0):
            raise ValueError("boxes must be [lo, hi] with lo <= hi, positive range and closing")
        mean, cov = box_moments((y0, y1), (v0, v1), (xa, xb), (c0, c1), e, self.coords)
        return self.belief(mean, cov, (xa, xb) if self.range_constraint else None)

    # -- Estimator interface ---------------------------------------------------------
    def threshold(self, belief: GaussianBelief, dt_s: float) -> GaussianBelief:
        """Condition on ``x >= eps + e dt`` (states that pass under ``eps`` are dropped).

        The Gaussian analogue of the set's threshold (docs/models.md §1.4): when the n-sigma
        ellipsoid reaches under ``x_lo = eps + e dt``, ``x`` is replaced by its normal
        distribution truncated at ``x_lo`` (moments ``m + s lambda``,
        ``s^2 (1 + b lambda - lambda^2)``, ``b = (x_lo - m)/s``,
        ``lambda = phi(b)/(1 - Phi(b))``) and the other coordinates follow through
        their regression on ``x`` (Simon & Simon's truncation of a Gaussian). When the
        whole ellipsoid is under ``x_lo`` the belief becomes empty, status
        ``Status.TERMINAL``: guidance ends, as with an emptied set.
        """
        if belief.is_empty:
            return belief
        x_lo = self.model.eps_m + self.model.e * dt_s
        m, p = belief.mean, belief.cov
        sx = math.sqrt(p[2, 2])
        n = belief.n_sigma
        if m[2] + n * sx < x_lo:
            return replace(belief, status=Status.TERMINAL)
        if m[2] - n * sx >= x_lo or sx == 0.0:
            return belief
        b = (x_lo - m[2]) / sx
        lam = math.sqrt(2.0 / math.pi) / float(special.erfcx(b / math.sqrt(2.0)))
        new_var = p[2, 2] * max(1.0 + b * lam - lam * lam, 0.0)
        gain = p[:, 2] / p[2, 2]
        mean = m + gain * (sx * lam)
        cov = p - np.outer(gain, gain) * (p[2, 2] - new_var)
        return replace(belief, mean=mean, cov=cov)

    def predict(
        self, belief: GaussianBelief, dt_s: float, control: float | Impulse | None = None
    ) -> GaussianBelief:
        """The impulse ``control`` at the step's start (:meth:`_impulse`), the threshold
        (:meth:`threshold`), then the propagation over ``dt_s`` (exact map, ``Q``). A
        propagation that overflows or is not finite (a filter that ran off) gives the
        belief with status ``Status.DIVERGED``: empty, reported, not propagated."""
        check_step(dt_s)
        self._check(belief)
        if control is not None:
            belief = self._impulse(belief, control)
        belief = self.threshold(belief, dt_s)
        if belief.is_empty:
            return belief
        try:
            mean, cov = self._moments(belief, dt_s)
        except OverflowError:  # the mean ran off to ~1e308 (an unstable gain, theta near 1)
            return replace(belief, status=Status.DIVERGED)
        if not (np.isfinite(mean).all() and np.isfinite(cov).all()):
            return replace(belief, status=Status.DIVERGED)  # emptied and reported
        bounds = belief.x_bounds_m
        if bounds is not None:  # the true range moves at any speed of the interval
            e_lo, e_hi = self.speed_interval
            bounds = (bounds[0] - e_hi * dt_s, bounds[1] - e_lo * dt_s)
        # the map moves x at the nominal e, inside the interval's speeds, but the
        # threshold's truncation (and an e outside [e_lo, e_hi]) can push the mean out
        return self.constrain(replace(belief, mean=mean, cov=cov, x_bounds_m=bounds))

    def _moments(self, belief: GaussianBelief, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
        """Mean and covariance propagated over ``dt_s`` (the EKF's Jacobian or the UKF's
        sigma points through the exact map, plus ``Q``)."""
        x0 = float(belief.mean[2])
        q = self.process_noise(x0, dt_s)

        def fx(s, dt=dt_s):
            return self.step(s, dt)

        if self.kind == "ekf":
            f = MappedEKF(fx)
            f.x, f.P = belief.mean.copy(), belief.cov.copy()
            f.F, f.Q = self.step_jacobian(belief.mean, dt_s), q
            f.predict()
        else:
            f = self._ukf(belief, fx)
            f.Q = q
            f.predict(dt=dt_s)
            # the unscented transform recomputes the variance of a coordinate known
            # exactly (x with a point range box: x1 = x0 - e dt, no process noise) from
            # sigma points that differ by rounding (1 ulp of 3e6 m gives 1e-18 m^2);
            # what the prior knew exactly and the step adds no noise to stays exact
            known = (np.diag(belief.cov) == 0.0) & (np.diag(q) == 0.0)
            if known.any():
                f.P[known, :] = 0.0
                f.P[:, known] = 0.0
        return f.x, f.P

    def _impulse(self, belief: GaussianBelief, control: float | Impulse) -> GaussianBelief:
        """Impulse ``k`` (m/s, relative velocity): ``omega -> omega + k/x``.

        An :class:`~kalman_vs_infoset.estim.intercept.model.Impulse` known to ``+-dk`` adds the
        variance of a uniform error, ``(dk x/e)^2/3``, to the rate coordinate.
        """
        self._check(belief)
        k, dk = impulse_parts(control)
        if dk > 0.0 and not belief.is_empty:
            x = float(belief.mean[2])
            gain = x / self.model.e if self.coords == "zem" else 1.0 / x
            cov = belief.cov.copy()
            cov[1, 1] += (dk * gain) ** 2 / 3.0
            belief = replace(belief, cov=cov)
        if k == 0.0 or belief.is_empty:
            return belief

        def fx(s, dt=0.0):
            return self.shift_map(s, k)

        if self.kind == "ekf":
            f = MappedEKF(fx)
            f.x, f.P = belief.mean.copy(), belief.cov.copy()
            f.F, f.Q = self.shift_jacobian(belief.mean, k), np.zeros((3, 3))
            f.predict()
        else:
            f = self._ukf(belief, fx)
            f.Q = np.zeros((3, 3))
            f.predict(dt=0.0)
        # x is unchanged by the impulse (the UKF's recombination only to rounding)
        return self.constrain(replace(belief, mean=f.x, cov=f.P))

    def update(self, belief: GaussianBelief, measurement: Bearing | Range) -> GaussianBelief:
        """Kalman update with a bearing (linear) or a range (nonlinear) measurement."""
        self._check(belief)
        if belief.is_empty:
            return belief
        if isinstance(measurement, Bearing):
            z = float(measurement.alpha_rad)
            a = float(self.model.bearing_bound(abs(float(belief.mean[2]))))
            r = a * a / 3.0 * self.noise_inflation

            def hx(s):
                return np.array([s[0]])

            def jac(s):
                return _H_BEARING
        elif isinstance(measurement, Range):
            z = float(measurement.range_m)
            d_hat = float(self.range_of(belief.mean))
            r = (self.model.range_rel_bound * d_hat) ** 2 / 3.0 * self.noise_inflation

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
            f = self._ukf(belief, _identity, hx)
            f.compute_process_sigmas(0.0, fx=_identity)  # sigmas of the current belief
            f.update(zs, R=np.array([[r]]))
        innovation = float(np.ravel(f.y)[0])
        s_var = float(np.ravel(f.S)[0])
        outlier = innovation**2 > belief.n_sigma**2 * s_var
        # the update is where the bearings drag the range estimate (game noise
        # drives it far under the truth): the constraint acts here
        return self.constrain(
            replace(
                belief,
                mean=np.ravel(f.x),
                cov=f.P,
                innovation_outliers=belief.innovation_outliers + int(outlier),
            )
        )

    def constrain(self, belief: GaussianBelief) -> GaussianBelief:
        """Project the mean onto the range interval ``x_bounds_m`` (when it is violated).

        Off (the belief returned as is) unless ``range_constraint`` is set and the
        belief carries an interval. A mean with ``x`` outside ``[lo, hi]`` moves to
        the violated bound by :func:`project_on_bound` (the ``P^-1``-metric
        projection, which also corrects ``alpha`` and ``r`` through their
        correlation with ``x``). The covariance is kept: the constraint is an
        inequality and the truth lies *inside* the interval, not on the bound, so the
        equality projection ``P - P[:, x] P[x, :]/P[x, x]`` (zero variance of ``x``)
        would claim the range known at the bound and freeze it (no later bearing
        could move it). Keeping ``P`` is conservative: the interval is convex and
        holds the truth, so projecting onto it never increases the error in the
        ``P^-1`` norm (Simon & Chia 2002 show the same for equality constraints).
        """
        bounds = belief.x_bounds_m
        if not self.range_constraint or bounds is None or belief.is_empty:
            return belief
        x = float(belief.mean[2])
        if bounds[0] <= x <= bounds[1]:
            return belief
        bound = bounds[0] if x < bounds[0] else bounds[1]
        return replace(belief, mean=project_on_bound(belief.mean, belief.cov, 2, bound))

    # -- helpers -----------------------------------------------------------------------
    def _check(self, belief: GaussianBelief) -> None:
        if belief.coords != self.coords:
            raise ValueError(
                f"belief in {belief.coords!r} coordinates, estimator in {self.coords!r}"
            )

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


def _identity(s, dt=0.0):
    return s
