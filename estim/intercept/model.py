"""The auxiliary linear model of one guidance channel (docs/models.md §1.3, seed 003 section 4).

Per channel (lateral shown; the vertical channel is the same with theta, z) the
state is the bearing ``alpha`` (rad), its rate ``omega`` (rad/s) and the range
``x`` (m), with the nominal closing law ``x(t) = x(t0) - e (t - t0)``::

    d alpha/dt = omega
    d omega/dt = 2 e omega / x + v / x + (1/x) sum_i k(t_i) delta(t - t_i)

``|v| <= nu`` stands for everything neglected (opponent's control). The impulse
``k`` (m/s) is the change of the *relative* lateral velocity of the target with
respect to the spacecraft; the spacecraft itself changes its velocity by ``-k``.

Exact one-step solution (derivation: ``d(omega x^2)/dt = v x`` and
``int dt/x^2 = Delta/(x0 x1)``), with ``x1 = x0 - e Delta`` and ``v`` constant over
the step::

    omega1 = omega0 x0^2/x1^2 + v Delta (x0 + x1) / (2 x1^2)
    alpha1 = alpha0 + omega0 x0 Delta / x1 + v Delta^2 / (2 x1)

The second ``v`` coefficient follows from ``int_0^Delta (x0 t - e t^2/2)/x(t)^2 dt
= Delta^2 / (2 x1)``. A natural companion coordinate is the zero-effort miss
``w = omega x^2 / e`` (m): the prediction becomes the unit-determinant shear
``alpha1 = alpha0 + w0 e Delta/(x0 x1)``, ``w1 = w0 + v Delta (x0 + x1)/(2 e)``.

Miss forecast for free motion (seed 003 section 5)::

    Pi(alpha, omega, x) = omega x^2 / e + sign(omega) nu (x/e)^2 / 2
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True)
class BearingBound:
    """Bearing error bound growing linearly as the range closes (docs/models.md §1.2).

    ``bound(d) = end_rad + (start_rad - end_rad) * d / ref_range_m``: ``start_rad``
    at the nominal initial range, ``end_rad`` at zero range.
    """

    start_rad: float = 1.5e-4
    end_rad: float = 2.3e-4
    ref_range_m: float = 5801.3e3

    def __post_init__(self) -> None:
        if not (self.start_rad > 0 and self.end_rad > 0 and self.ref_range_m > 0):
            raise ValueError("bearing bounds and reference range must be positive")
        if self.start_rad > self.end_rad:
            # estimators take the bound at the smallest range of an interval as its widest
            raise ValueError("start_rad must be <= end_rad (the bound grows as the range closes)")

    @property
    def _slope_radpm(self) -> float:
        """How fast the line falls with the range (rad/m; 0 for a constant bound)."""
        return (self.end_rad - self.start_rad) / self.ref_range_m

    @property
    def max_range_m(self) -> float:
        """Largest range at which the bound is still positive."""
        slope = self._slope_radpm
        return np.inf if slope <= 0 else self.end_rad / slope

    @property
    def floor_rad(self) -> float:
        """The floor under the line (the bound beyond :attr:`linear_range_m`)."""
        return 1e-3 * min(self.start_rad, self.end_rad)

    @property
    def linear_range_m(self) -> float:
        """Largest range at which the bound is the line, not its floor. The set
        estimators need every range of their states within it: there the bound times
        the range is concave, so a bearing's constraint is convex in the states (with
        the floor it is not, and the node set's bounds between its nodes lost the truth)."""
        slope = self._slope_radpm
        return np.inf if slope <= 0 else (self.end_rad - self.floor_rad) / slope

    def __call__(self, range_m: ArrayLike) -> NDArray[np.float64]:
        d = np.asarray(range_m, dtype=float)
        b = self.end_rad + (self.start_rad - self.end_rad) * d / self.ref_range_m
        return np.maximum(b, self.floor_rad)


@dataclass(frozen=True)
class Bearing:
    """A bearing measurement of one channel (rad): an angle in ``[-pi, pi]`` (NaN, inf or
    a number beyond is refused here, so that no estimator mistakes it for a fault of its
    own belief: 1e300 overflowed in the EKF)."""

    alpha_rad: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.alpha_rad) and abs(self.alpha_rad) <= np.pi):
            raise ValueError(
                f"a bearing measurement must be in [-pi, pi] rad, got {self.alpha_rad}"
            )


