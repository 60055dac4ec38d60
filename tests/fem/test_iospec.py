"""Actuators and sensors from a TOML file, and the plant of any model (fem.iospec).

Checked against closed forms on the inch cantilever deck (Euler-Bernoulli, cubic
elements: nodal static deflections are exact) and against fem.actuators directly."""

from pathlib import Path

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.actuators import strain_actuator_loads
from trussid.fem.iospec import io_loads, io_plant, read_io
from trussid.fem.nastran import read_bdf

ROOT = Path(__file__).resolve().parents[2]
DECK = ROOT / "examples" / "decks" / "cantilever_inch.bdf"
L, E, I = 40.0, 1.0e7, 0.001389761559  # in, psi, in^4 (the deck's PBAR)

TIP = """
[[actuator]]
name = "tip_force"
node = 21
direction = [0, 0, 1]
gain = 2.0

[[actuator]]
name = "tip_moment"
type = "moment"
node = 21
direction = [0, -1, 0]

[[sensor]]
name = "tip_w"
node = 21
direction = [0, 0, 1]
quantity = "displacement"

[[sensor]]
name = "mid_w"
node = 11
direction = [0, 0, 1]
quantity = "displacement"
"""


def spec_file(tmp_path, text, name="io.toml"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_static_gain_of_the_cantilever_plant_is_the_beam_formula(tmp_path):
    model, info = read_bdf(DECK)
    spec = read_io(spec_file(tmp_path, TIP))
    # every finite-frequency mode: 100 of the 120 free DOFs carry mass (the deck's lumped
    # mass has no rotary inertia), and the sum over those modes is the static solution
    n_all = 6 * 20
    sc, sd, modes, n = io_plant(model, spec, n_modes=n_all, damping=0.0)
    assert sd is None and n == 100
    dc = -np.asarray(sc.C) @ np.linalg.solve(np.asarray(sc.A), np.asarray(sc.B)) + sc.D
    a = L / 2
    # tip force P = 2 (gain) lbf: w(L) = P L^3 / 3EI, w(L/2) = P a^2 (3L - a) / 6EI
    np.testing.assert_allclose(dc[:, 0], [2 * L**3 / (3 * E * I),
                                          2 * a**2 * (3 * L - a) / (6 * E * I)], rtol=1e-8)
    # tip moment M = 1 about -y (bends the tip up, +z): w(x) = M x^2 / 2EI
    np.testing.assert_allclose(dc[:, 1], [L**2 / (2 * E * I), a**2 / (2 * E * I)], rtol=1e-8)
    assert list(sc.input_labels) == ["tip_force", "tip_moment"]
    assert list(sc.output_labels) == ["tip_w", "mid_w"]


def test_first_mode_and_the_discrete_plant_follow_the_sample_rate(tmp_path):
    model, _ = read_bdf(DECK)
    spec = read_io(spec_file(tmp_path, TIP + "\n[plant]\nfs = 200.0\n"))
    sc, sd, modes, n = io_plant(model, spec)
    f = np.asarray(modes.frequencies_hz)
    assert sd is not None and sd.dt == pytest.approx(1 / 200)
    assert (f[:n] < 100).all() and (n == f.size or f[n] >= 100)  # every mode below Nyquist
    assert f[0] == pytest.approx(11.4745, rel=1e-3)  # 1.8751^2/(2 pi L^2) sqrt(EI/m)


def test_strain_actuator_loads_are_fem_actuators_loads(tmp_path):
    from trussid.fem.actuators import Wafer

    text = """
[[actuator]]
name = "pzt"
type = "strain"
elements = [1, 2]
offset = 0.26
arrangement = "bending"
face_axis = "z"
wafer = { width = 0.4, length = 1.5, thickness = 0.01, youngs_modulus = 9e6, d31 = -7e-9 }

[[sensor]]
node = 21
direction = [0, 0, 1]
"""
    model, _ = read_bdf(DECK)
    spec = read_io(spec_file(tmp_path, text))
    wafer = Wafer(0.4, 1.5, 0.01, 9e6, -7e-9)
    expected = strain_actuator_loads(model, [1, 2], wafer, 0.26, face_axis="z",
                                     arrangement="bending", n_wafers=2)
    np.testing.assert_array_equal(io_loads(model, spec)[:, 0], expected)
    assert spec.sensors[0].name == "y1" and spec.sensors[0].quantity == "acceleration"


@pytest.mark.parametrize("text, match", [
    (TIP.replace("node = 11", "node = 99"), "sensor 'mid_w': unknown node 99"),
    (TIP.replace("node = 21\ndirection = [0, 0, 1]\ngain", "node = 77\ndirection = [0, 0, 1]\ngain"),
     "actuator 1 'tip_force': undefined node 77"),
    (TIP.replace("gain = 2.0", "gian = 2.0"), "actuator 1 'tip_force': unknown key 'gian'"),
    (TIP.replace("direction = [0, -1, 0]", "direction = [0, 0]"),
     "actuator 2 'tip_moment': 'direction' must be three numbers"),
    (TIP.replace('quantity = "displacement"\n\n[[sensor]]', 'quantity = "strain"\n\n[[sensor]]'),
     "sensor 1 'tip_w': quantity must be one of"),
    (TIP.split("[[sensor]]")[0], "no [[sensor]] entries"),
    (TIP.replace('name = "mid_w"', 'name = "tip_w"'), "the name 'tip_w' is used twice"),
    ("[[actuator\n", "not valid TOML"),
])
def test_bad_io_files_name_the_entry_and_key(tmp_path, text, match):
    model, _ = read_bdf(DECK)
    with pytest.raises(ModelError, match=match.replace("[", r"\[").replace("]", r"\]")
                       .replace("(", r"\(").replace(")", r"\)")):
        io_plant(model, read_io(spec_file(tmp_path, text)), n_modes=4)
