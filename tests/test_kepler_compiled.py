"""The compiled Kepler step against its numpy formulation (Curtis, *Orbital Mechanics
for Engineering Students*, Alg. 3.3-3.4) and against ``solve_ivp``.

The numpy formulation below is the one the truth model used before the step was
compiled; the compiled step keeps its expression order, so the two agree to the last
bit and no engagement result moved.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from kalman_vs_infoset.guidance.intercept.truth import (
    K_SUN_KM3PS2,
    TwoBodyTruth,
    kepler_propagate,
)
from scipy.integrate import solve_ivp


def _stumpff_np(z):
    small = np.abs(z) < 1e-3
    c, s = np.empty_like(z), np.empty_like(z)
    zs = z[small]
    c[small] = 1 / 2 - zs / 24 + zs**2 / 720 - zs**3 / 40320
    s[small] = 1 / 6 - zs / 120 + zs**2 / 5040 - zs**3 / 362880
    pos, neg = (~small) & (z > 0), (~small) & (z < 0)
    sq = np.sqrt(z[pos])
    c[pos], s[pos] = (1 - np.cos(sq)) / z[pos], (sq - np.sin(sq)) / sq**3
    sq = np.sqrt(-z[neg])
    c[neg], s[neg] = (np.cosh(sq) - 1) / -z[neg], (np.sinh(sq) - sq) / sq**3
    return c, s


def _kepler_np(r0v, v0v, dt_s, mu):
    sqmu = np.sqrt(mu)
    r0 = np.linalg.norm(r0v, axis=1)
    vr0 = np.einsum("ij,ij->i", r0v, v0v) / r0
    alpha = 2.0 / r0 - np.einsum("ij,ij->i", v0v, v0v) / mu
    chi = sqmu * dt_s / r0
    for _ in range(20):
        z = alpha * chi**2
        c, s = _stumpff_np(z)
        f_val = r0 * vr0 / sqmu * chi**2 * c + (1 - alpha * r0) * chi**3 * s + r0 * chi
        f_val -= sqmu * dt_s
        df = r0 * vr0 / sqmu * chi * (1 - z * s) + (1 - alpha * r0) * chi**2 * c + r0
        step = f_val / df
        chi = chi - step
        if np.all(np.abs(step) <= 4e-16 * np.abs(chi)):
            break
    z = alpha * chi**2
    c, s = _stumpff_np(z)
    f, g = 1 - chi**2 / r0 * c, dt_s - chi**3 * s / sqmu
    r1v = f[:, None] * r0v + g[:, None] * v0v
    r1 = np.linalg.norm(r1v, axis=1)
    fdot = sqmu / (r1 * r0) * (alpha * chi**3 * s - chi)
    gdot = 1 - chi**2 / r1 * c
    return r1v, fdot[:, None] * r0v + gdot[:, None] * v0v


def _states(rng, n):
    """Pairs (SC, target) as the truth model forms them: 1 AU circular orbit, target
    within a few thousand km moving at tens of km/s relative."""
    truth = TwoBodyTruth()
    for _ in range(n):
        rel = truth.initial(rng.uniform(-1, 1, 3) * [6e3, 50, 50], rng.normal(0, 30, 3))
        yield (
            np.stack([rel[0:3], rel[0:3] + rel[6:9]]),
            np.stack([rel[3:6], rel[3:6] + rel[9:12]]),
        )


def test_compiled_step_bit_identical_to_numpy_formulation():
    """Decision steps and closest-approach arguments (0..200 s): identical bits."""
    rng = np.random.default_rng(20261201)
    for pos, vel in _states(rng, 300):
        dt = float(rng.choice([0.5, 0.125, rng.uniform(1e-6, 200.0)]))
        got = kepler_propagate(pos, vel, dt, K_SUN_KM3PS2)
        want = _kepler_np(pos, vel, dt, K_SUN_KM3PS2)
        assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])


@pytest.mark.parametrize("kind", ["elliptic_large_z", "hyperbolic"])
def test_compiled_step_matches_solve_ivp_outside_the_series(kind):
    """|z| >= 1e-3 (trig/hyperbolic Stumpff branches): a quarter orbit of a low orbit,
    and a hyperbolic flyby, against DOP853 integration of the two-body equations."""
    mu = 398600.4418
    r0 = np.array([[7000.0, 0.0, 0.0]])
    v0 = np.array([[0.0, 7.5, 1.0]]) if kind == "elliptic_large_z" else np.array([[0.0, 12.0, 0.0]])
    dt = 1500.0

    def rhs(_t, y):
        r = y[:3]
        return np.r_[y[3:], -mu * r / np.linalg.norm(r) ** 3]

    sol = solve_ivp(rhs, (0, dt), np.r_[r0[0], v0[0]], method="DOP853", rtol=1e-12, atol=1e-9)
    r1, v1 = kepler_propagate(r0, v0, dt, mu)
    np.testing.assert_allclose(r1[0], sol.y[:3, -1], rtol=1e-8, atol=1e-5)
    np.testing.assert_allclose(v1[0], sol.y[3:, -1], rtol=1e-8, atol=1e-8)


def test_relative_step_agrees_with_the_integrated_relative_motion_to_rounding():
    """The truth's relative state (:func:`._kepler.relative_step`) against DOP853 on
    the relative equations ``r'' = g(R + r) - g(R)`` (``TwoBodyTruth.rhs``, which
    integrates ``r`` itself): within a few units in the last place of ``r`` (1e-11 km),
    where the difference of the two heliocentric Kepler positions is off by up to
    ~2e-8 km (the rounding of 1 AU). The spacecraft's own state is the plain Kepler
    step's, bit for bit."""
    rng = np.random.default_rng(20261202)
    truth = TwoBodyTruth()
    tight = replace(truth, rtol=1e-13, atol_km=1e-16)
    worst_old = 0.0
    for _ in range(20):
        s0 = truth.initial(rng.uniform(-1, 1, 3) * [6e3, 50, 50], rng.normal(0, 30, 3))
        dt = float(rng.choice([0.05, 0.5, 5.0]))
        got = truth.propagate(s0, dt)
        want = tight.propagate_numeric(s0, dt)
        np.testing.assert_allclose(got[6:9], want[6:9], rtol=0, atol=1e-11)
        np.testing.assert_allclose(got[9:12], want[9:12], rtol=0, atol=1e-13)
        pos = np.stack([s0[0:3], s0[0:3] + s0[6:9]])
        vel = np.stack([s0[3:6], s0[3:6] + s0[9:12]])
        p1, v1 = kepler_propagate(pos, vel, dt, K_SUN_KM3PS2)
        assert np.array_equal(got[0:3], p1[0]) and np.array_equal(got[3:6], v1[0])
        worst_old = max(worst_old, float(np.abs(p1[1] - p1[0] - want[6:9]).max()))
    assert worst_old > 1e-9  # the formulation it replaced did carry the rounding of 1 AU


