"""Prediction-error refinement of the predictor gain (:mod:`trussid.plid.pem`)."""

import numpy as np
import pytest
import scipy.linalg

from trussid.plid.experiment import simulate
from trussid.plid.metrics import predictor_gain
from trussid.plid.pem import refine_gain, refine_gain_from, significant_change


@pytest.fixture(scope="module")
def coloured():
    """The accelerometer plant (A, B, C, D known) with a narrow-band output disturbance
    that no Kalman gain of the plant represents: the gain has work to do."""
    from tests.plid.plants import accelerometer_plant

    plant = accelerometer_plant(seed=5)
    rng = np.random.default_rng(21)
    u = rng.standard_normal((2500, plant.ninputs))
    y0 = simulate(plant, u)
    w = rng.standard_normal(y0.shape)
    v = np.zeros_like(w)
    for k in range(2, len(w)):
        v[k] = 1.9 * np.cos(0.3) * v[k - 1] - 0.9025 * v[k - 2] + w[k]
    y = y0 + 0.3 * v * np.std(y0, 0) / np.std(v, 0)
    n, p = plant.nstates, plant.noutputs
    sy2 = np.mean(y ** 2, 0)
    starts = {"kalman": predictor_gain(plant, 1e-2 * np.eye(n) * sy2.mean(), np.diag(sy2)),
              "zero": np.zeros((n, p))}
    return plant, u, y, starts


def _logdet_of(plant, u, y, K, x0):
    """``log det`` of the innovation covariance (outputs scaled to unit RMS) of the
    predictor with gain ``K`` from ``x0``, by an explicit loop over the samples."""
    A, B, C, D = (np.asarray(M, float) for M in (plant.A, plant.B, plant.C, plant.D))
    x = np.array(x0, float)
    E = np.empty_like(y)
    for k in range(len(y)):
        E[k] = y[k] - C @ x - D @ u[k]
        x = A @ x + B @ u[k] + K @ E[k]
    E /= np.sqrt(np.mean(y ** 2, 0))
    return np.linalg.slogdet(E.T @ E / len(E))[1]


def test_refine_gain_from_keeps_the_start_that_leads_after_the_race(coloured):
    plant, u, y, starts = coloured
    race, total = 2, 8
    got = refine_gain_from(plant, u, y, starts, iterations=total, race=race,
                           race_gap=np.inf)
    # independently: each start refined alone for the race's iterations
    heats = {lab: refine_gain(plant, u, y, K0, iterations=race).logdet_end
             for lab, K0 in starts.items()}
    assert got.race_logdet == pytest.approx(heats, rel=1e-12)
    assert got.start == min(heats, key=heats.get)
    # the leader continues as an uninterrupted refinement from its start would
    alone = refine_gain(plant, u, y, starts[got.start], iterations=total)
    np.testing.assert_allclose(got.fit.K, alone.K, rtol=1e-10, atol=1e-12 * np.abs(alone.K).max())
    assert got.fit.iterations == alone.iterations
    # its criterion is the predictor's, computed sample by sample from the returned K, x0
    assert got.fit.logdet_end == pytest.approx(_logdet_of(plant, u, y, got.fit.K, got.fit.x0),
                                               abs=1e-8)
    assert got.fit.logdet_end <= min(heats.values())


def test_a_start_too_far_behind_at_the_start_does_not_race(coloured):
    # a gap under the two starts' difference: the one behind keeps its start value (its
    # criterion with x0 fitted, recomputed sample by sample) and the other continues as a
    # refinement from it alone would; with no gap both race and the same start is kept
    plant, u, y, starts = coloured
    at_start = {lab: refine_gain(plant, u, y, K0, iterations=0) for lab, K0 in starts.items()}
    logdet0 = {lab: _logdet_of(plant, u, y, starts[lab], f.x0) for lab, f in at_start.items()}
    ahead, behind = sorted(logdet0, key=logdet0.get)
    gap = logdet0[behind] - logdet0[ahead]
    assert gap > 0.05
    got = refine_gain_from(plant, u, y, starts, iterations=6, race_gap=0.5 * gap)
    assert got.start == ahead
    assert got.race_logdet[behind] == pytest.approx(logdet0[behind], abs=1e-8)
    alone = refine_gain(plant, u, y, starts[ahead], iterations=6)
    np.testing.assert_allclose(got.fit.K, alone.K, rtol=1e-10, atol=1e-12 * np.abs(alone.K).max())
    full = refine_gain_from(plant, u, y, starts, iterations=6, race_gap=np.inf)
    assert full.start == ahead
    assert full.race_logdet[behind] < got.race_logdet[behind]


def test_the_significance_stop_ends_at_the_first_step_that_gains_less_than_q_over_n(coloured):
    plant, u, y, starts = coloured
    N, p, n = y.shape[0], plant.noutputs, plant.nstates
    least = significant_change(N, n, p)
    assert least == pytest.approx((n * p + n) / N)
    fit = refine_gain(plant, u, y, starts["kalman"], iterations=30, tol=None)
    assert fit.converged and 1 <= fit.iterations < 30
    # independently: the same start refined for a fixed number of steps (tol 0 never
    # stops early), the criterion recomputed sample by sample from each returned K, x0
    path = [refine_gain(plant, u, y, starts["kalman"], iterations=i, tol=0.0)
            for i in range(fit.iterations + 1)]
    logdets = [_logdet_of(plant, u, y, f.K, f.x0) for f in path]
    gains = -np.diff(logdets)
    assert np.all(gains[:-1] >= least)           # every earlier step was significant
    assert 0 <= gains[-1] < least                # the last one was not, and ended it
    np.testing.assert_allclose(fit.K, path[-1].K, rtol=1e-10, atol=1e-12 * np.abs(fit.K).max())


