"""LQR attitude control with the analytic Riccati solution (seed 002_97f9366df23bfd3c,
docs/models.md §2.3).

Plant (seed eq. (1)): ``J dw/dt + w x J w = u``, ``dlam/dt = 1/2 (lam0 w + lam x w)``;
linearised (eq. (2)) with ``x = (w, lam)``::

    A = [[0, 0], [E/2, 0]],   B = [J^-1; 0],   Q = diag(q_1..q_6),   R = diag(r_1..r_3)

For diagonal ``J`` and ``z_i = 1/(r_i J_i^2)`` the stabilising solution of
``A^T P + P A - P B R^-1 B^T P + Q = 0`` is ``P = [[P11, P12], [P12, P22]]`` with
diagonal blocks (seed slides "Поиск стабилизирующего решения")::

    p_i   = J_i sqrt(r_i q_{i+3})                 (P12)
    p'_i  = sqrt((p_i + q_i) / z_i)               (P11)
    p''_i = 2 z_i p'_i p_i = 2 sqrt(q_{i+3} (p_i + q_i))   (P22)

and the control ``u = -R^-1 B^T P x = -diag(sqrt(y_i J_i + q_i/r_i)) w - diag(y_i) lam``,
``y_i = sqrt(q_{i+3}/r_i)``. The seed's Lyapunov function
``V = 1/2 w^T P12^-1 Z^-1 w + 2 (1 - lam0) = sum_i J_i w_i^2 / (2 y_i) + 2 (1 - lam0)``
has ``dV/dt = -w^T P12^-1 P11 w - w1 w2 w3 C`` with
``C = (J3 - J2)/y1 + (J1 - J3)/y2 + (J2 - J1)/y3``: the gain constraint (*) is ``C = 0``
(Wie, Weiss, Arapostathis 1989), which gives global asymptotic stability of the
nonlinear loop. Non-diagonal ``J = W J_diag W^T`` with ``Q1, Q2, R`` diagonal in the
same basis: ``P = diag(W, W) P_diag diag(W, W)^T`` (seed, last slides).

On a plant with reaction wheels the command adds ``w x h`` so that the body obeys
eq. (1) exactly (``J dw/dt + w x (J w + h) = u + w x h``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from kalman_vs_infoset.estim.base import Belief
from kalman_vs_infoset.guidance.attitude.pd import error_quaternion
from kalman_vs_infoset.guidance.attitude.wheels import cross
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def _positive(a: ArrayLike, n: int, name: str) -> FloatArray:
    arr = np.asarray(a, dtype=float)
    if arr.shape != (n,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ValueError(f"{name} must be {n} positive numbers, got {arr}")
    return arr


def riccati_blocks(J_diag: ArrayLike, q: ArrayLike, r: ArrayLike) -> tuple[FloatArray, ...]:
    """Diagonals ``(p', p, p'')`` of ``P11, P12, P22`` (closed form of docs/models.md §2.3)."""
    j = _positive(J_diag, 3, "J_diag")
    q = _positive(q, 6, "q")
    r = _positive(r, 3, "r")
    z = 1.0 / (r * j**2)
    p = j * np.sqrt(r * q[3:])
    p1 = np.sqrt((p + q[:3]) / z)
    p2 = 2.0 * np.sqrt(q[3:] * (p + q[:3]))
    return p1, p, p2


def analytic_riccati(J_diag: ArrayLike, q: ArrayLike, r: ArrayLike) -> FloatArray:
    """Stabilising solution ``P`` (6x6) of the ARE for ``x = (w, lam)``, diagonal ``J``.

    Parameters
    ----------
    J_diag : sequence of 3
        Principal moments of inertia (kg m^2).
    q : sequence of 6
        Diagonal of ``Q`` (first three weigh ``w``, last three ``lam``).
    r : sequence of 3
        Diagonal of ``R``.
    """
    p1, p, p2 = riccati_blocks(J_diag, q, r)
    return np.block([[np.diag(p1), np.diag(p)], [np.diag(p), np.diag(p2)]])


def linear_model(J: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``A`` (6x6) and ``B`` (6x3) of the linearised model (2) for any SPD ``J``."""
    j = np.asarray(J, dtype=float)
    a = np.zeros((6, 6))
    a[3:, :3] = 0.5 * np.eye(3)
    b = np.vstack([np.linalg.inv(j), np.zeros((3, 3))])
    return a, b


def rate_gains(J_diag: ArrayLike, q: ArrayLike, r: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``(k_w, y)``: ``u_i = -k_w,i w_i - y_i lam_i``, ``k_w,i = sqrt(y_i J_i + q_i/r_i)``."""
    j = _positive(J_diag, 3, "J_diag")
    q = _positive(q, 6, "q")
    r = _positive(r, 3, "r")
    y = np.sqrt(q[3:] / r)
    return np.sqrt(y * j + q[:3] / r), y


def constraint_residual(J_diag: ArrayLike, y: ArrayLike) -> float:
    """``C = (J3 - J2)/y1 + (J1 - J3)/y2 + (J2 - J1)/y3``; constraint (*) is ``C = 0``."""
    j = np.asarray(J_diag, dtype=float)
    y = np.asarray(y, dtype=float)
    a = np.array([j[2] - j[1], j[0] - j[2], j[1] - j[0]])
    return float(np.sum(a / y))


def complete_weights(J_diag: ArrayLike, q: ArrayLike, r: ArrayLike) -> FloatArray:
    """Return ``q`` with one attitude weight changed so that constraint (*) holds.

    With ``a = (J3 - J2, J1 - J3, J2 - J1)`` (``sum a = 0``) the constraint is
    ``sum a_i / y_i = 0``. The coefficient of the axis of intermediate inertia has
    the sign opposite to the other two, so solving for that axis,
    ``1/y_m = -(sum_{i != m} a_i / y_i) / a_m``, always gives ``y_m > 0``; then
    ``q_{m+3} = y_m^2 r_m``. Equal ``y_i`` always satisfy (*) (the classic
    ``K_lam = k I``); if two moments are equal the intermediate ``y`` equals the
    other one of the pair; for a spherical body ``q`` is returned unchanged.
    """
    j = _positive(J_diag, 3, "J_diag")
    q = _positive(q, 6, "q").copy()
    r = _positive(r, 3, "r")
    y = np.sqrt(q[3:] / r)
    a = np.array([j[2] - j[1], j[0] - j[2], j[1] - j[0]])
    m = int(np.argsort(j, kind="stable")[1])
    if abs(a[m]) <= 1e-12 * np.max(j):
        if np.all(np.abs(a) <= 1e-12 * np.max(j)):
            return q
        # two equal moments: the intermediate one equals one of the others
        others = [i for i in range(3) if i != m]
        twin = others[int(np.argmin(np.abs(j[others] - j[m])))]
        y_m = y[twin]
    else:
        rest = sum(a[i] / y[i] for i in range(3) if i != m)
        y_m = -a[m] / rest
    q[3 + m] = y_m**2 * r[m]
    return q


def principal_axes(J: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``(J_diag, W)`` with ``J = W diag(J_diag) W^T`` (``W`` orthogonal, right-handed)."""
    vals, vecs = np.linalg.eigh(np.asarray(J, dtype=float))
    if np.linalg.det(vecs) < 0:
        vecs[:, 0] = -vecs[:, 0]
    return vals, vecs


def riccati_full(J_diag: ArrayLike, W: ArrayLike, q: ArrayLike, r: ArrayLike) -> FloatArray:
    """``P`` for ``J = W diag(J_diag) W^T`` with ``Q``, ``R`` diagonal in the basis ``W``.

    ``P = diag(W, W) P_diag diag(W, W)^T`` (seed, "non-diagonal inertia" slides);
    ``q``, ``r`` are ordered like the columns of ``W``.
    """
    w = np.asarray(W, dtype=float)
    if w.shape != (3, 3) or not np.allclose(w.T @ w, np.eye(3), atol=1e-10):
        raise ValueError("W must be an orthogonal 3x3 matrix")
    t = np.kron(np.eye(2), w)
    return t @ analytic_riccati(J_diag, q, r) @ t.T


@dataclass(frozen=True)
class LQRController:
    """The LQR law of seed 002 for a rigid body with (optionally) reaction wheels.

    Parameters
    ----------
    inertia_kgm2 : array (3, 3)
        Symmetric positive definite ``J`` (any orientation of the principal axes).
    q, r : sequences of 6 and 3
        Diagonals of ``Q`` and ``R`` in the principal basis of ``J``.
    enforce_constraint : bool
        Replace the intermediate-axis attitude weight so that (*) holds.
    q_target : unit quaternion (scalar last)
        Target attitude; ``lam`` is the vector part of ``q_t^-1 (x) q``.
    shortest : bool
        Flip the error quaternion to ``lam0 >= 0``. The seed's law and its ``V``
        use ``lam`` as is (default False).
    axes : array (3, 3) or None
        ``W`` whose columns are the principal axes that ``q``, ``r`` refer to; by
        default the eigenvectors of ``J`` in ascending order of the moments.
    """

    inertia_kgm2: FloatArray
    q: tuple[float, ...]
    r: tuple[float, ...]
    enforce_constraint: bool = True
    q_target: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
    shortest: bool = False
    axes: FloatArray | None = None
    j_diag: FloatArray = field(init=False, repr=False)
    w_axes: FloatArray = field(init=False, repr=False)
    k_w: FloatArray = field(init=False, repr=False)
    y: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        j = np.array(self.inertia_kgm2, dtype=float)
        if j.shape != (3, 3) or not np.allclose(j, j.T) or np.any(np.linalg.eigvalsh(j) <= 0):
            raise ValueError("inertia_kgm2 must be a symmetric positive definite 3x3 matrix")
        if self.axes is None:
            jd, w = principal_axes(j)
        else:
            w = np.array(self.axes, dtype=float)
            if w.shape != (3, 3) or not np.allclose(w.T @ w, np.eye(3), atol=1e-10):
                raise ValueError("axes must be an orthogonal 3x3 matrix")
            jp = w.T @ j @ w
            if not np.allclose(jp, np.diag(np.diag(jp)), atol=1e-9 * np.max(np.abs(j))):
                raise ValueError("axes must be principal axes of inertia_kgm2")
            jd = np.diag(jp).copy()
        q = _positive(self.q, 6, "q")
        r = _positive(self.r, 3, "r")
        if self.enforce_constraint:
            q = complete_weights(jd, q, r)
        k_w, y = rate_gains(jd, q, r)
        items = (("inertia_kgm2", j), ("j_diag", jd), ("w_axes", w), ("k_w", k_w), ("y", y))
        for name, value in items:
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "q", tuple(float(v) for v in q))
        object.__setattr__(self, "r", tuple(float(v) for v in r))
        qt = np.asarray(self.q_target, dtype=float)
        if qt.shape != (4,) or not np.isclose(np.linalg.norm(qt), 1.0):  # as QuaternionPD
            raise ValueError("q_target must be a unit quaternion (scalar last)")
        object.__setattr__(self, "q_target", tuple(float(v) for v in qt))

    @property
    def constraint(self) -> float:
        """Residual ``C`` of constraint (*) for the gains in use."""
        return constraint_residual(self.j_diag, self.y)

    def _lam(self, x: FloatArray) -> FloatArray:
        return error_quaternion(x[..., 0:4], self.q_target, shortest=self.shortest)

    def torque(self, x: ArrayLike) -> FloatArray:
        """Command ``u + w x h`` (N m) for states ``(..., 10) = (q, w, h)``.

        ``u = -W diag(k_w) W^T w - W diag(y) W^T lam`` (seed: last slide, the
        non-diagonal case); ``w x h`` cancels the wheels' gyroscopic torque.
        """
        x = np.asarray(x, dtype=float)
        w, h = x[..., 4:7], x[..., 7:10]
        lam = self._lam(x)[..., :3]
        wa = self.w_axes
        u_p = -(self.k_w * (w @ wa) + self.y * (lam @ wa))
        return u_p @ wa.T + cross(w, h)

    def from_belief(self, belief: Belief) -> FloatArray:
        """The law at the belief's point estimate."""
        return self.torque(belief.centre())

    def lyapunov(self, x: ArrayLike) -> FloatArray:
        """Seed's ``V = 1/2 w^T P12^-1 Z^-1 w + 2 (1 - lam0)`` (= sum J_i w_i^2/(2 y_i) + ...)."""
        x = np.asarray(x, dtype=float)
        wp = x[..., 4:7] @ self.w_axes
        lam0 = self._lam(x)[..., 3]
        return 0.5 * np.sum(self.j_diag * wp**2 / self.y, axis=-1) + 2.0 * (1.0 - lam0)

    def closed_loop_decay_rate(self) -> float:
        """Slowest decay rate (1/s) of the linearised closed loop (for horizons in tests)."""
        a, b = linear_model(np.diag(self.j_diag))
        k = np.hstack([np.diag(self.k_w), np.diag(self.y)])
        return float(-np.max(np.linalg.eigvals(a - b @ k).real))
