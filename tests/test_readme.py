"""The README's Python example runs as written (on simulated testbed data for u, y)."""

import re
from pathlib import Path

import control
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow  # a 141-state plant and a 30-state identify_reduced: about a minute
def test_readme_python_example_runs_as_written(tmp_path, monkeypatch):
    block = re.search(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S).group(1)
    from trussid.testbed import testbed_plant
    from trussid.plid.experiment import run_experiment

    # "u (N x m), y (N x p): measured data at 1600 Hz": channel 1 of the testbed plant
    p = testbed_plant().discrete
    sub = control.ss(p.A, np.asarray(p.B)[:, :1], p.C, np.asarray(p.D)[:, :1], p.dt)
    e = run_experiment(sub, 3000, rms=1.0, seed=1, snr_db=50)
    ns = {"u": e.data.u, "y": e.data.y}
    monkeypatch.chdir(tmp_path)
    exec(compile(block, "README.md", "exec"), ns)  # noqa: S102 - the documentation's code
    assert len(ns["modes"].frequencies_hz) == 30
    assert ns["plant"].discrete.nstates == 141
    assert (tmp_path / "mode7.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert ns["est"].model.nstates == 30 and ns["fit"].model.nstates == 30
