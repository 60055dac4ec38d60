"""Simulated experiments: excitation signals, converters (quantisation, clipping), noise."""

import control
import numpy as np
import pytest

from trussid.plid.errors import DataError
from trussid.plid.experiment import EXCITATIONS, excitation, lsb, quantize, run_experiment, simulate

FS = 1000.0


@pytest.fixture
def plant():
    """Two lightly damped modes (60 and 210 Hz), 1 input, 2 outputs, ZOH at 1 kHz."""
    A = np.zeros((4, 4))
    for i, (f, z) in enumerate([(60.0, 0.01), (210.0, 0.02)]):
        w = 2 * np.pi * f
        A[2 * i, 2 * i + 1] = 1
        A[2 * i + 1, 2 * i] = -w**2
        A[2 * i + 1, 2 * i + 1] = -2 * z * w
    B = np.array([[0], [1], [0], [1.0]])
    C = np.array([[1e4, 0, 3e4, 0], [0, 10, 0, 5]])
    return control.c2d(control.ss(A, B, C, 0), 1 / FS)


@pytest.mark.parametrize("kind", EXCITATIONS)
def test_excitation_has_the_requested_rms_and_repeats_with_its_seed(kind):
    x = excitation(kind, 3000, 3, FS, rms=[0.5, 1.0, 2.0], seed=4)
    assert x.shape == (3000, 3)
    np.testing.assert_allclose(np.sqrt(np.mean(x**2, axis=0)), [0.5, 1.0, 2.0], rtol=1e-12)
    np.testing.assert_array_equal(x, excitation(kind, 3000, 3, FS, rms=[0.5, 1.0, 2.0], seed=4))
    assert not np.array_equal(x, excitation(kind, 3000, 3, FS, rms=[0.5, 1.0, 2.0], seed=5))


@pytest.mark.parametrize("kind", EXCITATIONS)
def test_channels_are_nearly_uncorrelated(kind):
    x = excitation(kind, 4000, 2, FS, band=(20, 300), seed=1)
    r = np.corrcoef(x.T)[0, 1]
    assert abs(r) < 0.1


@pytest.mark.parametrize("kind", ["white", "multisine"])
def test_band_limited_signals_have_no_power_outside_the_band(kind):
    x = excitation(kind, 4096, 1, FS, band=(50, 200), seed=2)[:, 0]
    X = np.abs(np.fft.rfft(x)) ** 2
    f = np.fft.rfftfreq(x.size, 1 / FS)
    outside = (f < 50) | (f > 200)
    assert X[outside].sum() < 1e-20 * X.sum()


def test_chirp_power_lies_in_its_band():
    x = excitation("chirp", 8000, 1, FS, band=(50, 200), seed=0)[:, 0]
    X = np.abs(np.fft.rfft(x)) ** 2
    f = np.fft.rfftfreq(x.size, 1 / FS)
    assert X[(f > 40) & (f < 210)].sum() > 0.98 * X.sum()


def test_prbs_is_binary_and_holds_bits_for_its_band():
    x = excitation("prbs", 2000, 1, FS, rms=1.0, band=(0, 100), seed=0)[:, 0]
    levels = np.unique(np.round(x, 9))
    assert levels.size == 2
    hold = int(0.4 * FS / 100)
    assert np.all(x.reshape(-1, hold) == x.reshape(-1, hold)[:, :1])


def test_bad_excitation_options_are_named():
    with pytest.raises(DataError, match="unknown excitation 'pink'"):
        excitation("pink", 100)
    with pytest.raises(DataError, match="band \\(300, 200\\) Hz"):
        excitation("white", 100, fs=FS, band=(300, 200))
    with pytest.raises(DataError, match="rms must be positive"):
        excitation("white", 100, rms=-1)


def test_12_bit_converter_error_is_within_half_lsb(rng):
    fsv = 10.0
    q = lsb(12, fsv)
    assert q == pytest.approx(20.0 / 4096)
    x = rng.uniform(-fsv, fsv - q / 2, (100_000, 2))  # the whole representable range
    xq, clipped = quantize(x, 12, fsv)
    err = xq - x
    assert np.max(np.abs(err)) <= q / 2 * (1 + 1e-12)
    assert np.max(np.abs(err)) > 0.49 * q  # and the bound is attained, not loose
    assert clipped.tolist() == [0, 0]
    assert np.unique(xq).size <= 4096
    np.testing.assert_allclose(xq / q, np.round(xq / q), atol=1e-9)  # on the code grid


def test_clipping_is_counted_per_channel_and_clamps_to_the_end_codes():
    fsv, q = 10.0, lsb(12, 10.0)
    x = np.zeros((1000, 2))
    x[:37, 0] = 15.0                 # 37 above the top
    x[100:105, 0] = -10.0 - q        # 5 below the bottom code by more than LSB/2
    x[200:203, 1] = 10.0 - 0.6 * q   # still the top code: not clipped
    x[300:311, 1] = 1e6              # 11 far above
    xq, clipped = quantize(x, 12, fsv)
    assert clipped.tolist() == [42, 11]
    assert xq[:37, 0].max() == pytest.approx(fsv - q)
    assert xq[100, 0] == pytest.approx(-fsv)
    assert xq[200, 1] == pytest.approx(fsv - q)