@dataclass(frozen=True)
class Range:
    """A range-finder measurement (m).

    The range finder measures ``d``, the estimators work in ``x = d cos(phi)``,
    ``phi`` the line of sight's total off-axis angle (both axes). ``off_axis_rad``
    bounds ``phi`` at this measurement (the caller derives it from the bearings of
    both axes: :func:`off_axis_bound_rad`); ``None`` falls back on the model's
    ``max_off_axis_rad``, an assumption rather than a measurement.
    """

    range_m: float
    off_axis_rad: float | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.range_m) and self.range_m > 0):
            raise ValueError(
                f"a range measurement must be a finite positive number, got {self.range_m}"
            )
        if self.off_axis_rad is not None and not 0 <= self.off_axis_rad <= np.pi / 2:
            raise ValueError("off_axis_rad must be in [0, pi/2] (or None)")


def off_axis_bound_rad(bearings_rad: ArrayLike, bounds_rad: ArrayLike) -> float:
    """Bound of the line of sight's total off-axis angle from one bearing per axis.

    With ``alpha = atan2(y, x)`` and ``beta = atan2(z, x)`` the range is
    ``d = x sqrt(1 + tan^2 alpha + tan^2 beta)``, so ``x = d cos(phi)`` with
    ``tan^2 phi = tan^2 alpha + tan^2 beta``. A bearing ``a_m`` measured within
    ``+-b`` of the truth gives ``|alpha| <= |a_m| + b``, hence::

        phi <= atan( sqrt( sum_i tan^2 min(|a_m,i| + b_i, pi/2) ) )

    Parameters
    ----------
    bearings_rad, bounds_rad : array
        Measured bearing of each axis (both axes, guided or not) and the bound of
        its error at this range (the largest over the ranges the range measurement
        allows: the bound grows as the range closes).

    Returns
    -------
    float
        The bound (rad), in ``[0, pi/2]``.
    """
    a = np.minimum(
        np.abs(np.asarray(bearings_rad, float)) + np.asarray(bounds_rad, float), np.pi / 2
    )
    return float(min(np.arctan(np.sqrt(np.sum(np.tan(a) ** 2))), np.pi / 2))


@dataclass(frozen=True)
class Impulse:
    """A control impulse ``k_mps`` (relative velocity, m/s) known to within
    ``+-uncertainty_mps`` (e.g. thrust misalignment from a pointing error)."""

    k_mps: float
    uncertainty_mps: float = 0.0

    def __post_init__(self) -> None:
        if not math.isfinite(self.k_mps):
            raise ValueError(f"an impulse must be finite, got k_mps={self.k_mps}")
        if not (math.isfinite(self.uncertainty_mps) and self.uncertainty_mps >= 0):
            raise ValueError(
                f"uncertainty_mps must be finite and non-negative, got {self.uncertainty_mps}"
            )


def impulse_parts(control: float | Impulse) -> tuple[float, float]:
    """``(k, uncertainty)`` of a control given as a number or an :class:`Impulse`
    (ValueError for a number that is not finite)."""
    if isinstance(control, Impulse):
        return float(control.k_mps), float(control.uncertainty_mps)
    if isinstance(control, str | bytes) or not isinstance(control, numbers.Real):
        # float("3") read a text as 3 m/s
        raise TypeError(f"an impulse is a number (m/s) or an Impulse, got {control!r}")
    k = float(control)
    if not math.isfinite(k):
        raise ValueError(f"an impulse must be finite, got {k}")
    return k, 0.0


def check_step(dt_s: float) -> None:
    """A prediction's step: finite and not negative (the model moves forward in time;
    a NaN step left some estimators' beliefs NaN with status ``ok``)."""
    if not (math.isfinite(dt_s) and dt_s >= 0.0):
        raise ValueError(f"dt_s must be a finite number >= 0, got {dt_s}")


