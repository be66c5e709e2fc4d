"""Game law of the auxiliary linear system ``eta_i'' = u*_i + v*_i`` (seed 004, docs/models.md
§2.4).

* Switching function (seed 2.7): ``psi_i = -eta_i - eta'_i |eta'_i| / (2 (1 - rho_i) a*_i)``,
  ``u*_i = a*_i sign psi_i`` off the curve, sliding along ``psi_i = 0`` to the origin.
* Disturbance level (seed 2.3, Cauchy-Schwarz): ``|v*_i| <= beta* =
  1/2 ||(beta_1/(A_1-J_1), beta_2/(A_2-J_2), beta_3/(A_3-J_3))||`` and the design needs
  ``beta* <= rho_i a*_i`` with ``0 < rho_i < 1`` (seed 2.5).
* Guaranteed time (seed 2.8): ``tau = max_i 2 sqrt(|eta_i0| / ((1 - rho_i) a*_i))``.
* The a* iteration of seed section 3: pick a*, bound ``|u_i|`` of (2.1) over the states
  reachable by the auxiliary system (and the rotor rates they imply), adjust a*.

Sliding-mode implementation (stated, as the issue asks): **exact discrete switching**.
The law is sampled every ``h`` seconds; at each sample ``u*_i`` is the value in
``[-a*_i, a*_i]`` that puts the state on the switching curve ``psi_i = 0`` at the next
sample even if the disturbance is the worst one (``rho_i a*_i`` pushing towards
overshoot), clipped to the bound. Far from the curve the clip is active and the law is
the bang-bang ``a*_i sign psi_i``; on the curve it is the discrete equivalent control
(the Filippov average of the infinitely fast switching), so it does not chatter. Only in
a small zone around the target, where the curve is vertical and its one-step landing
would be a high-gain (noise-amplifying, marginally stable) law, a linear law that fits
within ``a*`` takes over (a terminal boundary layer). ``mode="sign"`` gives the raw
``a* sign psi`` for comparison.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from kalman_vs_infoset.guidance.attitude.gyrostat import Gyrostat, aux_disturbance_matrix
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]


def beta_star(gyro: Gyrostat, beta_Nm: ArrayLike) -> float:
    """Seed eq. (2.3): ``beta* = 1/2 sqrt(sum_i (beta_i / (A_i - J_i))^2)`` (same for all i)."""
    b = np.asarray(beta_Nm, dtype=float) / gyro.body_moments_kgm2
    return 0.5 * float(np.linalg.norm(b))


def switching_function(eta: Array, deta: Array, a_star: Array, rho: Array) -> Array:
    """Seed (2.7): ``psi = -eta - eta' |eta'| / (2 (1 - rho) a*)`` per channel."""
    return -eta - deta * np.abs(deta) / (2.0 * (1.0 - rho) * a_star)


def guaranteed_time_s(eta0_v: ArrayLike, a_star: ArrayLike, rho: ArrayLike) -> float:
    """Seed (2.8): ``tau = max_i 2 sqrt(|eta_i0| / ((1 - rho_i) a*_i))`` (rest to rest)."""
    e0 = np.abs(np.asarray(eta0_v, dtype=float))
    b = (1.0 - np.asarray(rho, dtype=float)) * np.asarray(a_star, dtype=float)
    return float(np.max(2.0 * np.sqrt(e0 / b)))


def time_to_go_s(eta: Array, deta: Array, decel: Array) -> Array:
    """Minimum time of ``eta'' = w, |w| <= decel`` to the origin: the game's guaranteed
    time-to-go when ``decel = (1 - rho) a*`` (the value function of seed section 2).

    ``T = (-s eta' + 2 sqrt(eta'^2 / 2 - s decel eta)) / decel`` with ``s = sign psi``.
    """
    s = np.where(switching_function(eta, deta, decel, np.zeros_like(decel)) >= 0, 1.0, -1.0)
    rad = np.maximum(0.5 * deta**2 - s * decel * eta, 0.0)
    return (-s * deta + 2.0 * np.sqrt(rad)) / decel


@dataclass(frozen=True)
class GameLaw:
    """The auxiliary bang-bang / sliding law for the three channels.

    Parameters
    ----------
    a_star : auxiliary control levels ``a*_i`` (1/s^2), ``|u*_i| <= a*_i``.
    rho : ratios ``0 < rho_i < 1`` with ``beta* <= rho_i a*_i``.
    period_s : sampling period ``h`` of the discrete switching.
    mode : ``"discrete"`` (exact discrete switching, default) or ``"sign"``.
    """

    a_star: Array
    rho: Array
    period_s: float
    mode: str = "discrete"
    decel: Array = field(init=False, repr=False)

    def __post_init__(self) -> None:
        a = np.array(self.a_star, dtype=float)
        r = np.array(self.rho, dtype=float)
        if a.shape != (3,) or r.shape != (3,) or np.any(a <= 0) or not np.all(np.isfinite(a)):
            raise ValueError("a_star must be three positive numbers")
        if r.shape != (3,) or not np.all((r > 0) & (r < 1)):  # NaN fails both
            raise ValueError("rho must be three numbers in (0, 1)")
        if not (self.period_s > 0 and np.isfinite(self.period_s)):
            raise ValueError("period_s must be positive and finite")
        if self.mode not in ("discrete", "sign"):
            raise ValueError("mode must be 'discrete' or 'sign'")
        d = (1.0 - r) * a
        for arr, name in ((a, "a_star"), (r, "rho"), (d, "decel")):
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)

    def psi(self, eta: Array, deta: Array) -> Array:
        return switching_function(eta, deta, self.a_star, self.rho)

    def u_star(self, eta: Array, deta: Array) -> Array:
        """Auxiliary controls ``u*`` for channel states ``eta_v``, ``eta_v'`` (batched).

        Discrete mode, per channel (``b = (1 - rho) a*``, ``d = rho a*`` the design's worst
        ``|v*|``):

        1. landing: with ``C = eta + eta' h / 2`` the next-sample velocity on the curve
           ``psi = 0`` is ``w = -sign(C) (sqrt(b^2 h^2 + 8 b |C|) - b h) / 2`` and the
           nominal acceleration that lands there is ``n = (w - eta') / h``;
        2. robust landing: the worst disturbance pushes along the velocity (towards
           overshoot), so ``u* = clip(n - d sat(eta' / (4 d h)), -a*, a*)``; against
           ``v* = -rho a* sign u*`` the state then stays exactly on the curve with
           ``u* = a*``, which is what the continuous game needs to arrive at ``tau``;
        3. terminal zone: the curve is vertical at the origin (infinite gain), so where
           the linear law ``-omega^2 eta - 2 omega eta'`` is admissible (``<= a*``) it is
           used instead (a boundary layer around the target only, ``omega = 0.1/h``).
        """
        if self.mode == "sign":
            return self.a_star * np.sign(self.psi(eta, deta))
        h, b, a = self.period_s, self.decel, self.a_star
        d = self.rho * a
        c = eta + 0.5 * h * deta
        w = -np.sign(c) * 0.5 * (np.sqrt((b * h) ** 2 + 8.0 * b * np.abs(c)) - b * h)
        n = (w - deta) / h
        u_curve = np.clip(n - d * np.clip(deta / (4.0 * d * h), -1.0, 1.0), -a, a)
        om = self.terminal_omega_radps
        u_lin = -(om**2) * eta - 2.0 * om * deta
        return np.where(np.abs(u_lin) <= a, u_lin, u_curve)

    @property
    def terminal_omega_radps(self) -> float:
        """Bandwidth of the terminal linear zone, ``0.1 / h``."""
        return 0.1 / self.period_s

    def guaranteed_time_s(self, eta0_v: ArrayLike) -> float:
        return guaranteed_time_s(eta0_v, self.a_star, self.rho)


# --------------------------------------------------------------------------- a* design


def reachable_torque_bound_Nm(
    gyro: Gyrostat, eta0_v: ArrayLike, a_star: ArrayLike, rho: ArrayLike, beta_Nm: ArrayLike
) -> Array:
    """Upper bound of ``|u_i|`` of (2.1) over the states reachable in the auxiliary game.

    Rest-to-rest from ``eta_v0`` (``eta40 > 0``): each channel moves monotonically to 0, so
    ``|eta_i| <= e_i = |eta_i0|``, ``eta4 >= eta40``, and its speed peaks at the switching
    curve, ``|eta'_i| <= sqrt((1 - rho_i^2) a*_i e_i)``. By (3.1) ``|x| <= 2 |eta_v'| / eta40``;
    the total momentum obeys ``K' + x x K = v`` with ``K(0) = 0``, so ``|K| <= ||beta|| tau``.
    Then ``|u_i| <= |K| |x| + (A_i - J_i) |x'_des,i|`` with ``x'_des`` bounded entrywise
    through ``|G^-1_ii| <= max(1 + e_i^2, eta40 + e_i^2/eta40)``,
    ``|G^-1_ij| <= e_i e_j / eta40 + e_k``.
    """
    e = np.abs(np.asarray(eta0_v, dtype=float))
    a = np.asarray(a_star, dtype=float)
    r = np.asarray(rho, dtype=float)
    e40 = float(np.sqrt(max(1.0 - e @ e, 0.0)))
    if e40 <= 0:
        raise ValueError("the design needs eta4 != 0 (turns below 180 deg)")
    deta = np.sqrt((1.0 - r**2) * a * e)
    x_max = 2.0 * float(np.linalg.norm(deta)) / e40
    tau = guaranteed_time_s(e, a, r)
    k_max = float(np.linalg.norm(np.asarray(beta_Nm, dtype=float))) * tau
    ginv = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            if i == j:
                ginv[i, i] = max(1.0 + e[i] ** 2, e40 + e[i] ** 2 / e40)
            else:
                k = 3 - i - j
                ginv[i, j] = e[i] * e[j] / e40 + e[k]
    xdot = 2.0 * ginv @ a + 0.5 * e * x_max**2 / e40
    return k_max * x_max + gyro.body_moments_kgm2 * xdot


@dataclass(frozen=True)
class Design:
    """Outcome of the a* iteration (seed section 3)."""

    a_star: Array
    rho: Array
    beta_star: float
    tau_s: float
    torque_bound_Nm: Array
    iterations: tuple[tuple[float, float], ...]  # (scale s, max_i bound_i / alpha_i)


def design_a_star(
    gyro: Gyrostat,
    eta0_v: ArrayLike,
    alpha_Nm: ArrayLike,
    beta_Nm: ArrayLike,
    rho: ArrayLike,
    n_bisect: int = 40,
) -> Design:
    """The a* iteration of seed section 3 (steps 2-4), as a bisection on one scale ``s``.

    ``a*_i(s) = max(s |eta_i0| / (1 - rho_i), beta* / rho_i)``: the first term makes every
    channel arrive at ``tau = 2 / sqrt(s)``; the floor keeps ``beta* <= rho_i a*_i`` (2.5).
    Step 4 checks ``bound_i <= alpha_i`` with :func:`reachable_torque_bound_Nm`; ``s`` is
    increased while there is reserve and decreased when the check fails.

    Raises
    ------
    ValueError
        if even the floor ``a* = beta*/rho`` violates the torque limits (beta too large).
    """
    e = np.abs(np.asarray(eta0_v, dtype=float))
    alpha = np.asarray(alpha_Nm, dtype=float)
    r = np.asarray(rho, dtype=float)
    bstar = beta_star(gyro, beta_Nm)
    floor = bstar / r

    def a_of(s: float) -> Array:
        return np.maximum(s * e / (1.0 - r), floor)

    def ratio(s: float) -> float:
        return float(np.max(reachable_torque_bound_Nm(gyro, e, a_of(s), r, beta_Nm) / alpha))

    iterations: list[tuple[float, float]] = []
    r0 = ratio(0.0)
    iterations.append((0.0, r0))
    if r0 > 1.0:
        # the bound grows with the disturbance (the floor) and with the initial error
        # (the rates the turn reaches): name both
        raise ValueError(
            f"disturbance bound too large for this turn: even with the least a* = "
            f"beta*/rho the rotor torques may reach {r0:.3g} x alpha (beta* = {bstar:.3g} "
            "1/s^2); a smaller disturbance bound or initial angle, larger torque limits "
            "alpha or a larger rho"
        )
    if not np.any(e > 0):
        a = a_of(0.0)
        bound = reachable_torque_bound_Nm(gyro, e, a, r, beta_Nm)
        return Design(a, r, bstar, 0.0, bound, tuple(iterations))
    lo, hi = 0.0, 1e-6
    while (rh := ratio(hi)) <= 1.0:
        iterations.append((hi, rh))
        lo, hi = hi, hi * 4.0
    iterations.append((hi, rh))
    for _ in range(n_bisect):
        mid = 0.5 * (lo + hi) if lo == 0 else float(np.sqrt(lo * hi))
        rm = ratio(mid)
        iterations.append((mid, rm))
        lo, hi = (mid, hi) if rm <= 1.0 else (lo, mid)
    a = a_of(lo)
    bound = reachable_torque_bound_Nm(gyro, e, a, r, beta_Nm)
    return Design(a, r, bstar, guaranteed_time_s(e, a, r), bound, tuple(iterations))


# --------------------------------------------------------------------------- disturbances


def adversarial_disturbance_Nm(
    gyro: Gyrostat,
    eta: Array,
    deta: Array,
    u_star: Array,
    law: GameLaw,
    beta_Nm: ArrayLike,
) -> Array:
    """The admissible ``v`` (a vertex of the box ``|v_i| <= beta_i``) that most delays arrival.

    For each of the 8 vertices the auxiliary state is predicted one sample ahead
    (``eta'' = u* + M v``, ``M = G diag(1/(A-J))/2``) and scored by the guaranteed
    time-to-go :func:`time_to_go_s`; the score is ``max_i T_i + 0.01 sum_i T_i`` (delay the
    last channel first). Batched over a leading axis of ``eta`` (shape (R, 4)).
    """
    beta = np.asarray(beta_Nm, dtype=float)
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], float)
    verts = signs * beta  # (8, 3)
    m = aux_disturbance_matrix(gyro, eta)  # (R, 3, 3)
    vstar = np.einsum("rij,kj->rki", m, verts)  # (R, 8, 3)
    acc = u_star[:, None, :] + vstar
    h = law.period_s
    ev = eta[:, None, :3] + deta[:, None, :] * h + 0.5 * acc * h * h
    dv = deta[:, None, :] + acc * h
    t = time_to_go_s(ev, dv, law.decel)
    score = t.max(axis=-1) + 0.01 * t.sum(axis=-1)
    return verts[np.argmax(score, axis=-1)]
