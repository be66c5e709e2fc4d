"""The flight ("shtatny") baseline: rest-to-rest turn about the Euler axis (seed 000,
docs/models.md §2.1).

Seed 000, introduction and section 5: the Resurs-P flight algorithm rotates about the
fixed Euler axis in three stages -- acceleration, constant rate, deceleration -- and
each acceleration stage has three sub-phases with linearly rising, constant and
falling (in magnitude) angular acceleration. The seed publishes no phase durations;
they are parameters here (``accel_time_s`` per stage, ``jerk_time_s`` per ramp).

The angle travelled ``s(t)`` is the double integral of the trapezoidal acceleration
``s''(t) = a_max g(t)`` (``g`` piecewise linear, scipy ``PPoly``), ``a_max`` chosen so
that ``s(T) = theta0``; the profile is symmetric, so ``s'(T) = 0``.

Tracking law (attitude error measured from the target, body axes)::

    M = J w_ref' + w x (J w + h) - J (kp delta + kd (w - w_ref))

with the reference error rotation ``R_ref(t) = exp([e (theta0 - s(t))]x)``,
``w_ref = -e s'(t)``, ``delta = rotvec(R_ref^-1 R)``; ``kp = wn^2``, ``kd = 2 zeta wn``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from kalman_vs_infoset.guidance.attitude.plant import RigidBody
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import PPoly
from scipy.spatial.transform import Rotation


@dataclass(frozen=True)
class EulerAxisProfile:
    """Jerk-limited accelerate / coast / decelerate profile of the turn angle.

    Parameters
    ----------
    angle_rad : theta0, the total turn angle (> 0).
    duration_s : T, the turn time.
    accel_time_s : duration of each acceleration (and deceleration) stage, <= T/2.
    jerk_time_s : duration of each linear ramp of the acceleration, <= accel_time_s/2.
    """

    angle_rad: float
    duration_s: float
    accel_time_s: float
    jerk_time_s: float
    _angle: PPoly = field(init=False, repr=False)
    _rate: PPoly = field(init=False, repr=False)
    _accel: PPoly = field(init=False, repr=False)

    def __post_init__(self) -> None:
        t, ta, tj = self.duration_s, self.accel_time_s, self.jerk_time_s
        if not (self.angle_rad > 0 and t > 0 and np.isfinite([self.angle_rad, t]).all()):
            raise ValueError("angle_rad and duration_s must be positive and finite")
        if not 0 < ta <= t / 2:
            raise ValueError("accel_time_s must be in (0, duration_s/2]")
        if not 0 <= tj <= ta / 2:
            raise ValueError("jerk_time_s must be in [0, accel_time_s/2]")
        knots = [0.0, tj, ta - tj, ta, t - ta, t - ta + tj, t - tj, t]
        values = [0.0, 1.0, 1.0, 0.0, 0.0, -1.0, -1.0, 0.0]
        xs, vs = [knots[0]], [values[0]]
        for k, v in zip(knots[1:], values[1:], strict=True):
            if k > xs[-1]:
                xs.append(k)
                vs.append(v)
            else:  # zero-length phase: the value jumps (only at the ramp ends, where equal)
                vs[-1] = v
        x = np.asarray(xs)
        vals = np.asarray(vs)
        slope = np.diff(vals) / np.diff(x)
        unit_accel = PPoly(np.vstack([slope, vals[:-1]]), x)
        unit_angle = unit_accel.antiderivative(2)
        a_max = self.angle_rad / float(unit_angle(t))
        accel = PPoly(unit_accel.c * a_max, x)
        object.__setattr__(self, "_accel", accel)
        object.__setattr__(self, "_rate", accel.antiderivative(1))
        object.__setattr__(self, "_angle", accel.antiderivative(2))

    def _clip(self, t_s: ArrayLike) -> NDArray[np.float64]:
        return np.clip(np.asarray(t_s, dtype=float), 0.0, self.duration_s)

    def angle(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """Angle travelled ``s(t)`` (rad); ``theta0`` after T."""
        return self._angle(self._clip(t_s))

    def rate(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """``s'(t)`` (rad/s); zero before 0 and after T."""
        t = np.asarray(t_s, dtype=float)
        return np.where((t >= 0) & (t <= self.duration_s), self._rate(self._clip(t)), 0.0)

    def accel(self, t_s: ArrayLike) -> NDArray[np.float64]:
        """``s''(t)`` (rad/s^2); zero outside [0, T)."""
        t = np.asarray(t_s, dtype=float)
        return np.where((t >= 0) & (t < self.duration_s), self._accel(self._clip(t)), 0.0)


