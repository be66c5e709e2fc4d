"""estim.intercept.hinf.filter against an independent, literal transcription of Simon's recursion,
the Kalman filter at theta = 0, the game's cost bound, and filterpy's HInfinityFilter."""

import numpy as np
import pytest
from filterpy.hinfinity import HInfinityFilter
from kalman_vs_infoset.estim.intercept.hinf.filter import (
    HInfinityEstimate,
    HInfinityModel,
    hinf_filter,
    hinf_step,
)
from scipy.linalg import block_diag, eigh


def simon_reference(f, h, q, r, lm, s, theta, x0, p0, ys):
    """Simon (2006) Section 11.3, written out with explicit inverses, plus the existence
    condition at each step (returned as the smallest eigenvalue of M_k)."""
    n = len(x0)
    s_bar, r_inv, eye = lm.T @ s @ lm, np.linalg.inv(r), np.eye(n)
    x, p = np.array(x0, dtype=float), np.array(p0, dtype=float)
    xs, ps, min_eig = [x], [p], []
    for y in ys:
        min_eig.append(np.linalg.eigvalsh(np.linalg.inv(p) - theta * s_bar + h.T @ r_inv @ h)[0])
        bracket = np.linalg.inv(eye - theta * s_bar @ p + h.T @ r_inv @ h @ p)
        k = p @ bracket @ h.T @ r_inv
        x = f @ x + f @ k @ (y - h @ x)
        p = f @ p @ bracket @ f.T + q
        xs.append(x)
        ps.append(p)
    return np.array(xs), np.array(ps), np.array(min_eig)


def kalman_predictor(f, h, q, r, x0, p0, ys):
    """The textbook Kalman filter, update then predict; returns the predictions."""
    x, p = np.array(x0, dtype=float), np.array(p0, dtype=float)
    xs, ps = [x], [p]
    for y in ys:
        s = h @ p @ h.T + r
        k = p @ h.T @ np.linalg.inv(s)
        x_post, p_post = x + k @ (y - h @ x), (np.eye(len(x)) - k @ h) @ p
        x, p = f @ x_post, f @ p_post @ f.T + q
        xs.append(x)
        ps.append(p)
    return np.array(xs), np.array(ps)


def _system(rng):
    f = np.array([[0.95, 0.1, 0.0], [-0.1, 0.9, 0.05], [0.0, 0.2, 0.8]])
    h = rng.normal(size=(2, 3))
    q = np.diag([0.02, 0.01, 0.03])
    r = np.array([[0.2, 0.05], [0.05, 0.1]])
    lm = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]])
    s = np.diag([1.0, 2.0])
    return f, h, q, r, lm, s


def test_matches_the_written_out_recursion():
    rng = np.random.default_rng(0)
    f, h, q, r, lm, s = _system(rng)
    theta = 0.2
    x0, p0 = rng.normal(size=3), np.eye(3)
    ys = rng.normal(size=(40, 2))
    xs_ref, ps_ref, min_eig = simon_reference(f, h, q, r, lm, s, theta, x0, p0, ys)
    assert np.all(min_eig > 0)  # the example is inside the existence region
    xs, ps = hinf_filter(HInfinityModel(f, h, q, r, theta, lm, s), x0, p0, ys)
    np.testing.assert_allclose(xs, xs_ref, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ps, ps_ref, rtol=1e-10, atol=1e-12)


def test_theta_zero_is_the_kalman_filter_and_theta_to_zero_tends_to_it():
    rng = np.random.default_rng(1)
    f, h, q, r, _, _ = _system(rng)
    x0, p0 = rng.normal(size=3), 2.0 * np.eye(3)
    ys = rng.normal(size=(30, 2))
    xs_kf, ps_kf = kalman_predictor(f, h, q, r, x0, p0, ys)
    xs, ps = hinf_filter(HInfinityModel(f, h, q, r, 0.0), x0, p0, ys)
    np.testing.assert_allclose(xs, xs_kf, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ps, ps_kf, rtol=1e-10, atol=1e-12)
    gaps = [
        np.abs(hinf_filter(HInfinityModel(f, h, q, r, th), x0, p0, ys)[0] - xs_kf).max()
        for th in (1e-1, 1e-3, 1e-5)
    ]
    assert gaps[0] > gaps[1] > gaps[2] and gaps[2] < 1e-5


