"""Energy-saving discrete attitude control (seed 000, Petrishchev 2017; docs/models.md §2.1).

Given system, seed eqs. (3.9)-(3.11), state ``X = (phi1, phi2, phi3, w1, w2, w3)``::

    X_{i+1} = A_i X_i + B_i U_i
    A_i = [[E, dt E], [0, E + dt F]]
    B_i = [[(dt^2/2) J^-1], [(dt E + (dt^2/2) F) J^-1]]

with ``F = J^-1 [K x]``, ``K = J w + K_G`` the total angular momentum. Derivation
(the seed's (3.8) is garbled): (3.5) ``dw/dt = -J^-1 (w x K) + J^-1 M`` and
``-w x K = K x w = [K x] w``; hence ``F = J^-1 [K x]`` whose first row is
``(m12 k3 - m13 k2, m13 k1 - m11 k3, m11 k2 - m12 k1)`` -- the seed's row with the
dropped ``k2`` restored and the stray ``k2`` removed.

Auxiliary system, seed (1.2), (4.6)::

    xi_{i+1} = C_i xi_i + D_i U_i,  D_i = -B_i,  xi_0 = X_0
    C_i = [[E, dt E], [-f1_i E, (1 - f2_i) E]]
    f1_i = 2.5e-5 (1 + 5e-3 i),  f2_i = 0.01 (1 + 2.5e-4 i)

Control law (1.3), gain (2.4), covariance update (2.5), stability condition (2.6)::

    U_{i+1} = U_i + P_{i+1} (X~_{i+1} - xi_{i+1}),   X~ = X + eps, eps ~ N(0, K_eps)
    P_{i+1} = -K_U,i (B-D)^T [A K_X A^T + C K_xi C^T + (B-D) K_U,i (B-D)^T + K_eps]^-1
    K_U,i+1 = [P_{i+1} (B-D) + E] K_U,i
    Tr[P_{i+1} (B-D) K_U,i] < 0

``K_X`` and ``K_xi`` are held constant, as in the seed. Note that with ``D = -B`` the
difference ``X_{i+1} - xi_{i+1} = A X_i - C_i xi_i + 2 B U_i``: the law acts through
``B - D = 2B``, and the torque that keeps ``X`` on ``xi`` is half of ``J`` times the
auxiliary acceleration -- which is what the seed's ``U_0 = (-5.4, -1.1, -2.4)`` N m is
(tests check it), a confirmation of this reading of ``J`` and ``D``. Angles are in radians, so
``K_X = diag(1, 1, 1, 0.01, 0.01, 0.01)`` means 1 rad^2 and 0.01 (rad/s)^2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

#: Seed 000, section 4: the printed "22 147 144 321 / 0 10 213 752 / 0 0 24 497" is the
#: upper triangle with a space as thousands separator (N m s^2).
RESURS_P_INERTIA_DIAG = (22147.0, 10213.0, 24497.0)
RESURS_P_INERTIA_PRODUCTS = (144.0, 321.0, 752.0)  # |J12|, |J13|, |J23|
#: Named readings of the products' lost signs: the signs of the tensor entries
#: ``(J12, J13, J23)``. ``standard``: the printed numbers are the products of inertia
#: ``I_jk = integral x_j x_k dm`` and the tensor is ``J_jk = -I_jk`` off the diagonal (the
#: usual convention of rigid-body mechanics); ``entries``: the printed numbers are the
#: tensor's entries themselves (all "+").
INERTIA_SIGN_READINGS: dict[str, tuple[int, int, int]] = {
    "standard": (-1, -1, -1),
    "entries": (1, 1, 1),
}


def inertia_product_signs(reading: str | ArrayLike = "standard") -> tuple[int, int, int]:
    """Signs of the tensor entries ``(J12, J13, J23)`` of a reading.

    Parameters
    ----------
    reading : str or (3,) array_like
        A name of :data:`INERTIA_SIGN_READINGS` or three signs, each +1 or -1.

    Returns
    -------
    tuple of int
    """
    if isinstance(reading, str):
        if reading not in INERTIA_SIGN_READINGS:
            raise ValueError(f"inertia sign reading must be one of {list(INERTIA_SIGN_READINGS)}")
        return INERTIA_SIGN_READINGS[reading]
    signs = np.asarray(reading, dtype=float)
    if signs.shape != (3,) or not np.all(np.isin(signs, (-1.0, 1.0))):
        raise ValueError("product signs must be three values, each +1 or -1")
    return tuple(int(v) for v in signs)  # type: ignore[return-value]


def resurs_p_inertia(products_sign: str | ArrayLike = "standard") -> NDArray[np.float64]:
    """Resurs-P inertia tensor (N m s^2) under a reading of the products' signs.

    The seed's print does not preserve the signs of the products of inertia (section 4).
    ``products_sign`` is ``"standard"`` (``J_jk = -I_jk``, all "-"), ``"entries"`` (the
    printed numbers are the entries, all "+") or three signs ``(s12, s13, s23)`` of the
    entries; see :func:`inertia_product_signs`.
    """
    signs = inertia_product_signs(products_sign)
    j = np.diag(RESURS_P_INERTIA_DIAG)
    for (r, c), p, s in zip(
        ((0, 1), (0, 2), (1, 2)), RESURS_P_INERTIA_PRODUCTS, signs, strict=True
    ):
        j[r, c] = j[c, r] = s * p
    return j


def skew(v: ArrayLike) -> NDArray[np.float64]:
    """Cross-product matrix ``[v x]`` with ``[v x] u = v x u``."""
    x, y, z = np.asarray(v, dtype=float)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def given_system(
    inertia_inv: NDArray[np.float64], momentum_Nms: ArrayLike, dt_s: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(A_i, B_i)`` of seed eqs. (3.10), (3.11) with ``F = J^-1 [K x]``."""
    f = inertia_inv @ skew(momentum_Nms)
    eye = np.eye(3)
    a = np.zeros((6, 6))
    a[:3, :3] = eye
    a[:3, 3:] = dt_s * eye
    a[3:, 3:] = eye + dt_s * f
    b = np.vstack([0.5 * dt_s**2 * inertia_inv, (dt_s * eye + 0.5 * dt_s**2 * f) @ inertia_inv])
    return a, b


