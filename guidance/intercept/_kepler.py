"""Compiled universal-variable Kepler step (Curtis, Alg. 3.3-3.4), ``n`` bodies at once.

The truth model calls it every decision step and many times in the closest-approach
search; in numpy it cost about 220 us per call (10-12 % of a random-noise
engagement), in numba a few microseconds. Every expression keeps the order of the
numpy formulation it replaced, powers go through ``math.pow`` (libm ``pow``, as
numpy's ``**`` with exponent 3) and squares are products (as numpy's ``**2``), and
numba does not contract ``a * b + c`` into fused multiply-adds, and ``1 + (-y)`` is
``1 - y`` to the bit (the small parts ``F = f - 1`` are shared with
:func:`relative_step`): results are bit-identical to that formulation (a test compares
them on random states).
"""

from __future__ import annotations

import math

import numpy as np

from kalman_vs_infoset._jit import njit


@njit(cache=True)
def _stumpff(z: float) -> tuple[float, float]:
    """Stumpff functions C(z), S(z); series for small |z| (no cancellation)."""
    if abs(z) < 1e-3:  # the usual case: steps of seconds on year-long orbits
        z2, z3 = z * z, math.pow(z, 3.0)
        return (
            1 / 2 - z / 24 + z2 / 720 - z3 / 40320,
            1 / 6 - z / 120 + z2 / 5040 - z3 / 362880,
        )
    if z > 0:
        sq = math.sqrt(z)
        return (1 - math.cos(sq)) / z, (sq - math.sin(sq)) / math.pow(sq, 3.0)
    sq = math.sqrt(-z)
    return (math.cosh(sq) - 1) / -z, (math.sinh(sq) - sq) / math.pow(sq, 3.0)


@njit(cache=True)
def _solve_chi(r0v, v0v, dt_s, mu_km3ps2):
    """Universal anomaly ``chi`` of each body after ``dt_s`` by Newton's method (with
    ``|r0|``, the radial speed and ``alpha = 1/a``), all bodies iterating together
    until every step is at round-off."""
    n = r0v.shape[0]
    sqmu = math.sqrt(mu_km3ps2)
    r0 = np.empty(n)
    vr0 = np.empty(n)
    alpha = np.empty(n)
    chi = np.empty(n)
    for i in range(n):
        x, y, z = r0v[i, 0], r0v[i, 1], r0v[i, 2]
        r0[i] = math.sqrt(x * x + y * y + z * z)
        rv = r0v[i, 0] * v0v[i, 0] + r0v[i, 1] * v0v[i, 1] + r0v[i, 2] * v0v[i, 2]
        vv = v0v[i, 0] * v0v[i, 0] + v0v[i, 1] * v0v[i, 1] + v0v[i, 2] * v0v[i, 2]
        vr0[i] = rv / r0[i]
        alpha[i] = 2.0 / r0[i] - vv / mu_km3ps2
        chi[i] = sqmu * dt_s / r0[i]  # exact to first order in dt
    for _ in range(20):
        done = True
        for i in range(n):
            z = alpha[i] * (chi[i] * chi[i])
            c, s = _stumpff(z)
            ch = chi[i]
            f_val = r0[i] * vr0[i] / sqmu * (ch * ch) * c
            f_val = f_val + (1 - alpha[i] * r0[i]) * math.pow(ch, 3.0) * s + r0[i] * ch
            f_val -= sqmu * dt_s
            df = r0[i] * vr0[i] / sqmu * ch * (1 - z * s) + (1 - alpha[i] * r0[i]) * (ch * ch) * c
            df = df + r0[i]
            step = f_val / df
            chi[i] = ch - step
            # stop at round-off level (a tighter test could cycle on the last bit)
            if not abs(step) <= 4e-16 * abs(chi[i]):
                done = False
        if done:
            break
    return r0, alpha, chi


@njit(cache=True)
def _fg(ch, alpha, r0, dt_s, sqmu):
    """The small parts ``F = f - 1`` and ``G = g - dt`` of the Lagrange coefficients,
    each computed directly (no cancellation), with the Stumpff values ``C, S``."""
    c, s = _stumpff(alpha * (ch * ch))
    return -(ch * ch) / r0 * c, -math.pow(ch, 3.0) * s / sqmu, c, s


@njit(cache=True)
def _rates(ch, alpha, r0, r1, c, s, sqmu):
    """``fdot`` and the small part ``Gd = gdot - 1`` at the new radius ``r1``."""
    fdot = sqmu / (r1 * r0) * (alpha * math.pow(ch, 3.0) * s - ch)
    return fdot, -(ch * ch) / r1 * c


