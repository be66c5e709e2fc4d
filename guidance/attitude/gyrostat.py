"""Three-rotor gyrostat plant and the linearising rotor torques (seed 004, docs/models.md §2.4).

Plant (seed eq. 1.1), principal axes, cyclic ``(i, j, k) = (1, 2, 3), (2, 3, 1), (3, 1, 2)``::

    (A_i - J_i) dx_i/dt = (A_j - A_k) x_j x_k + J_j x_k phidot_j - J_k x_j phidot_k - u_i + v_i
    J_i (phiddot_i + dx_i/dt) = u_i

``A_i`` total principal moments of the gyrostat, ``J_i`` rotor axial moments, ``x`` body
rates, ``phidot`` rotor rates relative to the body, ``u`` rotor (internal) torques,
``v`` disturbance torques. With the total momentum ``K = A x + J phidot`` the first
line reads ``(A - J) dx/dt = K x x - u + v`` (the OCR of (1.1) is garbled; this is the
reading that makes ``dK/dt + x x K = v``, checked in the tests).

Kinematics (seed eq. 1.2), scalar-last quaternion ``eta = (eta_v, eta4)`` as in
:func:`kalman_vs_infoset.numerics.rotations.quaternion_rate`::

    2 deta_v/dt = eta4 x + eta_v x x,     2 deta4/dt = -eta_v . x

With ``G = eta4 I + [eta_v x]`` one has ``deta_v/dt = G x / 2`` and, exactly,
``eta_v'' = G x' / 2 - eta_v |x|^2 / 4``. The linearising torques (seed eq. 2.1)
choose ``x'_des = 2 G^-1 (u* + eta_v |x|^2 / 4)`` and ``u = K x x - (A - J) x'_des``,
so that the closed loop is ``eta_v'' = u* + v*`` with ``v* = G diag(1/(A-J)) v / 2``
(seed eq. 2.2). All functions accept a leading batch dimension.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from kalman_vs_infoset.numerics import integrate
from kalman_vs_infoset.numerics.integrate import renormalised
from kalman_vs_infoset.numerics.rotations import cross, quaternion_rate

Array = NDArray[np.float64]

#: State vector layout: quaternion (4, scalar last), body rates x (3), rotor rates (3).
STATE_DIM = 10
Q, X, PHI = slice(0, 4), slice(4, 7), slice(7, 10)


@dataclass(frozen=True)
class Gyrostat:
    """Asymmetric body with three rotors on its principal axes.

    Parameters
    ----------
    A_kgm2 : total principal moments of inertia of the gyrostat (rotors included).
    rotor_J_kgm2 : axial moments of inertia of the three rotors.
    """

    A_kgm2: Array
    rotor_J_kgm2: Array

    def __post_init__(self) -> None:
        a = np.array(self.A_kgm2, dtype=float)
        j = np.array(self.rotor_J_kgm2, dtype=float)
        if a.shape != (3,) or j.shape != (3,):
            raise ValueError("A_kgm2 and rotor_J_kgm2 must be 3-vectors")
        if not (np.all(np.isfinite(a)) and np.all(np.isfinite(j))):
            raise ValueError("inertias must be finite")
        if np.any(j <= 0) or np.any(a - j <= 0):
            raise ValueError("need 0 < J_i < A_i for every rotor")
        if np.any(a > np.roll(a, 1) + np.roll(a, 2)):
            raise ValueError("A_kgm2 violates the triangle inequality of principal moments")
        for arr, name in ((a, "A_kgm2"), (j, "rotor_J_kgm2")):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    @property
    def body_moments_kgm2(self) -> Array:
        """``A_i - J_i``, the coefficients of ``dx_i/dt`` in (1.1)."""
        return self.A_kgm2 - self.rotor_J_kgm2


def g_matrix(eta: Array) -> Array:
    """``G = eta4 I + [eta_v x]`` so that ``eta_v' = G x / 2``; shape (..., 3, 3)."""
    e1, e2, e3, e4 = (eta[..., i] for i in range(4))
    g = np.empty(eta.shape[:-1] + (3, 3))
    g[..., 0, 0] = g[..., 1, 1] = g[..., 2, 2] = e4
    g[..., 0, 1], g[..., 0, 2] = -e3, e2
    g[..., 1, 0], g[..., 1, 2] = e3, -e1
    g[..., 2, 0], g[..., 2, 1] = -e2, e1
    return g


def g_inverse(eta: Array) -> Array:
    """``G^-1 = (eta4^2 I + eta_v eta_v^T - eta4 [eta_v x]) / (eta4 |eta|^2)`` (seed eq. 2.1/3.1).

    Exact inverse of :func:`g_matrix` for any ``eta`` with ``eta4 != 0``.
    """
    ev, e4 = eta[..., :3], eta[..., 3]
    norm2 = np.sum(eta * eta, axis=-1)
    outer = ev[..., :, None] * ev[..., None, :]
    skew = g_matrix(np.concatenate([ev, np.zeros_like(e4)[..., None]], axis=-1))
    num = (e4**2)[..., None, None] * np.eye(3) + outer - e4[..., None, None] * skew
    return num / (e4 * norm2)[..., None, None]


