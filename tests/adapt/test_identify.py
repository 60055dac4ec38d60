"""Closed-loop identification: the direct method finds the plant's modes under feedback."""

import numpy as np
import pytest

from trussid.adapt.experiment import closed_loop_record
from trussid.adapt.identify import identify_n4sid, identify_plid, nearest_modes

from .conftest import FREQS, ZETA


@pytest.fixture(scope="module")
def record(structure, controller):
    # the closed loop's sensors carry about 2.6 mV RMS under 1 V of dither: the A/D ranged
    # to 8 times that, sensor noise 5 % of it
    return closed_loop_record(structure, controller, 4000, dither_rms=1.0, noise_rms=1.3e-4,
                              adc_full_scale=0.02, dac_full_scale=10.0, bits=12, seed=7)


@pytest.mark.parametrize("identify, df, dz", [(identify_plid, 1e-4, 0.05),
                                               (identify_n4sid, 5e-3, 1.0)])
def test_dominant_modes_found_under_feedback(record, identify, df, dz):
    """The modes of the plant, not of the closed loop (which the LQG damps to 7 %); N4SID,
    whose instruments are correlated with the noise through the feedback, less closely
    (measured here: PLID within 0.002 % in frequency and 0.7 % in damping; N4SID within
    0.24 % and 72 %)."""
    fit = identify(record, 12, block_rows=(20,))
    assert list(fit.model.input_labels) == ["ch1", "ch2", "ch3"]
    assert list(fit.model.output_labels) == ["acc1", "acc2", "acc3"]
    assert fit.K.shape == (12, 3) and fit.cpu_seconds > 0
    for (f, z), f0 in zip(nearest_modes(fit.model, FREQS[1:]), FREQS[1:]):
        assert abs(f / f0 - 1) < df
        assert abs(z / ZETA - 1) < dz   # the closed loop's own poles are at 5-10 %


def test_nearest_modes_of_the_plant_itself(structure):
    for (f, z), f0 in zip(nearest_modes(structure, FREQS), FREQS):
        assert f == pytest.approx(f0, rel=1e-3) and z == pytest.approx(ZETA, rel=1e-2)


def test_plid_is_closer_than_n4sid_under_feedback(record):
    """The closed-loop bias: PLID's worst damping error on the three dominant modes is a
    fraction of N4SID's on the same record."""
    err = {}
    for name, identify in (("plid", identify_plid), ("n4sid", identify_n4sid)):
        fit = identify(record, 12, block_rows=(20,))
        err[name] = max(abs(z / ZETA - 1) for _, z in nearest_modes(fit.model, FREQS[1:]))
    assert err["plid"] < 0.2 * err["n4sid"]