def test_refine_gain_from_is_indifferent_to_the_order_of_the_starts(coloured):
    plant, u, y, starts = coloured
    a = refine_gain_from(plant, u, y, starts, iterations=6)
    b = refine_gain_from(plant, u, y, dict(reversed(list(starts.items()))), iterations=6)
    assert a.start == b.start
    np.testing.assert_array_equal(a.fit.K, b.fit.K)


def test_refine_gain_from_gives_a_rounding_level_tie_to_the_earlier_start(coloured):
    # two starts a hair apart reach the same point after the race; which one is "lower" is
    # then a matter of summation order, and the kept start must not flip on it: the earlier
    # start (identify puts its chosen candidate first) keeps the lead
    plant, u, y, starts = coloured
    K0 = starts["kalman"]
    twin = K0 * (1 + 1e-13)
    a = refine_gain_from(plant, u, y, {"first": K0, "twin": twin}, iterations=4)
    b = refine_gain_from(plant, u, y, {"twin": twin, "first": K0}, iterations=4)
    assert abs(a.race_logdet["first"] - a.race_logdet["twin"]) < 1e-9
    assert (a.start, b.start) == ("first", "twin")


def test_refine_gain_from_refines_a_repeated_start_once(coloured):
    plant, u, y, starts = coloured
    got = refine_gain_from(plant, u, y, {"a": starts["kalman"], "b": starts["kalman"].copy()},
                           iterations=4)
    assert list(got.race_logdet) == ["a"]
    alone = refine_gain(plant, u, y, starts["kalman"], iterations=4)
    np.testing.assert_array_equal(got.fit.K, alone.K)


def test_normal_equations_in_modal_coordinates_equal_those_of_a_finite_difference_jacobian():
    # J by central differences of the predictor's residual in vec K (column-major) and
    # x0, with no modal algebra; the Gram matrix and gradient the Levenberg-Marquardt step
    # uses must be J^T W^T W J and J^T W^T W e of it. A well-scaled 2 x 2 system with two
    # resonances and a real pole (differences need comparable parameter scales).
    from trussid.plid.pem import _normal_equations

    rng = np.random.default_rng(3)
    blocks = [0.95 * np.array([[np.cos(w), -np.sin(w)], [np.sin(w), np.cos(w)]])
              for w in (0.3, 1.1)]
    A = scipy.linalg.block_diag(*blocks, [[0.6]])
    n, p, m = 5, 2, 2
    B, C, D = rng.standard_normal((n, m)), rng.standard_normal((p, n)), np.zeros((p, m))
    K = 0.02 * rng.standard_normal((n, p))
    assert np.max(np.abs(np.linalg.eigvals(A - K @ C))) < 1
    x0 = rng.standard_normal(n)
    W = np.linalg.cholesky(np.array([[2.0, 0.3], [0.3, 1.0]])).T
    uu = rng.standard_normal((400, m))
    yy = rng.standard_normal((400, p))

    def residual(theta):
        Kt = theta[:n * p].reshape(p, n).T
        xt = np.array(theta[n * p:])
        E = np.empty_like(yy)
        for k in range(len(yy)):
            E[k] = yy[k] - C @ xt - D @ uu[k]
            xt = A @ xt + B @ uu[k] + Kt @ E[k]
        return E

    theta = np.concatenate([K.T.ravel(), x0])
    E = residual(theta)
    h = 1e-6
    J = np.empty((len(yy), p, theta.size))
    for i in range(theta.size):
        d = np.zeros_like(theta)
        d[i] = h
        # yhat = y - e: d yhat / d theta = -d e / d theta
        J[:, :, i] = -(residual(theta + d) - residual(theta - d)) / (2 * h)
    JW = np.matmul(W, J).reshape(-1, theta.size)
    H_fd, g_fd = JW.T @ JW, JW.T @ (E @ W.T).ravel()
    H, g = _normal_equations(A - K @ C, C, E, W)
    np.testing.assert_allclose(H, H_fd, rtol=0, atol=1e-7 * np.abs(H_fd).max())
    np.testing.assert_allclose(g, g_fd, rtol=0, atol=1e-7 * np.abs(g_fd).max())


def test_a_start_dropped_before_the_race_is_never_kept_even_with_no_gap(coloured):
    # race_gap 0: only the start lowest at the start races; a tie tolerance wide enough to
    # take in the dropped start (10 in log det) must not bring it back
    plant, u, y, starts = coloured
    got = refine_gain_from(plant, u, y, starts, iterations=3, race_gap=0.0, tol=10.0)
    at_start = {lab: refine_gain(plant, u, y, K0, iterations=0).logdet_end
                for lab, K0 in starts.items()}
    assert got.start == min(at_start, key=at_start.get)
