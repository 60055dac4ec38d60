"""Metrics: prediction ratio, simulation fit, FRF error and pole matching against closed forms."""

import control
import numpy as np
import pytest
import scipy.linalg

from trussid.plid.errors import DataError
from trussid.plid.experiment import run_experiment, simulate
from trussid.plid.frf import FRF, frequency_response
from trussid.plid.metrics import (compare_poles, frf_error, modal_parameters, one_step_predict,
                          prediction_ratio_db, predictor_gain, simulation_fit)

FS = 1000.0
MODES = [(60.0, 0.02), (210.0, 0.01), (330.0, 0.05)]


def continuous_plant(modes=MODES, n_in=1):
    k = len(modes)
    A = np.zeros((2 * k, 2 * k))
    for i, (f, z) in enumerate(modes):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w**2, -2 * z * w]]
    rng = np.random.default_rng(1)
    B = np.zeros((2 * k, n_in))
    B[1::2] = rng.uniform(0.5, 1.5, (k, n_in))
    C = np.zeros((2, 2 * k))
    C[:, 0::2] = 1e4 * rng.uniform(0.5, 1.5, (2, k))
    return control.ss(A, B, C, np.zeros((2, n_in)))


@pytest.fixture
def plant():
    return control.c2d(continuous_plant(), 1 / FS)


def test_modal_parameters_of_a_zoh_plant_are_the_continuous_ones(plant):
    f, z, _ = modal_parameters(plant)
    np.testing.assert_allclose(f, [m[0] for m in MODES], rtol=1e-10)
    np.testing.assert_allclose(z, [m[1] for m in MODES], rtol=1e-8)
    fc, zc, _ = modal_parameters(continuous_plant())
    np.testing.assert_allclose(fc, f, rtol=1e-10)


def test_pole_matching_pairs_each_true_mode_with_its_estimate(plant):
    # An "identified" model: the modes shifted a little, listed in another order, plus a
    # spurious real pole.
    shifted = [(330.0 * 1.001, 0.051), (60.0 * 0.999, 0.021), (210.0 * 1.002, 0.0105)]
    ident = control.append(control.c2d(continuous_plant(shifted), 1 / FS),
                           control.ss([[0.3]], [[1.0]], [[1.0]], [[0.0]], 1 / FS))
    rows = compare_poles(ident, plant)
    assert len(rows) == 4
    for row, (f, z) in zip(rows[:3], MODES):
        assert row.true_frequency_hz == pytest.approx(f)
        est = next(s for s in shifted if abs(s[0] - f) < 2)
        assert row.frequency_hz == pytest.approx(est[0], rel=1e-9)
        assert row.damping == pytest.approx(est[1], rel=1e-6)
        assert row.frequency_error_percent == pytest.approx(100 * (est[0] / f - 1), rel=1e-6)
    spurious = rows[3]
    assert spurious.true_frequency_hz is None
    assert spurious.frequency_hz == pytest.approx(np.log(0.3) * -FS / (2 * np.pi))


def test_far_pairs_are_not_called_matches(plant):
    far = control.c2d(continuous_plant([(60.0, 0.02), (420.0, 0.02), (330.0, 0.05)]), 1 / FS)
    rows = compare_poles(far, plant)
    by_true = {round(r.true_frequency_hz): r for r in rows
               if r.true_frequency_hz is not None}
    assert by_true[60].frequency_hz == pytest.approx(60.0)
    assert by_true[210].frequency_hz is None  # 420 Hz is 100 % away
    extra = [r for r in rows if r.true_frequency_hz is None]
    assert [r.frequency_hz for r in extra] == [pytest.approx(420.0)]
    kept = compare_poles(far, plant, max_relative_distance=None)
    assert all(r.frequency_hz is not None for r in kept) and len(kept) == 3


