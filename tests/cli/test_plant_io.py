"""``trussid plant DECK.bdf --io IO.toml``: a plant for a user's own deck (issue 19)."""

import json
from pathlib import Path

import numpy as np
import pytest

from trussid.cli import main
from trussid.plid.modelfile import load_model

ROOT = Path(__file__).resolve().parents[2]
DECK = ROOT / "examples" / "decks" / "frame.bdf"
IO = ROOT / "examples" / "decks" / "frame_io.toml"


def test_the_example_deck_gets_a_discrete_and_continuous_plant(tmp_path, capsys):
    out = tmp_path / "table.npz"
    assert main(["plant", str(DECK), "--io", str(IO), "--out", str(out), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["inputs"] == ["shaker", "pzt_leg1"] and s["outputs"] == ["acc_top_x", "acc_top_y"]
    assert s["sample_rate_hz"] == 2000.0 and s["stable"]
    f = np.array(s["mode_frequencies_hz"])
    assert f.max() < 1000.0 and s["states"] == 2 * s["modes_kept"]
    from trussid.fem import read_bdf, solve_modes

    deck_model, info = read_bdf(DECK)  # as `trussid modes` gives it
    f_modes = solve_modes(deck_model, n_modes=1, autospc=info.autospc).frequencies_hz
    assert f[0] == pytest.approx(f_modes[0], rel=1e-9)
    sd, meta = load_model(out)
    sc, _ = load_model(out, which="continuous")
    assert sd.dt == 1 / 2000 and meta.stability.stable and sc.dt == 0


def test_a_deck_without_io_and_io_without_a_deck_say_what_is_needed(tmp_path, capsys):
    code = main(["plant", str(DECK), "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert code == 2 and "give them with --io IO.toml for a NASTRAN deck" in err
    code = main(["plant", "--io", str(IO), "--out", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert code == 2 and "--io needs a NASTRAN deck" in err
    assert not (tmp_path / "p.npz").exists()
