"""Frequency responses: exact model FRF, H1/H2 estimates from data, stepped-sine analyser."""

import control
import numpy as np
import pytest

from trussid.plid.errors import DataError
from trussid.plid.experiment import run_experiment, simulate
from trussid.plid.frf import frequency_response, h1, h2, stepped_sine

FS = 1000.0


def modal_plant(freqs, zetas, n_in=1, seed=0):
    """Continuous modal model (displacement outputs, one row per mode-combination)."""
    rng = np.random.default_rng(seed)
    k = len(freqs)
    A = np.zeros((2 * k, 2 * k))
    for i, (f, z) in enumerate(zip(freqs, zetas)):
        w = 2 * np.pi * f
        A[2 * i, 2 * i + 1] = 1
        A[2 * i + 1, 2 * i] = -w**2
        A[2 * i + 1, 2 * i + 1] = -2 * z * w
    B = np.zeros((2 * k, n_in))
    B[1::2] = rng.uniform(0.5, 1.5, (k, n_in))
    C = np.zeros((2, 2 * k))
    C[:, 0::2] = rng.uniform(0.5, 1.5, (2, k)) * (2 * np.pi * np.asarray(freqs)) ** 2
    return control.ss(A, B, C, np.zeros((2, n_in)))


def test_model_frf_matches_the_resolvent_and_the_closed_form():
    sc = modal_plant([60.0], [0.02])
    f = np.array([10.0, 59.0, 60.0, 200.0])
    s = 2j * np.pi * f
    w = 2 * np.pi * 60.0
    closed = sc.C[:, 0] * sc.B[1, 0] / (s[:, None] ** 2 + 2 * 0.02 * w * s[:, None] + w**2)
    np.testing.assert_allclose(frequency_response(sc, f)[:, :, 0], closed, rtol=1e-12)
    sd = control.c2d(sc, 1 / FS)
    z = np.exp(2j * np.pi * f / FS)
    direct = np.array([sd.C @ np.linalg.solve(zk * np.eye(2) - sd.A, sd.B) for zk in z])
    np.testing.assert_allclose(frequency_response(sd, f), direct, rtol=1e-12)


def rel_error(est, plant, lo=20.0, hi=400.0):
    keep = (est.f >= lo) & (est.f <= hi)
    G = frequency_response(plant, est.f[keep])
    return np.sqrt(np.mean(np.abs(est.H[keep] - G) ** 2 / np.abs(G) ** 2))


def test_h1_converges_to_the_plant_as_averages_increase():
    """With 10 dB output noise the random error of H1 falls like 1/sqrt(averages)."""
    plant = control.c2d(modal_plant([60.0, 210.0], [0.05, 0.05]), 1 / FS)
    nperseg = 512
    e = run_experiment(plant, nperseg * 129, seed=7, snr_db=10.0)
    errors, averages = [], []
    for segs in (4, 16, 64, 256):
        n = nperseg * (segs + 1) // 2  # 50 % overlap
        est = h1(e.data.u[:n], e.data.y[:n], FS, nperseg=nperseg)
        averages.append(est.n_averages)
        errors.append(rel_error(est, plant))
    assert averages == [4, 16, 64, 256]
    assert all(b < a for a, b in zip(errors, errors[1:])), errors
    # Random error ~ 1/sqrt(averages): error * sqrt(averages) stays about constant, i.e. no
    # bias floor appears up to 256 averages (64 times the averages: error / 8).
    scaled = np.array(errors) * np.sqrt(averages)
    assert scaled.max() < 1.5 * scaled.min(), scaled
    assert errors[-1] < errors[0] / 6, errors


def test_h1_is_exact_enough_without_noise_and_coherence_is_one():
    plant = control.c2d(modal_plant([60.0, 210.0], [0.05, 0.05]), 1 / FS)
    e = run_experiment(plant, 20000, seed=1)
    est = h1(e.data.u, e.data.y, FS, nperseg=1024)
    assert rel_error(est, plant) < 0.02  # only window leakage of a 1 Hz-resolution grid
    band = (est.f > 20) & (est.f < 400)
    # Coherence is one but for Welch leakage, which dips it slightly at the resonance peaks.
    assert np.median(est.coherence[band]) > 0.999
    assert est.coherence[band].min() > 0.95


def test_mimo_h1_separates_two_inputs():
    plant = control.c2d(modal_plant([60.0, 210.0], [0.05, 0.05], n_in=2, seed=3), 1 / FS)
    e = run_experiment(plant, 40000, seed=2, snr_db=30.0)
    est = h1(e.data.u, e.data.y, FS, nperseg=512)
    assert est.H.shape[1:] == (2, 2)
    assert rel_error(est, plant) < 0.05


