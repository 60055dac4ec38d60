"""The demo runs in the lab it is given: records and closed loop use the testbed's own
converters and rate, read back from ``summary.json`` and the written files (issue 22,
acceptance item 2).

A testbed in a 16-bit +-5 V lab at 3200 Hz (not the thesis's 12-bit +-10 V at 1600 Hz):
every record's D/A and A/D steps, the records' rate, the true plant's recorded lab and the
closed loop's simulated converters must be exactly those, recomputed here from
``2 full_scale / 2**bits``, not echoed from the settings.
"""

import json

import numpy as np
import pytest

from trussid.campaign.demo import demo_settings, run_demo
from trussid.geometry.lab import LabSpec, recorded_lab
from trussid.geometry.spec import Testbed
from trussid.plid.datafile import read_data
from trussid.plid.modelfile import load_model

BITS, FULL_SCALE, RATE = 16, 5.0, 3200.0


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    lab = LabSpec.from_dict({"daq": {"sample_rate": RATE, "bits": BITS,
                                     "full_scale": FULL_SCALE}})
    out = tmp_path_factory.mktemp("demo_lab") / "report"
    # the quick campaign, smaller still: the lab, not the identification, is under test
    settings = demo_settings(True, n_identification=3000, n_validation=2000, simo_channels=(),
                             mimo_order=18, h1_nperseg=256)
    run_demo(out, settings, progress=None, testbed=Testbed().with_lab(lab))
    return out, json.loads((out / "summary.json").read_text()), lab


@pytest.mark.slow
def test_the_records_use_the_labs_converters_and_rate(report):
    out, s, lab = report
    assert s["plant"]["sample_rate_hz"] == RATE
    assert (s["plant"]["converter_bits"], s["plant"]["converter_full_scale_v"]) == (BITS, FULL_SCALE)
    assert LabSpec.from_dict(s["plant"]["lab"]) == lab
    dac_lsb = 2 * FULL_SCALE / 2**BITS
    assert s["experiments"]
    for r in s["experiments"]:
        assert r["sample_rate_hz"] == RATE
        assert r["dac_lsb_v"] == [dac_lsb]
        # the A/D range of each output is the lab's divided by its conditioner step
        assert r["adc_full_scale_v"] == [FULL_SCALE / g for g in r["conditioner_steps"]]
        assert r["adc_lsb_v"] == [2 * fs / 2**BITS for fs in r["adc_full_scale_v"]]
        assert r["adc_bits"] == [BITS] * len(r["adc_full_scale_v"])
    # and the written record is on that D/A grid, at that rate
    d = read_data(out / "data_mimo_ide.npz")
    assert d.fs == RATE
    np.testing.assert_allclose(d.u / dac_lsb, np.round(d.u / dac_lsb), atol=1e-6)
    assert np.max(np.abs(d.u)) <= FULL_SCALE


@pytest.mark.slow
def test_the_true_plant_file_records_the_lab(report):
    out, _, lab = report
    plant, meta = load_model(out / "plant_true.npz", which="discrete")
    assert plant.dt == 1 / RATE
    assert recorded_lab(meta.extra, "plant_true.npz") == lab


@pytest.mark.slow
def test_the_closed_loop_ran_behind_the_labs_converters(report):
    _, s, _ = report
    control = s["control"]
    assert "error" not in control, control
    row = control["rows"]["nominal"]
    conv = row["converters"]
    assert conv["sample_rate_hz"] == RATE
    assert conv["dac_lsb_v"] == [2 * FULL_SCALE / 2**BITS] * 3
    assert conv["adc_lsb_v"] == [2 * FULL_SCALE / 2**BITS] * 3
    assert (conv["bits"], conv["full_scale_v"]) == (BITS, FULL_SCALE)
