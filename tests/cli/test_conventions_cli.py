"""``--conventions nx|msc`` on ``trussid modes`` and ``trussid plant``: the NASTRAN build whose
conventions a deck is read with, recorded in the JSON and the notes (issue 25)."""

import json
from pathlib import Path

import pytest

from trussid.cli import main

ROOT = Path(__file__).resolve().parents[2]
IO = ROOT / "examples" / "decks" / "frame_io.toml"
FRAME = ROOT / "examples" / "decks" / "frame.bdf"

#: A cantilever of PBARL ROD bars: the only entry whose conversion differs between builds.
ROD_DECK = ("BEGIN BULK\nMAT1,1,70.+9,,0.33,2700.\nPBARL,1,1,,ROD\n,0.01\n"
            + "".join(f"GRID,{i + 1},,{0.02 * i},0.,0.\n" for i in range(4))
            + "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(3))
            + "SPC1,1,123456,1\nENDDATA\n")


def _modes(capsys, *args):
    assert main(["modes", *map(str, args), "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_modes_json_and_notes_name_the_conventions_and_msc_changes_the_rod(tmp_path, capsys):
    deck = tmp_path / "rod.bdf"
    deck.write_text(ROD_DECK)
    nx = _modes(capsys, deck)
    msc = _modes(capsys, deck, "--conventions", "msc")
    assert nx["conventions"] == "nx" and msc["conventions"] == "msc"
    assert any(n.startswith("conventions: nx (the default") for n in nx["notes"])
    assert any(n.startswith("conventions: msc (given") for n in msc["notes"])
    # 6/7 < 0.9: the msc shear area is smaller, so the shear-sensitive modes are lower.
    assert all(a <= b * (1 + 1e-12) for a, b in zip(msc["frequencies_hz"], nx["frequencies_hz"]))
    assert any(a < b * (1 - 1e-4) for a, b in zip(msc["frequencies_hz"], nx["frequencies_hz"]))
    explicit = _modes(capsys, deck, "--conventions", "nx")
    assert explicit["frequencies_hz"] == nx["frequencies_hz"]


def test_plant_with_io_records_the_conventions(tmp_path, capsys):
    out = tmp_path / "p.npz"
    assert main(["plant", str(FRAME), "--io", str(IO), "--out", str(out), "--json", "--conventions", "msc"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["conventions"] == "msc"
    assert any(n.startswith("conventions: msc") for n in s["notes"])


@pytest.mark.parametrize("args", [["modes", "--conventions", "msc"],
                                  ["plant", "--conventions", "msc", "--out", "X.npz"]])
def test_conventions_without_a_deck_is_one_line(tmp_path, capsys, args):
    args = [str(tmp_path / a) if a == "X.npz" else a for a in args]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--conventions applies to" in err[0]
    assert not (tmp_path / "X.npz").exists()


def test_unknown_conventions_are_refused_by_the_parser(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["modes", str(FRAME), "--conventions", "abaqus"])
    assert exc.value.code == 2
    assert "invalid choice" in capsys.readouterr().err
