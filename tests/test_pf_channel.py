"""The intercept channel's particle filter (estim.intercept.pf.estimator): its mean converges to a
Kalman filter written out below on a linear-Gaussian case (Gordon, Salmond & Smith 1993:
the bootstrap filter approximates the Bayes recursion), its bounded likelihood holds the
truth on the channel with uniform errors, a contradiction is reported, not raised, and
randomness comes from its seed only."""

import numpy as np
import pytest
from kalman_vs_infoset.estim.base import Status
from kalman_vs_infoset.estim.intercept.costs import MissForecast
from kalman_vs_infoset.estim.intercept.model import Bearing, ChannelModel, ChannelPrior, Range
from kalman_vs_infoset.estim.intercept.pf.belief import ParticleBelief, particle_rows
from kalman_vs_infoset.estim.intercept.pf.estimator import ParticleChannelEstimator
from kalman_vs_infoset.estim.intercept.pf.filter import ParticleSet

MODEL = ChannelModel()
E, NU, DT = MODEL.e, MODEL.nu_mps2, 0.5
PRIOR = ChannelPrior((-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3))


def kalman_y_v(m0, p0, x0_m, zs):
    """The Kalman filter of (Y, V) at a known range, written out: Y'' = v with v of
    variance nu^2/3, bearing Y/x with variance a(x)^2/3; update first, then predict.
    Returns the posterior means."""
    f = np.array([[1.0, DT], [0.0, 1.0]])
    g = np.array([DT**2 / 2.0, DT])
    q = np.outer(g, g) * NU**2 / 3.0
    m, p, x, out = np.array(m0, float), np.array(p0, float), x0_m, []
    for z in zs:
        h = np.array([1.0 / x, 0.0])
        r = float(MODEL.bearing_bound(x)) ** 2 / 3.0
        k = p @ h / (h @ p @ h + r)
        m, p = m + k * (z - h @ m), p - np.outer(k, h @ p)
        out.append((m.copy(), p.copy()))
        m, p, x = f @ m, f @ p @ f.T + q, x - E * DT
    return out


def test_linear_gaussian_mean_converges_to_the_kalman_filter():
    """Known range and closing speed, Gaussian prior, disturbance and bearing error: the
    channel is linear-Gaussian (the bearing atan2(Y, x) differs from Y/x by 3e-10 rad, a
    millionth of its error), so the posterior mean is the Kalman filter's. Roughening, a
    deliberate perturbation, is off. The error (root mean square over the steps, in
    Kalman standard deviations, averaged over seeds) shrinks as N grows, by about
    sqrt(10) a decade."""
    x0 = 1000e3
    m0, p0 = np.array([300.0, -2.0]), np.diag([800.0**2, 3.0**2])
    rng = np.random.default_rng(0)
    truth = rng.multivariate_normal(m0, p0)
    zs, x = [], x0
    for _ in range(25):
        zs.append(float(np.arctan2(truth[0], x) + rng.normal(0, MODEL.bearing_bound(x) / 3**0.5)))
        v = rng.normal(0, NU / 3**0.5)
        truth = truth + np.array([truth[1] * DT + v * DT**2 / 2, v * DT])
        x -= E * DT
    ref = kalman_y_v(m0, p0, x0, zs)

    def error(n, seed):
        est = ParticleChannelEstimator(
            MODEL, n_particles=n, seed=seed, roughening=0.0,
            disturbance="gaussian", bearing_error="gaussian",
        )  # fmt: skip
        draw = np.random.default_rng(seed + 100).multivariate_normal(m0, p0, n)
        cloud = np.column_stack([draw, np.full(n, x0), np.full(n, E)])
        b = ParticleBelief(ParticleSet(cloud), MODEL, draws=1)
        errs = []
        for z, (m_kf, p_kf) in zip(zs, ref, strict=True):
            b = est.update(b, Bearing(z))
            m_pf = b.weights @ b.particles[:, :2]
            errs.append((m_pf - m_kf) / np.sqrt(np.diag(p_kf)))
            b = est.predict(b, DT)
        return float(np.sqrt(np.mean(np.square(errs))))

    errs = [np.mean([error(n, s) for s in range(3)]) for n in (300, 3000, 30000)]
    assert errs[0] > 2 * errs[1] > 4 * errs[2], errs
    assert errs[2] < 0.04, errs


def test_bounded_likelihood_holds_the_truth_on_the_channel_with_uniform_errors():
    """Truth on the auxiliary model (Y'' = v uniform in +-nu, closing speed constant in
    the interval), bearings with uniform errors: no update is rejected, the truth is in
    the cloud's range of x and Y at every step and inside the moments' 3-sigma
    ellipsoid in most steps."""
    speed = (57.9e3, 58.1e3)
    est = ParticleChannelEstimator(MODEL, closing_speed_mps=speed)
    rng = np.random.default_rng(5)
    inside, steps = 0, 0
    for _ in range(3):
        y, vy = rng.uniform(*PRIOR.lateral_m), rng.uniform(*PRIOR.lateral_vel_mps)
        x, e = rng.uniform(*PRIOR.x_m), rng.uniform(*speed)
        b = est.initial(PRIOR)
        for _ in range(80):
            a = MODEL.bearing_bound(np.hypot(x, y))
            b = est.update(b, Bearing(float(np.arctan2(y, x) + rng.uniform(-a, a))))
            assert b.status is Status.OK
            live = b.particles[b.weights > 0]
            assert live[:, 2].min() <= x <= live[:, 2].max()
            assert live[:, 0].min() <= y <= live[:, 0].max()
            inside += b.contains(MODEL.from_cartesian(y, vy, x, -e))
            steps += 1
            b = est.predict(b, DT)
            v = rng.uniform(-NU, NU)
            y, vy, x = y + vy * DT + v * DT**2 / 2, vy + v * DT, x - e * DT
    assert inside >= 0.9 * steps, (inside, steps)


