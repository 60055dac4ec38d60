"""Modal view of a discrete state-space model: poles as continuous frequency and damping,
residues, the real block-diagonal (modal) form and modal truncation.

python-control's ``modal_form`` returns the block-diagonal form but not which block is
which pole nor the residues the design and the evaluation select modes by, hence these
few functions on ``numpy.linalg.eig``.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np

from trussid.plid.modal import pole_parameters

__all__ = ["freq_damping", "ModalData", "modal_data", "real_modal_basis", "modal_truncation"]


def freq_damping(z, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Frequency [Hz] and damping ratio [-] of discrete poles ``z`` (ZOH equivalents): the
    conversion of :func:`trussid.plid.modal.pole_parameters`, without the s-plane images."""
    f, zeta, _ = pole_parameters(z, dt)
    return f, zeta


@dataclass
class ModalData:
    """Eigen-decomposition of a discrete system, one row per pole.

    Attributes
    ----------
    poles : (n,) complex
        Discrete poles (eigenvalues of A).
    frequency_hz, damping : (n,) float
        Their continuous-time equivalents.
    residue : (n,) float
        Largest singular value of the residue matrix ``(C v_i)(w_i^H B)`` (``w_i`` the
        rows of ``V^-1``), in output units per input unit.
    V, Vinv : (n, n) complex
        Right eigenvectors and their inverse.
    """

    poles: np.ndarray
    frequency_hz: np.ndarray
    damping: np.ndarray
    residue: np.ndarray
    V: np.ndarray
    Vinv: np.ndarray


def modal_data(A, B, C, dt: float) -> ModalData:
    """Poles, their continuous frequency and damping, and residue norms of ``(A, B, C)``."""
    A, B, C = (np.asarray(M, dtype=float) for M in (A, B, C))
    lam, V = np.linalg.eig(A)
    Vinv = np.linalg.inv(V)
    CV, WB = C @ V, Vinv @ B
    res = np.array([np.linalg.norm(np.outer(CV[:, i], WB[i]), 2) for i in range(lam.size)])
    f, z = freq_damping(lam, dt)
    return ModalData(lam, f, z, res, V, Vinv)


def real_modal_basis(A) -> tuple[np.ndarray, list[np.ndarray]]:
    """Real basis T that makes ``T^-1 A T`` block diagonal (2x2 per complex pair, 1x1 per
    real pole), and the eigenvalue of each block (upper-half-plane member for pairs).

    Returns
    -------
    T : (n, n) float
    blocks : list of (indices, eigenvalue)
        State indices of each block in the new coordinates and its eigenvalue.
    """
    A = np.asarray(A, dtype=float)
    lam, V = np.linalg.eig(A)
    cols, blocks = [], []
    used = np.zeros(lam.size, bool)
    for i in np.argsort(np.abs(np.angle(lam)), kind="stable"):
        if used[i]:
            continue
        used[i] = True
        if abs(lam[i].imag) > 1e-12 * max(abs(lam[i]), 1e-300):
            # its conjugate partner
            j = np.argmin(np.abs(lam - np.conj(lam[i])) + used * 1e300)
            used[j] = True
            v = V[:, i] if lam[i].imag > 0 else V[:, j]
            k = len(cols)
            cols += [v.real, v.imag]
            blocks.append((np.array([k, k + 1]), lam[i] if lam[i].imag > 0 else lam[j]))
        else:
            k = len(cols)
            cols.append(V[:, i].real)
            blocks.append((np.array([k]), lam[i].real + 0j))
    return np.column_stack(cols), blocks


def modal_truncation(sys: control.StateSpace, keep) -> tuple[control.StateSpace, list]:
    """The modes ``keep`` of ``sys`` (a boolean or index selection over the blocks of
    :func:`real_modal_basis`) in real block-diagonal coordinates.

    Each kept mode keeps its exact pole and residue; the others are dropped (no static
    correction: the design model describes the target band only).
    """
    T, blocks = real_modal_basis(sys.A)
    Ti = np.linalg.inv(T)
    A = Ti @ np.asarray(sys.A) @ T
    B = Ti @ np.asarray(sys.B)
    C = np.asarray(sys.C) @ T
    idx = np.arange(len(blocks))[keep] if np.asarray(keep).dtype == bool else np.asarray(keep)
    sel = np.concatenate([blocks[i][0] for i in idx]) if len(idx) else np.array([], int)
    kept = [blocks[i] for i in idx]
    red = control.ss(A[np.ix_(sel, sel)], B[sel], C[:, sel], np.asarray(sys.D), sys.dt,
                     inputs=list(sys.input_labels), outputs=list(sys.output_labels))
    return red, kept
