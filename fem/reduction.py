"""Guyan (static) and Craig-Bampton reductions of an assembled system, as NASTRAN's
OMIT/ASET and QSET do them.

The omitted DOFs ``o`` follow the retained ones ``a`` statically: ``u_o = -K_oo^-1 K_oa u_a``,
so ``K_aa' = T^T K T`` and ``M_aa' = T^T M T`` with ``T = [I; -K_oo^-1 K_oa]``. This is exact
for the stiffness and for omitted DOFs without mass (their inertia is zero, so they are
static anyway); with mass on the omitted DOFs it is Guyan's approximation, which NASTRAN
makes too, and the frequencies rise.

Scaling: ``K_oo`` is factorised sparse once (SuperLU), but ``T`` has ``n_o x n_a`` dense
entries and the reduced matrices are dense ``n_a x n_a``: meant for a-sets of up to a few
thousand DOFs (NASTRAN's use: a handful of retained DOFs), not for large models.

Craig-Bampton (:func:`craig_bampton`) adds to the static shapes the lowest modes of the
omitted DOFs with the retained ones held (fixed-interface component modes); their amplitudes
are the generalized coordinates NASTRAN puts on Q-set scalar points.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.linalg as la
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from trussid.fem.errors import ModelError
from trussid.fem.eigen import DENSE_MAX_DOF, dense_modes

__all__ = ["MAX_A_SET", "guyan", "craig_bampton"]

#: Retained DOFs beyond which the dense reduced matrices are refused (memory ~ 8 n_a^2 bytes
#: for each of K, M plus 8 n_o n_a for the transformation).
MAX_A_SET = 20000


def _static_shapes(system, omit: np.ndarray):
    """``(a, o, lu, X)``: retained and omitted DOFs, the factor of ``K_oo`` and the static
    shapes ``X = -K_oo^-1 K_oa``; a singular ``K_oo`` is a ModelError naming a DOF."""
    a = np.flatnonzero(~omit)
    o = np.flatnonzero(omit)
    if len(a) == 0:
        raise ModelError("OMIT/ASET: every DOF is omitted; nothing is left to solve for")
    if len(a) > MAX_A_SET:
        raise ModelError(f"OMIT/ASET: {len(a)} retained DOFs; Guyan reduction is dense in the a-set "
                         f"and is limited to {MAX_A_SET}")
    K = system.K.tocsc()
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
    return a, o, lu, X


def _fixed_interface_modes(Koo, Moo, lu, n_modes: int) -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``n_modes`` eigenpairs of ``K_oo phi = lambda M_oo phi`` that carry mass,
    mass-normalised: ``(lambda, Phi)``, fewer when ``M_oo`` has a smaller rank.

    Up to :data:`trussid.fem.eigen.DENSE_MAX_DOF` omitted DOFs from the one dense solver,
    :func:`trussid.fem.eigen.dense_modes` (its inverted problem suits ``K_oo``, which is
    definite, and a singular ``M_oo``: massless omitted DOFs get ``mu = 0``); beyond, from
    ARPACK shift-invert at 0."""
    n_o = Koo.shape[0]
    if n_o <= DENSE_MAX_DOF:
        lam, P = dense_modes(Koo.toarray(), Moo.toarray(), min(n_modes, n_o))
        with np.errstate(divide="ignore"):
            mu = 1.0 / lam  # massless directions come back at lambda = inf: mu = 0
    else:
        op = spla.LinearOperator(Koo.shape, matvec=lu.solve, dtype=float)
        lam, P = spla.eigsh(Koo, k=min(n_modes, n_o - 1), M=Moo, sigma=0.0, OPinv=op,
                            v0=np.random.default_rng(0).standard_normal(n_o))
        mu = 1.0 / lam
        order = np.argsort(-mu)
        mu, P = mu[order], P[:, order]
    keep = mu > 1e-12 * max(float(mu.max(initial=0.0)), 1e-300)
    mu, P = mu[keep][:n_modes], P[:, keep][:, :n_modes]
    P = P / np.sqrt(np.einsum("ij,ij->j", P, Moo @ P))
    return 1.0 / mu, P


def craig_bampton(system, omit: np.ndarray, q_dofs: np.ndarray):
    """Reduce ``system`` to its retained DOFs plus component-mode amplitudes.

    The omitted DOFs ``o`` move as ``u_o = Psi u_b + Phi q``: the static shapes ``Psi =
    -K_oo^-1 K_ob`` of :func:`guyan` plus the lowest ``len(q_dofs)`` modes ``Phi`` of the
    omitted DOFs with the retained ones ``b`` held (mass-normalised). The reduced matrices
    are ``G^T K G`` and ``G^T M G`` with ``G = [[I, 0], [Psi, Phi]]``; the stiffness is
    block-diagonal, ``diag(K_bb + K_bo Psi, omega^2)``.

    Parameters
    ----------
    system : trussid.fem.assembly.System
        Without the generalized coordinates.
    omit : (system.n_dof,) bool
        DOFs of ``system`` to reduce (the o-set); the others are the boundary.
    q_dofs : (n_q,) int
        Full DOF index of each generalized coordinate (component 0 of a scalar point),
        taking the modes in ascending order.

    Returns
    -------
    System
        On the boundary DOFs followed by the generalized coordinates; ``T`` expands both to
        the full DOFs (a generalized coordinate's own DOF shows its amplitude). Points
        beyond the number of modes that carry mass are left out and listed in ``autospc``.
    """
    omit = np.asarray(omit, bool)
    q_dofs = np.asarray(q_dofs, dtype=np.int64)
    if not omit.any():
        return dataclasses.replace(system, autospc=system.autospc + _unused(system, q_dofs))
    a, o, lu, X = _static_shapes(system, omit)
    K, M = system.K.tocsc(), system.M.tocsc()
    lam, Phi = _fixed_interface_modes(K[o][:, o], M[o][:, o].tocsc(), lu, len(q_dofs))
    nb, nq = len(a), Phi.shape[1]
    G = np.zeros((system.n_dof, nb + nq))
    G[a, np.arange(nb)] = 1.0
    G[o, :nb] = X
    G[o, nb:] = Phi
    Kr = G.T @ (K @ G)
    Mr = G.T @ (M @ G)
    # The coupling K_bq is zero analytically (Phi's columns are K_oo-orthogonal to the
    # static correction): set it so, and the modal block to omega^2 exactly.
    Kr[:nb, nb:] = Kr[nb:, :nb] = 0.0
    Kr[nb:, nb:] = np.diag(lam)
    Kr, Mr = 0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T)
    T = sp.lil_matrix(system.T @ G)
    T[q_dofs[:nq], nb + np.arange(nq)] = 1.0
    T = sp.csr_matrix(T)
    T.eliminate_zeros()
    return dataclasses.replace(system, K=sp.csr_matrix(Kr), M=sp.csr_matrix(Mr), T=T, n_dof=nb + nq,
                               dofs=np.r_[system.dofs[a], q_dofs[:nq]],
                               autospc=system.autospc + _unused(system, q_dofs[nq:]))


def _unused(system, q_dofs) -> list:
    """``(node id, "ux")`` of generalized coordinates left without a mode."""
    return [(int(system.node_ids[d // 6]), "ux") for d in q_dofs]


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
    a, o, _lu, X = _static_shapes(system, omit)
    K = system.K.tocsc()
    M = system.M.tocsc()
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
