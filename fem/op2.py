"""Real modes as a NASTRAN OP2 file, written and read by trussid's own code.

:func:`write_op2` writes the eigenvalues and mass-normalised eigenvectors of a
:class:`trussid.fem.modal.Modes` as NASTRAN writes a SOL 103 eigenvector table (OUGV1,
table code 7: one record per mode, each with its mode number, eigenvalue ``omega^2`` and
frequency in the record header), which pyNastran, FEMAP, Patran and HyperView read.

Written here rather than through pyNastran, whose releases declare ``numpy<2`` and whose OP2
reader fails on numpy >= 2.5 (issue 30): the one table written is a few dozen lines of
:mod:`struct`. The layout is NASTRAN's little-endian MSC form as pyNastran 1.4.1 writes it
(byte for byte, checked when this module was written): Fortran records (``[n] data [n]``,
``n`` in bytes) of 32-bit words; a file header (date, ``NASTRAN FORT TAPE ID CODE - ``, a
label); then the table: its name, a 7-word header, the ``OUG1`` record with the date, and
per mode a 146-word header record (approach code 2 = modes, device 2, table code 7, mode,
eigenvalue, frequency, format 1 = real, 8 words per grid, then title, subtitle and label of
32 words each) and a data record of ``(10 id + 2, 1 = grid, T1, T2, T3, R1, R2, R3)`` per grid;
each pair separated by the descending record markers ``-1, -2, ...`` that NASTRAN writes, and
closed by a zero record.

Precision: results are stored as 32-bit reals, as NASTRAN's own default OP2s do; a value read
back equals the trussid value rounded to float32 (relative difference below 6e-8).
"""

from __future__ import annotations

import datetime
import os
import struct

import numpy as np

from trussid.fem.errors import ModelError
from trussid._util.files import atomic_path

__all__ = ["write_op2", "read_op2_modes"]

_EIGENVECTOR_TABLES = ("OUGV1", "BOUGV1", "OUG1", "OPHIG")


def _record(data: bytes) -> bytes:
    n = struct.pack("<i", len(data))
    return n + data + n


def _ints(*values: int) -> bytes:
    return _record(struct.pack(f"<{len(values)}i", *values))


def _marker(out: list, itable: int) -> None:
    """The three records NASTRAN writes between a table's records: ``[itable] [1] [0]``."""
    out += [_ints(itable), _ints(1), _ints(0)]


def _text(s: str, n_bytes: int) -> bytes:
    return s.encode("ascii", "replace")[:n_bytes].ljust(n_bytes)


