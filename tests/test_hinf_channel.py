"""The intercept channel's H-infinity filter (estim.intercept.hinf.estimator) against Simon's (2006,
Section 11.3) recursion written out below with explicit inverses, the package's EKF at
theta = 0, and the Sherman-Morrison reading of its weight (a Kalman update of an
inflated prior)."""

import numpy as np
import pytest
from kalman_vs_infoset.estim.intercept.hinf.estimator import HInfinityChannelEstimator
from kalman_vs_infoset.estim.intercept.model import Bearing, ChannelModel

MODEL = ChannelModel()
E, NU, DT = MODEL.e, MODEL.nu_mps2, 0.5
B_Y, D_VY, B_X = (-10e3, 10e3), (-100.0, 100.0), (5301.3e3, 6301.3e3)


def _bearings(x0_m, steps, seed):
    """Bearings of a truth on the auxiliary model with uniform errors (rows alpha, w, x)."""
    rng = np.random.default_rng(seed)
    y, vy = rng.uniform(*B_Y), rng.uniform(*D_VY)
    s = np.array([y / x0_m, vy / x0_m + E * y / x0_m**2, x0_m])
    out = []
    for _ in range(steps):
        a = MODEL.bearing_bound(s[2])
        out.append(float(s[0] + rng.uniform(-a, a)))
        s = MODEL.step(s, DT, rng.uniform(-NU, NU))
    return out


def simon_known_range(m0, p0, x0, ys, theta, weight):
    """Simon's one-step predictor for (alpha, w) at a known range, written out::

        K = P [I - theta Sbar P + H^T R^-1 H P]^-1 H^T R^-1
        xhat+ = F xhat + F K (y - H xhat),  P+ = F P [I - theta Sbar P + H^T R^-1 H P]^-1 F^T + Q

    with Sbar = L^T (L P L^T)^-1 L (L = I or (0, 1)), F and Q of models.md §1.3 in w."""
    h = np.array([[1.0, 0.0]])
    lm = np.eye(2) if weight == "state" else np.array([[0.0, 1.0]])
    x, p, xr = np.array(m0, float), np.array(p0, float), x0
    out = []
    for y in ys:
        x1 = xr - E * DT
        f = np.array([[1.0, E * DT / (xr * x1)], [0.0, 1.0]])
        g = np.array([DT**2 / (2 * x1), DT * (xr + x1) / (2 * E)])
        q = np.outer(g, g) * NU**2 / 3.0
        r_inv = np.array([[3.0 / float(MODEL.bearing_bound(xr)) ** 2]])
        s_bar = lm.T @ np.linalg.inv(lm @ p @ lm.T) @ lm
        bracket = np.linalg.inv(np.eye(2) - theta * s_bar @ p + h.T @ r_inv @ h @ p)
        k = p @ bracket @ h.T @ r_inv
        x = f @ x + f @ k @ (np.array([y]) - h @ x)
        p = f @ p @ bracket @ f.T + q
        xr = x1
        out.append((x.copy(), p.copy()))
    return out


