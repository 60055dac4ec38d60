"""Real modes as a NASTRAN OP2 file, through pyNastran's OP2 writer.

:func:`write_op2` writes the eigenvalues and mass-normalised eigenvectors of a
:class:`trussid.fem.modal.Modes` as NASTRAN writes a SOL 103 eigenvector table (OUGV1,
table code 7: one record per mode, each with its mode number, eigenvalue ``omega^2`` and
frequency in the record header), which pyNastran, FEMAP, Patran and HyperView read.

Precision: pyNastran's writer (1.4) stores results as 32-bit reals, as NASTRAN's own
default OP2s do; a value read back equals the trussid value rounded to float32 (relative
difference below 6e-8), not the float64 value.
"""

from __future__ import annotations

import os
import warnings

import numpy as np

from trussid.fem.errors import ModelError
from trussid._util.files import atomic_path

__all__ = ["write_op2", "read_op2_modes"]


def write_op2(path: str | os.PathLike, modes, frames: np.ndarray | None = None,
              title: str = "trussid real modes") -> None:
    """Write ``modes`` as an OP2 eigenvector table (OUGV1) readable by pyNastran.

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
        Case title stored in the table header.

    Raises
    ------
    ModelError
        Node ids beyond 32 bits (the OP2 format's limit) or no modes.
    """
    from cpylog import SimpleLogger  # deferred: ~1.5 s to load, OP2 only
    from pyNastran.op2.op2 import OP2  # deferred: ~1.5 s to load, OP2 only
    from pyNastran.op2.tables.oug.oug_eigenvectors import RealEigenvectorArray  # deferred: as OP2

    n = len(modes.frequencies_hz)
    if n == 0:
        raise ModelError("write_op2: there are no modes to write")
    node_ids = np.asarray(modes.node_ids, dtype=np.int64)
    if node_ids.max(initial=0) >= 2**31:
        raise ModelError(f"write_op2: node id {node_ids.max()} does not fit the OP2 format (32-bit ids)")
    shapes = np.asarray(modes.shapes_full, float).reshape(len(node_ids), 6, n)
    if frames is not None:
        F = np.asarray(frames, float)
        shapes = np.concatenate([np.einsum("nij,njm->nim", F, shapes[:, :3]),
                                 np.einsum("nij,njm->nim", F, shapes[:, 3:])], axis=1)
    order = np.argsort(node_ids, kind="stable")  # NASTRAN lists grids in ascending id
    data = np.ascontiguousarray(shapes[order].transpose(2, 0, 1))  # (n_modes, n_nodes, 6)
    eig = np.asarray(modes.omega, float) ** 2
    node_gridtype = np.column_stack([node_ids[order], np.ones(len(node_ids), dtype=np.int64)])
    vec = RealEigenvectorArray.add_modal_case(
        "OUGV1", node_gridtype, data, 1, np.arange(1, n + 1), eig, np.asarray(modes.frequencies_hz, float),
        is_sort1=True, title=title)
    vec.table_code = 7  # eigenvector (add_modal_case leaves the displacement code 1)
    vec.data_code["table_code"] = 7
    op2 = OP2(log=SimpleLogger(level="critical"))
    op2.set_mode("msc")
    op2.eigenvectors[1] = vec
    with atomic_path(path) as tmp, warnings.catch_warnings():
        # pyNastran warns that it writes the float64 arrays as 32-bit reals: documented above
        warnings.filterwarnings("ignore", message="downcasting", category=UserWarning)
        op2.write_op2(str(tmp), nastran_format="msc")


def read_op2_modes(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eigenvalues, node ids and eigenvectors of an OP2's first eigenvector table.

    Returns
    -------
    eigenvalues : (n,) float
        ``omega^2`` [rad^2/s^2].
    node_ids : (n_nodes,) int
    vectors : (n, n_nodes, 6) float
        Per mode and grid: T1, T2, T3, R1, R2, R3 in the grid's displacement frame.
    """
    from cpylog import SimpleLogger  # deferred: ~1.5 s to load, OP2 only
    from pyNastran.op2.op2 import OP2  # deferred: ~1.5 s to load, OP2 only

    op2 = OP2(log=SimpleLogger(level="critical"))
    try:
        op2.read_op2(str(path))
    except Exception as exc:  # pyNastran raises many types for unreadable files
        raise ModelError(f"{path}: not a readable OP2 file ({' '.join(str(exc).split())[:200]})") from None
    if not op2.eigenvectors:
        raise ModelError(f"{path}: no eigenvector table")
    vec = op2.eigenvectors[min(op2.eigenvectors)]
    return np.asarray(vec.eigns, float), vec.node_gridtype[:, 0].astype(np.int64), np.asarray(vec.data, float)
