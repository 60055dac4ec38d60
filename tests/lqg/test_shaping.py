"""The frequency-shaped input weight: its gain is what its sections say (its use in a
design is specified in test_design)."""

import numpy as np
import pytest

from trussid.lqg import ControlError
from trussid.lqg.shaping import InputWeight

from .conftest import FS


def test_input_weight_gain_is_one_at_low_frequency_and_its_peak_at_the_band():
    """|W| from its sections: 1 at DC; at f0, with poles at radius rp and zeros at rz on the
    ray e^{j theta}, |W| is close to (1 - rz) / (1 - rp), about the asked ``gain``."""
    w = InputWeight(((300.0, 10.0, 5.0),), 1 / FS)
    rp, rz = np.exp(-2 * np.pi * 10.0 / FS), np.exp(-2 * np.pi * 50.0 / FS)
    assert w.gain([0.0])[0] == pytest.approx(1.0, rel=1e-12)
    assert w.gain([300.0])[0] == pytest.approx((1 - rz) / (1 - rp), rel=0.15)
    assert 4.0 < w.gain([300.0])[0] < 5.5
    assert w.gain([100.0])[0] < 1.1  # away from the band the weight is 1
    with pytest.raises(ControlError, match="input weight peak"):
        InputWeight(((900.0, 10.0, 5.0),), 1 / FS).siso()  # above Nyquist