@pytest.mark.parametrize(
    ("theta", "p_inf", "gain"), [(0.0, (1 + 5**0.5) / 2, 0.618034), (0.5, 2.0, 1.0)]
)
def test_scalar_steady_state_worked_by_hand(theta, p_inf, gain):
    """F = H = Q = R = L = S = 1: ``P = P / (1 + (1 - theta) P) + 1`` has the fixed point
    ``P = (1 + sqrt(1 + 4 / (1 - theta))) / 2`` -- the golden ratio for the Kalman filter,
    2 for theta = 1/2, where the gain ``P / (1 - theta P + P)`` is 1 (``xhat+ = y``)."""
    model = HInfinityModel(1.0, 1.0, 1.0, 1.0, theta)
    est = HInfinityEstimate([0.0], [[1.0]])
    for _ in range(100):
        est = hinf_step(est, [0.0], model)
    assert est.P[0, 0] == pytest.approx(p_inf, rel=1e-12)
    assert est.P[0, 0] / (1 - theta * est.P[0, 0] + est.P[0, 0]) == pytest.approx(gain, rel=1e-6)
    assert hinf_step(est, [3.0], model).x[0] == pytest.approx(gain * 3.0, rel=1e-6)


def test_existence_condition_is_enforced():
    model = HInfinityModel(1.0, 1.0, 1.0, 1.0, 3.0)
    # M = 1/P - 3 + 1 = -1 < 0 at P = 1; the bound is theta < 1/P + 1 = 2
    with pytest.raises(ValueError, match=r"existence condition.*theta < 2\b"):
        hinf_step(HInfinityEstimate([0.0], [[1.0]]), [0.0], model)
    assert hinf_step(HInfinityEstimate([0.0], [[0.25]]), [0.0], model).P[0, 0] > 0  # M = 2
    with pytest.raises(ValueError, match="existence condition"):
        hinf_step(HInfinityEstimate([0.0], [[0.5]]), [0.0], model)  # M = 0: not definite
    with pytest.raises(ValueError):
        HInfinityModel(1.0, 1.0, 1.0, 0.0, 0.1)  # R must be positive definite
    with pytest.raises(ValueError):
        HInfinityModel(1.0, 1.0, 1.0, 1.0, -0.1)
    with pytest.raises(ValueError):
        HInfinityEstimate([0.0, 0.0], np.diag([1.0, 0.0]))


def _worst_cost(model: HInfinityModel, n_steps: int, p0: np.ndarray) -> float:
    """max over all disturbances d = (x0 - xhat0, w_0.., v_0..) of J(d). The estimation
    error is linear in d (e = T d, T from the filter's unit responses), so the maximum of
    ``d^T T^T S T d / d^T W d`` is the largest generalised eigenvalue of the pair."""
    n, p = model.dim, model.H.shape[0]
    cols = []
    for d in np.eye(n + n_steps * (n + p)):
        x, est, out = d[:n].copy(), HInfinityEstimate(np.zeros(n), p0), []
        w = d[n : n + n * n_steps].reshape(n_steps, n)
        v = d[n + n * n_steps :].reshape(n_steps, p)
        for k in range(n_steps):
            out.append(model.L @ (x - est.x))
            est = hinf_step(est, model.H @ x + v[k], model)
            x = model.F @ x + w[k]
        cols.append(np.concatenate(out))
    t = np.column_stack(cols)
    q_inv, r_inv = np.linalg.inv(model.Q), np.linalg.inv(model.R)
    w_blk = block_diag(np.linalg.inv(p0), *[q_inv] * n_steps, *[r_inv] * n_steps)
    s_blk = np.kron(np.eye(n_steps), model.S)
    return float(eigh(t.T @ s_blk @ t, w_blk, eigvals_only=True)[-1])


