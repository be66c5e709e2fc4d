"""Quaternion PD law with reaction wheels (seed 001_065e7380b52b75c9, docs/models.md §2.2).

Law (seed eq. (6) with ``K_w = K_q = J``, ``M_ext = 0``, rest target ``w_t = 0``)::

    M_u = w x (J w + L) - J (k_w w_d + k_q s qbar_d)                       (6)

so that, away from the wheel limits, ``dw_d/dt + k_w w_d + k_q s qbar_d = 0`` (eq. (8)).
``qbar_d`` is the vector part of the error quaternion ``q_d = q_t^-1 (x) q`` (eq. (4)),
taken in the hemisphere ``q_d4 >= 0`` (shortest turn). The factor ``s`` is the
convention the seed leaves open:

* ``quaternion_term="vector"`` (``s = 1``, the seed's text: ``qbar ~ phi/2``);
* ``quaternion_term="twice"`` (``s = 2``, ``2 qbar ~ phi``, the rotation vector).

The two are the same law with ``k_q`` rescaled by 2. The seed's reference maneuver
(150 deg, ``k_q ~ 1.375``, ``k_w = 2.625``, eqs. (13)-(24)) is written with the vector
part; its f0 table is reproduced with ``"twice"`` (see :mod:`gain_study`).

Also here: the settle criterion (angle < 0.01 deg and rate < 0.01 deg/s from then
on, seed text before Fig. 3), the regime boundaries (24) and the baseline rule (10).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from kalman_vs_infoset.estim.base import Belief
from kalman_vs_infoset.guidance.attitude.plant import RigidBody, positive_finite
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics.rotations import cross, error_quaternion

FloatArray = NDArray[np.float64]
QuaternionTerm = Literal["vector", "twice"]
_SCALE = {"vector": 1.0, "twice": 2.0}

#: Settle criterion of the seed: 0.01 deg and 0.01 deg/s.
ANGLE_TOL_DEG = 0.01
RATE_TOL_DEGPS = 0.01


def term_scale(quaternion_term: str) -> float:
    """``s`` in ``k_q s qbar``: 1 for ``"vector"``, 2 for ``"twice"``."""
    try:
        return _SCALE[quaternion_term]
    except KeyError:
        raise ValueError(
            f"quaternion_term must be 'vector' or 'twice', got {quaternion_term!r}"
        ) from None


@dataclass(frozen=True)
class QuaternionPD:
    """The quaternion PD law (6)/(8) with gyroscopic compensation.

    Parameters
    ----------
    body : RigidBody
        Inertia ``J`` used both as ``K_w = K_q`` and in the compensation term.
    k_q, k_w : float
        Gains (1/s^2, 1/s), positive finite numbers.
    quaternion_term : {"vector", "twice"}
        Whether ``k_q`` multiplies ``qbar`` or ``2 qbar`` (module docstring).
    q_target : array (4,)
        Target attitude (scalar last); rest target (``w_t = 0``).
    """

    body: RigidBody
    k_q: float
    k_w: float
    quaternion_term: QuaternionTerm = "vector"
    q_target: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        positive_finite(self.k_q, "k_q")
        positive_finite(self.k_w, "k_w")
        term_scale(self.quaternion_term)
        qt = np.asarray(self.q_target, dtype=float)
        if qt.shape != (4,) or not np.isclose(np.linalg.norm(qt), 1.0):
            raise ValueError("q_target must be a unit quaternion (scalar last)")
        object.__setattr__(self, "q_target", tuple(float(v) for v in qt))

    def torque(self, x: ArrayLike) -> FloatArray:
        """Commanded torque ``M_u`` (N m) for plant states ``(..., 10) = (q, w, h)``."""
        x = np.asarray(x, dtype=float)
        q, w, h = x[..., 0:4], x[..., 4:7], x[..., 7:10]
        qbar = error_quaternion(q, self.q_target)[..., :3]
        jmat = self.body.inertia_kgm2
        gyro = cross(w, w @ jmat.T + h)
        pd = self.k_w * w + self.k_q * term_scale(self.quaternion_term) * qbar
        return gyro - pd @ jmat.T

    def from_belief(self, belief: Belief) -> FloatArray:
        """The law evaluated at the belief's point estimate (never the truth)."""
        return self.torque(belief.centre())


def regime_boundaries(
    k_q: float,
    k_w: float,
    inertia_kgm2: float,
    torque_max_Nm: float,
    momentum_max_Nms: float,
    quaternion_term: QuaternionTerm = "vector",
) -> tuple[float, float]:
    """Regime boundaries ``(phi10, phi20)`` in radians, seed eq. (24).

    ``phi10 = 2 arcsin(M_max / (k_q J))`` (torque limit reached at the start, eq. (14));
    ``phi20 = L_max^2 / (2 J M_max) + 2 arcsin(k_w L_max / (k_q J))`` (momentum limit
    reached, eq. (23)). With ``"twice"`` ``k_q`` stands for ``2 k_q``. An arcsin
    argument above 1 means the limit is never reached: ``inf``.

    The gains, the inertia and both limits must be positive finite numbers
    (ValueError otherwise): a zero divides, a negative one gives a negative angle,
    and a limit that does not exist has no boundary to give.
    """
    kq = positive_finite(k_q, "k_q") * term_scale(quaternion_term)
    k_w = positive_finite(k_w, "k_w")
    j = positive_finite(inertia_kgm2, "inertia_kgm2")
    torque_max_Nm = positive_finite(torque_max_Nm, "torque_max_Nm")
    momentum_max_Nms = positive_finite(momentum_max_Nms, "momentum_max_Nms")

    def two_asin(arg: float) -> float:
        return 2.0 * float(np.arcsin(arg)) if arg <= 1.0 else np.inf

    phi10 = two_asin(torque_max_Nm / (kq * j))
    # L (L / (2 J M)), not L**2 / (2 J M): a momentum limit past 1e154 N m s (never
    # reached) overflows the square, which Python's float raises on; the product is inf
    phi20 = momentum_max_Nms * (momentum_max_Nms / (2.0 * j * torque_max_Nm)) + two_asin(
        k_w * momentum_max_Nms / (kq * j)
    )
    return phi10, phi20