@dataclass(frozen=True)
class ChannelModel:
    """Parameters of the auxiliary model shared by every estimator of a channel."""

    closing_speed_mps: float = 58.0e3
    nu_mps2: float = 0.005
    bearing_bound: BearingBound = field(default_factory=BearingBound)
    range_rel_bound: float = 0.05
    eps_m: float = 5.0e3
    #: assumed bound on the line of sight's total off-axis angle (both channels) for a
    #: range measurement that carries none (``Range.off_axis_rad``): the range finder
    #: measures d, the sections are in x = d cos(angle) >= d cos(max_off_axis)
    max_off_axis_rad: float = 0.1
    #: how far the truth may depart from a constant closing speed over an engagement
    #: (an acceleration along the line of sight, e.g. differential gravity, ``|de/dt|
    #: <= a`` for a time ``T``): its closing speed by ``a T``, its range from ``x0 - e
    #: t`` by ``a T^2 / 2``. The set estimators widen their closing-speed interval, the
    #: range of their prior box, every range interval and the threshold by these (zero:
    #: the seed's constant closing speed)
    closing_drift_mps: float = 0.0
    range_drift_m: float = 0.0

    def __post_init__(self) -> None:
        if not self.closing_speed_mps > 0:
            raise ValueError("closing_speed_mps must be positive")
        if not self.nu_mps2 >= 0:
            raise ValueError("nu_mps2 must be non-negative")
        if not 0 < self.range_rel_bound < 1:
            raise ValueError("range_rel_bound must be in (0, 1)")
        if not self.eps_m > 0:
            raise ValueError("eps_m must be positive")
        if not 0 <= self.max_off_axis_rad < np.pi / 2:
            raise ValueError("max_off_axis_rad must be in [0, pi/2)")
        if not 0 <= self.closing_drift_mps < 0.5 * self.closing_speed_mps:
            raise ValueError("closing_drift_mps must be in [0, closing_speed_mps / 2)")
        if not 0 <= self.range_drift_m < 0.5 * self.eps_m:
            raise ValueError("range_drift_m must be in [0, eps_m / 2)")

    @property
    def e(self) -> float:
        return self.closing_speed_mps

    @property
    def eps_sets_m(self) -> float:
        """The least range the set estimators keep: ``eps`` less :attr:`range_drift_m`
        (a truth at ``eps`` lies up to that below its constant-speed line)."""
        return self.eps_m - self.range_drift_m

    def drifted_speeds(self, speeds_mps: tuple[float, float] | None) -> tuple[float, float]:
        """A closing-speed interval (None: ``e`` exactly) widened by
        :attr:`closing_drift_mps` on both sides: every closing speed the truth reaches."""
        lo, hi = speeds_mps if speeds_mps is not None else (self.e, self.e)
        return lo - self.closing_drift_mps, hi + self.closing_drift_mps

    def step_coefficients(self, x0_m: ArrayLike, dt_s: float) -> dict[str, NDArray[np.float64]]:
        """Coefficients of the exact one-step map from ``x0`` to ``x1 = x0 - e dt``.

        Returns ``x1``, ``a_w`` (alpha gain on w: e dt/(x0 x1)), ``omega_gain``
        (x0^2/x1^2), ``alpha_omega`` (x0 dt/x1), ``g_alpha`` (dt^2/(2 x1)),
        ``g_omega`` (dt (x0+x1)/(2 x1^2)), ``g_w`` (dt (x0+x1)/(2 e)): the ``g`` are
        the coefficients of ``v``.
        """
        x0 = np.asarray(x0_m, dtype=float)
        x1 = x0 - self.e * dt_s
        return {
            "x1": x1,
            "a_w": self.e * dt_s / (x0 * x1),
            "omega_gain": x0**2 / x1**2,
            "alpha_omega": x0 * dt_s / x1,
            "g_alpha": dt_s**2 / (2.0 * x1),
            "g_omega": dt_s * (x0 + x1) / (2.0 * x1**2),
            "g_w": dt_s * (x0 + x1) / (2.0 * self.e),
        }

    def step(
        self,
        state: ArrayLike,
        dt_s: float,
        v_mps2: ArrayLike = 0.0,
        closing_speed_mps: float | None = None,
    ) -> NDArray[np.float64]:
        """Exact one-step propagation of ``(alpha, omega, x)`` rows with constant ``v``:
        the auxiliary linear model's motion (docs/models.md §1.3).

        ``closing_speed_mps`` (default ``e``) is the true closing speed: the same
        formulas hold for any constant closing speed, with ``x1 = x0 - e_true dt``.

        This is not the Cartesian motion the default information set is sound for (with
        its kinematic margin on, it models the nonlinear motion and may leave out states
        of this model: a truth moved by this map from a corner of the prior box can lie
        outside it late in an approach). Pair it with ``kinematic_margin=False``, or move
        a Cartesian truth (:mod:`kalman_vs_infoset.guidance.intercept.truth`).
        """
        s = np.asarray(state, dtype=float)
        e_true = self.e if closing_speed_mps is None else closing_speed_mps
        c = ChannelModel(e_true, self.nu_mps2).step_coefficients(s[..., 2], dt_s)
        v = np.asarray(v_mps2, dtype=float)
        alpha = s[..., 0] + c["alpha_omega"] * s[..., 1] + c["g_alpha"] * v
        omega = c["omega_gain"] * s[..., 1] + c["g_omega"] * v
        return np.stack([alpha, omega, c["x1"] + 0.0 * alpha], axis=-1)

    def miss_forecast_m(self, points: ArrayLike) -> NDArray[np.float64]:
        """``Pi(alpha, omega, x)`` of seed 003 section 5 for rows ``(alpha, omega, x)``."""
        p = np.asarray(points, dtype=float)
        omega, x = p[..., 1], p[..., 2]
        t_go = x / self.e
        return omega * x * t_go + np.sign(omega) * self.nu_mps2 * t_go**2 / 2.0

    def zero_effort_miss_m(self, omega_radps: ArrayLike, x_m: ArrayLike) -> NDArray[np.float64]:
        """``w = omega x^2 / e``."""
        return np.asarray(omega_radps) * np.asarray(x_m) ** 2 / self.e

    def omega_from_w(self, w_m: ArrayLike, x_m: ArrayLike) -> NDArray[np.float64]:
        return np.asarray(w_m) * self.e / np.asarray(x_m) ** 2

    def from_cartesian(self, lateral_m, lateral_vel_mps, x_m, vx_mps) -> NDArray[np.float64]:
        """Exact ``(alpha, omega, x)`` of a relative Cartesian state of one channel.

        ``alpha = atan2(y, x)``, ``omega = (x Vy - y Vx) / (x^2 + y^2)``.
        """
        y, vy, x, vx = (
            np.asarray(a, dtype=float) for a in (lateral_m, lateral_vel_mps, x_m, vx_mps)
        )
        alpha = np.arctan2(y, x)
        omega = (x * vy - y * vx) / (x**2 + y**2)
        return np.stack([alpha, omega, x + 0.0 * alpha], axis=-1)