def test_frf_error_of_a_gain_error_is_that_gain_in_db(plant):
    err = frf_error(plant * 1.1, plant, band=(10, 450))
    assert err.max_db == pytest.approx(20 * np.log10(1.1), rel=1e-9)
    assert err.rms_db == pytest.approx(20 * np.log10(1.1), rel=1e-9)
    assert err.max_deg < 1e-9
    assert np.shape(err.per_channel["max_db"]) == (2, 1)


def test_frf_error_of_a_one_sample_delay_is_a_linear_phase(plant):
    delay = control.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]], 1 / FS)  # z^-1
    err = frf_error(plant * delay, plant, band=(10, 450))
    assert err.max_db < 1e-9
    assert err.max_deg == pytest.approx(360 * 450 / FS, rel=1e-6)


def test_frf_error_against_an_estimate_uses_its_grid(plant):
    f = np.linspace(0, 500, 101)
    ref = FRF(f=f, H=frequency_response(plant, f) * 10 ** (0.5 / 20))
    err = frf_error(plant, ref, band=(20, 400))
    assert err.max_db == pytest.approx(0.5, rel=1e-9)
    assert err.band == (20.0, 400.0)


def test_frf_error_refuses_mismatched_sizes(plant):
    with pytest.raises(DataError, match="the model has 1 inputs and 2 outputs, the reference 1 "
                                        "and 1"):
        frf_error(plant, plant[0, 0])


def test_simulation_fit_of_a_gain_error_is_closed_form(plant, rng):
    u = rng.standard_normal((2000, 1))
    y = simulate(plant, u)
    fit = simulation_fit(plant * (1 + 1e-3), u, y)
    np.testing.assert_allclose(fit.per_output, [60.0, 60.0], rtol=1e-9)
    assert fit.overall == pytest.approx(60.0, rel=1e-9)
    np.testing.assert_allclose(fit.nrmse_percent, 99.9, atol=1e-3)


def test_prediction_ratio_of_the_true_plant_is_the_sensor_snr(plant):
    e = run_experiment(plant, 20000, seed=2, snr_db=30.0)
    sigma2 = e.sensor_noise_rms**2
    # No state noise: the optimal predictor is the plant itself (K = 0); its error is the
    # sensor noise, so the ratio is RMS(y)/RMS(noise) = sqrt(1 + 10^-3) * 10^(30/20).
    K = predictor_gain(plant, np.zeros((6, 6)), np.diag(sigma2))
    assert np.max(np.abs(K)) < 1e-12
    r = prediction_ratio_db(plant, e.data.u, e.data.y, K=K)
    noise = e.data.y - e.y_clean
    realised = 20 * np.log10(np.sqrt(np.mean(e.data.y**2, 0) / np.mean(noise**2, 0)))
    np.testing.assert_allclose(r.per_output, realised, rtol=1e-9)
    # overall: the thesis's RMS over all sensors and samples; mean_normalised: the mean of
    # the per-channel normalised error powers
    pooled = 10 * np.log10(np.sum(e.data.y**2) / np.sum(noise**2))
    assert r.overall == pytest.approx(pooled, rel=1e-9)
    normalised = -10 * np.log10(np.mean(np.mean(noise**2, 0) / np.mean(e.data.y**2, 0)))
    assert r.mean_normalised == pytest.approx(normalised, rel=1e-9)
    # and that is the requested SNR up to the sampling spread of the noise power
    # (relative std 1/sqrt(2 N) = 0.5 %, i.e. 0.03 dB; allow 4 sigma)
    np.testing.assert_allclose(realised, 30.0 + 10 * np.log10(1 + 1e-3), atol=0.13)


def test_predictor_gain_agrees_with_python_control_dlqe(plant):
    Q = 1e-6 * np.eye(6)
    R = np.diag([1e-4, 4e-4])
    K = predictor_gain(plant, Q, R)
    L, _, _ = control.dlqe(plant.A, np.eye(6), plant.C, Q, R)  # its L is the predictor gain
    np.testing.assert_allclose(K, L, rtol=1e-8, atol=1e-10 * np.abs(K).max())