def test_h2_is_unbiased_by_input_noise_where_h1_is_biased_low():
    plant = control.c2d(modal_plant([60.0], [0.05]), 1 / FS)
    rng = np.random.default_rng(5)
    u = rng.standard_normal((60000, 1))
    y = simulate(plant, u)
    u_meas = u + 0.5 * rng.standard_normal(u.shape)  # input measured with noise, |N/U|^2 = 1/4
    e1 = h1(u_meas, y, FS, nperseg=512)
    e2 = h2(u_meas, y, FS, nperseg=512)
    keep = (e1.f > 20) & (e1.f < 400)
    G = frequency_response(plant, e1.f[keep])
    ratio1 = np.median(np.abs(e1.H[keep] / G))
    ratio2 = np.median(np.abs(e2.H[keep] / G))
    assert ratio1 == pytest.approx(1 / 1.25, abs=0.02)  # H1 = G S_uu / (S_uu + S_nn)
    assert ratio2 == pytest.approx(1.0, abs=0.02)


def test_square_mimo_h2_recovers_the_plant():
    plant = control.c2d(modal_plant([60.0, 210.0], [0.05, 0.05], n_in=2, seed=3), 1 / FS)
    e = run_experiment(plant, 40000, seed=2)
    # Noise-free, the only error is window leakage, which H2 (output spectra in the
    # numerator) feels more than H1: at 2 Hz resolution it was 8 %, at 0.5 Hz 0.7 %.
    est = h2(e.data.u, e.data.y, FS, nperseg=2048)
    assert est.H.shape[1:] == (2, 2)
    assert rel_error(est, plant) < 0.01


def test_h2_refuses_non_square_mimo(rng):
    with pytest.raises(DataError, match="H2 needs one input or as many outputs as inputs"):
        h2(rng.standard_normal((2000, 2)), rng.standard_normal((2000, 3)), FS, nperseg=256)


def test_stepped_sine_matches_the_plant_response_without_noise():
    plant = control.c2d(modal_plant([60.0, 210.0], [0.01, 0.02], n_in=2, seed=4), 1 / FS)
    f = np.array([15.0, 59.0, 60.0, 61.5, 133.3, 210.0, 333.0, 480.0])
    est = stepped_sine(plant, f, amplitude=0.3)
    G = frequency_response(plant, f)
    assert est.H.shape == G.shape == (8, 2, 2)
    assert np.max(np.abs(est.H - G) / np.abs(G)) < 1e-6


def test_stepped_sine_refuses_unstable_plants_and_bad_frequencies():
    unstable = control.ss([[1.01]], [[1.0]], [[1.0]], [[0.0]], 1 / FS)
    with pytest.raises(DataError, match="not stable"):
        stepped_sine(unstable, [10.0])
    stable = control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 1 / FS)
    with pytest.raises(DataError, match="test frequencies must lie in"):
        stepped_sine(stable, [600.0])


def test_h1_with_fewer_segments_than_inputs_names_the_record_length_not_the_inputs():
    """Audit B88: 20 samples of 3 independent inputs were reported as 'linearly dependent'."""
    from trussid.plid.errors import DataError

    rng = np.random.default_rng(0)
    u, y = rng.standard_normal((20, 3)), rng.standard_normal((20, 3))
    with pytest.raises(DataError, match=r"20 samples give 1 Welch segment\(s\) of 20 samples, "
                                        r"but an H1 estimate with 3 inputs needs at least 3"):
        h1(u, y, 1000.0, nperseg=64)


def test_frequency_response_by_eigendecomposition_matches_python_control():
    """The O(n)-per-frequency path agrees with python-control's own evaluation (an n x n
    solve per frequency), and a defective A falls back to the latter."""
    import control

    from trussid.plid.frf import frequency_response

    sysc = control.rss(12, 2, 3, strictly_proper=False)
    sysd = control.c2d(control.ss(sysc.A - 0.1 * np.eye(12), sysc.B, sysc.C, sysc.D), 1 / 1600)
    f = np.linspace(1, 790, 300)
    z = np.exp(2j * np.pi * f / 1600)
    ref = np.moveaxis(np.asarray(sysd(z, squeeze=False)), -1, 0)
    H = frequency_response(sysd, f)
    np.testing.assert_allclose(H, ref, rtol=1e-8, atol=1e-12 * np.abs(ref).max())
    jordan = control.ss([[0.5, 1.0], [0.0, 0.5]], [[0.0], [1.0]], [[1.0, 0.0]], 0, 1.0)
    zj = np.exp(2j * np.pi * np.array([0.1, 0.2]))
    np.testing.assert_allclose(frequency_response(jordan, [0.1, 0.2])[:, 0, 0],
                               1 / (zj - 0.5) ** 2, rtol=1e-12)
