"""A deck whose E and density no consistent unit system gives a solid is said loudly
(issue 24, newcomer audit 2: N05 mm/MPa with kg/m^3; N31 inch deck without WTMASS)."""

import warnings
from pathlib import Path

import pytest

from trussid.fem.errors import UnitsWarning
from trussid.fem.materials import wave_speed_problem
from trussid.fem.nastran import read_bdf
from tests.fem.test_nastran import cantilever_deck, write

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("E, rho, unit", [
    (68.9e9, 2700.0, "m"),        # SI: 5050 m/s
    (68.9e3, 2.7e-9, "mm"),       # mm, N, s: MPa and t/mm^3
    (1.0e7, 0.0975 * 0.00259, "in"),  # inch-pound with WTMASS applied
    (3.0e9, 1200.0, "m"),         # a polymer: 1580 m/s
])
def test_consistent_units_are_accepted(E, rho, unit):
    assert wave_speed_problem(E, rho) is None


def test_mm_mpa_with_kg_per_m3_is_named():
    why = wave_speed_problem(68.9e3, 2700.0)
    assert "sqrt(E/rho) = 5.05" in why and "MPa with kg/m^3" in why


def test_deck_in_mm_and_mpa_with_si_density_warns_naming_the_material(tmp_path):
    deck = cantilever_deck(n_el=4, L=1000.0, E=68.9e3, rho=2700.0, A=100.0, I1=2e3, I2=2e3,
                           J=4e3)
    with pytest.warns(UnitsWarning, match=r"MAT1 1: sqrt\(E/rho\) = 5.05"):
        read_bdf(write(tmp_path, deck, "mm.bdf"))


def test_inch_deck_without_wtmass_warns(tmp_path):
    text = (ROOT / "examples" / "decks" / "cantilever_inch.bdf").read_text()
    text = "\n".join(line for line in text.splitlines() if not line.startswith("PARAM,WTMASS"))
    with pytest.warns(UnitsWarning, match="inch-pound units with a weight density"):
        read_bdf(write(tmp_path, text + "\n", "inch.bdf"))


def test_the_example_decks_raise_no_units_warning():
    decks = sorted((ROOT / "examples" / "decks").glob("*.bdf"))
    assert decks
    for deck in decks:
        with warnings.catch_warnings():
            warnings.simplefilter("error", UnitsWarning)
            read_bdf(deck)