def test_optimal_predictor_errors_are_white_with_state_noise(plant, rng):
    n = 30000
    Q = 1e-8 * np.eye(6)
    R = np.diag([1e-4, 1e-4])
    w = rng.standard_normal((n, 6)) * 1e-4
    u = rng.standard_normal((n, 1))
    aug = control.ss(plant.A, np.hstack([plant.B, np.eye(6)]), plant.C, np.zeros((2, 7)), 1 / FS)
    y = simulate(aug, np.hstack([u, w])) + rng.standard_normal((n, 2)) * 1e-2
    K = predictor_gain(plant, Q, R)
    e = y - one_step_predict(plant, u, y, K=K)
    e = e[1000:, 0] - e[1000:, 0].mean()
    lags = [np.dot(e[:-k], e[k:]) / np.dot(e, e) for k in range(1, 11)]
    assert np.max(np.abs(lags)) < 4 / np.sqrt(e.size)  # white within sampling error
    # and the simulation (K = 0) error is far from white
    e0 = y - simulate(plant, u)
    assert np.dot(e0[:-1, 0], e0[1:, 0]) / np.dot(e0[:, 0], e0[:, 0]) > 0.5


def test_prediction_needs_matching_sizes(plant, rng):
    with pytest.raises(DataError, match="the model has 2 outputs but the data has 3"):
        prediction_ratio_db(plant, rng.standard_normal((10, 1)), rng.standard_normal((10, 3)))


def _innovations_plant(rng):
    """x+ = A x + B u + K e, y = C x + e: a known noise model (two lightly damped modes)."""
    from trussid.plid.metrics import predictor_gain

    A = np.zeros((4, 4))
    for i, (r, w) in enumerate([(0.97, 0.3), (0.95, 1.1)]):
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = r * np.array([[np.cos(w), -np.sin(w)],
                                                             [np.sin(w), np.cos(w)]])
    B = rng.standard_normal((4, 1))
    C = rng.standard_normal((2, 4))
    W = rng.standard_normal((4, 4))
    # a steady-state Kalman gain of some state noise: its predictor A - K C is stable
    K = predictor_gain(control.ss(A, B, C, np.zeros((2, 1)), 1.0), 0.05 * W @ W.T, np.eye(2))
    return A, B, C, K


def _innovations_data(A, B, C, K, n_samples, rng):
    u = rng.standard_normal((n_samples, 1))
    e = 0.5 * rng.standard_normal((n_samples, 2))
    x = np.zeros(4)
    y = np.empty((n_samples, 2))
    for k in range(n_samples):
        y[k] = C @ x + e[k]
        x = A @ x + B @ u[k] + K @ e[k]
    return u, y


def test_least_squares_gain_refinement_recovers_a_known_noise_model(rng):
    from trussid.plid.metrics import refine_predictor_gain

    A, B, C, K = _innovations_plant(rng)
    u, y = _innovations_data(A, B, C, K, 6000, rng)
    model = control.ss(A, B, C, np.zeros((2, 1)), 1.0)
    gains = refine_predictor_gain(model, u, y)          # from a long autoregression
    assert gains
    assert np.linalg.norm(gains[-1] - K) < 0.1 * np.linalg.norm(K)


def test_best_predictor_is_never_worse_than_simulation_and_near_the_true_gain(rng):
    from trussid.plid.metrics import SCORE_TIE_DB, best_predictor

    A, B, C, K = _innovations_plant(rng)
    u, y = _innovations_data(A, B, C, K, 4000, rng)
    model = control.ss(A, B, C, np.zeros((2, 1)), 1.0)
    K_best, label, info = best_predictor(model, u, y)
    sc = info["identification_ratio_db"]
    assert sc[label] >= max(sc.values()) - SCORE_TIE_DB
    assert sc[label] >= sc["none (free-run simulation)"]
    skip = u.shape[0] // 8
    truth = prediction_ratio_db(model, u, y, K=K, skip=skip).mean_normalised
    assert sc[label] > truth - 0.05          # as good as the true noise model, to 0.05 dB