def total_momentum_Nms(gyro: Gyrostat, x_radps: Array, phidot_radps: Array) -> Array:
    """Total angular momentum in body axes ``K = A x + J phidot``."""
    return gyro.A_kgm2 * x_radps + gyro.rotor_J_kgm2 * phidot_radps


def rhs(state: Array, gyro: Gyrostat, u_Nm: Array, v_Nm: Array) -> Array:
    """Right-hand side of (1.1)-(1.2) for the state ``(eta[4], x[3], phidot[3])`` (batched).

    Written column by column (no temporaries of shape (..., 3) stacked) because it is the
    hot loop of the fixed-step integrator; equal to ``(quaternion_rate(eta, x),
    (K x x - u + v)/(A - J), u/J - x')`` (checked in the tests).
    """
    e1, e2, e3, e4 = state[..., 0], state[..., 1], state[..., 2], state[..., 3]
    x1, x2, x3 = state[..., 4], state[..., 5], state[..., 6]
    a, j, b = gyro.A_kgm2, gyro.rotor_J_kgm2, gyro.body_moments_kgm2
    k1 = a[0] * x1 + j[0] * state[..., 7]
    k2 = a[1] * x2 + j[1] * state[..., 8]
    k3 = a[2] * x3 + j[2] * state[..., 9]
    f = v_Nm - u_Nm
    out = np.empty(np.broadcast_shapes(state.shape, f.shape[:-1] + (STATE_DIM,)))
    out[..., 0] = 0.5 * (e4 * x1 + e2 * x3 - e3 * x2)
    out[..., 1] = 0.5 * (e4 * x2 + e3 * x1 - e1 * x3)
    out[..., 2] = 0.5 * (e4 * x3 + e1 * x2 - e2 * x1)
    out[..., 3] = -0.5 * (e1 * x1 + e2 * x2 + e3 * x3)
    out[..., 4] = (k2 * x3 - k3 * x2 + f[..., 0]) / b[0]
    out[..., 5] = (k3 * x1 - k1 * x3 + f[..., 1]) / b[1]
    out[..., 6] = (k1 * x2 - k2 * x1 + f[..., 2]) / b[2]
    out[..., 7:10] = u_Nm / j - out[..., 4:7]
    return out


def rk4_step(gyro: Gyrostat, state: Array, u_Nm: Array, v_Nm: Array, dt_s: float) -> Array:
    """One step of the shared RK4 (:mod:`kalman_vs_infoset.numerics.integrate`) with ``u`` and ``v``
    held (zero-order hold); renormalises the quaternion."""
    return renormalised(integrate.rk4_step(rhs, state, dt_s, gyro, u_Nm, v_Nm), Q)


def eta_v_rate(eta: Array, x_radps: Array) -> Array:
    """``eta_v' = G x / 2`` (the variable ``eta'`` of the auxiliary system 2.2)."""
    return quaternion_rate(eta, x_radps)[..., :3]


def linearising_torque(
    gyro: Gyrostat, eta: Array, x_radps: Array, phidot_radps: Array, u_star: Array
) -> Array:
    """Rotor torques of seed eq. (2.1) for the auxiliary controls ``u*`` (batched).

    ``u_i = (A_j x_j + J_j phidot_j) x_k - (A_k x_k + J_k phidot_k) x_j - (A_i - J_i) x'_des,i``
    with ``x'_des = 2 G^-1 (u* + eta_v |x|^2 / 4)``. Requires ``eta4 != 0`` (turns < 180 deg).
    """
    ev = eta[..., :3]
    w2 = np.sum(x_radps * x_radps, axis=-1, keepdims=True)
    target = u_star + 0.25 * ev * w2
    xdot_des = 2.0 * np.einsum("...ij,...j->...i", g_inverse(eta), target)
    k = total_momentum_Nms(gyro, x_radps, phidot_radps)
    return cross(k, x_radps) - gyro.body_moments_kgm2 * xdot_des


def aux_disturbance_matrix(gyro: Gyrostat, eta: Array) -> Array:
    """``M = G diag(1/(A - J)) / 2`` so that ``v* = M v`` (seed eq. 2.2)."""
    return 0.5 * g_matrix(eta) / gyro.body_moments_kgm2


def aux_disturbance(gyro: Gyrostat, eta: Array, v_Nm: Array) -> Array:
    """The "disturbance" of the auxiliary system ``v* = G diag(1/(A-J)) v / 2``."""
    return np.einsum("...ij,...j->...i", aux_disturbance_matrix(gyro, eta), v_Nm)


def eta_v_accel(gyro: Gyrostat, state: Array, u_Nm: ArrayLike, v_Nm: ArrayLike) -> Array:
    """``eta_v''`` of the plant under torques ``u``, ``v``: ``G x'/2 - eta_v |x|^2/4`` (exact)."""
    state = np.asarray(state, dtype=float)
    eta, x = state[..., Q], state[..., X]
    dx = rhs(state, gyro, np.asarray(u_Nm, float), np.asarray(v_Nm, float))[..., X]
    w2 = np.sum(x * x, axis=-1, keepdims=True)
    return 0.5 * np.einsum("...ij,...j->...i", g_matrix(eta), dx) - 0.25 * eta[..., :3] * w2
