"""Mode shapes in an offline 3-D page (fem.render_html, ``trussid render --html``).

The drawn shapes are checked against closed-form beam theory (a cantilever's first bending
mode), the identified-mode markers against a shape made from the FE one with a known
complex factor, and the page against its promise: no reference outside the file.
"""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np
import pytest

from trussid.cli import main as cli_main
from trussid.fem.materials import ALUMINIUM
from trussid.fem.modal import solve_modes
from trussid.fem.assembly import assemble
from trussid.fem.model import Model
from trussid.fem.render import RenderError
from trussid.fem.render_html import (IdentifiedMode, SensorAxis, external_references,
                                     mode_viewer_data, write_mode_viewer)
from trussid.fem.sections import Section

ROOT = Path(__file__).resolve().parents[2]
FRAME = ROOT / "examples" / "decks" / "frame.bdf"
#: beta L of a cantilever's first bending mode (Blevins, Table 8-1).
BETA_L1 = 1.8751040687119611


def _decode(s):
    return np.frombuffer(base64.b64decode(s), dtype="<f4").astype(float).reshape(-1, 3)


def _cantilever(n_el=10, length=1.0):
    m = Model(name="cantilever")
    m.add_nodes(np.arange(1, n_el + 2), np.c_[np.linspace(0, length, n_el + 1),
                                               np.zeros((n_el + 1, 2))])
    m.add_beams(np.arange(1, n_el + 1), np.c_[np.arange(1, n_el + 1), np.arange(2, n_el + 2)],
                Section.rectangle(0.02, 0.01), ALUMINIUM, orient=[0, 0, 1])
    m.fix(1)
    return m


@pytest.fixture(scope="module")
def cantilever():
    m = _cantilever()
    return m, solve_modes(assemble(m), n_modes=4)


def test_the_drawn_first_mode_is_the_closed_form_cantilever_shape(cantilever):
    """Between the nodes the viewer draws the Hermite interpolation of the FE mode: along
    the whole beam it is the Euler-Bernoulli shape to 1e-3 of the tip deflection."""
    m, modes = cantilever
    data = mode_viewer_data(m, modes, n_samples=7)
    beams = data["sets"][0]
    x0, u = _decode(beams["x0"]), _decode(beams["u"][0])
    keep = np.isfinite(x0[:, 0])
    x, w = x0[keep, 0], np.linalg.norm(u[keep], axis=1)
    b = BETA_L1 * x
    sig = (np.cosh(BETA_L1) + np.cos(BETA_L1)) / (np.sinh(BETA_L1) + np.sin(BETA_L1))
    phi = np.cosh(b) - np.cos(b) - sig * (np.sinh(b) - np.sin(b))
    phi = np.abs(phi) / np.abs(phi).max()
    assert np.max(np.abs(w - phi)) < 1e-3
    assert np.isclose(w.max(), 1.0, atol=1e-6)  # each mode is drawn with its largest |u| = 1
    assert len(data["modes"]) == 4 and data["modes"][0]["frequency_hz"] == pytest.approx(
        modes.frequencies_hz[0])


def test_an_identified_shape_is_drawn_in_the_fe_scale_with_its_mac(cantilever):
    """A shape that is the FE one at the sensors times any complex number is drawn exactly
    as the FE one (least-squares modal scale factor); its MAC and frequency are shown."""
    m, modes = cantilever
    sensors = [SensorAxis("tip_z", 11, (0, 0, 1)), SensorAxis("mid_z", 6, (0, 0, 1)),
               SensorAxis("mid_y", 6, (0, 1, 0))]
    plain = mode_viewer_data(m, modes, sensors=sensors)
    fe = _decode(plain["sets"][-1]["u"][0])           # FE mode 1 on the sensors' axes
    proj = np.array([fe[0, 2], fe[1, 2], fe[2, 1]])
    psi = (0.3 - 2.0j) * proj
    ident = IdentifiedMode("mimo", 1, 8.3, 0.004, 0.97, tuple(psi))
    data = mode_viewer_data(m, modes, sensors=sensors, identified=[ident])
    drawn = data["sets"][-1]
    assert drawn["u"][1] is None and drawn["u"][0] is not None  # only mode 1 was identified
    np.testing.assert_allclose(_decode(drawn["u"][0]), fe, atol=1e-6)
    assert data["modes"][0]["matches"] == [{"model": "mimo", "frequency_hz": 8.3,
                                            "damping": 0.004, "mac": 0.97}]
    with pytest.raises(RenderError, match="2 sensor values for 3 sensors"):
        mode_viewer_data(m, modes, sensors=sensors,
                         identified=[IdentifiedMode("mimo", 1, 8.3, 0.004, 0.97, (1, 2))])


def test_the_page_is_self_contained_and_a_bad_mode_writes_nothing(cantilever, tmp_path):
    m, modes = cantilever
    out = tmp_path / "modes.html"
    size = write_mode_viewer(m, modes, out, title="cantilever", first_mode=2)
    text = out.read_text()
    assert size == len(text.encode()) and external_references(text) == []
    assert "Plotly.newPlot" in text and "trussidModeViewer" in text
    assert "location.hash = 'mode=2'" in text
    # the checker itself finds what leaves the file
    assert external_references('<img src="a.png"><a href="#x">x</a>'
                               '<script src="https://cdn.example/p.js"></script>') == [
        ("img", "src", "a.png"), ("script", "src", "https://cdn.example/p.js")]
    bad = tmp_path / "bad.html"
    with pytest.raises(RenderError, match="mode 9 is out of range: valid mode numbers are 1 to 4"):
        write_mode_viewer(m, modes, bad, first_mode=9)
    assert not bad.exists()


def _one_line(capsys):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    return err


@pytest.mark.parametrize("model", [str(FRAME), None], ids=["deck", "testbed"])
def test_render_html_on_a_deck_and_on_the_testbed(model, tmp_path, capsys):
    out = tmp_path / "modes.html"
    args = ([model] if model else []) + ["--html", str(out), "--mode", "3"]
    assert cli_main(["render", *args]) == 0
    text = out.read_text()
    assert external_references(text) == [] and "location.hash = 'mode=3'" in text
    assert "mode 3 selected" in capsys.readouterr().out


def test_render_html_refuses_a_bad_mode_and_an_unwritable_path(tmp_path, capsys):
    out = tmp_path / "modes.html"
    assert cli_main(["render", str(FRAME), "--html", str(out), "--mode", "500"]) == 2
    assert "--mode 500 is out of range" in _one_line(capsys) and not out.exists()
    missing = tmp_path / "no" / "modes.html"
    assert cli_main(["render", str(FRAME), "--html", str(missing)]) == 2
    assert "does not exist" in _one_line(capsys) and not missing.parent.exists()
    file_as_dir = tmp_path / "f"
    file_as_dir.write_text("")
    assert cli_main(["render", str(FRAME), "--html", str(file_as_dir / "x.html")]) == 2
    assert "is not a directory" in _one_line(capsys)
    assert cli_main(["render", str(FRAME), "--html", str(tmp_path / "x.png")]) == 2
    assert "give an .html file" in _one_line(capsys)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]
