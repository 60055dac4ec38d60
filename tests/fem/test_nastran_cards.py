"""The NASTRAN parser (fem/nastran/cards.py): every card format and continuation form gives
the same fields, INCLUDEs are read where the including file says, fields convert by NASTRAN's
rules and a bad field is one line naming file, line, entry and field.

Expected values are written by hand from the QRG's format rules (columns of small and large
fields, continuation markers), independent of the parser."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.nastran.cards import (Card, deck_text, integer, integer_or_blank, nastran_value, parse_deck,
                                       real, real_or_blank)

#: CBAR 10 with pin flag and an offset, as fields 1-9 of its first line and its continuation
CBAR_FIELDS = ("CBAR", "10", "1", "1", "2", "0.", "0.", "1.", "", "", "456", "", "0.1", "", "", "", "")


def small(*fields: str) -> str:
    """One small-field line: 8-column fields, continuation field 10 blank."""
    return "".join(f"{f:<8}" for f in fields)


def large_lines(name: str, data: list, marker: str = "*") -> list:
    """A large-field entry: name*, four 16-column fields per line, continuations starting ``*``."""
    out = []
    for k in range(0, len(data), 4):
        head = f"{name + '*':<8}" if k == 0 else f"{marker:<8}"
        out.append(head + "".join(f"{v:>16}" for v in data[k:k + 4]))
    return out


def cards_of(tmp_path, text: str, name: str = "deck.bdf"):
    p = tmp_path / name
    p.write_text(text)
    return parse_deck(p).cards


def fields(card: Card) -> tuple:
    f = list(card.fields)
    while f and f[-1] == "":
        f.pop()
    return tuple(f)


WANT = tuple(f for f in CBAR_FIELDS[:13])


@pytest.mark.parametrize("form,text", [
    ("small, explicit +name", small("CBAR", "10", "1", "1", "2", "0.", "0.", "1.", "", "+C1") + "\n"
     + small("+C1", "", "456", "", "0.1") + "\n"),
    ("small, implicit blank continuation", small("CBAR", "10", "1", "1", "2", "0.", "0.", "1.") + "\n"
     + small("", "", "456", "", "0.1") + "\n"),
    ("small, tabs", "CBAR\t10\t1\t1\t2\t0.\t0.\t1.\n\t\t456\t\t0.1\n"),
    ("large, *name continuation", "\n".join(large_lines("CBAR", ["10", "1", "1", "2", "0.", "0.", "1.", "",
                                                                 "", "456", "", "0.1"], marker="*C1")) + "\n"),
    ("free field", "CBAR,10,1,1,2,0.,0.,1.\n,,456,,0.1\n"),
    ("free field, +marker", "CBAR,10,1,1,2,0.,0.,1.,,+A\n+A,,456,,0.1\n"),
    ("free field, auto-continuation", "CBAR,10,1,1,2,0.,0.,1.,,,,,456,,0.1\n"),
    ("large free field", "CBAR*,10,1,1,2\n*,0.,0.,1.,\n*,,456,,0.1\n"),
    ("large free field, auto-continuation", "CBAR*,10,1,1,2,,*,0.,0.,1.,,,*,,456,,0.1\n"),
    ("mixed: small then free", small("CBAR", "10", "1", "1", "2", "0.", "0.", "1.") + "\n,,456,,0.1\n"),
    ("lower case, comments, blank lines", "$ a comment\ncbar,10,1,1,2,0.,0.,1. $ the bar\n\n,,456,,0.1\n"),
])
def test_every_format_and_continuation_form_gives_the_same_fields(tmp_path, form, text):
    (card,) = cards_of(tmp_path, "BEGIN BULK\n" + text + "ENDDATA\n")
    assert card.name == "CBAR"
    assert fields(card) == WANT, form
    assert card.line == (3 if form.startswith("lower case") else 2)  # the comment takes line 2


def test_small_field_columns_73_to_80_are_the_continuation_field(tmp_path):
    line = small("GRID", "7", "", "1.5", "2.5", "3.5", "", "", "") + "+G7"
    (card,) = cards_of(tmp_path, f"BEGIN BULK\n{line}\n{small('+G7')}\nENDDATA\n")
    assert fields(card) == ("GRID", "7", "", "1.5", "2.5", "3.5")


def test_enddata_ends_the_bulk_data_and_executive_case_control_are_read(tmp_path):
    text = ("ID X,Y\nSOL 103 $ modes\nCEND\nTITLE = t\nMETHOD = 5\nSPC = 1\nSUBCASE 1\n  SPC = 2\n"
            "SUBCASE 2\n  DISPLACEMENT(PLOT) = ALL\nBEGIN BULK\nGRID,1,,0.,0.,0.\nENDDATA\nGRID,2,,1.,0.,0.\n")
    p = tmp_path / "d.dat"
    p.write_text(text)
    deck = parse_deck(p)
    assert deck.sol == "103" and [c.name for c in deck.cards] == ["GRID"]
    assert deck.case.values("METHOD") == ["5"]
    assert deck.case.values("SPC") == ["1", "2"]  # global first, then subcase 1
    assert deck.case.values("DISPLACEMENT") == ["ALL"]


def test_a_file_without_begin_bulk_is_bulk_data(tmp_path):
    cards = cards_of(tmp_path, "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\n")
    assert [c.get(1) for c in cards] == ["1", "2"]


# ------------------------------------------------------------------ INCLUDE
def test_include_forms_relative_quoted_windows_multiline_and_nested(tmp_path):
    sub = tmp_path / "sub"
    (sub / "deeper").mkdir(parents=True)
    (sub / "a.bdf").write_text("GRID,1,,0.,0.,0.\nINCLUDE 'deeper/b.bdf'\n")  # relative to sub/
    (sub / "deeper" / "b.bdf").write_text("GRID,2,,1.,0.,0.\n")
    (sub / "c.bdf").write_text("GRID,3,,2.,0.,0.\n")
    (sub / "d.bdf").write_text("GRID,4,,3.,0.,0.\n")
    (tmp_path / "e.bdf").write_text("GRID,5,,4.,0.,0.\n")
    main = ("SOL 103\nCEND\nBEGIN BULK\nINCLUDE 'sub/a.bdf'\ninclude 'sub\\c.bdf'\n"
            "INCLUDE 'sub/\n         d.bdf'\nINCLUDE e.bdf\nENDDATA\n")
    cards = cards_of(tmp_path, main, "main.bdf")
    assert [int(c.get(1)) for c in cards] == [1, 2, 3, 4, 5]
    assert cards[1].file.endswith("deeper/b.bdf") and cards[1].line == 1


def test_include_errors_name_the_including_file_and_line(tmp_path):
    with pytest.raises(ModelError, match=r"main.bdf, line 3: INCLUDE '.*nope.bdf': no such file"):
        cards_of(tmp_path, "BEGIN BULK\nGRID,1,,0.,0.,0.\nINCLUDE 'nope.bdf'\n", "main.bdf")
    (tmp_path / "loop.bdf").write_text("INCLUDE 'loop.bdf'\n")
    with pytest.raises(ModelError, match="includes itself"):
        cards_of(tmp_path, "BEGIN BULK\nINCLUDE 'loop.bdf'\n", "main2.bdf")


def test_an_error_in_an_included_file_names_that_file_and_its_line(tmp_path):
    (tmp_path / "inc.bdf").write_text("$ grids\nGRID,1,,0.,0.,0.\nGRID,2,,x,0.,0.\n")
    from trussid.fem.nastran import read_bdf

    p = tmp_path / "main.bdf"
    p.write_text("BEGIN BULK\nINCLUDE 'inc.bdf'\nENDDATA\n")
    with pytest.raises(ModelError, match=r"inc.bdf, line 3: GRID 2: field 4: X1 must be a real number"):
        read_bdf(p)


# ------------------------------------------------------------------ field rules
@pytest.mark.parametrize("text,value", [
    ("1.5", 1.5), (".5", 0.5), ("-.5", -0.5), ("1.", 1.0), ("1.-3", 1e-3), ("1.+5", 1e5), ("-2.5-2", -0.025),
    ("+3.25+1", 32.5), ("1.E5", 1e5), ("1.5D-3", 1.5e-3), ("7.0E+1", 70.0), (".7E2", 70.0), ("0.7+2", 70.0),
])
def test_reals_follow_nastrans_forms(text, value):
    card = Card("X", ("X", text), "f", (1,), (8,))
    assert real(card, 1, "V") == pytest.approx(value, rel=1e-15)
    assert nastran_value(text) == pytest.approx(value, rel=1e-15)


def test_integers_blanks_and_defaults():
    card = Card("X", ("X", "12", "", "-3"), "f", (1,), (8,))
    assert integer(card, 1, "ID") == 12 and integer(card, 3, "ID") == -3
    assert integer_or_blank(card, 2, "CP", 7) == 7 and real_or_blank(card, 2, "X", 0.0) == 0.0
    assert real_or_blank(card, 9, "X", 1.0) == 1.0  # beyond the entry's end: blank
    assert nastran_value("12") == 12 and isinstance(nastran_value("12"), int)
    assert nastran_value("yes") == "YES"


@pytest.mark.parametrize("field_text,which,match", [
    ("5", "real", r"f.bdf, line 4: CBAR 10: field 3: W must be a real number \(with a decimal point\), got '5'"),
    ("1.2.3", "real", r"field 3: W must be a real number .*got '1.2.3'"),
    ("", "real", r"field 3: W must be a real number .*got blank"),
    ("1.5", "integer", r"field 3: W must be an integer, got '1.5'"),
    ("ABC", "integer", r"field 3: W must be an integer, got 'ABC'"),
])
def test_a_bad_field_is_one_line_naming_file_line_entry_and_field(field_text, which, match):
    card = Card("CBAR", ("CBAR", "10", field_text), "f.bdf", (4,), (8,))
    with pytest.raises(ModelError, match=match) as err:
        (real if which == "real" else integer)(card, 2, "W")
    assert "\n" not in str(err.value)


def test_a_field_on_a_continuation_names_its_line_and_place():
    card = Card("PBAR", ("PBAR",) + ("",) * 16 + ("X",), "p.bdf", (10, 11, 12), (8, 8, 8))
    with pytest.raises(ModelError, match=r"p.bdf, line 12: PBAR: field 2 of continuation 2: K1 must be"):
        real(card, 17, "K1")


def test_nastran95_free_field_and_replicators_are_refused_naming_the_line(tmp_path):
    with pytest.raises(ModelError, match=r"line 2: NASTRAN-95 free-field input \(CBAR 10 with blank-separated"):
        cards_of(tmp_path, "BEGIN BULK\nCBAR,  10  1   1   2  0. 0. 1.\n")
    with pytest.raises(ModelError, match=r"line 3: NASTRAN-95 free-field input \(a replicator"):
        cards_of(tmp_path, "BEGIN BULK\nGRID,1,,0.,0.,0.\n=(3),*(1)\n", "r.bdf")


# ------------------------------------------------------------------ round trip
def _random_field(rng) -> str:
    kind = rng.integers(4)
    if kind == 0:
        return ""
    if kind == 1:
        return str(int(rng.integers(-10**6, 10**7)))
    if kind == 2:
        return repr(float(rng.normal() * 10.0 ** rng.integers(-12, 12)))[:8 if rng.random() < 0.3 else 16]
    return "".join(rng.choice(list("ABCXYZ123"), size=int(rng.integers(1, 8))))


def _fits(v: str, width: int) -> bool:
    return len(v) <= width


def test_random_cards_in_small_large_and_free_field_read_back_equal(tmp_path):
    """A property check: 300 random entries (1-40 fields of blanks, integers, reals and
    words) written in each format by the QRG's rules read back to the same fields."""
    rng = np.random.default_rng(30)
    entries = []
    for k in range(300):
        n = int(rng.integers(1, 41))
        data = [_random_field(rng) for _ in range(n)]
        data[0] = data[0] or "1"
        entries.append((f"C{k % 7}X", data))
    small_lines, large, free = [], [], []
    for name, data in entries:
        d8 = [v if _fits(v, 8) else v[:8] for v in data]
        rows = [d8[i:i + 8] for i in range(0, len(d8), 8)]
        for r, row in enumerate(rows):
            small_lines.append(small(name if r == 0 else "+", *row))
        large.extend(large_lines(name, data))
        free.append(name + "," + ",".join(data[:8]))
        free.extend("," + ",".join(data[i:i + 8]) if any(data[i:i + 8]) else "," for i in range(8, len(data), 8))
    for label, lines, want in (("small", small_lines, lambda d: [v[:8] for v in d]),
                               ("large", large, lambda d: d), ("free", free, lambda d: d)):
        cards = cards_of(tmp_path, "BEGIN BULK\n" + "\n".join(lines) + "\nENDDATA\n", f"{label}.bdf")
        assert len(cards) == len(entries), label
        for card, (name, data) in zip(cards, entries):
            got = list(fields(card))
            exp = [name] + want(data)
            while exp and exp[-1] == "":
                exp.pop()
            assert got == [x.upper() for x in exp], (label, name)


