"""``trussid modes`` on malformed or unsupported decks: exit status 2, one line on stderr that
names the entry and its id (as the user can find it in the deck), none of pyNastran's
internals, and no file written (not even the OP2 that was asked for)."""

from __future__ import annotations

import re

import pytest

from trussid.cli import main

BEAM = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nMAT1,1,70.+9,,0.3,2700.\nPBAR,1,1,1.-4,2.-9,2.-9,4.-9\n"
CBAR = "CBAR,10,1,1,2,0.,0.,1.\n"

#: (case, bulk data, the entry and id the message must name)
BAD_DECKS = [
    ("no orientation", BEAM + "CBAR,10,1,1,2\n", "CBAR 10"),
    ("undefined grid", BEAM + "CBAR,10,1,1,7,0.,0.,1.\n", "CBAR 10"),
    ("undefined property", BEAM + "CBAR,10,5,1,2,0.,0.,1.\n", "CBAR 10"),
    ("text in an integer field", BEAM + "CBAR,10,1,1,abc,0.,0.,1.\n", "CBAR 10"),
    ("offsets", BEAM + "CBAR,10,1,1,2,0.,0.,1.\n,,,1.,0.,0.\n", "CBAR 10"),
    ("bad pin flag", BEAM + "CBAR,10,1,1,2,0.,0.,1.\n,7\n", "CBAR 10"),
    ("undefined material", BEAM.replace("PBAR,1,1,", "PBAR,1,9,") + CBAR, "PBAR 1"),
    ("unknown PBARL shape", BEAM + "PBARL,2,1,,HAT\n,1.,2.,3.,4.\nCBAR,10,2,1,2,0.,0.,1.\n", "PBARL 2"),
    ("tapered PBEAM with no area at end B", BEAM + "PBEAM,3,1,1.-4,2.-9,2.-9,,4.-9\n,YES,1.,0.,3.-9,3.-9,,4.-9\n"
     "CBEAM,10,3,1,2,0.,0.,1.\n", "PBEAM 3"),
    ("tapered PBEAML with a station beyond end B", BEAM + "PBEAML,3,1,,BAR\n,0.01,0.02,,NO,1.5,0.01,0.03\n"
     ",,YES,1.,0.01,0.04\nCBEAM,10,3,1,2,0.,0.,1.\n", "PBEAML 3"),
    ("tapered PBEAM with pin flags", BEAM + "PBEAM,3,1,1.-4,2.-9,2.-9,,4.-9\n,YES,1.,2.-4,3.-9,3.-9,,4.-9\n"
     "CBEAM,10,3,1,2,0.,0.,1.\n,4\n", "CBEAM 10"),
    ("text in a GRID coordinate", "GRID,1,,0.,x,0.\n", "GRID 1"),
    ("CONM2 on an undefined grid", BEAM + CBAR + "CONM2,20,9,,1.\n", "CONM2 20"),
    ("negative CONM2 mass", BEAM + CBAR + "CONM2,20,2,,-1.\n", "CONM2 20"),
    ("CELAS2 component 9", BEAM + CBAR + "CELAS2,30,1.,2,9\n", "CELAS2 30"),
    ("RBE2 on an undefined grid", BEAM + CBAR + "RBE2,40,1,123456,8\n", "RBE2 40"),
    ("GENEL short of terms", BEAM + CBAR + "GENEL,50,,1,1,2,1\n,Z,1.,2.\n", "GENEL 50"),
    ("CONM1 with text", BEAM + CBAR + "CONM1,60,2,0,abc\n", "CONM1 60"),
    ("EIGR with text in ND", BEAM + CBAR + "EIGR,70,FEER,0.,10.,,abc\n", "EIGR 70"),
    ("EIGRL with text", BEAM + CBAR + "EIGRL,1,abc\n", "EIGRL 1"),
    ("SPC1 on an undefined grid", BEAM + CBAR + "SPC1,90,123456,5\n", "SPC1 90"),
    ("CMASS4 on a GRID", BEAM + CBAR + "CMASS4,100,1.,1\n", "CMASS4 100"),
    ("CMASS3 without its PMASS", BEAM + CBAR + "SPOINT,5\nCMASS3,100,1,5\n", "CMASS3 100"),
    ("GENEL with a blank inside its K terms", BEAM + CBAR + "GENEL,51,,1,1,2,1\n,K,1.,,3.\n", "GENEL 51"),
    ("GENEL with UD and no S", BEAM + CBAR + "GENEL,52,,1,1\n,UD,,2,1\n,K,1.\n", "GENEL 52"),
    ("GENEL with a singular Z", BEAM + CBAR + "GENEL,53,,1,1,2,1\n,Z,1.,1.,1.\n", "GENEL 53"),
    ("GENEL on a component of a scalar point", BEAM + CBAR + "SPOINT,7\nGENEL,54,,7,3\n,K,1.\n", "GENEL 54"),
    ("GENEL on an undefined scalar point", BEAM + CBAR + "GENEL,55,,8,0\n,K,1.\n", "scalar point 8"),
    ("scalar spring on no scalar point", BEAM + CBAR + "CELAS4,57,1.\n", "CELAS4 57"),
    ("scalar element on a point that is not an id", "PELAS,1,100.\nCELAS3,58,1,abc,2\nCMASS4,59,1.,2\n",
     "CELAS3 58"),
    ("scalar-point deck with an undefined PELAS", "CELAS3,58,9,1,2\nCMASS4,59,1.,1\n", "CELAS3 58"),
    ("a mass moving alone inside a structure (mechanism)", "GRID,1,,0.,0.,0.,,123456\nGRID,2,,1.,0.,0.,,236\n"
     "GRID,3,,2.,0.,0.,,23456\nMAT1,1,70.+9,,0.3,2700.\nPROD,1,1,1.-4,1.-9\nCROD,1,1,1,2\nCROD,2,1,2,3\n"
     "CONM2,3,2,,1.,,,,,\n,,,.1\n", "node 2 ry"),
    ("Q-set scalar point with an element", BEAM + CBAR + "SPOINT,9\nASET1,123456,2\nQSET1,0,9\n"
     "CELAS4,56,1.,9\n", "QSET 9"),
    ("component field with a letter", BEAM + CBAR + "RBE2,40,2,12 X,1\n", "RBE2 40: components"),
    ("DMIG with text in a term", BEAM + CBAR + "DMIG,KX,0,6,1,0\nDMIG,KX,1,1,,1,abc,1.\n", "DMIG KX"),
    ("matrix scale factor", BEAM + CBAR + "PARAM,CK1,2.\n", "PARAM,CK1"),
    ("boundary set alone", BEAM + CBAR + "BSET1,123456,1\n", "BSET1 (grid 1)"),
    ("Q-set on a grid", BEAM + CBAR + "QSET1,123456,2\n", "QSET1 2"),
    ("text WTMASS", BEAM + CBAR + "PARAM,WTMASS,abc\n", "PARAM,WTMASS"),
    ("NASTRAN-95 blank-separated free field", BEAM + "CBAR,  10  1   1   2  0. 0. 1.\n", "CBAR 10"),
    ("NASTRAN-95 replicator", BEAM + CBAR + "=(3),*(1),=,*(1),/\n", "line 7: NASTRAN-95 free-field input (a replicator"),
    ("shell elements", BEAM + CBAR + "CQUAD4,200,1,1,2,2,1\n", "CQUAD4 200"),
    ("GRDSET with an undefined system", "GRDSET,,,,,,7\n" + BEAM + CBAR, "GRID 1"),
    ("GRDSET with text", "GRDSET,,abc\n" + BEAM + CBAR, "GRDSET"),
]

