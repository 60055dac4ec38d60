"""Real NASTRAN decks, as their authors published them, against NASTRAN's own frequencies.

The corpus (``../shared/nastran-corpus`` beside the repository: 21 beam/rod/spring/mass decks
from pyNastran, NASTRAN_CoFE and NASTRAN-95 with the frequencies real NASTRAN runs printed)
is independent of trussid. Every published deck must be read unmodified; the lowest
``n_compare`` elastic modes must agree within 1e-4, except for the three decks below whose
reference run is not the published deck's own answer. The test is skipped where the corpus
is absent (set ``TRUSSID_NASTRAN_CORPUS`` to point at it elsewhere).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf

ROOT = Path(__file__).resolve().parents[2]


def _corpus() -> Path | None:
    env = os.environ.get("TRUSSID_NASTRAN_CORPUS")
    for cand in ([Path(env)] if env else []) + [ROOT.parent / "shared" / "nastran-corpus",
                                                 ROOT.parent.parent / "shared" / "nastran-corpus"]:
        if (cand / "cases").is_dir():
            return cand
    return None


CORPUS = _corpus()
CASES = sorted(p.stem for p in (CORPUS / "cases").glob("*.json")) if CORPUS else []
TOL = 1e-4

#: Decks whose NASTRAN reference is not the answer to the deck as published.
NOT_THE_DECKS_ANSWER = {
    # The published deck says PARAM,COUPMASS,-1 (lumped); the f06 is of a coupled-mass run
    # whose deck was not committed. Their rewritten copies (COUPMASS,1) are checked below.
    "cofe_cantilever_bar_coupled": "published deck is lumped, reference is coupled",
    "cofe_cantilever_beam_coupled": "published deck is lumped, reference is coupled",
    # The same deck as pn_beam_modes_simcenter, solved by an MSC 2012 build that converts
    # PBARL/PBEAML ROD with K = 6/7 instead of 0.9: the two NASTRAN answers differ by 9.6e-3.
    "pn_beam_modes_msc2012": "NASTRAN builds differ (ROD shear factor 6/7 vs 0.9)",
}

pytestmark = [pytest.mark.slow,
              pytest.mark.skipif(CORPUS is None, reason="../shared/nastran-corpus is not present")]


def _case(cid: str) -> dict:
    return json.loads((CORPUS / "cases" / f"{cid}.json").read_text())


def _errors(cid: str, deck_key: str = "original_deck") -> np.ndarray:
    """Relative errors of the compared modes of ``cid``'s deck against NASTRAN."""
    c = _case(cid)
    r, n = c["rigid_modes"], c["n_compare"]
    model, info = read_bdf(CORPUS / c[deck_key])
    f = solve_modes(assemble(model, autospc=info.autospc), n_modes=r + n).frequencies_hz
    assert len(f) >= r + n
    return f[r:r + n] / np.asarray(c["nastran_hz"][r:r + n]) - 1.0


@pytest.mark.parametrize("cid", CASES)
def test_published_deck_is_read_and_agrees_with_nastran(cid):
    err = np.abs(_errors(cid))
    if cid in NOT_THE_DECKS_ANSWER:
        assert err.max() > TOL  # if this starts to agree, the note above is wrong
    else:
        assert err.max() <= TOL, f"{cid}: max |f / f_NASTRAN - 1| = {err.max():.2e}"


def test_at_least_eighteen_of_the_published_decks_agree():
    """21 decks, 3 whose reference is another run's: 18 agree within 1e-4 (acceptance 1)."""
    assert len(CASES) == 21
    agree = [cid for cid in CASES if np.abs(_errors(cid)).max() <= TOL]
    assert len(agree) >= 18 and not set(agree) & set(NOT_THE_DECKS_ANSWER)


def test_ignored_entries_are_listed_once_with_counts():
    c = _case("pn_freq_sine_good_sine")
    _, info = read_bdf(CORPUS / c["original_deck"])
    assert info.ignored == ["FORCE (3)", "FREQ1 (1)", "PARAM,OGEOM", "PARAM,POST", "PARAM,PRGPST", "RLOAD1 (3)",
                            "TABDMP1 (1)", "TABLED1 (1)"]
    assert any(n.startswith("SPOINT 1000") for n in info.notes)


def test_the_other_nastran_build_of_beam_modes_is_within_its_shear_factor_spread():
    """The MSC 2012 answer differs from Simcenter's by up to 9.6e-3 (K = 6/7 vs 0.9); trussid
    follows the newer builds and sits within that spread of the older one."""
    assert np.abs(_errors("pn_beam_modes_msc2012")).max() < 9.7e-3


@pytest.mark.parametrize("cid", ["cofe_cantilever_bar_coupled", "cofe_cantilever_beam_coupled"])
def test_coupled_mass_runs_agree_on_their_coupmass_copies(cid):
    """The coupled-mass references agree with the published decks given PARAM,COUPMASS,1 (the
    beam case exercises NASTRAN's coupled mass of a shear-flexible CBEAM)."""
    assert np.abs(_errors(cid, "compared_deck")).max() <= TOL


def _survey_decks():
    if CORPUS is None:
        return []
    survey = json.loads((CORPUS / "unsupported_cards.json").read_text())
    return [d for d in survey["decks"] if not d["beam_type"]]


@pytest.mark.parametrize("entry", _survey_decks(), ids=lambda d: d["deck"].split("/")[-1])
def test_shell_and_solid_decks_of_the_survey_get_one_line_naming_their_elements(tmp_path, entry):
    """The survey's shell/solid decks (not stored) rebuilt from their entry counts around a
    small beam model: one line naming the unsupported element entries, as the CLI prints it
    with exit status 2 (tests/cli), and no other failure."""
    from trussid.fem import ModelError
    from trussid.fem.nastran import IGNORED_CARDS, SUPPORTED_CARDS
    from trussid.fem.nastran.deck import _is_element_entry

    lines = ["BEGIN BULK", "MAT1,1,70.+9,,0.3,2700.", "PBAR,1,1,1.-4,2.-9,2.-9,4.-9",
             "GRID,1,,0.,0.,0.", "GRID,2,,1.,0.,0.", "CBAR,1,1,1,2,0.,0.,1.", "SPC1,1,123456,1"]
    for name, count in entry["unsupported"].items():
        if not name.startswith("PARAM,") and name not in SUPPORTED_CARDS:  # PARAMs: typed values
            lines += [f"{name},{i + 1}" for i in range(count)]
    p = tmp_path / "survey.bdf"
    p.write_text("\n".join(lines + ["ENDDATA"]) + "\n")
    with pytest.raises(ModelError) as exc:
        read_bdf(p)
    msg = str(exc.value)
    elements = sorted(k for k in entry["unsupported"] if _is_element_entry(k) and k not in SUPPORTED_CARDS
                      and k not in IGNORED_CARDS)
    assert "\n" not in msg
    assert msg.split(": ", 1)[1].startswith("unsupported element entries: " + elements[0])
    for k in elements:
        assert f"{k} ({entry['unsupported'][k]})" in msg
