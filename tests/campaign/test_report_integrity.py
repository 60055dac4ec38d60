"""The demo report says what a model lacks, and is written as a whole (issue 19).

Fast tests: the mode audit on hand-made pole lists (the independent truth is the list
itself), the report directory under real SIGINTs at several points, and run_demo's
refusals. The sections of a real report are checked from its summary.json in
tests/campaign/test_demo.py (slow tier)."""

import os
import signal
from pathlib import Path

import pytest

from trussid._util.errors import UserError
from trussid._util.files import atomic_directory
from trussid.campaign import demo as demo_mod
from trussid.campaign.demo import mode_audit
from trussid.geometry.lab import LabSpec
from trussid.plid.metrics import PoleMatch


def row(ft, zt, fi, zi):
    return PoleMatch(true_frequency_hz=ft, true_damping=zt, frequency_hz=fi, damping=zi)


POLES = [
    row(50.4, 0.0025, None, None),          # first bending: missed
    row(57.9, 0.0025, 71.0, 0.01),          # "matched" by the assignment 23 % away: missed
    row(79.4, 0.0025, 79.5, 0.0031),        # found
    row(120.0, 1.0, 113.1, 1.0),            # the 120 Hz low-pass: not a mode
    row(166.0, 0.0025, 166.2, 0.0024),      # found
    row(500.0, 0.0025, None, None),         # outside the band: not counted
    row(None, None, 441.5, 0.00013),        # spurious, lightly damped, above the excitation
    row(None, None, 550.0, 0.0033),         # spurious, lightly damped
    row(None, None, 300.0, 0.2),            # spurious, well damped, in the excited band
]


def test_every_true_mode_in_band_is_found_or_missing_and_filters_are_not_modes():
    a = mode_audit(POLES, (50, 350), (0, 400))
    assert (a.found, a.total) == (2, 4)
    assert a.missing == [50.4, 57.9]
    assert a.filter_poles_in_band == 1
    assert [r.found for r in a.true_modes_in_band] == [False, False, True, True]


def test_spurious_and_lightly_damped_poles_are_listed_anywhere():
    a = mode_audit(POLES, (50, 350), (0, 400))
    assert [e.frequency_hz for e in a.spurious] == [71.0, 300.0, 441.5, 550.0]
    light = {e.frequency_hz: e for e in a.lightly_damped}
    assert set(light) == {79.5, 166.2, 441.5, 550.0}  # damping under 1 %, found or not
    assert light[441.5].spurious and not light[441.5].in_excited_band
    assert not light[79.5].spurious and light[79.5].in_excited_band


def _interrupt():
    os.kill(os.getpid(), signal.SIGINT)  # a real SIGINT: Python raises KeyboardInterrupt


@pytest.fixture
def python_sigint():
    """Python's own SIGINT handler (KeyboardInterrupt) while the test runs, whatever the
    suite was started with: a shell without job control starts a background job (``&``,
    nohup, a batch script) with SIGINT ignored, and then no SIGINT would reach the code
    under test (issue 30; tests/test_started_anyhow.py runs this file so)."""
    old = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, old)


@pytest.mark.parametrize("point", ["before_any_file", "after_some_files", "after_all_files"])
@pytest.mark.parametrize("previous", [False, True])
def test_an_interrupted_report_leaves_the_previous_directory_or_none(tmp_path, point,
                                                                     previous, python_sigint):
    out = tmp_path / "report"
    if previous:
        out.mkdir()
        (out / "report.md").write_text("old report")
    with pytest.raises(KeyboardInterrupt):
        with atomic_directory(out, force=True) as tmp:
            if point != "before_any_file":
                (tmp / "model_simo_ch1.npz").write_text("new")
            if point == "after_all_files":
                (tmp / "report.md").write_text("new report")
            _interrupt()
    if previous:
        assert sorted(p.name for p in out.iterdir()) == ["report.md"]
        assert (out / "report.md").read_text() == "old report"
    else:
        assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == (["report"] if previous else [])


def test_a_complete_report_replaces_the_previous_one_only_with_force(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with pytest.raises(FileExistsError, match="give --force"):
        with atomic_directory(out) as tmp:
            pass
    with atomic_directory(out, force=True) as tmp:
        (tmp / "report.md").write_text("new")
    assert sorted(p.name for p in out.iterdir()) == ["report.md"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]  # no leftovers


def test_run_demo_refuses_an_existing_directory_before_computing(tmp_path, monkeypatch):
    out = tmp_path / "report"
    out.mkdir()
    monkeypatch.setattr(demo_mod, "build_plant", lambda *a: pytest.fail("computed"))
    with pytest.raises(UserError, match="exists; give --force"):
        demo_mod.run_demo(out, demo_mod.demo_settings(True), progress=None)
    with pytest.raises(UserError, match="does not exist"):
        demo_mod.run_demo(tmp_path / "no" / "such", demo_mod.demo_settings(True),
                          progress=None)


@pytest.mark.parametrize("stage", ["build_plant", "write_files", "write_figures"])
def test_run_demo_interrupted_at_a_stage_leaves_the_previous_report(tmp_path, monkeypatch,
                                                                    stage, python_sigint):
    """SIGINT while the plant is built, while the data/model files are written, and while
    the figures are drawn. The stages before are replaced by stand-ins (this tests the
    writing, not the campaign)."""
    out = tmp_path / "report"
    out.mkdir()
    (out / "report.md").write_text("old report")

    def stop(*a, **k):
        if stage == "write_files":
            (Path(a[0]) / "data_simo_ch1_ide.npz").write_text("partial")
        _interrupt()

    if stage == "build_plant":
        monkeypatch.setattr(demo_mod, "build_plant", stop)
    else:
        class TP:  # the plant's stand-in: nothing after it but writing is reached
            discrete = type("D", (), {"dt": 1 / 1600, "nstates": 1, "ninputs": 3,
                                      "noutputs": 3})()
            modes = type("M", (), {"frequencies_hz": __import__("numpy").array([10.0, 50.0])})()
            lab = LabSpec()

        monkeypatch.setattr(demo_mod, "build_plant", lambda tb: TP)
        monkeypatch.setattr(demo_mod, "run_experiments", lambda *a, **k: {})
        monkeypatch.setattr(demo_mod, "identify_records", lambda *a: ({}, {}))
        monkeypatch.setattr(demo_mod, stage, stop)
        if stage == "write_figures":
            monkeypatch.setattr(demo_mod, "write_files",
                                lambda o, *a: (Path(o) / "model.npz").write_text("x") and {})
    with pytest.raises(KeyboardInterrupt):
        demo_mod.run_demo(out, demo_mod.demo_settings(True), progress=None, force=True)
    assert [p.name for p in out.iterdir()] == ["report.md"]
    assert (out / "report.md").read_text() == "old report"
    assert [p.name for p in tmp_path.iterdir()] == ["report"]
