"""Actuators and sensors that could only give an all-zero channel are refused by name, and
the plant of a deck with massless directions can be asked for at any sample rate (issue 24,
newcomer audit 2: I07, I09, I15, I16, I28, I29)."""

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.iospec import io_plant, read_io
from trussid.fem.nastran import read_bdf
from tests.fem.test_massless_directions import inclined_truss_deck

SENSOR = """
[[sensor]]
name = "acc_tip"
node = 23
direction = [0, 0, 1]
quantity = "acceleration"
"""
SHAKER = """
[[actuator]]
name = "shaker"
type = "force"
node = {node}
direction = [0, 0, 1]
"""


@pytest.fixture()
def deck(tmp_path):
    """The inclined-bar truss (grids 1-4 clamped, tip 21-24) plus a bare grid 999."""
    text = inclined_truss_deck().replace("ENDDATA", "GRID,999,,2.,2.,2.\nENDDATA")
    path = tmp_path / "truss.bdf"
    path.write_text(text)
    return path


def plant_of(tmp_path, deck, io_text, **kw):
    (tmp_path / "io.toml").write_text(io_text)
    model, info = read_bdf(deck)
    return io_plant(model, read_io(tmp_path / "io.toml"), autospc=True, **kw)


@pytest.mark.parametrize("node, why", [(1, "node 1 is clamped"),
                                       (999, "node 999 has no element, mass or spring")])
def test_a_shaker_that_moves_nothing_is_refused(tmp_path, deck, node, why):
    with pytest.raises(ModelError, match=f"actuator 1 'shaker': the input moves no free DOF "
                                         f"\\({why}.*identically zero"):
        plant_of(tmp_path, deck, SHAKER.format(node=node) + SENSOR)


@pytest.mark.parametrize("node, why", [(2, "node 2 is clamped"),
                                       (999, "node 999 has no element")])
def test_a_sensor_that_reads_nothing_is_refused(tmp_path, deck, node, why):
    io = SHAKER.format(node=21) + SENSOR.replace("node = 23", f"node = {node}")
    with pytest.raises(ModelError, match=f"sensor 1 'acc_tip': it reads no free DOF \\({why}"):
        plant_of(tmp_path, deck, io)


def test_a_bending_pzt_pair_over_a_rod_is_refused(tmp_path, deck):
    text = deck.read_text().replace("ENDDATA", "PROD,2,1,1.e-4,1.e-9\nCROD,700,2,21,23\nENDDATA")
    deck.write_text(text)
    io = """
[[actuator]]
name = "pzt"
type = "strain"
elements = [700]
offset = 0.01
face_axis = "y"
arrangement = "bending"
n_wafers = 2
wafer = { width = 0.01, length = 0.05, thickness = 0.0005, youngs_modulus = 6.3e10, d31 = -1.9e-10 }
""" + SENSOR
    with pytest.raises(ModelError, match="element 700 is a rod"):
        plant_of(tmp_path, deck, io)


@pytest.mark.parametrize("kw", [{"fs": 20000.0}, {"n_modes": 500}])
def test_plant_of_a_deck_with_massless_directions_at_any_rate_or_mode_count(tmp_path, deck, kw):
    """I28/I29: more than half the DOFs asked for used to end in LinAlgError."""
    sc, sd, modes, n = plant_of(tmp_path, deck, SHAKER.format(node=21) + SENSOR, **kw)
    f = modes.frequencies_hz
    # every mode below Nyquist, or every mode that carries mass (158 of 180 DOFs)
    expect = int(np.sum(f < kw["fs"] / 2)) if "fs" in kw else len(f)
    assert n == expect > 60 and (len(f) == 158 or f[-1] >= kw.get("fs", 0) / 2)
    assert np.all(np.isfinite(np.asarray(sc.A)))
    assert np.max(np.real(np.linalg.eigvals(np.asarray(sc.A)))) < 0
