"""Truth model of the intercept: heliocentric two-body motion of both bodies (docs/models.md §1.1).

Both the spacecraft (SC) and the target move in the Sun's field,
``K = 1.324948e11 km^3/s^2``. The state integrated is the SC's heliocentric
position and velocity plus the target's position and velocity *relative* to the
SC, whose acceleration is the differential gravity

    a_rel = g(R_sc + r) - g(R_sc),   g(R) = -K R / |R|^3

(~1e-7 m/s^2 here: small, but included). Each body is propagated exactly by
the universal-variable Kepler solution (f and g functions, Curtis, *Orbital
Mechanics for Engineering Students*, Alg. 3.4); the relative state is their
difference, formed without differencing the two heliocentric positions
(:func:`._kepler.relative_step`: at 1 AU that difference would carry ~2e-8 km of
rounding every step). That is the exact two-body motion at a fraction of the cost of a
``solve_ivp`` call per decision step; :meth:`TwoBodyTruth.propagate_numeric`
integrates the same model with ``solve_ivp`` (DOP853) and the tests check that
both agree.

Guidance frame: inertial axes, origin at the SC, x from the SC to the nominal
target position (the SC's longitudinal axis), z along the heliocentric orbit
normal, y = z x x. The SC sits at ``sun_distance_km`` on the heliocentric X axis
on a circular orbit; the guidance x axis is the along-track direction
(heliocentric +Y). Units inside: km, km/s (as the paper); results in m, m/s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from kalman_vs_infoset.guidance.intercept._kepler import kepler_step, relative_step
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]

K_SUN_KM3PS2 = 1.324948e11

#: guidance-frame axes (rows) in heliocentric coordinates: x = +Y_h, y = -X_h, z = +Z_h
GUIDANCE_TO_HELIO = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]).T


@dataclass(frozen=True)
class TwoBodyTruth:
    """Heliocentric two-body truth model (configuration only)."""

    mu_km3ps2: float = K_SUN_KM3PS2
    sun_distance_km: float = 1.496e8
    rtol: float = 1e-12
    atol_km: float = 1e-10

    def __post_init__(self) -> None:
        values = (self.mu_km3ps2, self.sun_distance_km)
        if not (min(values) > 0 and np.isfinite(values).all()):
            raise ValueError("mu_km3ps2 and sun_distance_km must be positive and finite")

    def initial(self, rel_pos_km: ArrayLike, rel_vel_kmps: ArrayLike) -> FloatArray:
        """Full state ``(R_sc, V_sc, r, v)`` (km, km/s, heliocentric axes) from the
        target's relative position/velocity in guidance axes."""
        r_sc = np.array([self.sun_distance_km, 0.0, 0.0])
        v_sc = np.array([0.0, np.sqrt(self.mu_km3ps2 / self.sun_distance_km), 0.0])
        r = GUIDANCE_TO_HELIO @ np.asarray(rel_pos_km, dtype=float)
        v = GUIDANCE_TO_HELIO @ np.asarray(rel_vel_kmps, dtype=float)
        return np.concatenate([r_sc, v_sc, r, v])

    def relative(self, state: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Target position (km) and velocity (km/s) relative to the SC, guidance axes."""
        s = np.asarray(state, dtype=float)
        return GUIDANCE_TO_HELIO.T @ s[6:9], GUIDANCE_TO_HELIO.T @ s[9:12]

    def rhs(self, _t: float, s: FloatArray) -> FloatArray:
        r_sc, r = s[0:3], s[6:9]
        r_t = r_sc + r
        g_sc = -self.mu_km3ps2 * r_sc / np.linalg.norm(r_sc) ** 3
        g_t = -self.mu_km3ps2 * r_t / np.linalg.norm(r_t) ** 3
        return np.concatenate([s[3:6], g_sc, s[9:12], g_t - g_sc])

    def propagate(self, state: ArrayLike, dt_s: float) -> FloatArray:
        """State after ``dt_s`` seconds of free flight (exact Kepler propagation)."""
        s = np.array(state, dtype=float)  # a contiguous copy: one compiled signature
        if dt_s == 0:
            return s
        # the relative state is propagated without differencing heliocentric positions
        # (compiled :func:`._kepler.relative_step`; that difference jitters by ~2e-8 km)
        parts = relative_step(s[0:3], s[3:6], s[6:9], s[9:12], float(dt_s), self.mu_km3ps2)
        return np.concatenate(parts)

    def propagate_numeric(self, state: ArrayLike, dt_s: float, dense: bool = False):
        """The same motion integrated with ``solve_ivp`` (DOP853), for checks."""
        from scipy.integrate import solve_ivp  # here: the runs use the compiled Kepler step

        sol = solve_ivp(
            self.rhs,
            (0.0, dt_s),
            np.asarray(state, dtype=float),
            method="DOP853",
            rtol=self.rtol,
            atol=self.atol_km,
            dense_output=dense,
        )
        if not sol.success:  # pragma: no cover - smooth field
            raise RuntimeError(f"truth propagation failed: {sol.message}")
        return (sol.y[:, -1], sol.sol) if dense else sol.y[:, -1]

    def apply_impulse(self, state: ArrayLike, dv_rel_mps: ArrayLike) -> FloatArray:
        """Change the *relative* velocity by ``dv_rel_mps`` (guidance axes, m/s).

        The SC's own velocity changes by the opposite vector (its impulse); the
        target is untouched.
        """
        s = np.array(state, dtype=float)
        dv_kmps = GUIDANCE_TO_HELIO @ (np.asarray(dv_rel_mps, dtype=float) / 1e3)
        s[3:6] -= dv_kmps
        s[9:12] += dv_kmps
        return s

    def closest_approach(self, state: ArrayLike, horizon_s: float) -> tuple[float, float]:
        """Miss distance (m) and time (s) of closest approach within ``horizon_s``.

        Minimises the dense-output range over the interval (no last-sample bias).
        """

        def range_km(t: float) -> float:
            return float(np.linalg.norm(self.propagate(state, t)[6:9])) if t > 0 else r0

        from scipy.optimize import minimize_scalar

        r0 = float(np.linalg.norm(np.asarray(state, dtype=float)[6:9]))
        res = minimize_scalar(
            range_km, bounds=(0.0, horizon_s), method="bounded", options={"xatol": 1e-9}
        )
        best_t, best = float(res.x), float(res.fun)
        for t in (0.0, horizon_s):  # the minimum may sit at an end of the interval
            if range_km(t) < best:
                best_t, best = t, range_km(t)
        return best * 1e3, best_t


def kepler_propagate(
    pos_km: ArrayLike, vel_kmps: ArrayLike, dt_s: float, mu_km3ps2: float
) -> tuple[FloatArray, FloatArray]:
    """Two-body propagation of ``n`` bodies by universal variables (f and g functions).

    Solves ``sqrt(mu) dt = r0 vr0/sqrt(mu) chi^2 C(a chi^2) + (1 - a r0) chi^3 S(a chi^2)
    + r0 chi`` for ``chi`` by Newton's method (Curtis, Alg. 3.3-3.4), then
    ``R = f R0 + g V0``, ``V = fdot R0 + gdot V0``.
    """
    r0v = np.atleast_2d(np.asarray(pos_km, dtype=float))
    v0v = np.atleast_2d(np.asarray(vel_kmps, dtype=float))
    if dt_s == 0:
        return r0v.copy(), v0v.copy()
    # compiled (:mod:`._kepler`): every decision step and the closest-approach search
    return kepler_step(
        np.ascontiguousarray(r0v), np.ascontiguousarray(v0v), float(dt_s), float(mu_km3ps2)
    )
