"""The PLID recursions: exact moments, direct vs square-root, long low-noise runs."""

import warnings

import numpy as np
import pytest

from trussid.plid.canonical import ObserverBasis
from trussid.plid.estimator import PLID, PLIDWarning
from trussid.plid.recursion_common import Problem
from trussid.plid.recursion_direct import direct_init, direct_step
from trussid.plid.recursion_sqrt import sqrt_covariance, sqrt_init, sqrt_step


def _one_step_monte_carlo(pb, z0, P0, u, y, rng, n_draws):
    """Sample mean and covariance of [theta; x_next] by brute force.

    The posterior of z given y is the linear-Gaussian Kalman update (written out here
    independently); then x_next = (F + Abar C) x + B (u - n) + w through the true bilinear
    map, so no moment formula of the recursion is reused.
    """
    n, p, m, q = pb.n, pb.p, pb.m, pb.q
    H = np.hstack([np.zeros((p, q)), pb.C])
    S = H @ P0 @ H.T + pb.R
    K = P0 @ H.T @ np.linalg.inv(S)
    zp = z0 + K @ (y - H @ z0)
    Pp = P0 - K @ S @ K.T
    Z = rng.multivariate_normal(zp, 0.5 * (Pp + Pp.T), size=n_draws, method="eigh")
    Nn = rng.multivariate_normal(np.zeros(m), pb.N, size=n_draws)
    W = rng.multivariate_normal(np.zeros(n), pb.Q, size=n_draws)
    theta, x = Z[:, :q], Z[:, q:]
    Abar = theta[:, :n * p].reshape(-1, p, n).transpose(0, 2, 1)
    Bm = theta[:, n * p:].reshape(-1, m, n).transpose(0, 2, 1)
    A = pb.F[None] + Abar @ pb.C[None]
    x_next = (A @ x[:, :, None])[:, :, 0] + (Bm @ (u[None, :] - Nn)[:, :, None])[:, :, 0] + W
    out = np.hstack([theta, x_next])
    return out.mean(axis=0), np.cov(out.T)


@pytest.mark.parametrize("step,init,cov", [
    (direct_step, direct_init, lambda st: st.P),
    (sqrt_step, sqrt_init, sqrt_covariance),
])
def test_time_update_moments_match_monte_carlo(step, init, cov):
    rng = np.random.default_rng(7)
    n, p, m = 2, 1, 2
    pb = Problem(ObserverBasis.shift(n, p), m, Q=0.01 * np.eye(n), R=np.array([[0.2]]),
                 N=np.diag([0.3, 0.1]), Q_theta=None)
    # A broad prior so that the second-order (Isserlis) terms are large.
    G = rng.standard_normal((pb.dim, pb.dim))
    P0 = 0.3 * G @ G.T / pb.dim + 0.2 * np.eye(pb.dim)
    z0 = rng.standard_normal(pb.dim)
    u, y = np.array([0.7, -1.1]), np.array([0.9])
    st = init(pb, z0, P0)
    e = np.empty(p)
    step(pb, st, u, y, e)
    n_draws = 400_000
    mean_mc, cov_mc = _one_step_monte_carlo(pb, z0, P0, u, y, rng, n_draws)
    P_new = cov(st)
    sd = np.sqrt(np.diag(cov_mc))
    # Monte-Carlo standard errors: mean sd/sqrt(N), covariance ~ sd_i sd_j sqrt(2/N).
    assert np.all(np.abs(st.z - mean_mc) <= 5 * sd / np.sqrt(n_draws))
    tol = 6 * np.outer(sd, sd) * np.sqrt(2.0 / n_draws)
    assert np.all(np.abs(P_new - cov_mc) <= tol)