def _interval(value: Iterable[float], name: str) -> tuple[float, float]:
    lo, hi = (float(v) for v in value)
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        raise ValueError(f"{name} must be a finite interval [lo, hi] with lo <= hi")
    return lo, hi


@dataclass(frozen=True)
class ChannelPrior:
    """The a-priori box of one intercept channel in SI units: what every estimator of
    the channel starts from (:meth:`kalman_vs_infoset.estim.base.Estimator.initial`).

    Parameters
    ----------
    lateral_m, lateral_vel_mps : (float, float)
        Intervals of the channel's offset ``y`` (m) and velocity ``Vy`` (m/s).
    x_m : (float, float)
        Interval of the range along the nominal axis (m, positive).
    closing_speed_mps : (float, float) or None
        Interval of the closing speed ``-Vx`` (m/s, positive); None: the model's
        nominal ``e`` exactly.
    """

    lateral_m: tuple[float, float]
    lateral_vel_mps: tuple[float, float]
    x_m: tuple[float, float]
    closing_speed_mps: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in ("lateral_m", "lateral_vel_mps", "x_m"):
            object.__setattr__(self, name, _interval(getattr(self, name), name))
        if not self.x_m[0] > 0:
            raise ValueError("x_m must be positive")
        if self.closing_speed_mps is not None:
            speed = _interval(self.closing_speed_mps, "closing_speed_mps")
            if not speed[0] > 0:
                raise ValueError("closing_speed_mps must be positive")
            object.__setattr__(self, "closing_speed_mps", speed)

    def auxiliary_box(self, closing_speed_hi_mps: float) -> ChannelPrior:
        """The box of ``(Y, V) = (alpha x, omega x - c alpha)`` that holds the exact
        image (:meth:`ChannelModel.from_cartesian`) of every Cartesian state of this box
        closing at a speed ``c <= closing_speed_hi_mps``: the coordinates the set
        estimators' initial sets take for ``(y, Vy)`` (their small-angle map).

        With ``r = y / x``: ``Y = y atan(r) / r``, between ``y (1 - r^2/3)`` and ``y``,
        and ``V = (Vy - c f(r)) / (1 + r^2)`` with ``f(r) = (1 + r^2) atan(r) - r``, odd,
        of the sign of ``r`` and at most ``2 |r|^3 / 3``. Both shrink towards zero
        except through ``c f(r)``, so a face moves out only when that term beats the
        shrink: the upper ``V`` face by ``R^2 ((2/3) c R - Vy_hi)`` at most over the
        negative ``y`` (``R = max(-y_lo, 0) / x_lo``), the lower one symmetrically; a
        ``y`` face moves only towards zero, for a box that does not hold ``y = 0``.
        Seed 003's boxes (``|y| <= 10`` km at 5301 km, ``|Vy| <= 100`` m/s, 58 km/s)
        need no widening (``(2/3) c R = 73 < 100``); a box of +-100 km at that range
        left Cartesian states 0.5 m/s outside the initial set.
        """
        (y0, y1), (v0, v1), (xa, _) = self.lateral_m, self.lateral_vel_mps, self.x_m
        c = float(closing_speed_hi_mps)
        r_pos, r_neg = max(y1, 0.0) / xa, max(-y0, 0.0) / xa
        up = max(r_neg**2 * max(2.0 / 3.0 * c * r_neg - v1, 0.0), r_pos**2 * max(-v1, 0.0))
        down = max(r_pos**2 * max(2.0 / 3.0 * c * r_pos + v0, 0.0), r_neg**2 * max(v0, 0.0))
        y_up = max(-y1, 0.0) * (y1 / xa) ** 2 / 3.0
        y_down = max(y0, 0.0) * (y0 / xa) ** 2 / 3.0
        if up == down == y_up == y_down == 0.0:
            return self
        # and a relative 1e-12 for the rounding of the bounds themselves
        pad = 1e-12 * max(abs(v0), abs(v1), c * max(r_pos, r_neg))
        return replace(
            self,
            lateral_m=(y0 - y_down, y1 + y_up),
            lateral_vel_mps=(v0 - down - pad * (down > 0), v1 + up + pad * (up > 0)),
        )

    def drifted(self, model: ChannelModel) -> ChannelPrior:
        """The box with its range widened by ``model.range_drift_m`` on both sides (the
        set estimators' prior: a truth departing from a constant closing speed is, at
        any time, on a constant-speed line from a range that far outside the box)."""
        d = model.range_drift_m
        if d == 0.0:
            return self
        return replace(self, x_m=(self.x_m[0] - d, self.x_m[1] + d))

    def centre_state(self, model: ChannelModel) -> NDArray[np.float64]:
        """``(alpha, omega, x)`` of the box's centre (closing at the interval's middle)."""
        y, vy, x = (0.5 * (lo + hi) for lo, hi in (self.lateral_m, self.lateral_vel_mps, self.x_m))
        speed = self.closing_speed_mps or (model.e, model.e)
        return model.from_cartesian(y, vy, x, -0.5 * (speed[0] + speed[1]))


@dataclass(frozen=True)
class ChannelSetting:
    """What an intercept estimator is built with besides its own options: the channel's
    auxiliary model and the interval of the true closing speed its propagation may
    assume (None: the nominal ``e`` exactly, the seed's model)."""

    model: ChannelModel
    closing_speed_mps: tuple[float, float] | None = None


def channel_state(state: ArrayLike) -> tuple[float, float, float]:
    """A channel's true state ``(alpha rad, omega rad/s, x m)`` as three floats; one
    line for another shape (a ``(2,)`` state gave "not enough values to unpack", a
    ``(2, 3)`` array "only 0-dimensional arrays can be converted")."""
    s = np.asarray(state, dtype=float)
    if s.shape != (3,):
        raise ValueError(
            f"a channel state is (alpha rad, omega rad/s, x m): shape (3,), got {s.shape}"
        )
    return float(s[0]), float(s[1]), float(s[2])
