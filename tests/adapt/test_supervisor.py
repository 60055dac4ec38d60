"""The supervisor: damping per mode by the issue's rule, detection, and the checks a new
controller must pass before it replaces the running one."""

import control
import numpy as np
import pytest

from trussid.adapt.identify import ClosedLoopModel
from trussid.adapt.supervisor import (SupervisorSettings, check_candidate, detect,
                                      mode_damping)

from .conftest import FREQS, ZETA, modal_structure


def _zero(structure):
    return control.ss([], [], [], np.zeros((3, 3)), structure.dt,
                      inputs=list(structure.output_labels), outputs=list(structure.input_labels))


def _static(structure, gain):
    return control.ss([], [], [], gain * np.eye(3), structure.dt,
                      inputs=list(structure.output_labels), outputs=list(structure.input_labels))


def test_no_controller_leaves_every_mode_as_it_was(structure):
    md = mode_damping(structure, _zero(structure))
    np.testing.assert_allclose(md.frequency_hz, FREQS, rtol=1e-3)
    np.testing.assert_allclose([r.damping_worst_visible for r in md.rows], ZETA, rtol=1e-3)
    assert md.dominant_mask.sum() == 3 and not md.dominant_mask[0]  # 120 Hz: residue 1 %
    assert md.others_ratio == pytest.approx(1.0) and md.stable


def test_the_lqg_damps_the_dominant_modes(structure, controller):
    md = mode_damping(structure, controller)
    assert md.stable and np.all(md.dominant_damping > 0.05)
    assert md.others_ratio > 0.8


def test_a_destabilising_controller_is_refused(structure, controller):
    """Positive velocity feedback: the loop is unstable on the model; the running LQG
    stays."""
    v = check_candidate(structure, _static(structure, 5.0), controller)
    assert not v.accepted and "unstable" in v.reasons[0]


def test_a_controller_no_better_than_the_running_one_is_refused(structure, controller):
    v = check_candidate(structure, controller, controller)
    assert not v.accepted
    assert any("no better" in r for r in v.reasons)


def test_a_better_controller_passes(structure, controller):
    v = check_candidate(structure, controller, _zero(structure),
                        SupervisorSettings(band=(40.0, 450.0)))
    assert v.accepted, v.reasons
    assert v.figures.disk_margin_db >= 6


def test_detection_by_a_moved_mode_and_not_without(structure, controller):
    fit = ClosedLoopModel(structure, np.zeros((8, 3)), "truth", 0.0, 0.0)
    assert not detect(fit, controller, FREQS[1:]).changed
    moved = modal_structure([f * 0.97 for f in FREQS])
    fit = ClosedLoopModel(moved, np.zeros((8, 3)), "truth", 0.0, 0.0)
    d = detect(fit, controller, FREQS[1:])
    assert d.changed and max(d.shift) == pytest.approx(0.03, rel=0.05)