def test_second_order_terms_are_significant_in_the_moment_check():
    # Guard for the test above: without the Isserlis terms the x covariance would be
    # visibly wrong at that prior, so the check does test them.
    rng = np.random.default_rng(7)
    n, p, m = 2, 1, 2
    pb = Problem(ObserverBasis.shift(n, p), m, Q=0.01 * np.eye(n), R=np.array([[0.2]]),
                 N=np.diag([0.3, 0.1]), Q_theta=None)
    G = rng.standard_normal((pb.dim, pb.dim))
    P0 = 0.3 * G @ G.T / pb.dim + 0.2 * np.eye(pb.dim)
    z0 = rng.standard_normal(pb.dim)
    u, y = np.array([0.7, -1.1]), np.array([0.9])
    st = direct_init(pb, z0, P0)
    direct_step(pb, st, u, y, np.empty(p))
    _, cov_mc = _one_step_monte_carlo(pb, z0, P0, u, y, rng, 400_000)
    # First-order (linearised) propagation of the same Kalman posterior, written out densely.
    q = pb.q
    H = np.hstack([np.zeros((p, q)), pb.C])
    S = H @ P0 @ H.T + pb.R
    K = P0 @ H.T @ np.linalg.inv(S)
    Pp = P0 - K @ S @ K.T
    zp = z0 + K @ (y - H @ z0)
    Abar = zp[:n * p].reshape(p, n).T
    A = pb.F + Abar @ pb.C
    Phi = np.kron(np.r_[pb.C @ zp[q:], u][None, :], np.eye(n))
    Fx = np.hstack([Phi, A])
    first_order = Fx @ Pp @ Fx.T + pb.Q
    assert np.max(np.abs(first_order - cov_mc[q:, q:])) > 10 * np.max(
        np.abs(st.P[q:, q:] - cov_mc[q:, q:]))


@pytest.mark.parametrize("n,m,p,snr,extra", [
    (4, 1, 1, 40, {}),
    (12, 1, 3, 60, {}),
    (12, 3, 3, 40, {"N": 1e-4, "Q_theta": 1e-8}),
])
def test_direct_and_sqrt_forms_give_the_same_estimates(n, m, p, snr, extra, modal_plant,
                                                       simulate, rng):
    plant = modal_plant(np.linspace(50, 350, n // 2), [0.02] * (n // 2), m, p, 1600, rng)
    u = rng.standard_normal((1000, m))
    y, _ = simulate(plant, u, rng, snr)
    # Well conditioned: a prior variance of the size of the coefficients (|theta| < 10
    # here). With the default 1e4 prior the direct form's round-off alone separates the
    # two forms by 1e-9 .. 3e-8 on these problems.
    kw = dict(R=10 ** (-snr / 10), prior_theta_var=1e2, **extra)
    d = PLID(n, form="direct", **kw).fit(u, y)
    s = PLID(n, form="sqrt", **kw).fit(u, y)
    assert np.linalg.norm(d.theta - s.theta) <= 1e-8 * np.linalg.norm(s.theta)
    assert np.linalg.norm(d.x - s.x) <= 1e-8 * np.linalg.norm(s.x)
    assert d.cov_min_eig > 0 and s.cov_min_eig > 0


@pytest.mark.slow
def test_sqrt_form_stays_positive_definite_at_200db_where_direct_does_not(
        full, modal_plant, simulate, rng):
    # Full form: 1e6 samples (TRUSSID_FULL=1). Reduced form: 5000 samples, which already
    # shows the direct form's loss of definiteness (within the first tens of samples).
    n_samples = 1_000_000 if full else 5000
    plant = modal_plant([120.0, 330.0], [0.02, 0.02], 1, 1, 1600, rng)
    u = rng.standard_normal((n_samples, 1))
    y, _ = simulate(plant, u, rng, 200)
    kw = dict(R=1e-20, Q=0.0, history_every=0, progress=full)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = PLID(4, form="direct", **kw).fit(u, y)
    assert any(issubclass(w.category, PLIDWarning) for w in caught)
    assert not (d.finite and d.cov_min_eig > 0)
    assert d.first_negative_variance is not None
    with warnings.catch_warnings():
        warnings.simplefilter("error", PLIDWarning)
        s = PLID(4, form="sqrt", **kw).fit(u, y)
    assert s.finite and s.cov_min_eig > 0
    assert np.all(np.isfinite(s.theta_cov))
    # and the square-root estimate is the better one-step predictor at the end
    tail = slice(-1000, None)
    assert np.sqrt(np.mean(s.innovations[tail] ** 2)) < np.sqrt(np.mean(d.innovations[tail] ** 2))
