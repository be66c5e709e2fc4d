"""The H-infinity filter of one intercept guidance channel (Simon 2006, ch. 11).

State, model and reading are the EKF's (:mod:`estim.intercept.gaussian.estimator`,
``coords="zem"``): rows ``q = (alpha, w, x)`` with ``w = omega x^2/e`` the zero-effort miss, the
exact one-step map of the auxiliary model (models.md §1.3) with its Jacobian ``F``, the process
noise ``Q`` of a disturbance uniform in ``[-nu, nu]`` and the bearing variance
``R = a(x_hat)^2/3``; the belief is a :class:`~estim.intercept.gaussian.belief.GaussianBelief` read
as the n-sigma ellipsoid of ``P``. Only the measurement update differs: it is the
H-infinity update of :func:`kalman_vs_infoset.estim.intercept.hinf.filter.hinf_step`.

Split of Simon's step. Simon's filter (Section 11.3) is a one-step predictor::

    M_k       = P_k^-1 - theta Sbar_k + H^T R^-1 H
    xhat_k+1  = F (xhat_k + M_k^-1 H^T R^-1 (y_k - H xhat_k))
    P_k+1     = F M_k^-1 F^T + Q_k

The estimator interface separates the update from the prediction, so :meth:`update`
is that step with ``F = I, Q = 0`` (it returns ``xhat + K (y - H xhat)`` and
``M^-1``, computed by ``hinf_step`` itself), and :meth:`predict` is the EKF's
(exact map of the mean, ``F M^-1 F^T + Q``, the impulse and the threshold of
:meth:`estim.intercept.gaussian.estimator.KalmanChannelEstimator.predict`). Update then predict is
Simon's step, with the EKF's linearisation (an extended H-infinity filter). A range
measurement enters as in the EKF: ``H`` the Jacobian of ``d = x/cos(alpha)`` at the
mean and ``y - H xhat`` replaced by the innovation ``d_meas - h(xhat)``.

Weight and theta. What the filter bounds is the estimation error of ``z = L q``
weighted by ``S_k``. We weigh it by the inverse of its own a-priori covariance,
``S_k = (L P_k L^T)^-1`` (Simon lets ``S_k`` vary with ``k``; ``P_k`` is the filter's own,
fixed before ``y_k`` is seen), with ``L = I`` (``weight="state"``, default) or
``L = (0, 1, 0)``, the zero-effort miss alone (``weight="zem"``, the quantity the
guidance law centres). Then ``theta`` is dimensionless and the a-priori existence
condition of Hassibi, Sayed & Kailath, ``P_k^-1 - theta Sbar_k > 0`` (the one under
which ``J < 1/theta`` holds, see :mod:`kalman_vs_infoset.estim.intercept.hinf.filter`), reads
``theta < 1`` (``P^(1/2) Sbar P^(1/2)`` is a projection): it holds at every step for every
``theta < 1`` and the filter never ceases to exist along an engagement. What the weight
does is plain by Sherman-Morrison: with ``Pt = (P^-1 - theta Sbar)^-1``,

    Pt = P + theta/(1 - theta) P L^T (L P L^T)^-1 L P,    M^-1 = (Pt^-1 + H^T R^-1 H)^-1,

i.e. the H-infinity update is the Kalman update of a prior whose covariance along ``L``
(and the regression of the other coordinates on it) is inflated by ``1/(1 - theta)``;
for ``L = I``, ``Pt = P/(1 - theta)``, a fading-memory filter (Simon 2006, Section 7.4,
in our reading, inflates ``F P F^T`` only, we inflate ``F P F^T + Q``). Over many updates
old bearings are forgotten geometrically, by a factor ``1 - theta`` an update: a filter
that does not trust the noise statistics keeps a memory of about ``1/theta`` updates.
``theta = 0`` is the EKF.

Default ``weight="state"``, ``theta = 0.05``: a memory of about 20 bearing updates,
10 s at the seed's 0.5 s step, a tenth of a Fig. 5 approach. Weighting the zero-effort
miss alone leaves the range estimate to the EKF, and the EKF's failure under the game
noise is its range (the biased bearings drag it down until its threshold ends guidance
far too early, :mod:`estim.intercept.gaussian.estimator`); weighting the whole state lets the range
forget too. Measured on Fig. 5 (3 runs a noise, ``theta`` in 0.01, 0.02, 0.05, 0.1): with
``"state"``, 0.01 and 0.02 behave as the EKF (game noise ends guidance early, misses of
40-430 m), 0.05 is the first value at which the game noise no longer does (misses
2.5-95 m, bias 0.03 m, random 3-5 m for 690 m/s of fuel against the EKF's 355), and 0.1
loses the range under random noise (misses of kilometres); ``"zem"`` at 0.01-0.2 never
fixed the game noise. Other values are one option away (``[estimator.hinf] theta``).

Numerics. ``P`` mixes radians squared (1e-10) with metres squared (1e11), beyond what an
inverse in double precision can take, so the update is computed in coordinates scaled
by ``D = diag(sqrt(P_ii))`` (``P`` becomes its correlation matrix; the recursion is
covariant: ``M_s = D M D``, ``K_s = D^-1 K``). A coordinate known exactly (zero
variance, from a degenerate a-priori box) has zero gain in Simon's bracket form
``P [I - theta Sbar P + H^T R^-1 H P]^-1``; it is left out of the update (the core
needs ``P > 0``) and kept as it is.

References
----------
D. Simon, *Optimal State Estimation*, Wiley, 2006, Sections 7.4 and 11.3.
B. Hassibi, A. H. Sayed & T. Kailath, *Indefinite-Quadratic Estimation and Control*,
SIAM, 1999.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np
from kalman_vs_infoset.estim.base import Estimator
from kalman_vs_infoset.estim.intercept.gaussian.belief import GaussianBelief
from kalman_vs_infoset.estim.intercept.gaussian.estimator import KalmanChannelEstimator
from kalman_vs_infoset.estim.intercept.hinf.filter import (
    HInfinityEstimate,
    HInfinityModel,
    hinf_step,
)
from kalman_vs_infoset.estim.intercept.hinf.options import DEFAULTS
from kalman_vs_infoset.estim.intercept.model import (
    Bearing,
    ChannelModel,
    ChannelPrior,
    Impulse,
    Range,
)
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

WEIGHTS = ("zem", "state")
#: added to the diagonal of a correlation matrix singular to rounding (hinf_update)
RIDGE = 1e-12
#: row of L for weight="zem": the zero-effort miss w of (alpha, w, x)
_ZEM = 1


@dataclass(frozen=True)
class HInfinityChannelEstimator(Estimator[GaussianBelief, ChannelPrior]):
    """H-infinity filter of one guidance channel behind the estimator interface.

    Parameters
    ----------
    model : ChannelModel
        The channel's auxiliary model (as the EKF's).
    theta : float
        Performance bound ``J < 1/theta`` of the weighted cost, in ``[0, 1)`` with the
        relative weight of the module docstring (0 is the EKF; default 0.05).
    weight : {"state", "zem"}
        What is estimated: the whole state (``L = I``) or the zero-effort miss
        (``L = (0, 1, 0)``), each weighted by the inverse of its a-priori covariance.
    n_sigma : float
        Radius (standard deviations) of the ellipsoid the beliefs answer with.
    range_constraint, closing_speed_mps, noise_inflation
        As for :class:`estim.intercept.gaussian.estimator.KalmanChannelEstimator` (the prediction is
        its).
    """

    model: ChannelModel = field(default_factory=ChannelModel)
    theta: float = DEFAULTS.theta
    weight: Literal["zem", "state"] = DEFAULTS.weight
    n_sigma: float = DEFAULTS.n_sigma
    range_constraint: bool = DEFAULTS.range_constraint
    closing_speed_mps: tuple[float, float] | None = None
    noise_inflation: float = DEFAULTS.noise_inflation
    _ekf: KalmanChannelEstimator = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.theta) and 0.0 <= self.theta < 1.0):
            raise ValueError(f"theta must lie in [0, 1), got {self.theta}")
        if self.weight not in WEIGHTS:
            raise ValueError(f"weight must be one of {WEIGHTS}, got {self.weight!r}")
        ekf = KalmanChannelEstimator(
            self.model,
            kind="ekf",
            n_sigma=self.n_sigma,
            coords="zem",
            range_constraint=self.range_constraint,
            closing_speed_mps=self.closing_speed_mps,
            noise_inflation=self.noise_inflation,
        )
        object.__setattr__(self, "_ekf", ekf)

    @property
    def ekf(self) -> KalmanChannelEstimator:
        """The EKF whose model, prediction and reading this filter shares."""
        return self._ekf

    # -- Estimator interface ---------------------------------------------------------
    def initial(self, prior: ChannelPrior) -> GaussianBelief:
        """The EKF's moment-matched Gaussian of the a-priori boxes."""
        return self._ekf.initial(prior)

    def predict(
        self, belief: GaussianBelief, dt_s: float, control: float | Impulse | None = None
    ) -> GaussianBelief:
        """The EKF's prediction: impulse, threshold, ``f(xhat)`` and ``F P F^T + Q``."""
        return self._ekf.predict(belief, dt_s, control)

    def update(self, belief: GaussianBelief, measurement: Bearing | Range) -> GaussianBelief:
        """The H-infinity update with a bearing (``h = alpha``) or a range
        (``h = x/cos(alpha)``, linearised at the mean)."""
        if belief.coords != "zem":
            raise ValueError(f"belief in {belief.coords!r} coordinates, estimator in 'zem'")
        if belief.is_empty:
            return belief
        m = belief.mean
        s = self.noise_inflation
        if isinstance(measurement, Bearing):
            h = np.array([1.0, 0.0, 0.0])
            innovation = float(measurement.alpha_rad) - float(m[0])
            r = float(self.model.bearing_bound(abs(float(m[2])))) ** 2 / 3.0 * s
        elif isinstance(measurement, Range):
            ca = math.cos(float(m[0]))
            h = np.array([float(m[2]) * math.sin(float(m[0])) / ca**2, 0.0, 1.0 / ca])
            d_hat = float(m[2]) / ca
            innovation = float(measurement.range_m) - d_hat
            r = (self.model.range_rel_bound * d_hat) ** 2 / 3.0 * s
        else:
            raise TypeError(f"unsupported measurement {type(measurement).__name__}")
        mean, cov = self.hinf_update(m, belief.cov, h, innovation, r)
        s_var = float(h @ belief.cov @ h) + r
        outlier = innovation**2 > belief.n_sigma**2 * s_var
        return self._ekf.constrain(
            replace(
                belief,
                mean=mean,
                cov=cov,
                innovation_outliers=belief.innovation_outliers + int(outlier),
            )
        )

    # -- the update itself -----------------------------------------------------------
    def weight_matrix(
        self, cov: FloatArray, live: NDArray[np.bool_], corr: FloatArray | None = None
    ) -> FloatArray:
        """``Sbar = L^T (L P L^T)^-1 L`` in the coordinates scaled by ``sqrt(P_ii)``
        (rows and columns of the ``live`` coordinates only; ``corr``: their correlation
        matrix, if already formed)."""
        n = int(live.sum())
        if self.weight == "state":  # L = I: Sbar = P^-1, the inverse correlation matrix
            if corr is None:
                d = np.sqrt(np.diag(cov)[live])
                corr = cov[np.ix_(live, live)] / np.outer(d, d)
            inv = np.linalg.inv(corr)
            return 0.5 * (inv + inv.T)
        out = np.zeros((n, n))
        if live[_ZEM]:  # L = e_w: D_w e_w (1/P_ww) e_w^T D_w = e_w e_w^T
            j = int(live[:_ZEM].sum())
            out[j, j] = 1.0
        return out

    def hinf_update(
        self, mean: FloatArray, cov: FloatArray, h: FloatArray, innovation: float, r: float
    ) -> tuple[FloatArray, FloatArray]:
        """``(xhat + K (y - H xhat), M^-1)`` by :func:`hinf_step` with ``F = I, Q = 0``.

        Computed in the scaled coordinates ``q_s = D^-1 (q - xhat)`` (so the core's
        estimate is 0 and its measurement the innovation) over the coordinates with a
        positive variance; a known coordinate keeps its value and zero variance.
        """
        var = np.diag(cov)
        live = var > 0.0
        new_mean, new_cov = np.array(mean, dtype=float), np.array(cov, dtype=float)
        if not live.any():
            return new_mean, new_cov
        d = np.sqrt(var[live])
        corr = cov[np.ix_(live, live)] / np.outer(d, d)
        corr = 0.5 * (corr + corr.T)
        hs = (h[live] * d)[None, :]
        n = len(d)
        sbar = self.weight_matrix(cov, live, corr)
        if np.linalg.eigvalsh(corr)[0] <= 0.0 or np.linalg.eigvalsh(sbar)[0] < 0.0:
            # a covariance singular to rounding (a prior of zero width, then the rank-one
            # disturbance of a step): its correlation is not invertible, and the core
            # refused it; a correlation made definite by a trace of 1e-12 is
            corr = corr + RIDGE * np.eye(n)
            sbar = self.weight_matrix(cov, live, corr)
        core = HInfinityModel(
            F=np.eye(n),
            H=hs,
            Q=np.zeros((n, n)),
            R=np.array([[r]]),
            theta=self.theta,
            L=np.eye(n),
            S=sbar,
            condition="a_priori",
        )
        out = hinf_step(HInfinityEstimate(np.zeros(n), corr), [innovation], core)
        new_mean[live] += d * out.x
        new_cov[np.ix_(live, live)] = out.P * np.outer(d, d)
        return new_mean, new_cov
