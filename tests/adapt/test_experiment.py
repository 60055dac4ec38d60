"""Closed-loop records: the loop the lab runs, checked against the linear closed loop."""

import control
import numpy as np

from trussid.adapt.experiment import closed_loop_record, dither, run_loop, trial_rms
from trussid.lqg.evaluate import closed_loop


def test_ideal_converters_give_the_linear_closed_loop(structure, controller):
    """With 48-bit converters and no noise the record is the closed loop's response to the
    dither (python-control's forced_response of lqg.closed_loop, a different computation)."""
    d = dither(800, 3, structure.dt, 1.0, seed=3)
    rec = run_loop(structure, controller, d, 0.0, adc_full_scale=1e3, dac_full_scale=1e3,
                   bits=48)
    cl = closed_loop(structure, controller)
    W = np.hstack([d, np.zeros((800, 3))])   # d at the D/A, no sensor noise
    out = control.forced_response(cl, U=W.T).outputs.T
    np.testing.assert_allclose(rec.measured, out[:, :3], atol=1e-8 * np.abs(out).max())
    np.testing.assert_allclose(rec.command, out[:, 3:], atol=1e-8 * np.abs(out).max())
    np.testing.assert_allclose(rec.plant_input, rec.command + d, atol=1e-9)


def test_records_continue_one_another(structure, controller):
    """Two records started from the first one's final states equal one long record."""
    d = dither(600, 3, structure.dt, 1.0, seed=5)
    lab = dict(adc_full_scale=10.0, dac_full_scale=10.0, bits=12)   # the converters
    whole = run_loop(structure, controller, d, 0.0, **lab)
    a = run_loop(structure, controller, d[:250], 0.0, **lab)
    b = run_loop(structure, controller, d[250:], 0.0, x_plant=a.x_plant,
                 x_controller=a.x_controller, **lab)
    np.testing.assert_array_equal(np.vstack([a.measured, b.measured]), whole.measured)


def test_record_carries_names_noise_and_quantisation(structure, controller):
    rec = closed_loop_record(structure, controller, 500, dither_rms=0.5, noise_rms=1e-3,
                             adc_full_scale=[1.0, 2.0, 5.0], dac_full_scale=10.0, bits=12,
                             seed=1)
    assert rec.input_names == ["ch1", "ch2", "ch3"] and rec.output_names == ["acc1", "acc2", "acc3"]
    assert rec.n_samples == 500 and rec.dither.shape == (500, 3)
    lsb = 2 * np.array([1.0, 2.0, 5.0]) / 2**12
    np.testing.assert_allclose(rec.measured / lsb, np.round(rec.measured / lsb), atol=1e-6)
    assert abs(np.sqrt(np.mean(rec.dither**2)) - 0.5) < 0.05


def test_trial_rms_is_the_noise_free_loop(structure, controller):
    r = trial_rms(structure, controller, 1000, 1.0, seed=2)
    rec = run_loop(structure, controller, dither(1000, 3, structure.dt, 1.0, seed=2), 0.0,
                   adc_full_scale=1e4, dac_full_scale=1e4, bits=48)
    np.testing.assert_allclose(r, np.sqrt(np.mean(rec.measured**2, axis=0)))
