"""Modes written as OP2 read back in pyNastran's own OP2 reader to trussid's numbers.

pyNastran's writer stores 32-bit reals (as NASTRAN's default OP2s do), so what comes back
is trussid's float64 result rounded to float32, exactly, and its relative difference from
the float64 values is below float32's 6e-8.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf
from trussid.fem.op2 import write_op2

CORPUS_DECK = Path("/nonexistent")
for root in (Path(__file__).resolve().parents[3], Path(__file__).resolve().parents[4]):
    cand = root / "shared" / "nastran-corpus" / "decks" / "pn_pt145_swept_wing" / "pt145.bdf"
    if cand.is_file():
        CORPUS_DECK = cand
        break

# A deck with grids in a cylindrical displacement system (results in CD frames).
LOCAL_DECK = """BEGIN BULK
CORD2C,7,,0.,0.,0.,0.,0.,1.,
,1.,0.,0.
MAT1,1,70.+9,,0.3,2700.
PBAR,1,1,1.-4,2.-9,3.-9,4.-9
GRID,1,7,0.3,40.,0.,7
GRID,2,7,0.5,40.,0.,7
GRID,3,7,0.7,40.,0.,7
GRID,4,7,0.9,40.,0.,7
GRID,99,,0.,0.,1.
CBAR,1,1,1,2,99
CBAR,2,1,2,3,99
CBAR,3,1,3,4,99
SPC1,1,123456,1,99
CONM2,9,4,,0.05
ENDDATA
"""


def _read_back(path):
    from cpylog import SimpleLogger
    from pyNastran.op2.op2 import OP2

    op2 = OP2(log=SimpleLogger(level="critical"))
    op2.read_op2(str(path))
    vec = op2.eigenvectors[1]
    return np.asarray(vec.eigns, float), vec.node_gridtype[:, 0], np.asarray(vec.data, float)


@pytest.mark.parametrize("source", ["local", "corpus"])
def test_op2_reads_back_to_trussids_eigenvalues_and_vectors(tmp_path, source):
    if source == "corpus":
        if not CORPUS_DECK.is_file():
            pytest.skip("../shared/nastran-corpus is not present")
        deck = CORPUS_DECK
    else:
        deck = tmp_path / "cyl.bdf"
        deck.write_text(LOCAL_DECK)
    model, info = read_bdf(deck)
    system = assemble(model, autospc=info.autospc)
    modes = solve_modes(system, n_modes=6)
    np.testing.assert_allclose(modes.shapes.T @ (system.M @ modes.shapes), np.eye(6), atol=1e-10)
    out = tmp_path / "modes.op2"
    write_op2(out, modes, frames=model.node_frames())
    eig, nids, vecs = _read_back(out)

    lam = modes.omega**2
    np.testing.assert_array_equal(eig, lam.astype(np.float32).astype(float))
    assert np.abs(eig / lam - 1).max() < 6e-8
    # expected: global shapes turned into each grid's displacement frame, ascending ids
    order = np.argsort(model.node_ids)
    F = model.node_frames()
    F = np.broadcast_to(np.eye(3), (len(order), 3, 3)) if F is None else F
    u = modes.shapes_full.reshape(len(order), 6, -1)
    local = np.concatenate([np.einsum("nij,njm->nim", F, u[:, :3]), np.einsum("nij,njm->nim", F, u[:, 3:])], 1)
    want = local[order].transpose(2, 0, 1)
    np.testing.assert_array_equal(nids, model.node_ids[order])
    np.testing.assert_array_equal(vecs, want.astype(np.float32).astype(float))
    scale = np.abs(want).max(axis=(1, 2), keepdims=True)
    assert np.abs(vecs - want).max() <= 6e-8 * scale.max()


def test_op2_of_no_modes_is_refused(tmp_path):
    class Empty:
        frequencies_hz = np.zeros(0)

    with pytest.raises(ModelError, match="no modes"):
        write_op2(tmp_path / "x.op2", Empty())
    assert not (tmp_path / "x.op2").exists()
