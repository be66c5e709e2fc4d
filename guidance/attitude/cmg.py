"""Six gyrodines (control moment gyros) in three collinear pairs, Resurs-P layout.

Seed 000 (Petrishchev 2017), section 4, docs/models.md §2.1.

Geometry. The instrument frame of gyrodine k is reached from the body frame by two
rotations: about body ``y`` by the pair azimuth ``psi_k`` (0, 120, 240 deg), then about
the new ``z`` by the cone half-angle ``alpha`` (30 deg). Its ``y`` axis is the
precession (gimbal) axis, which therefore lies on a cone of half-angle ``alpha``
about body ``y``. With ``x_P, z_P`` the instrument axes in body coordinates::

    x_P = (cos a cos psi,  sin a, -cos a sin psi)
    z_P = (sin psi,        0,      cos psi)

Torque on the body, seed eq. (4.1)::

    M_k = S_k(beta_k) dbeta_k/dt,
    S_k = H (-(sin b cos psi cos a + cos b sin psi),
             -sin b sin a,
             sin b sin psi cos a - cos b cos psi)
        = -H (sin b x_P + cos b z_P)

Reading followed: the seed's (3.3) says the body torque is minus the rate of the
gyro momentum, so (4.1) fixes the rotor momentum as
``h_k = H (sin b z_P - cos b x_P)`` (then ``-dh_k/dbeta = S_k``; the seed does not
print h_k itself). With the seed's beta0 = 315, 225, ... deg the six momenta cancel.

Steering, seed eq. (4.5): ``beta_dot = S^T (S S^T)^-1 M`` (pseudo-inverse). Near a
singular ``S`` we use the singularity-robust inverse of Nakamura & Hanafusa,
``S^T (S S^T + lam E)^-1`` with ``lam = lam0 (1 - m/m0)^2`` when the normalised
manipulability ``m = sqrt(det(S S^T)) / H^3`` drops below ``m0``.
Precession angles are integrated as in the seed, ``beta_{i+1} = beta_i + beta_dot dt``;
the torque delivered over the step is the exact momentum exchange
``-(h(beta_{i+1}) - h(beta_i)) / dt`` (the rate is evaluated at the mid-step angles,
so this equals the requested torque to O(dt^2)).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from kalman_vs_infoset.guidance.attitude.plant import RigidBody, attitude_rhs
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from kalman_vs_infoset.numerics.integrate import renormalised
from kalman_vs_infoset.numerics.integrate import rk4_step as rk4

#: Seed 000, section 4: initial precession angles of the six gyrodines, degrees.
RESURS_P_BETA0_DEG = (315.0, 225.0, 315.0, 225.0, 315.0, 225.0)


@dataclass(frozen=True)
class CmgCluster:
    """Three collinear pairs of gyrodines (seed 000, section 4).

    Parameters
    ----------
    rotor_momentum_Nms : rotor angular momentum H of each gyrodine (seed: 250 N m s).
    cone_half_angle_deg : alpha, half-angle of the cone of precession axes about body y.
    pair_azimuths_deg : psi of each pair (the two gyrodines of a pair share it).
    sr_threshold : m0, normalised manipulability below which the SR inverse is used.
    sr_damping : lam0, the SR damping (in units of H^2) at zero manipulability.
    """

    rotor_momentum_Nms: float = 250.0
    cone_half_angle_deg: float = 30.0
    pair_azimuths_deg: tuple[float, ...] = (0.0, 120.0, 240.0)
    sr_threshold: float = 0.05
    sr_damping: float = 0.01
    x_axes: NDArray[np.float64] = field(init=False, repr=False)
    z_axes: NDArray[np.float64] = field(init=False, repr=False)
    gimbal_axes: NDArray[np.float64] = field(init=False, repr=False)
    _trig: tuple[NDArray[np.float64], ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (self.rotor_momentum_Nms > 0 and np.isfinite(self.rotor_momentum_Nms)):
            raise ValueError("rotor_momentum_Nms must be positive and finite")
        if not 0.0 < self.cone_half_angle_deg < 90.0:
            raise ValueError("cone_half_angle_deg must be in (0, 90)")
        if len(self.pair_azimuths_deg) < 1:
            raise ValueError("pair_azimuths_deg must list at least one pair")
        if not (0.0 < self.sr_threshold < 1.0 and 0.0 < self.sr_damping < np.inf):
            raise ValueError("sr_threshold must be in (0, 1) and sr_damping positive and finite")
        if not np.isfinite(np.asarray(self.pair_azimuths_deg, dtype=float)).all():
            raise ValueError("pair_azimuths_deg must be finite")
        psi = np.repeat(np.asarray(self.pair_azimuths_deg, dtype=float), 2)
        angles = np.column_stack([psi, np.full_like(psi, self.cone_half_angle_deg)])
        # intrinsic rotations: about body y by psi, then about the new z by alpha
        frames = Rotation.from_euler("YZ", angles, degrees=True)
        for name, axis in (("x_axes", 0), ("gimbal_axes", 1), ("z_axes", 2)):
            arr = frames.apply(np.eye(3)[axis])
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        psi_rad, a_rad = np.radians(psi), np.radians(self.cone_half_angle_deg)
        trig = (np.cos(psi_rad) * np.cos(a_rad), np.sin(psi_rad), np.sin(psi_rad) * np.cos(a_rad))
        object.__setattr__(self, "_trig", (*trig, np.cos(psi_rad), np.sin(a_rad)))

    @property
    def n_gyros(self) -> int:
        return self.x_axes.shape[0]

    def _check(self, beta_rad: ArrayLike) -> NDArray[np.float64]:
        beta = np.asarray(beta_rad, dtype=float)
        if beta.shape != (self.n_gyros,):
            raise ValueError(f"beta_rad must have shape ({self.n_gyros},), got {beta.shape}")
        return beta

    def gyro_momenta_Nms(self, beta_rad: ArrayLike) -> NDArray[np.float64]:
        """Rotor momenta ``h_k = H (sin b z_P - cos b x_P)``, shape (n, 3), body axes."""
        beta = self._check(beta_rad)
        return self.rotor_momentum_Nms * (
            np.sin(beta)[:, None] * self.z_axes - np.cos(beta)[:, None] * self.x_axes
        )

    def momentum_Nms(self, beta_rad: ArrayLike) -> NDArray[np.float64]:
        """Total gyro momentum ``K_G = sum_k h_k`` (seed eq. 3.2), body axes."""
        return self.gyro_momenta_Nms(beta_rad).sum(axis=0)

    def torque_matrix(self, beta_rad: ArrayLike) -> NDArray[np.float64]:
        """S(beta), 3 x n, seed eqs. (4.1), (4.4), written out component by component."""
        return self.rotor_momentum_Nms * self._unit_torque_matrix(self._check(beta_rad))

    def _unit_torque_matrix(self, b: NDArray[np.float64]) -> NDArray[np.float64]:
        """S(beta) / H: the steering below works with it, so that no power of H under- or
        overflows (a rotor of 1e-300 N m s divided by zero)."""
        cpsi_ca, spsi, spsi_ca, cpsi, sa = self._trig
        sb, cb = np.sin(b), np.cos(b)
        out = np.empty((3, b.size))
        out[0] = -(sb * cpsi_ca + cb * spsi)
        out[1] = -sb * sa
        out[2] = sb * spsi_ca - cb * cpsi
        return out

    @staticmethod
    def _unit_manipulability(uut: NDArray[np.float64]) -> float:
        """``sqrt(det(U U^T))`` from ``U U^T``, U = S / H (= sqrt(det(S S^T)) / H^3)."""
        return float(np.sqrt(max(float(np.linalg.det(uut)), 0.0)))

    def manipulability(self, beta_rad: ArrayLike) -> float:
        """Normalised manipulability ``sqrt(det(S S^T)) / H^3`` (0 at a singular state)."""
        u = self._unit_torque_matrix(self._check(beta_rad))
        return self._unit_manipulability(u @ u.T)

    def steering_rates(
        self, beta_rad: ArrayLike, torque_Nm: ArrayLike
    ) -> tuple[NDArray[np.float64], bool]:
        """Precession rates for a torque: seed eq. (4.5), SR inverse near singularity.

        ``S^T (S S^T + lambda I)^-1 torque`` with ``lambda = d H^2 (1 - m / m_sr)^2``
        below the threshold ``m_sr`` (0 above), computed as ``U^T (U U^T + lambda / H^2
        I)^-1 torque / H`` with ``U = S / H``. Returns ``(beta_dot_radps, singular)``
        where ``singular`` says the SR inverse was used (manipulability below
        ``sr_threshold``).
        """
        u = self._unit_torque_matrix(self._check(beta_rad))
        uut = u @ u.T
        m = self._unit_manipulability(uut)
        singular = m < self.sr_threshold
        if singular:
            uut = uut + self.sr_damping * (1.0 - m / self.sr_threshold) ** 2 * np.eye(3)
        rates = u.T @ np.linalg.solve(uut, np.asarray(torque_Nm, dtype=float))
        return rates / self.rotor_momentum_Nms, bool(singular)

    def step(
        self, beta_rad: ArrayLike, torque_Nm: ArrayLike, dt_s: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], bool]:
        """Produce ``torque_Nm`` for ``dt_s``: new angles, delivered torque, singular flag.

        The rates are evaluated at the mid-step angles (a predictor with the rates at
        the start); the delivered torque is ``-(h(beta_next) - h(beta)) / dt``.
        """
        beta = self._check(beta_rad)
        rates, sing0 = self.steering_rates(beta, torque_Nm)
        rates, sing1 = self.steering_rates(beta + 0.5 * dt_s * rates, torque_Nm)
        beta_next = beta + rates * dt_s
        delivered = -(self.momentum_Nms(beta_next) - self.momentum_Nms(beta)) / dt_s
        return beta_next, delivered, sing0 or sing1


def rk4_step(
    body: RigidBody,
    x: NDArray[np.float64],
    torque_Nm: NDArray[np.float64],
    dt_s: float,
    ext_torque_Nm: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """One step of the shared RK4 (:mod:`kalman_vs_infoset.numerics.integrate`) of the common plant
    (field of ``plant.attitude_rhs``), torque held.

    ``x = (q[4], w[3], h[3])``; the quaternion is renormalised. A cheap stand-in for
    ``plant.propagate`` (DOP853) for the 3000-step turns; tests compare the two.
    """
    ext = np.zeros(3) if ext_torque_Nm is None else ext_torque_Nm
    return renormalised(rk4(attitude_rhs, x, dt_s, body, torque_Nm, ext))