def test_free_flight_relative_motion_has_no_rounding_jitter():
    """Over 400 steps of 0.05 s of free flight the relative position's second
    difference (its implied acceleration) stays within the differential gravity's
    bound ``2 K |r| / R^3`` plus the rounding of ``r`` itself: no per-step jitter. (The
    difference of heliocentric positions jittered by ~2e-8 km a step, 0.007 m/s^2 at
    this step, above the set estimators' disturbance bound of 0.005 m/s^2; under the
    game adversary the node set then lost the truth at fine steps.)"""
    truth = TwoBodyTruth()
    s = truth.initial([5801.3, -8.0, 1.0], [-58.0, 0.05, -0.02])  # km, km/s
    dt = 0.05
    pos = [s[6:9].copy()]
    for _ in range(400):
        s = truth.propagate(s, dt)
        pos.append(s[6:9].copy())
    r = np.array(pos)
    accel = np.abs(r[2:] - 2 * r[1:-1] + r[:-2]) / dt**2  # km/s^2
    r_norm = np.linalg.norm(r, axis=1).max()
    bound = 2 * K_SUN_KM3PS2 * r_norm / truth.sun_distance_km**3 + 4 * np.spacing(r_norm) / dt**2
    assert accel.max() <= bound


def test_relative_step_outside_the_series_matches_the_integrated_relative_motion():
    """The relative step's algebra is exact for any orbit: a low Earth orbit over a
    quarter period (|z| >= 1e-3, the trigonometric Stumpff branch), a target 10 km away,
    against DOP853 on the relative equations."""
    truth = TwoBodyTruth(mu_km3ps2=398600.4418, sun_distance_km=7000.0)
    s0 = truth.initial([10.0, 0.5, -0.2], [-0.01, 0.002, 0.001])
    got = truth.propagate(s0, 1500.0)
    want = replace(truth, rtol=1e-13, atol_km=1e-14).propagate_numeric(s0, 1500.0)
    np.testing.assert_allclose(got[6:9], want[6:9], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got[9:12], want[9:12], rtol=0, atol=1e-12)