def baseline_gains(
    t_end_s: float, quaternion_term: QuaternionTerm = "vector"
) -> tuple[float, float]:
    """Baseline rule (10): ``k_w = 16/t_end``, ``k_q = k_w^2/2``; returns ``(k_q, k_w)``.

    Rule (10) goes with the stability-degree condition (9), ``k_w^2 <= 2 k_q``, which
    is critical damping of the linearised law *with the vector part*
    (``phi'' + k_w phi' + k_q phi/2 = 0``); with ``"twice"`` the same law has ``k_q/2``.
    """
    if not t_end_s > 0:
        raise ValueError(f"t_end_s must be positive, got {t_end_s}")
    k_w = 16.0 / t_end_s
    return k_w**2 / 2.0 / term_scale(quaternion_term), k_w


def baseline_kq(k_w: ArrayLike, quaternion_term: QuaternionTerm = "vector") -> FloatArray:
    """``k_q`` of rule (9)/(10) for given ``k_w`` (critical damping), in the chosen convention."""
    return np.asarray(k_w, dtype=float) ** 2 / 2.0 / term_scale(quaternion_term)


def settle_time(
    time_s: ArrayLike,
    angle_deg: ArrayLike,
    rate_degps: ArrayLike,
    angle_tol_deg: float = ANGLE_TOL_DEG,
    rate_tol_degps: float = RATE_TOL_DEGPS,
) -> float:
    """First sample time from which ``angle < tol`` and ``rate < tol`` hold to the end.

    Parameters
    ----------
    time_s : array_like (n,)
        Sample times (finite), n >= 1.
    angle_deg, rate_degps : array_like (n,)
        Error angle and rate at those samples. NaN is refused (ValueError): a NaN
        compares false with the tolerance and would read as settled.
    angle_tol_deg, rate_tol_degps : float
        The tolerances, positive.

    Returns
    -------
    float
        ``inf`` when the criterion fails at the last sample (not settled).
    """
    t = np.asarray(time_s, dtype=float)
    angle = np.asarray(angle_deg, dtype=float)
    rate = np.asarray(rate_degps, dtype=float)
    if t.ndim != 1 or t.size == 0:
        raise ValueError(f"time_s must be a non-empty 1-D array, got shape {t.shape}")
    for name, arr in (("angle_deg", angle), ("rate_degps", rate)):
        if arr.shape != t.shape:
            raise ValueError(f"{name} must have the shape of time_s {t.shape}, got {arr.shape}")
        if np.isnan(arr).any():
            raise ValueError(f"{name} must not contain NaN (a NaN sample is not a settled one)")
    if not np.isfinite(t).all():
        raise ValueError("time_s must be finite")
    for name, tol in (("angle_tol_deg", angle_tol_deg), ("rate_tol_degps", rate_tol_degps)):
        if not tol > 0:  # inf is allowed (no criterion on that quantity); NaN is not
            raise ValueError(f"{name} must be positive, got {tol!r}")
    bad = (angle >= angle_tol_deg) | (rate >= rate_tol_degps)
    if bad[-1]:
        return np.inf
    idx = np.flatnonzero(bad)
    return float(t[0]) if idx.size == 0 else float(t[idx[-1] + 1])


def rest_to_rest_initial_state(
    axis: ArrayLike, angle_deg: float, q_target: ArrayLike = (0.0, 0.0, 0.0, 1.0)
) -> FloatArray:
    """Plant state at rest turned by ``angle_deg`` about ``axis`` from the target (eq. (11)).

    ``axis`` must be a non-zero 3-vector of finite norm (it is normalised) and
    ``angle_deg`` a finite number (ValueError otherwise).
    """
    from scipy.spatial.transform import Rotation  # here: the gain study's options stay light

    axis = np.asarray(axis, dtype=float)
    # checked here: scipy would report a zero or NaN axis as "zero norm quaternions"
    norm = float(np.linalg.norm(axis)) if axis.shape == (3,) else 0.0
    if not (norm > 0 and np.isfinite(norm)):
        raise ValueError(f"axis must be a non-zero 3-vector of finite norm, got {axis.tolist()}")
    angle = np.asarray(angle_deg)
    if angle.ndim != 0 or angle.dtype.kind not in "iuf":
        raise TypeError(f"angle_deg must be a number, got {angle_deg!r}")
    if not np.isfinite(angle):
        raise ValueError(f"angle_deg must be finite, got {angle_deg!r}")
    rot = Rotation.from_quat(q_target) * Rotation.from_rotvec(
        np.radians(angle_deg) * axis / np.linalg.norm(axis)
    )
    return np.concatenate([rot.as_quat(), np.zeros(6)])


def angle_and_rate_deg(x: ArrayLike, q_target: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Principal error angle (deg) and body-rate norm (deg/s) along a state history."""
    x = np.asarray(x, dtype=float)
    err = error_quaternion(x[..., 0:4], q_target)
    angle = 2.0 * np.arctan2(np.linalg.norm(err[..., :3], axis=-1), err[..., 3])
    return np.degrees(angle), np.degrees(np.linalg.norm(x[..., 4:7], axis=-1))