@njit(cache=True)
def kepler_step(r0v, v0v, dt_s, mu_km3ps2):
    """Positions and velocities of ``n`` bodies after ``dt_s`` (arrays ``(n, 3)``).

    Solves ``sqrt(mu) dt = r0 vr0/sqrt(mu) chi^2 C(a chi^2) + (1 - a r0) chi^3
    S(a chi^2) + r0 chi`` for ``chi`` by Newton's method, all bodies iterating
    together until every step is at round-off, then ``R = f R0 + g V0``,
    ``V = fdot R0 + gdot V0``.
    """
    n = r0v.shape[0]
    r1v = np.empty((n, 3))
    v1v = np.empty((n, 3))
    sqmu = math.sqrt(mu_km3ps2)
    r0, alpha, chi = _solve_chi(r0v, v0v, dt_s, mu_km3ps2)
    for i in range(n):
        big_f, big_g, c, s = _fg(chi[i], alpha[i], r0[i], dt_s, sqmu)
        f, g = 1.0 + big_f, dt_s + big_g
        for k in range(3):
            r1v[i, k] = f * r0v[i, k] + g * v0v[i, k]
        r1 = math.sqrt(r1v[i, 0] * r1v[i, 0] + r1v[i, 1] * r1v[i, 1] + r1v[i, 2] * r1v[i, 2])
        fdot, small_gd = _rates(chi[i], alpha[i], r0[i], r1, c, s, sqmu)
        gdot = 1.0 + small_gd
        for k in range(3):
            v1v[i, k] = fdot * r0v[i, k] + gdot * v0v[i, k]
    return r1v, v1v


@njit(cache=True)
def relative_step(sc_pos, sc_vel, rel_pos, rel_vel, dt_s, mu_km3ps2):
    """A spacecraft's heliocentric state and a target's state *relative* to it after
    ``dt_s``, both in exact two-body motion (arrays ``(3,)``, km and km/s).

    The relative state is not the difference of the two heliocentric results: at 1 AU
    that difference carries ~2e-8 km of rounding every step, a jitter of the
    relative position far larger than the differential gravity moves it over a
    short step. With ``f = 1 + F``, ``g = dt + G``, ``gdot = 1 + Gd`` (each small term
    computed directly) the target's relative position is::

        r1 = (1 + F_t) r + (dt + G_t) v + (F_t - F_s) R + (G_t - G_s) V

    (``s``: spacecraft, ``t``: target, ``R, V`` the spacecraft's state): only small
    terms are differenced, and the rounding left is that of ``r1`` itself. The
    velocity is ``v1 = fdot_t r + (1 + Gd_t) v + (fdot_t - fdot_s) R + (Gd_t - Gd_s) V``.
    """
    r0v = np.empty((2, 3))
    v0v = np.empty((2, 3))
    for k in range(3):
        r0v[0, k], v0v[0, k] = sc_pos[k], sc_vel[k]
        # the target's own orbit: rounding of R + r moves its f and g by ~1e-16 of
        # their small parts only
        r0v[1, k], v0v[1, k] = sc_pos[k] + rel_pos[k], sc_vel[k] + rel_vel[k]
    sqmu = math.sqrt(mu_km3ps2)
    r0, alpha, chi = _solve_chi(r0v, v0v, dt_s, mu_km3ps2)
    big_f, big_g, fdot, small_gd = np.empty(2), np.empty(2), np.empty(2), np.empty(2)
    pos1 = np.empty((2, 3))
    for i in range(2):
        big_f[i], big_g[i], c, s = _fg(chi[i], alpha[i], r0[i], dt_s, sqmu)
        for k in range(3):
            pos1[i, k] = (1.0 + big_f[i]) * r0v[i, k] + (dt_s + big_g[i]) * v0v[i, k]
        r1 = math.sqrt(pos1[i, 0] * pos1[i, 0] + pos1[i, 1] * pos1[i, 1] + pos1[i, 2] * pos1[i, 2])
        fdot[i], small_gd[i] = _rates(chi[i], alpha[i], r0[i], r1, c, s, sqmu)
    sc_vel1 = np.empty(3)
    rel_pos1 = np.empty(3)
    rel_vel1 = np.empty(3)
    d_f, d_g = big_f[1] - big_f[0], big_g[1] - big_g[0]
    d_fdot, d_gd = fdot[1] - fdot[0], small_gd[1] - small_gd[0]
    for k in range(3):
        sc_vel1[k] = fdot[0] * sc_pos[k] + (1.0 + small_gd[0]) * sc_vel[k]
        rel_pos1[k] = (
            rel_pos[k] + (big_f[1] * rel_pos[k] + dt_s * rel_vel[k] + big_g[1] * rel_vel[k])
        ) + (d_f * sc_pos[k] + d_g * sc_vel[k])
        rel_vel1[k] = (rel_vel[k] + (fdot[1] * rel_pos[k] + small_gd[1] * rel_vel[k])) + (
            d_fdot * sc_pos[k] + d_gd * sc_vel[k]
        )
    return pos1[0].copy(), sc_vel1, rel_pos1, rel_vel1


def warm_up() -> None:
    """Load the compiled step the truth model calls in this process (forked workers
    then inherit it; :func:`kepler_step`, for ``n`` independent bodies, is loaded on use)."""
    z3, r3 = np.zeros(3), np.array([1.5e8, 0.0, 0.0])
    relative_step(r3, np.array([0.0, 30.0, 0.0]), z3 + 1e3, z3, 0.5, 1.3e11)
