"""``trussid identify --closed-loop`` and ``--reference`` (issue 34, acceptance 3): the
closed-loop recipe from the command line, said in the report; misuse named in one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from trussid.cli import main


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    from tests.plid.test_closedloop import _record

    u, y, r = _record(gain=1.0, n=4000)
    path = tmp_path_factory.mktemp("cl") / "loop.npz"
    np.savez(path, u=u, y=y, r=r, fs=1000.0)
    return path


def test_closed_loop_flag_runs_the_closed_loop_recipe_and_says_so(record, tmp_path, capsys):
    out = tmp_path / "m.npz"
    assert main(["identify", str(record), "--order", "4", "--out", str(out),
                 "--closed-loop", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["closed_loop"]["decided_by"] == "told"
    assert "output" in got["closed_loop"]["plid_passes"]
    assert got["start"].startswith("closed-loop") and got["form"] is None
    assert out.exists()


def test_a_reference_channel_showing_feedback_selects_it(record, tmp_path, capsys):
    out = tmp_path / "m.npz"
    assert main(["identify", str(record), "--order", "4", "--out", str(out), "--inputs", "u",
                 "--reference", "r", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    assert got["closed_loop"]["decided_by"] == "reference channel"


def test_closed_loop_with_the_scratch_start_is_refused_in_one_line(record, tmp_path, capsys):
    out = tmp_path / "m.npz"
    assert main(["identify", str(record), "--order", "4", "--out", str(out), "--closed-loop",
                 "--start", "scratch"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--closed-loop" in err[0] and not out.exists()
