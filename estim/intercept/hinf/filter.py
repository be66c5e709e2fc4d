"""The discrete-time H-infinity filter of D. Simon, *Optimal State Estimation* (2006), ch. 11.

Model (Simon's notation)::

    x_{k+1} = F_k x_k + w_k,    y_k = H_k x_k + v_k,    z_k = L_k x_k (to estimate)

The game-theory filter of Simon's Section 11.3 aims to bound the cost

    J = sum_k |z_k - zhat_k|^2_{S_k} / (|x_0 - xhat_0|^2_{P_0^-1}
        + sum_k (|w_k|^2_{Q_k^-1} + |v_k|^2_{R_k^-1})) < 1 / theta

for every disturbance sequence (the worst case, not an average; the condition under which
it does is discussed below). With
``Sbar_k = L_k^T S_k L_k`` the filter is (Simon 2006, Eq. (11.89) in our reading of the
first edition; the numbering is from memory and should be checked against a copy)::

    K_k       = P_k [I - theta Sbar_k P_k + H_k^T R_k^-1 H_k P_k]^-1 H_k^T R_k^-1
    xhat_{k+1} = F_k xhat_k + F_k K_k (y_k - H_k xhat_k)
    P_{k+1}   = F_k P_k [I - theta Sbar_k P_k + H_k^T R_k^-1 H_k P_k]^-1 F_k^T + Q_k

and it exists only while, at every step (stated with the filter),

    M_k = P_k^-1 - theta Sbar_k + H_k^T R_k^-1 H_k  is positive definite.

``xhat_k`` is a one-step *prediction* (it has seen ``y_0 .. y_{k-1}``). Since
``[I - theta Sbar P + H^T R^-1 H P] = M P``, the bracket terms are ``P (M P)^-1 = M^-1``:
this module computes ``K = M^-1 H^T R^-1`` and ``P+ = F M^-1 F^T + Q`` from one Cholesky
factor of ``M``, whose failure *is* the violated existence condition (raised as a
``ValueError`` naming the largest admissible ``theta`` at that step). With ``theta = 0``,
``K = (P^-1 + H^T R^-1 H)^-1 H^T R^-1 = P H^T (H P H^T + R)^-1`` and the recursion is the
Kalman filter in one-step-predictor form.

The condition ``M_k > 0`` does not by itself give ``J < 1/theta``
-----------------------------------------------------------------------
Because ``zhat_0 = L xhat_0`` uses no data, the disturbance ``x_0 - xhat_0 = e`` (with
``w = v = 0``) already gives ``J >= e^T Sbar e / e^T P_0^-1 e``, which exceeds ``1/theta``
unless ``P_0^-1 - theta Sbar >= 0``, whatever ``H^T R^-1 H`` adds to ``M_0``. The recursion
is the central *a priori* filter of Hassibi, Sayed & Kailath (1999) (their gain
``F Ptilde H^T (R + H Ptilde H^T)^-1`` with ``Ptilde = (P^-1 - theta Sbar)^-1`` equals
``F K`` above), whose existence condition is ``P_k^-1 - theta Sbar_k > 0`` at every step.
The tests compute the exact worst-case ``J`` over all disturbances: it stays under
``1/theta`` while that condition holds, reaches ``1/theta`` at its boundary, and exceeds it
beyond while ``M_k > 0`` still holds. ``condition="simon"`` (default) enforces Simon's
``M_k > 0`` (the recursion is defined); ``condition="a_priori"`` also enforces
``P_k^-1 - theta Sbar_k > 0`` (the cost bound holds).

filterpy's ``HInfinityFilter`` (filterpy 2.0.0), checked against these equations
------------------------------------------------------------------------------
Its names map as: ``gamma`` = theta, its ``Q`` = Sbar, ``W`` = Q, ``V`` = R, and its
``L`` is the bracket inverse above. Its covariance recursion is Simon's (``update``
sets ``P = F P L F^T + W``). Its state recursion is not: ``update`` computes
``x + F P L H^T V^-1 (z - H x)`` -- the gain ``F K`` *with* the ``F`` -- but does not apply
``F`` to ``x``; ``predict`` then applies ``F`` again (``x = F x + B u``). So
``update``-then-``predict`` gives ``F x + F^2 K (y - H x)`` and ``predict``-then-``update``
evaluates the residual at the wrong state; both agree with Simon only when ``F = I``
(the tests show the agreement for ``F = I`` and the discrepancy otherwise). Further:
``predict`` never propagates ``P`` (a step without a measurement leaves ``P`` unchanged),
the existence condition is not checked, ``self.K`` is never set, and ``__repr__`` prints
``dim_u`` as gamma. Hence this module's own implementation.

References
----------
D. Simon, *Optimal State Estimation: Kalman, H-infinity, and Nonlinear Approaches*,
Wiley, 2006, Section 11.3 (also D. Simon, "From here to infinity", Embedded Systems
Programming, 2001).
B. Hassibi, A. H. Sayed & T. Kailath, *Indefinite-Quadratic Estimation and Control*,
SIAM, 1999 (the a priori and a posteriori H-infinity filters and their conditions).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import cho_solve, eigh

__all__ = ["HInfinityEstimate", "HInfinityModel", "hinf_filter", "hinf_step"]

FloatArray = NDArray[np.float64]


def _mat(m: ArrayLike, shape: tuple[int, int], name: str) -> FloatArray:
    a = np.array(m, dtype=float).reshape(shape) if np.ndim(m) == 0 else np.array(m, dtype=float)
    if a.shape != shape or not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be a finite {shape} array, got {a.shape}")
    a.setflags(write=False)
    return a


def _sym_pd(m: FloatArray, name: str, semi: bool) -> None:
    if not np.allclose(m, m.T, rtol=1e-10, atol=1e-12 * max(1.0, np.abs(m).max())):
        raise ValueError(f"{name} must be symmetric")
    lam = np.linalg.eigvalsh(m)
    if lam[0] < 0 or (not semi and lam[0] <= 0):
        raise ValueError(f"{name} must be positive {'semi' if semi else ''}definite")


@dataclass(frozen=True, eq=False)
class HInfinityModel:
    """``x+ = F x + w``, ``y = H x + v``, ``z = L x``; weights ``Q``, ``R``, ``S``; bound ``theta``.

    ``L`` and ``S`` default to the identity (estimate the whole state, equally weighted).
    ``Q`` is positive semidefinite, ``R`` positive definite, ``S`` positive semidefinite,
    ``theta >= 0``. ``condition``: ``"simon"`` checks ``P^-1 - theta Sbar + H^T R^-1 H > 0``
    at each step, ``"a_priori"`` also ``P^-1 - theta Sbar > 0`` (see the module).
    Immutable; a time-varying system is a sequence of models.
    """

    F: FloatArray
    H: FloatArray
    Q: FloatArray
    R: FloatArray
    theta: float
    L: FloatArray | None = None
    S: FloatArray | None = None
    condition: Literal["simon", "a_priori"] = "simon"
    r_inv: FloatArray = field(init=False, repr=False)
    s_bar: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        f = np.atleast_2d(np.array(self.F, dtype=float))
        n = f.shape[0]
        h = np.atleast_2d(np.array(self.H, dtype=float))
        p = h.shape[0]
        f, h = _mat(f, (n, n), "F"), _mat(h, (p, n), "H")
        q, r = _mat(self.Q, (n, n), "Q"), _mat(self.R, (p, p), "R")
        lm = np.eye(n) if self.L is None else np.atleast_2d(np.array(self.L, dtype=float))
        lm = _mat(lm, (lm.shape[0], n), "L")
        s = np.eye(lm.shape[0]) if self.S is None else self.S
        s = _mat(s, (lm.shape[0], lm.shape[0]), "S")
        _sym_pd(q, "Q", semi=True)
        _sym_pd(r, "R", semi=False)
        _sym_pd(s, "S", semi=True)
        if self.condition not in ("simon", "a_priori"):
            raise ValueError(f"unknown condition {self.condition!r}")
        if not (np.isfinite(self.theta) and self.theta >= 0):
            raise ValueError(f"theta must be finite and >= 0, got {self.theta}")
        r_inv, s_bar = np.linalg.inv(r), lm.T @ s @ lm
        for name, value in (("F", f), ("H", h), ("Q", q), ("R", r), ("L", lm), ("S", s)):
            object.__setattr__(self, name, value)
        object.__setattr__(self, "theta", float(self.theta))
        object.__setattr__(self, "r_inv", _mat(0.5 * (r_inv + r_inv.T), (p, p), "R^-1"))
        object.__setattr__(self, "s_bar", _mat(0.5 * (s_bar + s_bar.T), (n, n), "Sbar"))

    @property
    def dim(self) -> int:
        return self.F.shape[0]


@dataclass(frozen=True, eq=False)
class HInfinityEstimate:
    """The prediction ``xhat_k`` and the Riccati matrix ``P_k`` (positive definite)."""

    x: FloatArray
    P: FloatArray

    def __post_init__(self) -> None:
        x = np.array(self.x, dtype=float).reshape(-1)
        p = _mat(self.P, (x.size, x.size), "P")
        if not np.all(np.isfinite(x)):
            raise ValueError("x must be finite")
        _sym_pd(p, "P", semi=False)
        x.setflags(write=False)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "P", p)

    @classmethod
    def _make(cls, x: FloatArray, p: FloatArray) -> HInfinityEstimate:
        """Internal constructor for the filter's own outputs (no checks: ``P+ = F M^-1 F^T
        + Q`` is positive semidefinite; a singular one is refused by the next step)."""
        obj = object.__new__(cls)
        x.setflags(write=False)
        p.setflags(write=False)
        object.__setattr__(obj, "x", x)
        object.__setattr__(obj, "P", p)
        return obj

    def estimate(self, model: HInfinityModel) -> FloatArray:
        """``zhat_k = L xhat_k``."""
        assert model.L is not None  # HInfinityModel.__post_init__ fills the default
        return model.L @ self.x


def _check_pd(
    m: NDArray[np.floating], base: NDArray[np.floating], model: HInfinityModel, what: str
) -> NDArray[np.floating]:
    """Lower Cholesky factor of ``m = base - theta Sbar``, or a ``ValueError`` naming
    ``what`` and the largest admissible ``theta`` (``1 / max eig(Sbar relative to base)``)."""
    m = 0.5 * (m + m.T)
    try:
        factor = np.linalg.cholesky(m)
        if np.min(np.diag(factor)) > 1e-12 * np.sqrt(np.abs(np.diag(m)).max()):
            return factor
    except np.linalg.LinAlgError:
        pass
    mu = eigh(model.s_bar, 0.5 * (base + base.T), eigvals_only=True)[-1]
    bound = np.inf if mu <= 0 else 1.0 / mu
    raise ValueError(
        f"H-infinity existence condition violated: {what} is not positive definite for "
        f"theta = {model.theta:.6g} (this step admits theta < {bound:.6g})"
    )


def _existence_factor(p: FloatArray, model: HInfinityModel) -> NDArray[np.floating]:
    """Cholesky factor of ``M = P^-1 - theta Sbar + H^T R^-1 H`` after the checks."""
    try:
        p_inv = np.linalg.inv(p)
    except np.linalg.LinAlgError:
        raise ValueError("P must be positive definite") from None
    if model.condition == "a_priori":
        _check_pd(p_inv - model.theta * model.s_bar, p_inv, model, "P^-1 - theta Sbar")
    info = p_inv + model.H.T @ model.r_inv @ model.H
    return _check_pd(
        info - model.theta * model.s_bar, info, model, "P^-1 - theta Sbar + H^T R^-1 H"
    )


def hinf_step(
    est: HInfinityEstimate,
    y: ArrayLike,
    model: HInfinityModel,
    input_term: ArrayLike | None = None,
) -> HInfinityEstimate:
    """One step of Simon's filter: ``(xhat_k, P_k), y_k -> (xhat_{k+1}, P_{k+1})``.

    ``input_term`` is an optional known ``B u_k`` added to ``xhat_{k+1}``. Raises
    ``ValueError`` when the existence condition fails at this step.
    """
    if est.x.size != model.dim:
        raise ValueError("estimate and model dimensions differ")
    y = np.asarray(y, dtype=float).reshape(-1)
    factor = (_existence_factor(est.P, model), True)
    gain = cho_solve(factor, model.H.T @ model.r_inv, check_finite=False)  # M^-1 H^T R^-1
    m_inv_ft = cho_solve(factor, model.F.T, check_finite=False)  # M^-1 F^T
    x_next = model.F @ (est.x + gain @ (y - model.H @ est.x))
    if input_term is not None:
        x_next = x_next + np.asarray(input_term, dtype=float).reshape(-1)
    p_next = model.F @ m_inv_ft + model.Q
    return HInfinityEstimate._make(x_next, 0.5 * (p_next + p_next.T))


def hinf_filter(
    model: HInfinityModel, x0: ArrayLike, p0: ArrayLike, ys: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Run :func:`hinf_step` over the rows of ``ys``; returns the predictions
    ``xhat_0 .. xhat_N`` (shape (N+1, n)) and ``P_0 .. P_N`` (shape (N+1, n, n))."""
    est = HInfinityEstimate(np.asarray(x0, dtype=float), np.asarray(p0, dtype=float))
    xs, ps = [est.x], [est.P]
    for y in np.atleast_2d(np.asarray(ys, dtype=float).T).T:
        est = hinf_step(est, y, model)
        xs.append(est.x)
        ps.append(est.P)
    return np.array(xs), np.array(ps)
