"""Guyan (static) reduction of an assembled system, as NASTRAN's OMIT/ASET do it.

The omitted DOFs ``o`` follow the retained ones ``a`` statically: ``u_o = -K_oo^-1 K_oa u_a``,
so ``K_aa' = T^T K T`` and ``M_aa' = T^T M T`` with ``T = [I; -K_oo^-1 K_oa]``. This is exact
for the stiffness and for omitted DOFs without mass (their inertia is zero, so they are
static anyway); with mass on the omitted DOFs it is Guyan's approximation, which NASTRAN
makes too, and the frequencies rise.

Scaling: ``K_oo`` is factorised sparse once (SuperLU), but ``T`` has ``n_o x n_a`` dense
entries and the reduced matrices are dense ``n_a x n_a``: meant for a-sets of up to a few
thousand DOFs (NASTRAN's use: a handful of retained DOFs), not for large models.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from trussid.fem.errors import ModelError

__all__ = ["MAX_A_SET", "guyan"]

#: Retained DOFs beyond which the dense reduced matrices are refused (memory ~ 8 n_a^2 bytes
#: for each of K, M plus 8 n_o n_a for the transformation).
MAX_A_SET = 20000


def guyan(system, omit: np.ndarray):
    """Condense the reduced DOFs flagged in ``omit`` out of ``system``.

    Parameters
    ----------
    system : trussid.fem.assembly.System
    omit : (system.n_dof,) bool
        DOFs of ``system`` (its reduced numbering) to condense.

    Returns
    -------
    System
        On the retained DOFs; ``T`` maps them to the full global displacement vector with
        the omitted DOFs recovered statically.

    Raises
    ------
    ModelError
        When ``K_oo`` is singular (an omitted set that is a mechanism on its own, naming a
        DOF), or when nothing or too much would be retained.
    """
    omit = np.asarray(omit, bool)
    if not omit.any():
        return system
    a = np.flatnonzero(~omit)
    o = np.flatnonzero(omit)
    if len(a) == 0:
        raise ModelError("OMIT/ASET: every DOF is omitted; nothing is left to solve for")
    if len(a) > MAX_A_SET:
        raise ModelError(f"OMIT/ASET: {len(a)} retained DOFs; Guyan reduction is dense in the a-set "
                         f"and is limited to {MAX_A_SET}")
    K = system.K.tocsc()
    M = system.M.tocsc()
    Koo = K[o][:, o].tocsc()
    Koa = K[o][:, a].toarray()
    try:
        lu = spla.splu(Koo)
        X = -lu.solve(Koa)
    except RuntimeError:
        X = None
    diag = np.abs(lu.U.diagonal()) if X is not None else np.zeros(1)
    if X is None or not np.isfinite(X).all() or diag.min() <= 1e-13 * diag.max():
        j = int(o[np.argmin(np.abs(Koo.diagonal()))])
        raise ModelError(f"OMIT/ASET: the omitted DOFs are a mechanism on their own (e.g. "
                         f"{system.dof_label(j)}); retain it, or support it")
    Kaa = K[a][:, a].toarray()
    Kao = K[a][:, o].toarray()
    Maa = M[a][:, a].toarray()
    Mao = M[a][:, o].toarray()
    Moo = M[o][:, o]
    Kr = Kaa + Kao @ X
    Mr = Maa + Mao @ X + X.T @ Mao.T + X.T @ (Moo @ X)
    Kr, Mr = 0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T)
    G = np.zeros((system.n_dof, len(a)))
    G[a, np.arange(len(a))] = 1.0
    G[o] = X
    T = sp.csr_matrix(system.T @ G)
    T.eliminate_zeros()
    return dataclasses.replace(system, K=sp.csr_matrix(Kr), M=sp.csr_matrix(Mr), T=T, n_dof=len(a),
                               dofs=system.dofs[a])