def write_op2(path: str | os.PathLike, modes, frames: np.ndarray | None = None,
              title: str = "trussid real modes", date: datetime.date | None = None) -> None:
    """Write ``modes`` as an OP2 eigenvector table (OUGV1).

    Parameters
    ----------
    path : path-like
        Output file (``.op2``); written to a temporary name and renamed, so a failure
        leaves no partial file.
    modes : trussid.fem.modal.Modes
        Frequencies and mass-normalised shapes (``shapes_full``, global axes).
    frames : (n_nodes, 3, 3) float, optional
        Displacement frames of the nodes (rows = axes, ``Model.node_frames()``): the
        eigenvectors are written in them, as NASTRAN writes each grid's results in its CD
        system. Default: global axes.
    title : str
        Case title stored in the table header (128 characters at most are kept).
    date : datetime.date, optional
        Date written in the file and table headers (default: today).

    Raises
    ------
    ModelError
        Node ids beyond the OP2 format's limit (the record stores ``10 id + 2`` in 32 bits)
        or no modes.
    """
    n = len(modes.frequencies_hz)
    if n == 0:
        raise ModelError("write_op2: there are no modes to write")
    node_ids = np.asarray(modes.node_ids, dtype=np.int64)
    if node_ids.max(initial=0) >= (2**31 - 1) // 10:
        raise ModelError(f"write_op2: node id {node_ids.max()} does not fit the OP2 format "
                         f"(10 id + 2 must fit 32 bits)")
    shapes = np.asarray(modes.shapes_full, float).reshape(len(node_ids), 6, n)
    if frames is not None:
        F = np.asarray(frames, float)
        shapes = np.concatenate([np.einsum("nij,njm->nim", F, shapes[:, :3]),
                                 np.einsum("nij,njm->nim", F, shapes[:, 3:])], axis=1)
    order = np.argsort(node_ids, kind="stable")  # NASTRAN lists grids in ascending id
    data = shapes[order].transpose(2, 0, 1)  # (n_modes, n_nodes, 6)
    eig = np.asarray(modes.omega, float) ** 2
    freq = np.asarray(modes.frequencies_hz, float)
    d = date or datetime.date.today()
    stamp = (d.month, d.day, d.year % 100)

    out = [_ints(3), _ints(*stamp), _ints(7), _record(b"NASTRAN FORT TAPE ID CODE - "), _ints(2),
           _record(b"XXXXXXXX"), _ints(-1), _ints(0)]
    out += [_ints(2), _record(_text("OUGV1", 8)), _ints(-1), _ints(7), _ints(102, 0, 0, 0, 512, 0, 0),
            _ints(-2), _ints(1), _ints(0), _ints(7), _record(_text("OUG1", 8) + struct.pack("<5i", *stamp, 0, 1))]
    # one grid's row: the id with device code 2 (10 id + 2), grid type 1, then six reals
    rows = np.zeros((len(order), 8), dtype="<i4")
    rows[:, 0] = node_ids[order] * 10 + 2
    rows[:, 1] = 1
    text = _text(title, 128) + _text("", 128) + _text("", 128)
    itable = -3
    for m in range(n):
        head = struct.pack("<5i", 22, 7, 0, 1, m + 1) + struct.pack("<2f", eig[m], freq[m]) \
            + struct.pack("<3i", 0, 1, 8) + bytes(4 * 40) + text
        _marker(out, itable)
        out += [_ints(len(head) // 4), _record(head)]
        itable -= 1
        rows[:, 2:] = data[m].astype("<f4").view("<i4")
        body = rows.tobytes()
        _marker(out, itable)
        out += [_ints(len(body) // 4), _record(body)]
        itable -= 1
    _marker(out, itable)
    out += [_ints(0), _ints(0)]
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(b"".join(out))


def _records(buf: bytes, path) -> list:
    """The Fortran records of an OP2 file, each checked against its closing length."""
    recs, i, n = [], 0, len(buf)
    while i < n:
        if i + 4 > n:
            raise ModelError(f"{path}: not a readable OP2 file (truncated record at byte {i})")
        (size,) = struct.unpack_from("<i", buf, i)
        end = i + 4 + size
        if size < 0 or end + 4 > n or struct.unpack_from("<i", buf, end)[0] != size:
            raise ModelError(f"{path}: not a readable OP2 file (little-endian Fortran records expected; "
                             f"record at byte {i} is malformed)")
        recs.append(buf[i + 4:end])
        i = end + 4
    return recs


def _word(rec: bytes):
    return struct.unpack("<i", rec)[0] if len(rec) == 4 else None


def read_op2_modes(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues, node ids and eigenvectors of an OP2's first eigenvector table.

    Reads the little-endian OP2 layout that :func:`write_op2` and NASTRAN write (tables of
    header/data record pairs, real SORT1 eigenvectors with 8 words per grid).

    Returns
    -------
    eigenvalues : (n,) float
        ``omega^2`` [rad^2/s^2].
    node_ids : (n_nodes,) int
    vectors : (n, n_nodes, 6) float
        Per mode and grid: T1, T2, T3, R1, R2, R3 in the grid's displacement frame.
    """
    try:
        buf = open(path, "rb").read()
    except OSError as exc:
        raise ModelError(f"{path}: cannot read ({exc.strerror})") from None
    recs = _records(buf, path)
    eig, ids, vecs = [], None, []
    k = 0
    while k < len(recs):
        r = recs[k]
        name = r.rstrip(b" \0").decode("ascii", "replace") if len(r) == 8 else ""
        if name not in _EIGENVECTOR_TABLES:
            k += 1
            continue
        # table: name, [-1], [7], 7-word header; then groups [itable] [1] [0] [size] record,
        # itable = -2, -3, ..., the first record the OUG1 identification; size 0 ends it.
        pos = k + 4  # the [-2] marker
        table_recs = []
        while pos + 3 < len(recs) and _word(recs[pos + 3]) not in (0, None):
            if pos + 4 >= len(recs):
                raise ModelError(f"{path}: not a readable OP2 file (table {name} is truncated)")
            table_recs.append(recs[pos + 4])
            pos += 5
        k = pos + 4
        for head, body in zip(table_recs[1::2], table_recs[2::2]):
            w = struct.unpack_from("<10i", head)
            if w[1] != 7 or w[8] != 1 or w[9] != 8:
                continue  # not a real SORT1 eigenvector record
            eig.append(struct.unpack_from("<f", head, 20)[0])
            a = np.frombuffer(body, dtype="<i4").reshape(-1, 8)
            ids = a[:, 0] // 10
            vecs.append(a[:, 2:].view("<f4").astype(float))
        if eig:
            break
    if not eig:
        raise ModelError(f"{path}: no eigenvector table")
    return np.asarray(eig, float), ids.astype(np.int64), np.stack(vecs)