@dataclass(frozen=True)
class EnergySavingConfig:
    """Parameters of the energy-saving law (seed 000, section 4; docs/models.md §2.1).

    Covariances are given by their diagonals (radians, rad/s, N m), non-negative.
    In each of the six components ``state_var`` (``K_X``) or ``meas_var`` (``K_eps``)
    must be positive: the gain (2.4) inverts ``S = A K_X A^T + C K_xi C^T +
    (B-D) K_U (B-D)^T + K_eps``, and a component zero in both leaves ``S`` singular
    (the control term has rank 3 and ``C_i`` may be singular, so neither can stand in).
    """

    dt_s: float = 0.1
    f1_0: float = 2.5e-5
    f1_growth: float = 5e-3
    f2_0: float = 0.01
    f2_growth: float = 2.5e-4
    state_var: tuple[float, ...] = (1.0, 1.0, 1.0, 0.01, 0.01, 0.01)  # K_X
    aux_var: tuple[float, ...] = (1.0, 1.0, 1.0, 0.01, 0.01, 0.01)  # K_xi
    meas_var: tuple[float, ...] = (3e-4**2,) * 3 + (7e-6**2,) * 3  # K_eps
    control_var0_N2m2: float = 5000.0**2  # K_U0 = (5 kN m)^2 E
    u0_Nm: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        if not (self.dt_s > 0 and np.isfinite(self.dt_s)):
            raise ValueError("dt_s must be positive and finite")
        gains = (self.f1_0, self.f1_growth, self.f2_0, self.f2_growth)
        if not np.isfinite(gains).all():
            raise ValueError("f1_0, f1_growth, f2_0 and f2_growth must be finite")
        for name in ("state_var", "aux_var", "meas_var"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (6,) or np.any(v < 0) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be six non-negative numbers")
        # S >= A K_X A^T + K_eps, A = [[E, dt E], [0, G]], G = E + dt J^-1 [K x]. With a
        # positive K_X or K_eps in each component, a null vector of that sum has a zero
        # angle part, and a rate part zero where K_eps > 0 and zero under G^T where
        # K_X > 0: none but 0 while dt |J^-1 K| << 1 (G near E), i.e. whenever the
        # discrete model resolves the motion. A component zero in both is left to the
        # control term (rank 3) and C_i K_xi C_i^T (C_i singular where f2_i = 1 + dt f1_i)
        both_zero = (np.asarray(self.state_var) == 0) & (np.asarray(self.meas_var) == 0)
        if both_zero.any():
            which = np.flatnonzero(both_zero).tolist()
            raise ValueError(
                "state_var or meas_var must be positive in each component (else the gain's "
                f"matrix is singular); both are zero in components {which}"
            )
        if not (self.control_var0_N2m2 > 0 and np.isfinite(self.control_var0_N2m2)):
            raise ValueError("control_var0_N2m2 must be positive and finite")
        u0 = np.asarray(self.u0_Nm, dtype=float)
        if u0.shape != (3,) or not np.isfinite(u0).all():
            raise ValueError("u0_Nm must be three finite numbers")
        if self.f1_0 < 0 or self.f2_0 < 0:
            raise ValueError("f1_0 and f2_0 must be non-negative")

    def f1(self, i: int) -> float:
        """``f1_i = 2.5e-5 (1 + 5e-3 i)`` (seed, after eq. 4.6)."""
        return self.f1_0 * (1.0 + self.f1_growth * i)

    def f2(self, i: int) -> float:
        """``f2_i = 0.01 (1 + 2.5e-4 i)`` (seed, after eq. 4.6)."""
        return self.f2_0 * (1.0 + self.f2_growth * i)

    def aux_matrix(self, i: int) -> NDArray[np.float64]:
        """``C_i`` of seed eq. (4.6)."""
        eye = np.eye(3)
        c = np.zeros((6, 6))
        c[:3, :3] = eye
        c[:3, 3:] = self.dt_s * eye
        c[3:, :3] = -self.f1(i) * eye
        c[3:, 3:] = (1.0 - self.f2(i)) * eye
        return c


@dataclass(frozen=True)
class EnergySavingState:
    """Controller memory at step i: auxiliary state, control, control covariance."""

    step: int
    xi: NDArray[np.float64]
    u_Nm: NDArray[np.float64]
    k_u: NDArray[np.float64]

    @classmethod
    def initial(cls, config: EnergySavingConfig, x0: ArrayLike) -> EnergySavingState:
        """``xi_0 = X_0``, ``U_0`` from the config, ``K_U0 = control_var0 E``."""
        return cls(
            0,
            np.array(x0, dtype=float),
            np.array(config.u0_Nm, dtype=float),
            config.control_var0_N2m2 * np.eye(3),
        )


@dataclass(frozen=True)
class StepDiagnostics:
    """Per-step quantities the seed plots or checks."""

    gain: NDArray[np.float64]  # P_{i+1}, 3 x 6
    trace_increment: float  # Tr[P_{i+1} (B_i - D_i) K_U,i], must be < 0 (eq. 2.6)
    trace_k_u: float  # Tr K_U,i+1


class EnergySavingController:
    """The energy-saving law of seed 000 (eqs. 1.2, 1.3, 2.4-2.6); configuration only.

    ``update(state, a_i, b_i, x_meas_next)`` advances from step i to i+1 after ``U_i``
    has acted on the plant: it propagates the auxiliary system with ``D_i = -B_i``,
    computes ``P_{i+1}``, ``K_U,i+1`` and ``U_{i+1}``.
    """

    def __init__(self, config: EnergySavingConfig) -> None:
        self.config = config
        self._k_x = np.diag(config.state_var)
        self._k_xi = np.diag(config.aux_var)
        self._k_eps = np.diag(config.meas_var)

    def update(
        self,
        state: EnergySavingState,
        a_i: NDArray[np.float64],
        b_i: NDArray[np.float64],
        x_meas_next: ArrayLike,
    ) -> tuple[EnergySavingState, StepDiagnostics]:
        """One step of seed eqs. (1.2), (2.4), (2.5), (1.3); returns the new state."""
        c_i = self.config.aux_matrix(state.step)
        d_i = -b_i
        xi_next = c_i @ state.xi + d_i @ state.u_Nm
        bd = b_i - d_i
        k_u = state.k_u
        innov_cov = (
            a_i @ self._k_x @ a_i.T + c_i @ self._k_xi @ c_i.T + bd @ k_u @ bd.T + self._k_eps
        )
        # P = -K_U bd^T S^-1  <=>  S P^T = -bd K_U  (S symmetric)
        gain = -np.linalg.solve(innov_cov, bd @ k_u).T
        delta = gain @ bd @ k_u
        k_u_next = delta + k_u
        k_u_next = 0.5 * (k_u_next + k_u_next.T)
        u_next = state.u_Nm + gain @ (np.asarray(x_meas_next, dtype=float) - xi_next)
        new_state = EnergySavingState(state.step + 1, xi_next, u_next, k_u_next)
        # float64 throughout (numpy's stubs type solve() as any floating)
        gain64 = cast(NDArray[np.float64], gain)
        diag = StepDiagnostics(gain64, float(np.trace(delta)), float(np.trace(k_u_next)))
        return new_state, diag