def test_deck_text_writes_a_deck_that_reads_back_to_the_same_cards(tmp_path):
    text = ("SOL 103\nCEND\nMETHOD = 1\nBEGIN BULK\n" + small("GRID", "1", "", "1.-3", ".5", "0.") + "\n"
            + "\n".join(large_lines("CBAR", ["10", "1", "1", "2", "0.", "0.", "1.", "", "", "", "",
                                             "", "", "", "", "0.25"])) + "\nEIGRL,1,,,4\nENDDATA\n")
    p = tmp_path / "a.bdf"
    p.write_text(text)
    deck = parse_deck(p)
    q = tmp_path / "b.bdf"
    q.write_text(deck_text(deck))
    again = parse_deck(q)
    assert [fields(c) for c in again.cards] == [fields(c) for c in deck.cards]
    assert again.case.values("METHOD") == ["1"] and again.sol == "103"
    assert math.isclose(real(again.cards[0], 3, "X"), 1e-3)


def test_an_entry_repeated_word_for_word_is_read_once_and_a_clash_is_named(tmp_path):
    from trussid.fem.nastran import read_bdf

    beam = ("MAT1,1,70.+9,,0.3,2700.\nPBAR,1,1,1.-4,2.-9,3.-9,4.-9\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\n"
            "CBAR,10,1,1,2,0.,0.,1.\nSPC1,1,123456,1\n")
    p = tmp_path / "twice.bdf"
    p.write_text("BEGIN BULK\n" + beam + "GRID,2,,1.,0.,0.\nMAT1,1,70.+9,,0.3,2700.\nCBAR,10,1,1,2,0.,0.,1.\n")
    model, _ = read_bdf(p)
    assert (model.n_nodes, len(model.beams)) == (2, 1)
    np.testing.assert_array_equal(model.xyz, [[0, 0, 0], [1, 0, 0]])
    p.write_text("BEGIN BULK\n" + beam + "CBAR,10,1,2,1,0.,0.,1.\n")
    with pytest.raises(ModelError, match=r"twice.bdf, line 8: CBAR 10: field 2: duplicate id 10 \(also on CBAR 10, "
                                         r".*twice.bdf line 6\)"):
        read_bdf(p)
