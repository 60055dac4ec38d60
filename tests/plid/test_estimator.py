"""The PLID estimator: accuracy (issue 5 items 1-3, 5), units, predictor gain, bad input."""

import control
import numpy as np
import pytest

from tests.plid.arx import arx_observer_form
from trussid.plid.canonical import ObserverBasis, from_statespace
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.estimator import PLID


def _rel(a, b):
    return np.linalg.norm(a - b) / np.linalg.norm(b)


# ---------------------------------------------------------------- item 1: noiseless
@pytest.mark.parametrize("n,m,p", [(4, 1, 1), (12, 1, 3), (12, 3, 3)])
def test_noiseless_data_gives_parameters_to_1e_8_and_roundoff_innovations(
        n, m, p, modal_plant, simulate, rng):
    plant = modal_plant(np.linspace(50, 350, n // 2), [0.02] * (n // 2), m, p, 1600, rng)
    theta_true, _ = from_statespace(plant, ObserverBasis.shift(n, p))
    u = rng.standard_normal((1000, m))
    y, _ = simulate(plant, u)
    # Noiseless: no state noise, output noise at round-off level (R must be > 0).
    res = PLID(n, R=1e-14, Q=0.0, dt=plant.dt).fit(u, y)
    assert _rel(res.theta, theta_true) <= 1e-8
    tail = res.innovations[-200:]
    assert np.max(np.abs(tail)) <= 1e-10 * np.max(np.abs(y))
    assert res.model.dt == plant.dt and res.model.nstates == n


# ---------------------------------------------------------------- item 2: 20 dB vs ARX
def test_20db_parameter_error_is_20_times_below_least_squares(modal_plant, simulate, rng):
    # 4 lightly damped states (1 % at 60 and 180 Hz, 1600 Hz sampling), collocated force
    # in / displacement out, white output noise 20 dB below the output RMS, 4000 samples.
    plant = modal_plant([60.0, 180.0], [0.01, 0.01], 1, 1, 1600, rng, collocated=True)
    theta_true, _ = from_statespace(plant, ObserverBasis.shift(4, 1))
    u = rng.standard_normal((4000, 1))
    y, _ = simulate(plant, u, rng, snr_db=20)
    theta_arx = arx_observer_form(u, y, 4)
    res = PLID(4, R=10 ** (-20 / 10)).fit(u, y)
    err_plid = _rel(res.theta, theta_true)
    err_arx = _rel(theta_arx, theta_true)
    assert err_plid * 20 <= err_arx
    assert err_plid < 5e-3  # the prototype's figure in docs/plid.md


# ---------------------------------------------------------------- item 3: unstable plant
def test_unstable_plant_poles_found_from_300_samples_at_60db(simulate, rng):
    fs = 1600.0
    p_u = 1.02 * np.exp(2j * np.pi * 60 / fs)
    p_s = 0.97 * np.exp(2j * np.pi * 200 / fs)
    plant = control.ss(control.zpk([0.5, -0.3], [p_u, np.conj(p_u), p_s, np.conj(p_s)], 1.0,
                                   dt=1 / fs))
    u = rng.standard_normal((300, 1))
    y, y_clean = simulate(plant, u, rng, snr_db=60)
    growth = np.max(np.abs(y_clean[-30:])) / np.max(np.abs(y_clean[:30]))
    assert growth > 100  # the open-loop response really grows (about 1.02^300 = 380)
    res = PLID(4, R=1e-6, dt=1 / fs).fit(u, y)
    poles = control.poles(res.model)
    unstable = poles[np.abs(poles) > 1]
    assert unstable.size == 2
    for target in (p_u, np.conj(p_u)):
        assert np.min(np.abs(unstable - target)) < 1e-3


# ---------------------------------------------------------------- item 5: streaming
@pytest.mark.parametrize("form", ["sqrt", "direct"])
def test_streaming_update_equals_batch_fit_bitwise(form, modal_plant, simulate, rng):
    plant = modal_plant([70.0, 150.0, 300.0], [0.02] * 3, 2, 3, 1600, rng)
    u = rng.standard_normal((400, 2))
    y, _ = simulate(plant, u, rng, snr_db=40)
    su, sy = np.sqrt(np.mean(u ** 2, 0)), np.sqrt(np.mean(y ** 2, 0))
    kw = dict(form=form, R=1e-4, N=1e-6, Q_theta=1e-9, history_every=7)
    batch = PLID(6, **kw).fit(u, y)           # scales default to the data RMS
    est = PLID(6, u_scale=su, y_scale=sy, **kw)
    e = np.array([est.update(u[k], y[k]) for k in range(len(u))])
    stream = est.result()
    assert np.array_equal(stream.theta, batch.theta)
    assert np.array_equal(stream.theta_cov, batch.theta_cov)
    assert np.array_equal(stream.x, batch.x)
    assert np.array_equal(stream.innovations, batch.innovations)
    assert np.array_equal(e, batch.innovations)
    assert np.array_equal(stream.theta_history, batch.theta_history)
    assert np.array_equal(stream.history_index, batch.history_index)


def test_update_continues_a_fit():
    rng = np.random.default_rng(3)
    u = rng.standard_normal((300, 1))
    y = np.convolve(u[:, 0], [0, 1.0, 0.5, 0.25])[:300, None]
    whole = PLID(2, R=1e-4).fit(u, y)
    est = PLID(2, R=1e-4, u_scale=whole.u_scale, y_scale=whole.y_scale)
    est.fit(u[:200], y[:200])
    for k in range(200, 300):
        est.update(u[k], y[k])
    assert np.array_equal(est.result().theta, whole.theta)


# ---------------------------------------------------------------- units and outputs
def test_model_is_returned_in_original_units(modal_plant, simulate, rng):
    # Badly scaled data (micrometre outputs, kilovolt inputs): the identified model must
    # be the true plant in those units, not in the internal unit-RMS ones.
    plant = modal_plant([80.0, 240.0], [0.02, 0.02], 1, 2, 1600, rng)
    su, sy = 1e3, np.array([1e-6, 3e-5])
    scaled = control.ss(plant.A, np.asarray(plant.B) / su, np.asarray(plant.C) * sy[:, None],
                        0, plant.dt)
    u = su * rng.standard_normal((2000, 1))
    y, _ = simulate(scaled, u)
    res = PLID(4, R=1e-14, Q=0.0, dt=plant.dt).fit(u, y)
    theta_true, _ = from_statespace(scaled, ObserverBasis.shift(4, 2))
    assert _rel(res.theta, theta_true) <= 1e-8
    w = np.exp(1j * np.linspace(0.1, 3, 25))
    H = np.array([scaled(z) for z in w])
    G = np.array([res.model(z) for z in w])
    assert np.max(np.abs(G - H)) <= 1e-7 * np.max(np.abs(H))
    assert np.array_equal(np.asarray(res.model.C), ObserverBasis.shift(4, 2).C)


def test_predictor_gain_is_the_steady_state_kalman_gain(modal_plant, simulate, rng):
    plant = modal_plant([90.0, 260.0], [0.02, 0.02], 1, 1, 1600, rng)
    u = rng.standard_normal((1500, 1))
    y, _ = simulate(plant, u, rng, snr_db=40)
    res = PLID(4, R=1e-4, Q=1e-4, N=1e-4).fit(u, y)
    assert res.K_source == "dare"
    A, B, C = (np.asarray(M) for M in (res.model.A, res.model.B, res.model.C))
    # Independent: iterate the Riccati difference equation of the one-step predictor.
    Qd = res.Q + B @ res.N @ B.T
    P = np.eye(4)
    for _ in range(20000):
        S = C @ P @ C.T + res.R
        K = A @ P @ C.T @ np.linalg.inv(S)
        P = A @ P @ A.T + Qd - K @ S @ K.T
    assert np.allclose(res.K, K, rtol=1e-6, atol=1e-9 * np.abs(K).max())
    assert np.max(np.abs(np.linalg.eigvals(A - res.K @ C))) < 1


def test_prior_model_starts_at_the_truth(modal_plant, simulate, rng):
    plant = modal_plant([100.0, 300.0], [0.02, 0.02], 1, 1, 1600, rng)
    theta_true, _ = from_statespace(plant, ObserverBasis.shift(4, 1))
    u = rng.standard_normal((500, 1))
    y, y_clean = simulate(plant, u, rng, snr_db=60)
    # The data has no state noise, so Q = 0 makes the true model the optimal predictor.
    tight = PLID(4, R=1e-6, Q=0.0, prior=plant, prior_theta_var=1e-12).fit(u, y)
    scratch = PLID(4, R=1e-6).fit(u, y)
    assert _rel(tight.theta, theta_true) < 1e-5
    assert _rel(tight.theta, theta_true) < _rel(scratch.theta, theta_true)
    # early one-step predictions are better with the true prior (only x_0 is unknown)
    early = slice(20, 60)
    rms = lambda a: np.sqrt(np.mean(a ** 2))  # noqa: E731
    assert rms(tight.innovations[early]) < 0.5 * rms(scratch.innovations[early])
    # and later they reach the noise floor
    late = slice(300, 500)
    assert rms(tight.innovations[late]) < 1.5 * rms((y - y_clean)[late])


def test_histories_have_the_documented_shapes():
    rng = np.random.default_rng(1)
    u = rng.standard_normal((250, 1))
    y = np.convolve(u[:, 0], [0, 1.0, 0.4])[:250, None]
    res = PLID(2, history_every=50, progress=False).fit(u, y)
    assert res.innovations.shape == (250, 1)
    assert res.theta_history.shape == (5, 4)
    assert np.array_equal(res.history_index, [50, 100, 150, 200, 250])
    assert np.array_equal(res.theta_history[-1], res.theta)
    assert res.theta_cov.shape == (4, 4) and res.x.shape == (2,)


# ---------------------------------------------------------------- bad input
def test_order_not_a_multiple_of_outputs_is_refused_with_suggestions():
    u = np.ones((100, 1))
    y = np.random.default_rng(0).standard_normal((100, 3))
    with pytest.raises(IdentificationError, match="try order 9 or 12"):
        PLID(10).fit(u, y)


@pytest.mark.parametrize("bad,match", [
    ("nan", r"y column 1 has a non-finite value \(nan\) at sample 17"),
    ("short", "u has 100 samples but y has 99"),
    ("few", "5 samples are fewer than the 6 parameters"),
    ("zero", "u column 0 is identically zero"),
])
def test_bad_data_is_refused_naming_column_and_sample(bad, match):
    rng = np.random.default_rng(0)
    u = rng.standard_normal((100, 1))
    y = rng.standard_normal((100, 2))
    if bad == "nan":
        y[17, 1] = np.nan
    elif bad == "short":
        y = y[:99]
    elif bad == "few":
        u, y = u[:5], y[:5]
    elif bad == "zero":
        u[:] = 0
    with pytest.raises(DataError, match=match):
        PLID(2).fit(u, y)


def test_streaming_without_scales_is_refused_clearly():
    with pytest.raises(IdentificationError, match="u_scale"):
        PLID(2).update([1.0], [0.5])


@pytest.mark.parametrize("kwargs,match", [
    (dict(form="chol"), "form must be one of"),
    (dict(R=0.0), "R must be positive definite"),
    (dict(Q=-1.0), "Q must be positive semi-definite"),
    (dict(passes=0), "passes"),
])
def test_bad_options_are_refused(kwargs, match):
    rng = np.random.default_rng(0)
    with pytest.raises(IdentificationError, match=match):
        PLID(2, **kwargs).fit(rng.standard_normal((50, 1)), rng.standard_normal((50, 1)))


def test_blas_threads_are_limited_during_the_recursion_and_restored():
    from trussid._util.threads import blas_thread_counts, blas_threads

    before = blas_thread_counts()
    if not before:
        pytest.skip("no BLAS library found to control")
    with blas_threads(1):
        assert blas_thread_counts() == [1] * len(before)
    assert blas_thread_counts() == before


def test_further_passes_refine_a_short_record(modal_plant, simulate, rng):
    # 1000 samples at 20 dB: one pass has not converged; passes restarted from the
    # previous estimate (re-inflated covariance, smaller Q) get closer to the truth.
    plant = modal_plant([60.0, 180.0], [0.01, 0.01], 1, 1, 1600, rng, collocated=True)
    theta_true, _ = from_statespace(plant, ObserverBasis.shift(4, 1))
    u = rng.standard_normal((1000, 1))
    y, _ = simulate(plant, u, rng, snr_db=20)
    one = PLID(4, R=1e-2).fit(u, y)
    three = PLID(4, R=1e-2, passes=3).fit(u, y)
    assert _rel(three.theta, theta_true) < 0.5 * _rel(one.theta, theta_true)
    assert three.innovations.shape == (1000, 1) and three.n_samples == 1000


def test_progress_is_shown_for_fits_expected_to_take_more_than_a_few_seconds():
    """Audit B78: an order-36 3 x 3 fit on 8000 samples (tens of seconds) and an order-300
    fit sat silent; the bar used to start at 20000 samples whatever the order."""
    from trussid.plid.estimator import PLID

    big = PLID(36, form="direct", dt=1 / 1600)
    big._start(3, 3)            # 216 parameters
    assert big._slow(8000)      # 8000 x 216^2 = 3.7e8 > PLID.PROGRESS_WORK
    small = PLID(4, dt=1e-3)
    small._start(1, 2)          # 12 parameters: 2000 samples take milliseconds
    assert not small._slow(2000)
    assert small._slow(10**6)
