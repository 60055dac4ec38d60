"""The stiffness of a general element given by a stiffness or flexibility matrix and a
rigid-body matrix (NASTRAN GENEL), over plain arrays.

A general element joins ``m`` independent DOFs ``u_i`` and ``n`` dependent DOFs ``u_d``.
Its data are a symmetric ``m x m`` matrix, the stiffness ``K`` or the flexibility ``Z``
(then ``K = Z^-1``), and an ``m x n`` matrix ``S`` that gives the ``u_i`` of a rigid-body
motion from its ``u_d``. The element is unstrained by those motions, so its stiffness on
``(u_i, u_d)`` is (NASTRAN QRG, GENEL)::

    [[   K,      -K S  ],
     [-S^T K,  S^T K S ]]

From the flexibility form ``u_i = Z f_i + S u_d``, ``f_d = -S^T f_i``, the same matrix.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.errors import ModelError

__all__ = ["lower_by_columns", "general_element_stiffness"]


def lower_by_columns(terms, m: int, label: str, name: str = "K") -> np.ndarray:
    """The symmetric ``m x m`` matrix whose lower triangle, column by column, is ``terms``
    (``M11, M21, ..., Mm1, M22, M32, ...``)."""
    terms = np.asarray(terms, float).ravel()
    need = m * (m + 1) // 2
    if len(terms) != need:
        raise ModelError(f"{label}: {name} needs {need} terms for {m} UI DOFs, got {len(terms)}")
    if not np.isfinite(terms).all():
        raise ModelError(f"{label}: {name} has a term that is not finite")
    A = np.zeros((m, m))
    A[np.triu_indices(m)] = terms  # the upper triangle by rows is the lower one by columns
    return A + np.triu(A, 1).T


def general_element_stiffness(matrix: np.ndarray, kind: str, S: np.ndarray | None, label: str) -> np.ndarray:
    """Stiffness of a general element on ``(u_i, u_d)``, ``(m + n, m + n)``.

    Parameters
    ----------
    matrix : (m, m) float
        Symmetric stiffness (``kind`` "K") or flexibility ("Z") on the independent DOFs, in
        the units of those DOFs [N/m, N m/rad, or their inverses].
    kind : {"K", "Z"}
    S : (m, n) float or None
        Rigid-body matrix: ``u_i`` of a rigid motion per unit ``u_d`` [m/m, m/rad...]; None
        (or ``n = 0``) for an element without dependent DOFs.
    label : str
        For messages (e.g. ``"GENEL 7"``).

    Raises
    ------
    ModelError
        A singular flexibility matrix, an unknown kind, or mismatched shapes.
    """
    A = np.asarray(matrix, float)
    m = A.shape[0]
    if A.shape != (m, m):
        raise ModelError(f"{label}: the {kind} matrix must be square, got shape {A.shape}")
    if kind == "K":
        K = A
    elif kind == "Z":
        try:
            K = np.linalg.inv(A)
        except np.linalg.LinAlgError:
            raise ModelError(f"{label}: the flexibility matrix Z is singular") from None
        if np.linalg.cond(A) > 1e12:
            raise ModelError(f"{label}: the flexibility matrix Z is singular (condition number "
                             f"{np.linalg.cond(A):.1e})")
    else:
        raise ModelError(f"{label}: matrix kind must be K or Z, got {kind!r}")
    S = np.zeros((m, 0)) if S is None else np.asarray(S, float)
    if S.ndim != 2 or S.shape[0] != m:
        raise ModelError(f"{label}: S must have {m} rows (one per UI DOF), got shape {S.shape}")
    KS = K @ S
    full = np.block([[K, -KS], [-KS.T, S.T @ KS]])
    return 0.5 * (full + full.T)
