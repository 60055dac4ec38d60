"""Entries that cannot change real modes are accepted with a note naming them and saying why
(issue 33): the modes equal those of the same deck without them; the case control decides
when they would count (RGYRO, TFL), and then they are refused, naming the entry. Component
fields written with embedded blanks (``12 4 6``, as MYSTRAN writes them) read as their digits.
"""

from __future__ import annotations

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf

BEAM = ("MAT1,1,70.+9,,0.3,2700.\nPBAR,1,1,1.-4,2.-9,3.-9,4.-9\n"
        + "".join(f"GRID,{i},,{0.25 * (i - 1)!r},0.,0.\n" for i in range(1, 6))
        + "".join(f"CBAR,{e},1,{e},{e + 1},0.,0.,1.\n" for e in range(1, 5)) + "SPC1,1,123456,1\n")
NOTED = ("EIGP,90,-1.,2.,1\nSEQGP,1,5,2,4\nROTORG,7,1,THRU,5\nROTORD,7,0.,100.,10\nTF,3,1,1,1.,0.,0.\n"
         "EPOINT,101\n")


def deck(tmp_path, bulk: str, case: str = "", name: str = "d.bdf"):
    p = tmp_path / name
    p.write_text(f"SOL 103\nCEND\nSPC = 1\n{case}BEGIN BULK\n{bulk}ENDDATA\n")
    return read_bdf(p)


def freqs(model, info):
    return solve_modes(model, n_modes=6, autospc=info.autospc).frequencies_hz


def test_entries_without_effect_are_noted_by_name_and_leave_the_modes_unchanged(tmp_path):
    plain = deck(tmp_path, BEAM)
    model, info = deck(tmp_path, BEAM + NOTED, name="noted.bdf")
    np.testing.assert_array_equal(freqs(model, info), freqs(*plain))
    for name, why in (("EIGP", "complex eigenvalue"), ("SEQGP", "resequencing"), ("ROTORD", "RGYRO"),
                      ("ROTORG", "RGYRO"), ("TF", "not selected by TFL"), ("EPOINT", "extra points")):
        assert any(n.startswith(f"{name} (1): ") and why in n and n.endswith("ignored") for n in info.notes), name
        assert f"{name} (1)" in info.ignored


@pytest.mark.parametrize("case,match", [
    ("RGYRO = 7\n", r"ROTORG 7: RGYRO = 7 in the case control asks for rotordynamics"),
    ("TFL = 3\n", r"TF 3: TFL = 3 in the case control selects transfer functions"),
])
def test_selected_by_the_case_control_they_are_refused_naming_the_entry(tmp_path, case, match):
    with pytest.raises(ModelError, match=match) as err:
        deck(tmp_path, BEAM + NOTED, case)
    assert "\n" not in str(err.value)


def small(*fields: str) -> str:
    return "".join(f"{f:<8}" for f in fields) + "\n"


def test_component_fields_with_embedded_blanks_read_as_their_digits(tmp_path):
    """GRDSET PS, SPC1 C, RBE2 CM and CBAR PA written ``1 2 3``-style in fixed fields (and in
    free field) give the model of the same deck with the digits together."""
    base = ("MAT1,1,70.+9,,0.3,2700.\nPBAR,1,1,1.-4,2.-9,3.-9,4.-9\n"
            + "".join(f"GRID,{i},,{0.25 * (i - 1)!r},0.,0.\n" for i in range(1, 7))
            + "".join(f"CBAR,{e},1,{e},{e + 1},0.,0.,1.\n" for e in range(1, 5))
            + "CONM2,9,6,,0.5\n")
    joined = (base + small("GRDSET", "", "", "", "", "", "", "6") + small("SPC1", "1", "123456", "1")
              + small("RBE2", "20", "5", "123", "6") + small("CBAR", "5", "1", "4", "6", "0.", "0.", "1.")
              + small("", "456"))
    blanks = (base + small("GRDSET", "", "", "", "", "", "", " 6") + small("SPC1", "1", "12 3456", "1")
              + small("RBE2", "20", "5", "1 2 3", "6") + small("CBAR", "5", "1", "4", "6", "0.", "0.", "1.")
              + small("", "4 5 6"))
    free = base + "GRDSET,,,,,,,6\nSPC1,1,1 2 3 4 5 6,1\nRBE2,20,5,12 3,6\nCBAR,5,1,4,6,0.,0.,1.\n,4 56\n"
    ref_model, ref_info = deck(tmp_path, joined, name="joined.bdf")
    f_ref = freqs(ref_model, ref_info)
    for name, text in (("blanks", blanks), ("free", free)):
        model, info = deck(tmp_path, text, name=f"{name}.bdf")
        np.testing.assert_array_equal(model.fixed_mask(), ref_model.fixed_mask())
        np.testing.assert_allclose(freqs(model, info), f_ref, rtol=1e-12)


def test_a_component_field_with_other_characters_is_refused_naming_the_entry(tmp_path):
    with pytest.raises(ModelError, match=r"RBE2 20.*components '1 2 X'") as err:
        deck(tmp_path, BEAM + small("RBE2", "20", "5", "1 2 X", "4"))
    assert "\n" not in str(err.value)