#: What pyNastran's own messages carry and a user's message must not.
INTERNALS = re.compile(r"uline=|allowed_methods=|allowed=|card=\[|Traceback|len\(\w+ card\)")


#: Decks whose case control selects what makes them bad: (case, case control, bulk, named).
CASE_BAD_DECKS = [
    ("rotor entries selected by RGYRO", "RGYRO = 10\n",
     BEAM + CBAR + "SPC1,1,123456,1\nROTORG,10,1,2\n", "ROTORG 10"),
    ("MPC on an undefined scalar point", "MPC = 5\n", BEAM + CBAR + "MPC,5,77,0,1.,2,1,-1.\n", "scalar point 77"),
]


def test_at_least_twenty_bad_decks():
    assert len(BAD_DECKS) >= 20


@pytest.mark.parametrize("case,bulk,named", [("", b, n) for _c, b, n in BAD_DECKS]
                         + [(cc, b, n) for _c, cc, b, n in CASE_BAD_DECKS],
                         ids=[c for c, _b, _n in BAD_DECKS] + [c for c, *_ in CASE_BAD_DECKS])
def test_bad_deck_exits_2_naming_the_entry_and_writes_nothing(tmp_path, monkeypatch, capsys, case, bulk, named):
    deck = tmp_path / "bad.bdf"
    deck.write_text(("SOL 103\nCEND\n" + case if case else "") + "BEGIN BULK\n" + bulk + "ENDDATA\n")
    monkeypatch.chdir(tmp_path)  # pyNastran leaves crash files in the working directory
    before = sorted(p.name for p in tmp_path.iterdir())
    code = main(["modes", str(deck), "--op2", str(tmp_path / "out.op2")])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("trussid modes: error: ")
    assert named in lines[0], lines[0]
    assert not INTERNALS.search(lines[0]), lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_rigid_format_13_is_refused_naming_the_analysis(tmp_path, capsys):
    deck = tmp_path / "d13.dat"
    deck.write_text("APP DISP\nSOL 13,0\nCEND\nBEGIN BULK\n" + BEAM + CBAR + "ENDDATA\n")
    assert main(["modes", str(deck)]) == 2
    err = capsys.readouterr().err
    assert "SOL 13" in err and "differential stiffness" in err
