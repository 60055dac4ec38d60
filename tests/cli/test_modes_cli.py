"""``trussid modes``: frequencies of a bulk-data deck as a table or JSON; bad input ends in
one line on stderr, a non-zero exit and no traceback."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from trussid.cli import main

ROOT = Path(__file__).resolve().parents[2]
FRAME = ROOT / "examples" / "decks" / "frame.bdf"


def run(*args, cwd=ROOT):
    """The real command line in a fresh interpreter (what a user sees, tracebacks included)."""
    return subprocess.run([sys.executable, "-m", "trussid", "modes", *map(str, args)],
                          capture_output=True, text=True, cwd=cwd)


class Result:
    def __init__(self, returncode, out, err):
        self.returncode, self.stdout, self.stderr = returncode, out, err


@pytest.fixture
def cli(capsys):
    """``trussid modes ...`` in this process (each subprocess costs seconds of imports)."""
    def call(*args):
        code = main(["modes", *map(str, args)])
        out, err = capsys.readouterr()
        return Result(code, out, err)
    return call


def one_line_error(res):
    assert res.returncode != 0
    assert res.stdout == ""
    assert "Traceback" not in res.stderr
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith("trussid modes: error: ")
    return lines[0]


SPRING_MASS = """BEGIN BULK
PARAM,WTMASS,0.5
EIGRL,1,,,1
GRID,1,,0.,0.,0.,,23456
CONM2,1,1,,2.
CELAS2,2,800.,1,1
ENDDATA
"""


def test_json_gives_ascending_frequencies_dof_count_and_mass_formulation(tmp_path, cli):
    # Independent reference: one spring and one mass, with WTMASS scaling the mass.
    deck = tmp_path / "sm.bdf"
    deck.write_text(SPRING_MASS)
    res = cli(deck, "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    assert out["n_dof"] == 1 and out["mass"] == "lumped" and out["model"] == str(deck)
    assert out["frequencies_hz"] == pytest.approx([math.sqrt(800.0 / (2.0 * 0.5)) / (2 * math.pi)],
                                                  rel=1e-12)


def test_example_frame_uses_the_decks_eigrl_count_and_consistent_mass(cli):
    res = cli(FRAME, "--json")
    assert res.returncode == 0, res.stderr
    out = json.loads(res.stdout)
    f = out["frequencies_hz"]
    assert len(f) == 10  # EIGRL ND
    assert f == sorted(f) and f[0] > 0
    assert out["mass"] == "consistent"
    assert out["n_dof"] == 6 * 33 - 6 * 4 - 6 * 4  # 33 grids, 4 clamped feet, 4 RBE2 slaves


def test_n_overrides_the_deck_and_the_table_names_mass_and_units():
    res = run(FRAME, "--n", "3")  # the installed command line, end to end
    assert res.returncode == 0, res.stderr
    rows = [line.split() for line in res.stdout.splitlines() if line.strip()[:1].isdigit()]
    assert [r[0] for r in rows] == ["1", "2", "3"]
    assert "frequency [Hz]" in res.stdout
    assert "mass: consistent" in res.stdout and "COUPMASS" in res.stdout
    assert "units" in res.stdout


@pytest.mark.parametrize("text,match", [
    ("BEGIN BULK\nGRID,1,,0.,0.,0.\nCQUAD4,1,1,1,2,3,4\nCHEXA,2,1,1,2,3,4,5,6\nENDDATA\n",
     "unsupported element entries: CHEXA (1), CQUAD4 (1)"),
    ("BEGIN BULK\nGRID,1,,0.,0.,0.\nCELAS2,2,800.,7,1\nENDDATA\n", "spring 2: grid 7 is not defined"),
    ("BEGIN BULK\nGRID,1,,0,0,0\nENDDATA\n", "line 2: GRID 1: field 4: X1 must be a real number"),
])
def test_bad_deck_exits_nonzero_with_one_line(tmp_path, cli, text, match):
    deck = tmp_path / "bad.bdf"
    deck.write_text(text)
    assert match in one_line_error(cli(deck))


def test_bad_deck_from_the_shell_prints_one_line_and_no_traceback(tmp_path):
    deck = tmp_path / "bad.bdf"
    deck.write_text("BEGIN BULK\nGRID,1,,0.,0.,0.\nCQUAD4,1,1,1,2,3,4\nNSM,7,PBAR,1,0.5\nENDDATA\n")
    line = one_line_error(run(deck))
    assert "CQUAD4 (1)" in line and "NSM (1)" in line


def test_missing_file_and_unknown_suffix_exit_with_one_line(tmp_path, cli):
    assert "no such file" in one_line_error(cli(tmp_path / "missing.bdf"))
    other = tmp_path / "model.xyz"
    other.write_text("")
    assert "unknown model file type" in one_line_error(cli(other))


def test_bad_n_exits_with_one_line(cli):
    assert "--n must be at least 1" in one_line_error(cli(FRAME, "--n", "0"))


def test_default_testbed_json_has_labelled_ascending_modes(cli):
    res = cli("--n", "24", "--json")
    assert res.returncode == 0, res.stderr
    data = json.loads(res.stdout)
    f, labels = data["frequencies_hz"], data["labels"]
    assert data["model"] == "default testbed" and len(f) == len(labels) == 24
    assert f == sorted(f) and data["n_dof"] > 0
    assert labels[:6] == ["suspension"] * 6 and max(f[:6]) < 5.0
    assert sum(s.endswith("bending 1 (plane y)") or s.endswith("bending 1 (plane z)") for s in labels) == 12
    assert labels.count("UDF rigid-body") == 6


def test_testbed_toml_is_a_model_and_the_table_shows_labels(tmp_path, cli):
    path = tmp_path / "clamped.toml"
    path.write_text('[base]\nsupport = "clamped"\n')
    res = cli(path, "--n", "8")
    assert res.returncode == 0, res.stderr
    assert "label" in res.stdout and "strut 0 bending 1" in res.stdout and "suspension" not in res.stdout


def test_bad_testbed_toml_exits_with_one_line_naming_the_key(tmp_path, cli):
    path = tmp_path / "bad.toml"
    path.write_text("[struts]\nlenght = 1.0\n")
    assert "lenght" in one_line_error(cli(path))


def test_decks_have_no_labels_in_json(cli):
    assert json.loads(cli(FRAME, "--json").stdout)["labels"] is None


def test_op2_option_writes_the_modes_for_pynastran(tmp_path, cli):
    from trussid.fem.op2 import read_op2_modes

    out = tmp_path / "frame.op2"
    res = cli(FRAME, "--n", "4", "--json", "--op2", out)
    assert res.returncode == 0, res.stderr
    f = np.asarray(json.loads(res.stdout)["frequencies_hz"])
    eig, _, vecs = read_op2_modes(out)
    np.testing.assert_allclose(np.sqrt(eig) / (2 * np.pi), f, rtol=1e-7)
    assert vecs.shape[0] == 4


def test_op2_onto_a_directory_is_one_line_and_leaves_no_file(tmp_path, cli):
    target = tmp_path / "out"
    target.mkdir()
    one_line_error(cli(FRAME, "--n", "2", "--op2", target))
    assert list(tmp_path.iterdir()) == [target] and not list(target.iterdir())


def test_decks_from_the_field_of_issue_33_run_from_the_command_line(tmp_path, cli):
    """Two decks NASTRAN solves that were refused before: a scalar-point string without GRID
    or SPOINT cards, and a free point mass tied by an MPC to a scalar point (0 Hz first)."""
    string = tmp_path / "string.bdf"
    n, k, m = 40, 1000.0, 0.5
    string.write_text("BEGIN BULK\n" + "".join(f"CMASS4,{i},{m},{i}\nCELAS4,{100 + i},{k},{i},{i + 1}\n"
                                              for i in range(1, n)) + f"CMASS4,{n},{m},{n}\nCELAS4,200,{k},{n}\n"
                      f"CELAS4,201,{k},1\nENDDATA\n")
    res = cli(string, "--json", "--n", "3")
    assert res.returncode == 0, res.stderr
    j = np.arange(1, 4)
    np.testing.assert_allclose(json.loads(res.stdout)["frequencies_hz"],
                               2 * math.sqrt(k / m) * np.sin(j * math.pi / (2 * (n + 1))) / (2 * math.pi), rtol=1e-9)
    free = tmp_path / "free.bdf"
    free.write_text("SOL 103\nCEND\nMPC = 10\nBEGIN BULK\nGRID,1,,0.,0.,0.,,123456\nGRID,2,,1.,0.,0.,,23456\n"
                    "GRID,3,,2.,0.,0.,,23456\nSPOINT,100\nEPOINT,200\nCELAS2,1,1000.,1,1,2,1\nCONM2,2,2,,1.\n"
                    "CONM2,3,3,,2.\nMPC,10,3,1,1.,100,0,-1.\nTF,5,200,,1.,0.,0.\nENDDATA\n")
    res = cli(free, "--json", "--n", "5")
    assert res.returncode == 0, res.stderr
    f = json.loads(res.stdout)["frequencies_hz"]
    assert f[0] == 0.0
    np.testing.assert_allclose(f[1:], [math.sqrt(1000.0) / (2 * math.pi)], rtol=1e-12)