@dataclass(frozen=True)
class EulerTurnTracker:
    """Feedforward + PD tracking of the Euler-axis profile (see module docstring).

    ``error0_rotvec_rad`` is the initial attitude error (body relative to target) as a
    rotation vector; the Euler axis is its direction and ``theta0`` its norm.
    ``inertia_kgm2`` must be a finite symmetric positive definite 3x3 matrix, as for
    :class:`~kalman_vs_infoset.guidance.attitude.plant.RigidBody` (ValueError otherwise).
    """

    inertia_kgm2: NDArray[np.float64]
    error0_rotvec_rad: NDArray[np.float64]
    duration_s: float
    accel_time_s: float
    jerk_time_s: float
    natural_freq_radps: float = 0.1
    damping: float = 0.9
    profile: EulerAxisProfile = field(init=False, repr=False)
    axis: NDArray[np.float64] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        phi0 = np.array(self.error0_rotvec_rad, dtype=float)
        theta0 = float(np.linalg.norm(phi0))
        if phi0.shape != (3,) or not (theta0 > 0 and np.isfinite(theta0)):
            raise ValueError("error0_rotvec_rad must be a finite non-zero 3-vector")
        gains = (self.natural_freq_radps, self.damping)
        if not (min(gains) > 0 and np.isfinite(gains).all()):
            raise ValueError("natural_freq_radps and damping must be positive and finite")
        # RigidBody's check: a negative or zero J flips or zeroes the torque, NaN gives NaN
        inertia = RigidBody(self.inertia_kgm2).inertia_kgm2
        object.__setattr__(self, "inertia_kgm2", inertia)
        object.__setattr__(self, "axis", phi0 / theta0)
        prof = EulerAxisProfile(theta0, self.duration_s, self.accel_time_s, self.jerk_time_s)
        object.__setattr__(self, "profile", prof)

    def reference(
        self, t_s: ArrayLike
    ) -> tuple[Rotation, NDArray[np.float64], NDArray[np.float64]]:
        """Reference error rotation(s), rate ``w_ref`` and acceleration ``w_ref'``.

        ``t_s`` may be a scalar or an array (then the rotation is a stack and the
        vectors have shape (n, 3)); precomputing a whole turn at once is cheap.
        """
        p = self.profile
        t = np.asarray(t_s, dtype=float)
        remaining = p.angle_rad - p.angle(t)
        rot = Rotation.from_rotvec(np.multiply.outer(remaining, self.axis))
        w_ref = -np.multiply.outer(p.rate(t), self.axis)
        dw_ref = -np.multiply.outer(p.accel(t), self.axis)
        return rot, w_ref, dw_ref

    def torque_from_reference(
        self,
        reference: tuple[Rotation, NDArray[np.float64], NDArray[np.float64]],
        error_rotvec_rad: ArrayLike,
        w_radps: ArrayLike,
        h_Nms: ArrayLike,
    ) -> NDArray[np.float64]:
        """Commanded body torque (N m) for one reference point ``(R_ref, w_ref, w_ref')``."""
        rot_ref, w_ref, dw_ref = reference
        j = self.inertia_kgm2
        w = np.asarray(w_radps, dtype=float)
        delta = (rot_ref.inv() * Rotation.from_rotvec(error_rotvec_rad)).as_rotvec()
        kp = self.natural_freq_radps**2
        kd = 2.0 * self.damping * self.natural_freq_radps
        gyro = np.cross(w, j @ w + np.asarray(h_Nms, dtype=float))
        return j @ dw_ref + gyro - j @ (kp * delta + kd * (w - w_ref))

    def torque(
        self, t_s: float, error_rotvec_rad: ArrayLike, w_radps: ArrayLike, h_Nms: ArrayLike
    ) -> NDArray[np.float64]:
        """Commanded body torque (N m) from the measured error, rate and gyro momentum."""
        return self.torque_from_reference(
            self.reference(float(t_s)), error_rotvec_rad, w_radps, h_Nms
        )