def test_best_predictor_gives_a_rounding_level_tie_to_the_earlier_candidate(rng):
    # a candidate a hair from K = 0 (the recursion's own gain can be 1e-10 of nothing)
    # scores the same as K = 0 to rounding; which one is "higher" is then a matter of
    # summation order, and the choice must not flip on it: K = 0 comes first and keeps it
    from trussid.plid.metrics import SCORE_TIE_DB, best_predictor

    A, B, C, K = _innovations_plant(rng)
    model = control.ss(A, B, C, np.zeros((2, 1)), 1.0)
    u, y = _innovations_data(A, B, C, K, 2000, rng)
    zero = "none (free-run simulation)"
    ahead = []
    for sign in (1.0, -1.0, 3.0, -3.0):
        hair = sign * 1e-12 * K
        # K = 0 and the hair alone (no Kalman candidates)
        _, label, info = best_predictor(model, u, y, {"hair": hair}, ratios=(), iso_ratios=(),
                                        refine=False)
        sc = info["identification_ratio_db"]
        assert set(sc) == {zero, "hair"}
        assert abs(sc["hair"] - sc[zero]) < SCORE_TIE_DB
        assert label == zero
        ahead.append(sc["hair"] > sc[zero])
    assert any(ahead)              # the hair was "higher" by rounding at least once


def test_predictor_gains_solve_each_riccati_equation_as_scipy_does(plant):
    # The batched doubling solve against scipy's solve_discrete_are (QZ), one Q at a time:
    # the 0.25-2 % damped plant's gains over eight decades of state-to-output noise.
    from trussid.plid.metrics import predictor_gains

    n = plant.nstates
    R = np.diag([1e-4, 4e-4])
    B = np.asarray(plant.B)
    Qs = [a * (B @ B.T + 1e-3 * np.eye(n)) for a in (1e2, 1.0, 1e-2, 1e-4, 1e-6)]
    Qs += [a * np.eye(n) for a in (1e-4, 1.0)]
    A, C = np.asarray(plant.A), np.asarray(plant.C)

    def riccati_residual(K):
        # P of the predictor with gain K (its Lyapunov equation), put into the filter
        # Riccati equation: zero for the optimal gain
        P = scipy.linalg.solve_discrete_lyapunov(A - K @ C, Q + K @ R @ K.T)
        G = A @ P @ A.T - A @ P @ C.T @ np.linalg.solve(C @ P @ C.T + R, C @ P @ A.T) + Q
        return np.linalg.norm(G - P) / np.linalg.norm(P)

    for K, Q in zip(predictor_gains(plant, Qs, R), Qs):
        Kr = predictor_gain(plant, Q, R)
        # the doubling solves each equation to a relative residual of at most 1.5e-10
        # here (scipy's QZ to 1e-15 on the worst, Q = 1e-6 (B B^T + ...)), so the gains
        # agree to 7e-5 relative there and to 1e-8 elsewhere: candidates for a
        # prediction-error refinement, not a gain to be used as is
        assert riccati_residual(K) <= 1e-9
        np.testing.assert_allclose(K, Kr, rtol=2e-4, atol=1e-7 * np.abs(Kr).max())


def test_predictor_gains_give_none_where_no_stabilising_solution_exists():
    # an unstable mode the output does not see: no stabilising predictor, for any Q
    from trussid.plid.metrics import predictor_gains

    sys_ = control.ss(np.diag([1.2, 0.5]), np.ones((2, 1)), [[0.0, 1.0]], [[0.0]], 1.0)
    with pytest.raises(DataError):
        predictor_gain(sys_, np.eye(2), np.eye(1))
    assert predictor_gains(sys_, [np.eye(2), 1e-3 * np.eye(2)], np.eye(1)) == [None, None]
