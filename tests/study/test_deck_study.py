"""``trussid study`` on a structure of one's own: the ``deck`` evaluator varies a PBAR
area and a CONM2 mass of a written deck (issue 24, acceptance 3).

Checked against an independent serial loop that builds each design through the API (no
deck editing), and run again to show that a finished study computes nothing more."""

import re

import numpy as np
import pandas as pd
import pytest

from trussid import fem
from trussid.cli import main
from tests.campaign.test_demo_any_structure import tower

SPEC = """
[study]
name = "tower"
evaluate = "deck"
chunk = 2

[evaluate]
deck = "{deck}"
n_modes = 8

[parameters]
"PBAR.1.A" = {{values = [2.0e-4, 2.6e-4]}}
"CONM2.{mass}.M" = {{values = [1.0, 2.0, 3.0]}}
"""


def tower_with(area: float, mass: float) -> fem.Model:
    """The tower built again through the API with the tube's area and node 31's mass."""
    m = tower()
    b = m.beams
    sec = fem.Section.general(area, float(b.Iy[0]), float(b.Iz[0]), float(b.J[0]))
    out = fem.Model(mass="lumped")
    out.add_nodes(m.node_ids, m.xyz)
    for i in range(len(b)):
        out.add_beams([b.ids[i]], [b.nodes[i]], sec, fem.STEEL, orient=b.orient[i])
    out.add_point_masses([31, 32, 33], [mass, 1.5, 1.0])
    out.fix([1, 2, 3])
    return out


@pytest.fixture()
def study(tmp_path):
    deck = tmp_path / "tower.bdf"
    fem.write_bdf(tower(), deck, n_modes=8)
    text = deck.read_text()
    # the CONM2 holding node 31's 2 kg (its id is the writer's choice)
    mass_id = next(int(m.group(1)) for m in re.finditer(
        r"^CONM2\*?\s+(\d+)\s+31\s", text, flags=re.M))
    spec = tmp_path / "s.toml"
    spec.write_text(SPEC.format(deck=deck, mass=mass_id))
    return spec, mass_id


def test_a_deck_study_equals_a_serial_loop_over_designs_and_resumes(tmp_path, study, capsys):
    spec, mass_id = study
    out = tmp_path / "o"
    assert main(["study", str(spec), "--out", str(out), "--workers", "0", "--quiet"]) == 0
    assert "6 points: computed 6 in this run (0 failed)" in capsys.readouterr().out
    table = pd.read_parquet(out).sort_values("point")
    assert (table["status"] == "ok").all()
    for _, row in table.iterrows():
        f = fem.solve_modes(tower_with(row["PBAR.1.A"], row[f"CONM2.{mass_id}.M"]),
                            n_modes=8).frequencies_hz
        np.testing.assert_allclose([row[f"f{k + 1}"] for k in range(8)], f, rtol=1e-9)
    # the two parameters act: the area and the mass each move the first mode
    assert table["f1"].nunique() == 6
    # a finished study: the same command computes nothing and keeps the table
    assert main(["study", str(spec), "--out", str(out), "--workers", "0", "--quiet"]) == 0
    assert "computed 0 in this run (0 failed), 6 already done" in capsys.readouterr().out
    again = pd.read_parquet(out).sort_values("point")
    pd.testing.assert_frame_equal(again.reset_index(drop=True), table.reset_index(drop=True))


@pytest.mark.parametrize("name, match", [
    ("PBAR.7.A", "the deck has no PBAR 7"),
    ("PBAR.1.Q", "PBAR field must be one of A, I1, I2, J"),
    ("wall0", "name it CARD.ID.FIELD"),
])
def test_a_deck_parameter_that_names_nothing_is_refused(tmp_path, study, capsys, name, match):
    spec, _ = study
    text = spec.read_text().replace('"PBAR.1.A"', f'"{name}"')
    spec.write_text(text)
    assert main(["study", str(spec), "--out", str(tmp_path / "o"), "--workers", "0"]) == 2
    err = capsys.readouterr().err
    assert match in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.slow  # starts a two-process Dask cluster
def test_two_workers_give_the_serial_table(tmp_path, study, capsys):
    spec, _ = study
    assert main(["study", str(spec), "--out", str(tmp_path / "serial"), "--workers", "0",
                 "--quiet"]) == 0
    assert main(["study", str(spec), "--out", str(tmp_path / "two"), "--workers", "2",
                 "--quiet"]) == 0
    cols = ["point", "PBAR.1.A"] + [f"f{k + 1}" for k in range(8)]
    a = pd.read_parquet(tmp_path / "serial").sort_values("point")[cols].reset_index(drop=True)
    b = pd.read_parquet(tmp_path / "two").sort_values("point")[cols].reset_index(drop=True)
    pd.testing.assert_frame_equal(a, b)
