"""estim.intercept.pf.filter: convergence to the Kalman filter on a linear-Gaussian model,
resampling identical to filterpy's given the same uniforms, and the step mechanics."""

import numpy as np
import pytest
from filterpy.monte_carlo import resampling as fp_resampling
from hypothesis import given, settings
from hypothesis import strategies as st
from kalman_vs_infoset.estim.intercept.pf.filter import (
    ParticleSet,
    bootstrap_step,
    stratified_resample,
    systematic_resample,
)

DT = 0.5
F = np.array([[1.0, DT], [0.0, 1.0]])
Q = np.array([[DT**3 / 3, DT**2 / 2], [DT**2 / 2, DT]]) * 0.5
H = np.array([[1.0, 0.0]])
R = np.array([[0.4]])
M0, P0 = np.array([0.0, 1.0]), np.diag([1.0, 0.5])
STEPS = 20


def _kalman(ys):
    """Kalman filter posteriors (mean, covariance) after each measurement, written out;
    the first measurement is taken after one prediction from (M0, P0)."""
    m, p, out = M0, P0, []
    for y in ys:
        m, p = F @ m, F @ p @ F.T + Q
        s = H @ p @ H.T + R
        k = p @ H.T @ np.linalg.inv(s)
        m, p = m + k @ (y - H @ m), (np.eye(2) - k @ H) @ p
        out.append((m, p))
    return out


def _simulate(rng):
    x, ys = rng.multivariate_normal(M0, P0), []
    for _ in range(STEPS):
        x = F @ x + rng.multivariate_normal(np.zeros(2), Q)
        ys.append(H @ x + rng.normal(0.0, np.sqrt(R[0, 0]), 1))
    return np.array(ys)


def _particle_errors(ys, kf, n, seed):
    """Largest (over steps) mean error in KF standard deviations, and covariance error
    relative to the KF covariance's norm."""
    rng = np.random.default_rng(seed)
    chol_q, r = np.linalg.cholesky(Q), R[0, 0]
    ps = ParticleSet(rng.multivariate_normal(M0, P0, size=n))
    mean_err, cov_err = 0.0, 0.0
    for y, (m_kf, p_kf) in zip(ys, kf, strict=True):
        weighted, ps = bootstrap_step(
            ps,
            rng,
            transition=lambda x: x @ F.T,
            sample_noise=lambda g, k: g.standard_normal((k, 2)) @ chol_q.T,
            likelihood=lambda x, y=y: np.exp(-0.5 * (y[0] - x[:, 0]) ** 2 / r),
        )
        mean_err = max(mean_err, np.max(np.abs(weighted.mean() - m_kf) / np.sqrt(np.diag(p_kf))))
        cov_err = max(cov_err, np.linalg.norm(weighted.covariance() - p_kf) / np.linalg.norm(p_kf))
    return mean_err, cov_err


def test_mean_and_covariance_converge_to_the_kalman_filter():
    ys = _simulate(np.random.default_rng(100))
    kf = _kalman(ys)
    errs = {
        n: np.mean([_particle_errors(ys, kf, n, seed) for seed in range(3)], axis=0)
        for n in (250, 2500, 25000)
    }
    (m1, c1), (m2, c2), (m3, c3) = errs[250], errs[2500], errs[25000]
    # Monte Carlo error ~ N^-1/2, a factor ~3.2 per decade (measured: mean 0.35, 0.080,
    # 0.038; covariance 0.37, 0.11, 0.032); ask for 1.5 per decade and a small final error
    assert m1 > 1.5 * m2 > 2.25 * m3 and c1 > 1.5 * c2 > 2.25 * c3
    assert m3 < 0.06 and c3 < 0.06


@pytest.mark.parametrize("name", ["systematic", "stratified"])
def test_resampling_matches_filterpy_given_the_same_uniforms(monkeypatch, name):
    ours = {"systematic": systematic_resample, "stratified": stratified_resample}[name]
    theirs = getattr(fp_resampling, f"{name}_resample")
    for seed in range(5):
        w = np.random.default_rng(seed).dirichlet(np.full(200, 0.3))
        fake = np.random.default_rng(1000 + seed)  # filterpy's uniforms, from a generator
        monkeypatch.setattr(fp_resampling, "random", lambda *size, g=fake: g.random(*size))
        np.testing.assert_array_equal(ours(w, np.random.default_rng(1000 + seed)), theirs(w))


def test_resampling_survives_weights_that_sum_below_one():
    w = np.full(10, 0.1 - 1e-12)  # the cumulative sum ends below every last position
    idx = systematic_resample(w, np.random.default_rng(0))
    assert idx.max() <= 9 and len(idx) == 10


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from(["systematic", "stratified"]))
def test_resampling_is_unbiased_in_counts(seed, method):
    rng = np.random.default_rng(seed)
    w = rng.dirichlet(np.ones(8))
    drawn = ParticleSet(np.arange(8.0), w).resample(rng, method).particles[:, 0]
    counts = np.bincount(drawn.astype(int), minlength=8)
    # systematic: floor(N w) or ceil(N w) copies; stratified: the interval of length N w
    # also meets two partly covered strata, each giving 0 or 1 copy
    slack = 1 if method == "systematic" else 2
    assert np.all(np.abs(counts - 8 * w) < slack)
    assert counts.sum() == 8


def test_ess_threshold_and_step_mechanics():
    rng = np.random.default_rng(0)
    ps = ParticleSet(np.arange(4.0)[:, None], [0.7, 0.1, 0.1, 0.1])
    assert ps.ess() == pytest.approx(1 / 0.52)
    assert ps.resample_if_needed(rng, threshold=0.4) is ps  # 1.92 >= 1.6
    res = ps.resample_if_needed(rng, threshold=0.5)  # 1.92 < 2
    assert res is not ps and np.allclose(res.weights, 0.25) and res.ess() == pytest.approx(4)
    uniform = ParticleSet(np.zeros((5, 2)))
    assert uniform.resample_if_needed(rng, threshold=1.0) is uniform
    with pytest.raises(ValueError, match="zero likelihood"):
        ps.update(lambda x: np.zeros(len(x)))
    up = ps.update(lambda x: np.array([0.0, 1.0, 1.0, 2.0]))
    np.testing.assert_allclose(up.weights, np.array([0, 0.1, 0.1, 0.2]) / 0.4)
    moved = ps.predict(lambda x: 2 * x, lambda g, k: np.ones((k, 1)), rng)
    np.testing.assert_allclose(moved.particles[:, 0], [1, 3, 5, 7])
    np.testing.assert_allclose(moved.weights, ps.weights)
    with pytest.raises(ValueError):
        ps.particles[0, 0] = 5.0


def test_randomness_comes_only_from_the_passed_generator():
    state = np.random.get_state()[1].copy()  # noqa: NPY002 (checks the global state is untouched)
    ps = ParticleSet(np.random.default_rng(1).normal(size=(100, 2)))

    def run(seed):
        rng = np.random.default_rng(seed)
        out = ps
        for _ in range(5):
            _, out = bootstrap_step(
                out,
                rng,
                lambda x: x,
                lambda g, k: g.normal(size=(k, 2)),
                lambda x: np.exp(-0.5 * x[:, 0] ** 2),
                threshold=1.0,
                method="stratified",
            )
        return out.particles

    np.testing.assert_array_equal(run(3), run(3))
    assert not np.array_equal(run(3), run(4))
    np.testing.assert_array_equal(np.random.get_state()[1], state)  # noqa: NPY002
