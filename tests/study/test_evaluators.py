"""Per-point evaluators against independent computations: the wall-basis modes and labels of
a design equal those of the testbed rebuilt at its walls; sensitivities equal differences of
frequencies; a fit is scored against the known truth."""

from __future__ import annotations

import numpy as np
import pytest

from trussid.geometry.spec import Testbed
from trussid.study.evaluators import EVALUATORS, WALLS
from trussid.testbed.labels import label_testbed_modes
from trussid.testbed.model import build_testbed
from trussid.testbed.walls import solve_testbed_modes

DESIGN = (0.0006, 0.0015, 0.0009, 0.0012446, 0.0011, 0.0016)


def test_modes_and_labels_equal_a_rebuilt_testbed_at_the_walls():
    ev = EVALUATORS["modes"]
    out = ev.point(ev.context({}), dict(zip(WALLS, DESIGN)), {"n_modes": 20})
    tbm = build_testbed(Testbed().with_walls(DESIGN))
    modes = solve_testbed_modes(tbm, 20)
    ref = modes.frequencies_hz
    f = np.array([out[f"f{k}"] for k in range(1, 21)])
    labels = [out[f"label{k}"] for k in range(1, 21)]
    assert labels == label_testbed_modes(tbm, modes).labels
    elastic = ref > 5.0
    np.testing.assert_allclose(f[elastic], ref[elastic], rtol=1e-8)
    # The six sub-hertz suspension modes are ill-conditioned in both (bungees against the
    # struts: 8 orders of magnitude in stiffness); they agree to what they are worth.
    np.testing.assert_allclose(f[~elastic], ref[~elastic], rtol=1e-4)
    assert sum(lab.startswith("strut 1 ") for lab in labels) == 2  # the thick strut's pair


def test_sensitivities_equal_central_differences_of_the_frequencies():
    ev, mv = EVALUATORS["sensitivities"], EVALUATORS["modes"]
    ctx = ev.context({})
    p = dict(zip(WALLS, DESIGN))
    out = ev.point(ctx, p, {"n_modes": 12})
    h = 1e-6  # 1.7e-3 of the thinnest wall: truncation 1e-6, eigensolver noise ~0.02 Hz/m
    for i in (0, 3):
        up = mv.point(ctx, {**p, WALLS[i]: DESIGN[i] + h}, {"n_modes": 12, "labels": False})
        dn = mv.point(ctx, {**p, WALLS[i]: DESIGN[i] - h}, {"n_modes": 12, "labels": False})
        for k in range(7, 13):  # elastic modes
            fd = (up[f"f{k}"] - dn[f"f{k}"]) / (2 * h)
            assert out[f"dfdt{k}_{i}"] == pytest.approx(fd, rel=1e-4, abs=1e-5 * out[f"f{k}"] / DESIGN[i])


def test_a_wall_outside_the_tube_raises_naming_the_strut():
    ev = EVALUATORS["modes"]
    with pytest.raises(Exception, match="strut 2 wall"):
        ev.point(ev.context({}), {"wall2": 0.01}, {})


@pytest.mark.slow  # ~5 s, most of it importing python-control and pandas
def test_an_n4sid_fit_of_a_noise_free_record_matches_the_truth():
    ev = EVALUATORS["identify"]
    opts = {"plant": "case_a", "n_validation": 1000, "block_rows": [20]}
    out = ev.point(ev.context(opts), {"seed": 3, "noise": "none", "order": 24, "method": "n4sid",
                                      "n_samples": 3000}, opts)
    assert out["stable"] and out["block_rows"] == 20
    assert out["rms_db"] < 0.05 and out["freq_err_max_pct"] < 0.05
    assert out["sim_db"] > 30
