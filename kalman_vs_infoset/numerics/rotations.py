"""Quaternion and rotation numerics shared by every plant, controller and estimator.

Quaternions are scalar last, ``q = (x, y, z, w)``, body -> reference, as scipy's
``Rotation`` (used for conversions where its per-call cost does not matter); the
functions here are batched over leading axes and written in numpy because they sit
in the hot loops (``Rotation``'s object overhead dominates small batches).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
_CONJ = np.array([-1.0, -1.0, -1.0, 1.0])


def cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """``a x b`` over the last axis (cheaper than ``np.cross`` on small arrays)."""
    if a.size == 3 and b.size == 3:
        # one vector each (the closed loops' usual case): the same products in Python
        # floats, a tenth of the cost of slicing and stacking arrays of three
        x0, x1, x2 = a.ravel().tolist()
        y0, y1, y2 = b.ravel().tolist()
        out = np.array([x1 * y2 - x2 * y1, x2 * y0 - x0 * y2, x0 * y1 - x1 * y0])
        return out.reshape(a.shape if a.ndim >= b.ndim else b.shape)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def qmul(p: FloatArray, q: FloatArray) -> FloatArray:
    """Hamilton product ``p (x) q`` (scalar last), i.e. ``Rotation(p) * Rotation(q)``."""
    pv, p4 = p[..., :3], p[..., 3:4]
    qv, q4 = q[..., :3], q[..., 3:4]
    vec = p4 * qv + q4 * pv + cross(pv, qv)
    sca = p4 * q4 - np.add.reduce(pv * qv, axis=-1, keepdims=True)
    return np.concatenate([vec, sca], axis=-1)


def qinv(q: FloatArray) -> FloatArray:
    """Inverse of a unit quaternion (its conjugate)."""
    return q * _CONJ


def quaternion_rate(q: FloatArray, w_radps: FloatArray) -> FloatArray:
    """``dq/dt = 1/2 q (x) (w, 0)`` for body rates ``w``: ``2 dq_v = q4 w + q_v x w``,
    ``2 dq4 = -q_v . w`` (batched)."""
    qv, q4 = q[..., :3], q[..., 3:4]
    dqv = 0.5 * (q4 * w_radps + cross(qv, w_radps))
    dq4 = -0.5 * np.sum(qv * w_radps, axis=-1, keepdims=True)
    return np.concatenate([dqv, dq4], axis=-1)


def error_quaternion(q: ArrayLike, q_target: ArrayLike, shortest: bool = True) -> FloatArray:
    """``q_target^-1 (x) q`` (the attitude relative to the target), batched; with
    ``shortest`` the sign that makes the scalar part non-negative."""
    err = qmul(qinv(np.asarray(q_target, dtype=float)), np.asarray(q, dtype=float))
    if shortest:
        err = np.where(err[..., 3:4] < 0, -err, err)
    return err


def qexp(rotvec: ArrayLike) -> FloatArray:
    """Quaternion of a rotation vector, batched; equals ``Rotation.from_rotvec(v).as_quat()``.

    ``(sin(t/2) v/t, cos(t/2))``, ``t = |v|``, with the series ``sin(t/2)/t = 1/2 - t^2/48 +
    t^4/3840`` for ``t < 1e-3``.
    """
    v = np.asarray(rotvec, dtype=float)
    t2 = np.add.reduce(v * v, axis=-1, keepdims=True)
    t = np.sqrt(t2)
    small = t < 1e-3
    safe = np.where(small, 1.0, t)
    s = np.where(small, 0.5 - t2 / 48.0 + t2 * t2 / 3840.0, np.sin(0.5 * safe) / safe)
    return np.concatenate([s * v, np.cos(0.5 * t)], axis=-1)


def qlog(q: ArrayLike) -> FloatArray:
    """Rotation vector (angle in [0, pi]) of a unit quaternion, batched; as ``as_rotvec()``."""
    q = np.asarray(q, dtype=float)
    q = np.where(q[..., 3:4] < 0, -q, q)
    qv, q4 = q[..., :3], q[..., 3:4]
    n2 = np.add.reduce(qv * qv, axis=-1, keepdims=True)
    n = np.sqrt(n2)
    small = n < 1e-6
    # t/n with t = 2 atan2(n, q4); for small n: 2/q4 (1 - n^2 / (3 q4^2))
    scale = np.where(
        small,
        2.0 / q4 * (1.0 - n2 / (3.0 * q4 * q4)),
        2.0 * np.arctan2(n, q4) / np.where(small, 1.0, n),
    )
    return scale * qv


def qmatrix(q: ArrayLike) -> FloatArray:
    """Rotation matrices of unit quaternions (body -> reference), batched."""
    q = np.asarray(q, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
            np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
            np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def error_angle_rad(eta: ArrayLike) -> FloatArray:
    """Principal angle of an error quaternion, ``2 atan2(|eta_v|, |eta4|)``."""
    eta = np.asarray(eta, dtype=float)
    return 2.0 * np.arctan2(np.linalg.norm(eta[..., :3], axis=-1), np.abs(eta[..., 3]))
