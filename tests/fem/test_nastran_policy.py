"""The entry policy (docs/nastran-entries.md, issue 33): every entry is used, ignored with a
note, or refused, and the documented table says the same as the reader's lists. Ignored
entries change nothing: a deck with them has the modes of the deck without them."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf
from trussid.fem.nastran.entries import (CASE_SELECTED_CARDS, IGNORED_CARDS, NOTED_CARDS, SUPPORTED_CARDS,
                                         THERMAL_CARDS)

DOC = Path(__file__).resolve().parents[2] / "docs" / "nastran-entries.md"


def documented() -> dict[str, str]:
    """Entry -> class from the doc's table of entries."""
    table = DOC.read_text().split("## The entries", 1)[1]
    out = {}
    for row in table.splitlines():
        cells = [c.strip() for c in row.strip().strip("|").split("|")]
        if len(cells) != 3 or cells[1] in ("class", "---"):
            continue
        for name in re.findall(r"`([A-Z0-9]+)`", cells[0]):
            out[name] = cells[1]
    return out


def test_the_documented_table_matches_the_readers_lists():
    doc = documented()
    assert {n for n in SUPPORTED_CARDS if doc.get(n) != "used"} == set()
    noted_only = set(NOTED_CARDS) - set(CASE_SELECTED_CARDS)
    assert {n for n in IGNORED_CARDS | noted_only if doc.get(n) != "ignored"} == set()
    assert {n for n in set(CASE_SELECTED_CARDS) | THERMAL_CARDS if doc.get(n) != "ignored unless selected"} == set()
    listed = {n for n, c in doc.items() if c in ("used", "ignored", "ignored unless selected")}
    assert listed - (SUPPORTED_CARDS | IGNORED_CARDS | set(NOTED_CARDS) | THERMAL_CARDS) == set()


def test_each_entry_has_one_class():
    """A case-selected entry is a noted one (ignored until a request selects it); no entry is in
    two of the lists."""
    assert set(CASE_SELECTED_CARDS) <= set(NOTED_CARDS)
    lists = [SUPPORTED_CARDS, IGNORED_CARDS, set(NOTED_CARDS), THERMAL_CARDS]
    assert sum(len(a) for a in lists) == len(set().union(*lists))


BEAM = ("GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nGRID,3,,2.,0.,0.\nMAT1,1,70.+9,,0.3,2700.\n"
        "PBAR,1,1,1.-4,2.-9,3.-9,4.-9\nCBAR,10,1,1,2,0.,0.,1.\nCBAR,11,1,2,3,0.,0.,1.\nSPC1,1,123456,1\n")
WITHOUT_EFFECT = "EIGP,90,1.,2.,1\nSEQGP,1,3,3,1\nROTORG,10,1,THRU,3\nROTORD,10,0.,100.,10,RPM,NO\n,,,,,,,,\n,1,10\n"


def modes_of(tmp_path, bulk, name, case=""):
    p = tmp_path / name
    p.write_text("SOL 103\nCEND\n" + case + "BEGIN BULK\n" + bulk + "ENDDATA\n")
    model, info = read_bdf(p)
    return solve_modes(model, n_modes=6, autospc=info.autospc).frequencies_hz, info


def test_entries_without_effect_are_ignored_with_a_note_and_change_nothing(tmp_path):
    plain, _ = modes_of(tmp_path, BEAM, "plain.bdf")
    extra, info = modes_of(tmp_path, BEAM + WITHOUT_EFFECT, "extra.bdf")
    np.testing.assert_array_equal(extra, plain)
    assert {"EIGP (1)", "SEQGP (1)", "ROTORG (1)", "ROTORD (1)"} <= set(info.ignored)


def test_rotor_entries_selected_by_rgyro_are_refused_naming_them(tmp_path):
    with pytest.raises(ModelError, match=r"ROTORG 10: RGYRO = 10 in the case control asks for rotordynamics"):
        modes_of(tmp_path, BEAM + WITHOUT_EFFECT, "rotor.bdf", case="RGYRO = 10\n")
