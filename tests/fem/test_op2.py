"""Modes written as OP2 read back to trussid's numbers: by pyNastran's own OP2 reader where
it can be imported (an independent reader; pyNastran 1.4 fails at import on numpy >= 2.4),
and always by decoding the file's Fortran records by hand, word by word, against NASTRAN's
OUGV1 layout.

The OP2 stores 32-bit reals (as NASTRAN's default OP2s do), so what comes back is trussid's
float64 result rounded to float32, exactly, and its relative difference from the float64
values is below float32's 6e-8.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf
from trussid.fem.op2 import read_op2_modes, write_op2

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
    try:
        from cpylog import SimpleLogger
        from pyNastran.op2.op2 import OP2
    except Exception as exc:  # ImportError, or AttributeError (np.in1d) on numpy >= 2.4
        pytest.skip(f"pyNastran's OP2 reader is not importable here ({type(exc).__name__})")

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


def _fortran_records(buf: bytes) -> list:
    """Records of a little-endian Fortran unformatted file: [n] n bytes [n]."""
    out, i = [], 0
    while i < len(buf):
        (n,) = struct.unpack_from("<i", buf, i)
        assert struct.unpack_from("<i", buf, i + 4 + n)[0] == n
        out.append(buf[i + 4:i + 4 + n])
        i += n + 8
    return out


def test_op2_records_decoded_by_hand_are_nastrans_eigenvector_table(tmp_path):
    """Two modes of three grids (ids out of order), decoded from the bytes: file header,
    table OUGV1, per mode a 146-word header (approach 2 = modes with device 2, table code 7,
    mode number, eigenvalue, frequency, real format, 8 words per grid, the title) and one
    row per grid (10 id + 2, grid type 1, six float32), markers -3, -4 ... and the end."""

    class Two:
        frequencies_hz = np.array([1.25, 3.5])
        omega = 2 * np.pi * frequencies_hz
        node_ids = np.array([30, 10, 20])
        shapes_full = np.random.default_rng(3).normal(size=(18, 2))

    out = tmp_path / "two.op2"
    write_op2(out, Two(), title="hand check")
    recs = _fortran_records(out.read_bytes())
    word = lambda r: struct.unpack("<i", r)[0]  # noqa: E731
    assert recs[3] == b"NASTRAN FORT TAPE ID CODE - "
    assert recs[9] == b"OUGV1   "
    assert [word(recs[k]) for k in (10, 13, 18, 23, 28, 33, 38)] == [-1, -2, -3, -4, -5, -6, -7]
    assert recs[17][:8] == b"OUG1    "
    order = np.argsort(Two.node_ids)
    u = Two.shapes_full.reshape(3, 6, 2)[order]
    for m, (head, body) in enumerate(((recs[22], recs[27]), (recs[32], recs[37]))):
        assert word(recs[21 + 10 * m]) == 146 and len(head) == 4 * 146
        w = struct.unpack("<146i", head)
        assert (w[0], w[1], w[3], w[4], w[8], w[9]) == (22, 7, 1, m + 1, 1, 8)
        lam, f = struct.unpack_from("<2f", head, 20)
        assert lam == np.float32(Two.omega[m] ** 2) and f == np.float32(Two.frequencies_hz[m])
        assert head[200:210] == b"hand check"
        for g in range(3):
            nid_dev, gtype = struct.unpack_from("<2i", body, 32 * g)
            vals = struct.unpack_from("<6f", body, 32 * g + 8)
            assert (nid_dev, gtype) == (10 * int(np.sort(Two.node_ids)[g]) + 2, 1)
            np.testing.assert_array_equal(vals, u[g, :, m].astype(np.float32))
    assert [word(r) for r in recs[38:]] == [-7, 1, 0, 0, 0]
    eig, nids, vecs = read_op2_modes(out)
    np.testing.assert_array_equal(nids, [10, 20, 30])
    np.testing.assert_array_equal(eig, (Two.omega**2).astype(np.float32))
    np.testing.assert_array_equal(vecs, u.transpose(2, 0, 1).astype(np.float32))