def test_simulation_matches_the_convolution_with_markov_parameters(plant, rng):
    u = rng.standard_normal((400, 1))
    A, B, C = plant.A, plant.B, plant.C
    h = np.array([C @ np.linalg.matrix_power(A, k - 1) @ B if k else plant.D
                  for k in range(400)])[:, :, 0]  # impulse response (400, 2)
    expected = np.column_stack([np.convolve(u[:, 0], h[:, j])[:400] for j in range(2)])
    np.testing.assert_allclose(simulate(plant, u), expected, rtol=1e-9,
                               atol=1e-9 * np.abs(expected).max())


def test_noise_free_experiment_records_the_plant_response(plant):
    e = run_experiment(plant, 1000, seed=3)
    np.testing.assert_array_equal(e.data.y, e.y_clean)
    np.testing.assert_allclose(e.y_clean, simulate(plant, e.data.u))
    assert e.data.fs == pytest.approx(FS)


def test_sensor_noise_reaches_the_requested_snr(plant):
    e = run_experiment(plant, 20000, seed=3, snr_db=[20.0, 40.0])
    noise = e.data.y - e.y_clean
    snr = 20 * np.log10(np.sqrt(np.mean(e.y_clean**2, 0)) / np.sqrt(np.mean(noise**2, 0)))
    np.testing.assert_allclose(snr, [20.0, 40.0], atol=0.1)  # 20000 samples: ~0.03 dB spread
    same = run_experiment(plant, 20000, seed=3, snr_db=[20.0, 40.0])
    np.testing.assert_array_equal(same.data.y, e.data.y)


def test_input_noise_disturbs_the_plant_but_not_the_record(plant):
    quiet = run_experiment(plant, 2000, seed=3)
    noisy = run_experiment(plant, 2000, seed=3, input_noise_rms=0.1)
    np.testing.assert_array_equal(noisy.data.u, quiet.data.u)
    np.testing.assert_array_equal(noisy.y_clean, quiet.y_clean)
    rel = np.sqrt(np.mean((noisy.data.y - noisy.y_clean) ** 2)) / np.sqrt(np.mean(noisy.y_clean**2))
    assert 0.03 < rel < 0.3  # 10 % input noise gives roughly 10 % output error


def test_converters_quantise_and_report_clipping(plant):
    e = run_experiment(plant, 3000, seed=1, rms=2.0, dac_bits=12, dac_full_scale=4.0,
                       adc_bits=12, adc_full_scale=0.5)
    q_dac, q_adc = lsb(12, 4.0), lsb(12, 0.5)
    np.testing.assert_allclose(e.data.u / q_dac, np.round(e.data.u / q_dac), atol=1e-9)
    np.testing.assert_allclose(e.data.y / q_adc, np.round(e.data.y / q_adc), atol=1e-9)
    # A 2 V-rms Gaussian drive is beyond +-4 V (2 sigma) in about 4.6 % of samples.
    assert 0.03 * 3000 < e.clipping["dac"][0] < 0.065 * 3000
    y_phys = simulate(plant, e.data.u)
    expected_adc = ((y_phys > 0.5 - q_adc / 2) | (y_phys < -0.5 - q_adc / 2)).sum(axis=0)
    assert e.clipping["adc"] == expected_adc.tolist()
    assert e.clipped_total == e.clipping["dac"][0] + sum(e.clipping["adc"])


def test_auto_ranged_adc_fills_each_channel_range(plant):
    analog = run_experiment(plant, 20000, seed=4, snr_db=50.0).data.y  # same noise, no ADC
    e = run_experiment(plant, 20000, seed=4, snr_db=50.0, adc_bits=12, adc_full_scale="auto")
    q = np.asarray(e.lsb["adc"])
    rms = np.sqrt(np.mean(e.y_clean**2, axis=0))
    # +-full scale = +-4 RMS per channel (the two outputs differ in size by orders)
    np.testing.assert_allclose(q * 2**11, 4 * rms, rtol=1e-3)
    np.testing.assert_allclose(e.data.y / q, np.round(e.data.y / q), atol=1e-9)
    full = q * 2**11
    beyond = (analog > full - q / 2) | (analog < -full - q / 2)  # past the end codes
    assert e.clipping["adc"] == beyond.sum(axis=0).tolist()
    assert 0 < sum(e.clipping["adc"]) < 20  # a few samples of a lightly damped response
    # Off the clipped samples the error is the 50 dB sensor noise (3.16e-3 of the RMS) and
    # the quantisation noise (q / sqrt(12) = 5.64e-4 of the RMS) in quadrature.
    for j in range(2):
        ok = ~beyond[:, j]
        err = e.data.y[ok, j] - e.y_clean[ok, j]
        rel = np.sqrt(np.mean(err**2)) / rms[j]
        assert rel == pytest.approx(np.hypot(10 ** (-50 / 20), 4 / 2048 / np.sqrt(12)), rel=0.03)
        assert np.max(np.abs(e.data.y[ok, j] - analog[ok, j])) <= q[j] / 2 * (1 + 1e-9)


def test_continuous_plant_is_refused(plant):
    with pytest.raises(DataError, match="must be discrete-time"):
        run_experiment(control.ss(-1.0, 1.0, 1.0, 0.0), 10)