def test_the_worst_case_cost_stays_under_one_over_theta():
    """The game bound (Simon's cost): J = sum_k |z_k - zhat_k|^2_S / (|x0 - xhat0|^2_{P0^-1}
    + sum_k |w_k|^2_{Q^-1} + |v_k|^2_{R^-1}) < 1/theta for *every* disturbance, computed
    exactly over 12 steps; the Kalman filter's worst case is larger."""
    f, h, q, r, lm, s = _system(np.random.default_rng(2))
    theta, p0 = 0.2, np.eye(3)
    worst = _worst_cost(HInfinityModel(f, h, q, r, theta, lm, s, condition="a_priori"), 12, p0)
    assert worst < 1.0 / theta
    assert worst < _worst_cost(HInfinityModel(f, h, q, r, 0.0, lm, s), 12, p0)


def test_simons_condition_alone_does_not_give_the_bound():
    """Here Sbar = L^T S L has largest eigenvalue 4 and P0 = I, so P0^-1 - theta Sbar > 0
    needs theta < 1/4. At theta = 1/4 the worst case is exactly 1/theta (x0 - xhat0 along
    the top eigenvector, nothing else); at theta = 0.3 Simon's M_k stays positive definite
    at every step, yet the worst case exceeds 1/theta, and condition="a_priori" refuses."""
    f, h, q, r, lm, s = _system(np.random.default_rng(2))
    p0 = np.eye(3)
    edge = _worst_cost(HInfinityModel(f, h, q, r, 0.25, lm, s), 12, p0)
    assert edge == pytest.approx(4.0, rel=1e-9)
    beyond = _worst_cost(HInfinityModel(f, h, q, r, 0.3, lm, s), 12, p0)  # "simon": runs
    assert beyond > 1.0 / 0.3 + 0.5
    strict = HInfinityModel(f, h, q, r, 0.3, lm, s, condition="a_priori")
    with pytest.raises(ValueError, match=r"P\^-1 - theta Sbar is not.*theta < 0.25\b"):
        hinf_step(HInfinityEstimate(np.zeros(3), p0), np.zeros(2), strict)


def test_filterpy_agrees_only_when_f_is_the_identity():
    """filterpy's gamma = theta, Q = Sbar, W = Q, V = R. Its covariance recursion is
    Simon's; its state recursion applies F twice to the correction (see the module)."""
    rng = np.random.default_rng(3)
    h, q, r, theta = np.array([[1.0, 0.3]]), 0.01 * np.eye(2), np.array([[0.1]]), 0.05
    ys = rng.normal(size=10)
    for f_mat, agrees in ((np.eye(2), True), (np.array([[1.0, 0.1], [0.0, 1.0]]), False)):
        with pytest.warns(DeprecationWarning):
            fp = HInfinityFilter(2, 1, 1, theta)
        fp.F, fp.H, fp.W, fp.V, fp.Q = f_mat, h, q, r, np.eye(2)
        fp.P, fp.x = np.eye(2), np.zeros((2, 1))
        xs, ps = hinf_filter(HInfinityModel(f_mat, h, q, r, theta), np.zeros(2), np.eye(2), ys)
        for y in ys:
            fp.update(np.array([[y]]))
            fp.predict()
        np.testing.assert_allclose(fp.P, ps[-1], rtol=1e-10)  # P always agrees
        assert np.allclose(fp.x.ravel(), xs[-1], rtol=1e-10) == agrees


def test_a_filter_that_runs_off_is_reported_diverged_not_a_failed_run():
    """``estimator.hinf.theta=0.999999`` (accepted: theta < 1) let the mean run off to
    ~1e308 and every run failed with ``OverflowError`` in the EKF's Jacobian. The
    Gaussian filters now report such a prediction as ``Status.DIVERGED`` (the belief is
    emptied and guidance stops on its channel), as the sets do, and the run completes."""
    import kalman_vs_infoset as kvi

    sc = kvi.load_scenario("kp_fig5", estimator={"hinf": {"theta": 0.999999}})
    row = kvi.run_engagement(sc, "hinf", "random", run=0).as_row()
    assert row["diverged"] and row["final_status"] == "diverged"
    assert kvi.run_engagement("kp_fig5", "hinf", "random", run=0).as_row()["diverged"] is False