def test_all_zero_weights_are_a_reported_contradiction_and_the_cloud_is_kept():
    est = ParticleChannelEstimator(MODEL, n_particles=500)
    b = est.update(est.initial(PRIOR), Bearing(0.0))
    bad = est.update(b, Bearing(0.5))  # 0.5 rad: no particle within the bound
    assert bad.status is Status.CONTRADICTION and bad.contradictions == 1
    assert bad.cloud is b.cloud and not bad.is_empty
    good = est.update(bad, Bearing(0.0))
    assert good.status is Status.OK and good.contradictions == 1
    far = est.update(b, Range(1e9))
    assert far.status is Status.CONTRADICTION and far.cloud is b.cloud


def test_extremes_are_over_the_particles_of_positive_weight():
    est = ParticleChannelEstimator(MODEL, n_particles=800)
    b = est.update(est.initial(PRIOR), Bearing(1e-4))
    assert 0 < np.count_nonzero(b.weights) < 800
    fc = MissForecast(MODEL)
    rows = particle_rows(b.particles, MODEL)[b.weights > 0]
    ext = b.extremes(fc)
    assert ext.min_value == fc(rows).min() and ext.max_value == fc(rows).max()
    np.testing.assert_array_equal(fc(ext.argmax[None, :]), [ext.max_value])
    # the centre is the weighted mean of (alpha, w, x), read back in (alpha, omega, x)
    q = rows.copy()
    q[:, 1] *= q[:, 2] ** 2 / E
    m = b.weights[b.weights > 0] @ q
    np.testing.assert_allclose(b.centre(), [m[0], m[1] * E / m[2] ** 2, m[2]], rtol=1e-12)


def test_randomness_comes_from_the_seed_and_beliefs_are_values():
    est = ParticleChannelEstimator(MODEL, n_particles=300, seed=7)
    b0 = est.update(est.initial(PRIOR), Bearing(0.0))
    b1, b1_again = est.predict(b0, DT, 1.0), est.predict(b0, DT, 1.0)
    np.testing.assert_array_equal(b1.particles, b1_again.particles)
    other = ParticleChannelEstimator(MODEL, n_particles=300, seed=7)
    np.testing.assert_array_equal(other.initial(PRIOR).particles, est.initial(PRIOR).particles)
    seed8 = ParticleChannelEstimator(MODEL, n_particles=300, seed=8)
    assert not np.array_equal(seed8.initial(PRIOR).particles, est.initial(PRIOR).particles)
    assert b1.draws == b0.draws + 1
    with pytest.raises(AttributeError):
        b1.draws = 0


def test_impulse_moves_the_lateral_velocity_exactly():
    est = ParticleChannelEstimator(MODEL, n_particles=50, roughening=0.0)
    b = est.initial(PRIOR)
    free, kicked = est.predict(b, DT), est.predict(b, DT, 2.0)
    np.testing.assert_allclose(kicked.particles[:, 1] - free.particles[:, 1], 2.0, atol=1e-12)
    np.testing.assert_allclose(kicked.particles[:, 0] - free.particles[:, 0], 2.0 * DT, atol=1e-9)


def test_the_cached_rows_of_a_particle_belief_are_read_only():
    """Beliefs are values: the rows a particle belief caches were writable, and a write
    into them changed that belief's extremes."""
    from kalman_vs_infoset.estim import registry
    from kalman_vs_infoset.estim.intercept.model import ChannelModel, ChannelPrior, ChannelSetting

    model = ChannelModel()
    est = registry.get("intercept", "pf").build(
        {"n_particles": 200}, ChannelSetting(model, (58e3, 58e3))
    )
    belief = est.initial(ChannelPrior((-1e3, 1e3), (-10.0, 10.0), (5.7e6, 5.9e6), (58e3, 58e3)))
    with pytest.raises(ValueError, match="read-only"):
        belief.rows[0, 0] = 1.0


def test_no_draw_of_the_filter_repeats_a_runs_own_stream():
    """Run ``j`` of a command draws its truth and errors from ``SeedSequence(seed,
    spawn_key=(j,))`` (``runner.run_seed``); the filter's draw ``k`` drew from
    ``SeedSequence(filter seed, spawn_key=(k,))``, so with ``--seed`` equal to the
    filter's seed (both 0 by default) its draw ``j`` was run ``j``'s stream. Its keys
    start above every run index now: no draw of the first hundred repeats the first
    uniforms of any run's stream or of its first child streams, for seeds 0 and 7."""
    from kalman_vs_infoset.experiments.options import MAX_RUNS
    from kalman_vs_infoset.experiments.runner import run_seed

    for seed in (0, 7):
        est = ParticleChannelEstimator(MODEL, seed=seed)
        b = est.initial(PRIOR)
        filt = set()
        for _ in range(100):
            filt.add(tuple(est.rng(b).uniform(size=4)))
            b = est.predict(b, 0.0)
        runs = set()
        for j in range(100):
            runs.add(tuple(np.random.default_rng(run_seed(seed, j)).uniform(size=4)))
            for child in run_seed(seed, j).spawn(2):
                runs.add(tuple(np.random.default_rng(child).uniform(size=4)))
        assert len(filt) == 100 and not filt & runs
    from kalman_vs_infoset.estim.intercept.pf.estimator import STREAM_KEY

    assert STREAM_KEY > MAX_RUNS
