"""Constraints by DOF transformation: supports (elimination) and rigid bodies (RBE2-like).

The full DOF vector (``6 * n_nodes``) is ``u = T @ q`` with ``q`` the independent DOFs that
remain: every DOF that is neither supported nor a dependent component of a rigid-body slave.
A dependent slave component follows its master rigidly,

    u_s = u_m + theta_m x (x_s - x_m),     theta_s = theta_m,

which is exact for small rotations and adds no stiffness (no penalty), so the reduced
``T^T K T`` keeps the conditioning of the unconstrained model. Masters may themselves be
slaves of another body (chains): the map is composed until only independent DOFs remain.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from trussid.fem.errors import ModelError
from trussid.fem.model import DOF_NAMES


def skew(r: np.ndarray) -> np.ndarray:
    """Cross-product matrices ``[r]x`` with ``[r]x @ a == r x a``; r (..., 3) -> (..., 3, 3)."""
    r = np.asarray(r, float)
    s = np.zeros(r.shape[:-1] + (3, 3))
    s[..., 0, 1], s[..., 0, 2] = -r[..., 2], r[..., 1]
    s[..., 1, 0], s[..., 1, 2] = r[..., 2], -r[..., 0]
    s[..., 2, 0], s[..., 2, 1] = -r[..., 1], r[..., 0]
    return s


def rigid_transform(r: np.ndarray) -> np.ndarray:
    """6x6 maps from a reference node's DOFs to a point at offset ``r`` (..., 3) [m].

    ``[u_p; theta_p] = S @ [u_ref; theta_ref]`` with ``S = [[I, -[r]x], [0, I]]``.
    """
    r = np.asarray(r, float)
    S = np.zeros(r.shape[:-1] + (6, 6))
    S[..., :3, :3] = np.eye(3)
    S[..., 3:, 3:] = np.eye(3)
    S[..., :3, 3:] = -skew(r)
    return S


def rigid_mass(mass, offset, inertia) -> np.ndarray:
    """6x6 mass matrices of rigid masses referred to a node (CONM2 / rigid-body mass).

    Parameters
    ----------
    mass : (...,) float
        Mass [kg].
    offset : (..., 3) float
        Centre of gravity relative to the node, global axes [m].
    inertia : (..., 3, 3) float
        Inertia tensor about the centre of gravity, global axes [kg m^2].

    Returns
    -------
    (..., 6, 6) float
        ``S^T diag(m I, I_cg) S`` with ``S`` the map from the node to the cg: translational
        block ``m I``, coupling ``-m [c]x``, rotational block the parallel-axis inertia
        ``I_cg + m (|c|^2 I - c c^T)`` [kg, kg m, kg m^2].
    """
    mass = np.asarray(mass, float)
    S = rigid_transform(offset)
    D = np.zeros(mass.shape + (6, 6))
    D[..., :3, :3] = mass[..., None, None] * np.eye(3)
    D[..., 3:, 3:] = inertia
    out = np.swapaxes(S, -1, -2) @ D @ S
    return 0.5 * (out + np.swapaxes(out, -1, -2))


def dof_label(node_ids: np.ndarray, dof: int) -> str:
    """``"node 7 rz"`` for global DOF index ``dof``."""
    return f"node {node_ids[dof // 6]} {DOF_NAMES[dof % 6]}"


def build_transformation(model, fixed: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    """Reduced-to-full DOF map for supports and rigid bodies.

    Parameters
    ----------
    model : fem.Model
    fixed : (n_nodes, 6) bool
        Supported components (plus any to be removed, e.g. AUTOSPC).

    Returns
    -------
    T : (6 n_nodes, n_red) scipy.sparse.csr_matrix
        ``u_full = T @ q``.
    independent : (n_red,) int
        Full DOF index of each reduced DOF (``T[independent[j], j] == 1``).

    Raises
    ------
    ModelError
        A slave node that is also supported in a dependent component, a node that is a
        slave of two rigid bodies (or in one twice), a slave that is its own body's master,
        or a cycle of rigid bodies. Each message names the node and bodies.
    """
    n_full = model.n_dof
    node_ids = model.node_ids
    xyz = model.xyz
    fixed_flat = np.asarray(fixed, bool).reshape(-1)
    dependent = np.zeros(n_full, bool)
    owner = np.full(n_full, -1, dtype=np.int64)  # body id owning each dependent DOF
    rows, cols, vals = [], [], []
    for body in model.rigid_bodies:
        what = f"rigid body {body.id}"
        m = int(model.index_of([body.master], what=f"{what} (master)")[0])
        s = np.atleast_1d(model.index_of(body.slaves, what=f"{what} (slave)"))
        if (s == m).any():
            raise ModelError(f"{what}: node {node_ids[m]} is both master and slave")
        uniq, counts = np.unique(s, return_counts=True)
        if (counts > 1).any():
            raise ModelError(f"{what}: slave node {node_ids[uniq[counts > 1][0]]} is listed twice")
        comps = np.flatnonzero(body.dofs)
        sd = (6 * s[:, None] + comps[None, :]).ravel()
        taken = dependent[sd]
        if taken.any():
            d = int(sd[taken][0])
            raise ModelError(f"node {node_ids[d // 6]} is a slave of two rigid bodies "
                             f"({owner[d]} and {body.id})")
        sup = fixed_flat[sd]
        if sup.any():
            d = int(sd[sup][0])
            raise ModelError(f"node {node_ids[d // 6]} is a slave of {what} and also supported in "
                             f"{DOF_NAMES[d % 6]}: support its master instead")
        dependent[sd] = True
        owner[sd] = body.id
        S = rigid_transform(xyz[s] - xyz[m])  # (k, 6, 6)
        Sk = S[:, comps, :]  # rows of the dependent components, (k, c, 6)
        r = np.broadcast_to(sd.reshape(len(s), len(comps))[:, :, None], Sk.shape)
        c = np.broadcast_to((6 * m + np.arange(6))[None, None, :], Sk.shape)
        nz = Sk != 0
        rows.append(r[nz])
        cols.append(c[nz])
        vals.append(Sk[nz])

    indep = np.flatnonzero(~dependent)
    if rows:
        # Full-to-full map: identity on independent DOFs, rigid rows on dependent ones.
        D = sp.csr_matrix((np.concatenate([np.ones(len(indep))] + vals),
                           (np.concatenate([indep] + rows), np.concatenate([indep] + cols))),
                          shape=(n_full, n_full))
        dep_cols = np.flatnonzero(dependent)
        for _ in range(len(model.rigid_bodies) + 1):
            still = D[:, dep_cols].nnz
            if not still:
                break
            D = (D @ D).tocsr()
        else:
            bad = dep_cols[np.asarray(abs(D[:, dep_cols]).sum(axis=0)).ravel() > 0][0]
            raise ModelError(f"rigid bodies form a cycle through {dof_label(node_ids, bad)}")
        D.eliminate_zeros()
    else:
        D = sp.identity(n_full, format="csr")
    keep = indep[~fixed_flat[indep]]
    T = D[:, keep].tocsr()
    return T, keep


def rigid_body_modes(xyz: np.ndarray, origin=None) -> np.ndarray:
    """The six rigid-body motions of a set of nodes, (6 n_nodes, 6).

    Columns: unit translations along x, y, z, then unit rotations about x, y, z through
    ``origin`` (default: the nodes' centroid, which keeps the columns well scaled).
    """
    xyz = np.asarray(xyz, float)
    origin = xyz.mean(axis=0) if origin is None else np.asarray(origin, float)
    S = rigid_transform(xyz - origin)  # (n, 6, 6) node <- origin
    return S.reshape(-1, 6)