@pytest.mark.parametrize("weight", ["state", "zem"])
def test_known_range_case_matches_simon_2006_recursion_written_out(weight):
    """With the range known exactly (x box of zero width) the channel is linear in
    (alpha, w); x is left out of the update (zero variance) and the filter must be
    Simon's recursion on the other two coordinates."""
    x0 = 3000e3
    est = HInfinityChannelEstimator(MODEL, theta=0.3, weight=weight)
    b = est.ekf.from_boxes(B_Y, D_VY, (x0, x0))
    assert b.cov[2, 2] == 0.0
    ys = _bearings(x0, 40, seed=1)
    ref = simon_known_range(b.mean[:2], b.cov[:2, :2], x0, ys, 0.3, weight)
    for y, (m_ref, p_ref) in zip(ys, ref, strict=True):
        b = est.predict(est.update(b, Bearing(y)), DT)
        np.testing.assert_allclose(b.mean[:2], m_ref, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(b.cov[:2, :2], p_ref, rtol=1e-7, atol=1e-16)
        assert b.cov[2, 2] == 0.0


@pytest.mark.parametrize("weight", ["state", "zem"])
def test_uncertain_range_matches_the_extended_recursion_written_out(weight):
    """Range uncertain: from the filter's own belief at each step, its update must be
    Simon's at the mean (bracket form, no P^-1: Sbar P = L^T (L P L^T)^-1 L P is I for
    L = I and e_w P[w, :]/P_ww for L = e_w) and its prediction the EKF's (exact map of
    the mean, F P F^T + Q with the Jacobian). theta = 0.05: a larger one forgets the
    range so fast (x's standard deviation x4 in 13 steps at 0.2) that the unscaled
    inverse written out here loses its digits."""
    theta = 0.05
    est = HInfinityChannelEstimator(MODEL, theta=theta, weight=weight)
    b = est.ekf.from_boxes(B_Y, D_VY, B_X)
    h = np.array([[1.0, 0.0, 0.0]])
    e_w = np.array([0.0, 1.0, 0.0])
    worst = 0.0
    for y in _bearings(5801.3e3, 60, seed=2):
        x, p = b.mean.copy(), b.cov.copy()
        r_inv = np.array([[3.0 / float(MODEL.bearing_bound(abs(x[2]))) ** 2]])
        s_bar_p = np.eye(3) if weight == "state" else np.outer(e_w, p[1]) / p[1, 1]
        bracket = np.linalg.inv(np.eye(3) - theta * s_bar_p + h.T @ r_inv @ h @ p)
        x = x + p @ bracket @ h.T @ r_inv @ (np.array([y]) - h @ x)
        p = p @ bracket
        f = est.ekf.step_jacobian(x, DT)
        p = f @ p @ f.T + est.ekf.process_noise(x[2], DT)
        x = est.ekf.step(x, DT)
        b = est.predict(est.update(b, Bearing(y)), DT)
        scale = np.sqrt(np.diag(p))
        unit = np.outer(scale, scale)
        worst = max(worst, np.abs((b.mean - x) / scale).max(), np.abs((b.cov - p) / unit).max())
    assert worst < 1e-8, worst


def test_theta_zero_is_the_ekf_and_theta_to_zero_tends_to_it():
    ys = _bearings(5801.3e3, 120, seed=3)

    ekf = HInfinityChannelEstimator(MODEL, theta=0.0).ekf

    def run(est):
        b = ekf.from_boxes(B_Y, D_VY, B_X)
        means = []
        for y in ys:
            b = est.predict(est.update(b, Bearing(y)), DT)
            means.append(b.mean / np.sqrt(np.diag(b.cov)))
        return np.array(means), b

    m_ekf, b_ekf = run(ekf)
    m0, b0 = run(HInfinityChannelEstimator(MODEL, theta=0.0))
    np.testing.assert_allclose(m0, m_ekf, rtol=0, atol=1e-7)
    np.testing.assert_allclose(b0.cov, b_ekf.cov, rtol=1e-7)
    gaps = [np.abs(run(HInfinityChannelEstimator(MODEL, theta=t))[0] - m_ekf).max()
            for t in (1e-2, 1e-4, 1e-6)]  # fmt: skip
    # first order in theta: a hundredth of theta, a hundredth of the gap
    assert gaps[0] > 50 * gaps[1] > 2500 * gaps[2] and gaps[2] < 1e-2, gaps


@pytest.mark.parametrize("weight", ["state", "zem"])
def test_update_is_the_kalman_update_of_the_inflated_prior(weight):
    """The module's Sherman-Morrison reading: M^-1 and the gain are the Kalman filter's
    for the prior Pt = P + theta/(1-theta) P L^T (L P L^T)^-1 L P."""
    theta = 0.4
    est = HInfinityChannelEstimator(MODEL, theta=theta, weight=weight)
    b = est.ekf.from_boxes(B_Y, D_VY, B_X)
    for y in _bearings(5801.3e3, 30, seed=4)[:-1]:
        b = est.ekf.predict(est.ekf.update(b, Bearing(y)), DT)
    m, p = b.mean, b.cov
    lm = np.eye(3) if weight == "state" else np.array([[0.0, 1.0, 0.0]])
    pt = p + theta / (1 - theta) * p @ lm.T @ np.linalg.solve(lm @ p @ lm.T, lm @ p)
    r = float(MODEL.bearing_bound(m[2])) ** 2 / 3.0
    z = float(m[0]) + 1e-4
    gain = pt[:, 0] / (pt[0, 0] + r)
    out = est.update(b, Bearing(z))
    scale = np.sqrt(np.diag(p))
    np.testing.assert_allclose((out.mean - m - gain * 1e-4) / scale, 0.0, atol=1e-9)
    p_ref = pt - np.outer(gain, pt[0, :])
    np.testing.assert_allclose(out.cov / np.outer(scale, scale), p_ref / np.outer(scale, scale),
                               atol=1e-9)  # fmt: skip
    assert np.all(np.diag(out.cov) >= np.diag(est.ekf.update(b, Bearing(z)).cov))


def test_theta_is_validated():
    for bad in (-0.1, 1.0, float("nan")):
        with pytest.raises(ValueError, match="theta"):
            HInfinityChannelEstimator(MODEL, theta=bad)


@pytest.mark.parametrize("weight", ["zem", "state"])
def test_a_prior_of_zero_width_is_filtered_like_the_kalman_filters_do(weight):
    """A point prior (a box of zero width, which ``ChannelPrior`` accepts): after one
    step the covariance is the rank-one disturbance's, singular to rounding, and the
    second bearing ended in "S must be positive semidefinite" where the EKF and UKF go
    on. Its correlation is made definite by a ridge of 1e-12; the estimate stays on the
    truth, which moves by the model."""
    from kalman_vs_infoset.estim import registry
    from kalman_vs_infoset.estim.intercept.model import ChannelPrior, ChannelSetting

    model = ChannelModel()
    prior = ChannelPrior((-8e3, -8e3), (0.0, 0.0), (5801.3e3, 5801.3e3), (58e3, 58e3))
    truth = model.from_cartesian(-8e3, 0.0, 5801.3e3, -58e3)
    est = registry.get("intercept", "hinf").build({"weight": weight},
                                                  ChannelSetting(model, (58e3, 58e3)))  # fmt: skip
    belief = est.update(est.initial(prior), Bearing(float(truth[0])))
    for _ in range(5):
        belief, truth = est.predict(belief, 0.5), model.step(truth, 0.5)
        belief = est.update(belief, Bearing(float(truth[0])))
        assert np.all(np.isfinite(belief.mean)) and np.all(np.isfinite(belief.cov))
    assert abs(belief.mean[0] - truth[0]) < 1e-9 and abs(belief.mean[2] - truth[2]) < 1e-3
