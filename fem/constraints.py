"""Constraints by DOF transformation: supports (elimination), rigid bodies (RBE2-like),
linear constraints (MPC, RBAR, RBE3) and node displacement frames.

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

__all__ = ["skew", "rigid_transform", "rigid_mass", "dof_label", "frame_transform",
           "build_transformation", "rigid_element", "rbe3_constraint", "rigid_body_modes"]


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


def frame_transform(frames: np.ndarray) -> np.ndarray:
    """6x6 maps from node-frame DOFs to global DOFs, ``u_global = Lam @ u_node``.

    ``frames`` (..., 3, 3) has the frame's axes as rows, so ``Lam = diag(F^T, F^T)``.
    """
    F = np.asarray(frames, float)
    Lam = np.zeros(F.shape[:-2] + (6, 6))
    Ft = np.swapaxes(F, -1, -2)
    Lam[..., :3, :3] = Ft
    Lam[..., 3:, 3:] = Ft
    return Lam


def build_transformation(model, fixed: np.ndarray) -> tuple[sp.csr_matrix, np.ndarray]:
    """Reduced-to-full DOF map for supports, rigid bodies and linear constraints.

    Parameters
    ----------
    model : fem.Model
    fixed : (n_nodes, 6) bool
        Supported components (plus any to be removed, e.g. AUTOSPC), in node frames.

    Returns
    -------
    T : (6 n_nodes, n_red) scipy.sparse.csr_matrix
        ``u_full = T @ q``, ``u_full`` in global axes.
    independent : (n_red,) int
        Node-frame DOF index (``6 * node_index + component``) of each reduced DOF.

    Raises
    ------
    ModelError
        A dependent DOF that is also supported, a DOF dependent in two rigid bodies or
        constraints (or twice in one), a slave that is its own body's master, or a cycle.
        Each message names the node and bodies.

    Notes
    -----
    With node displacement frames (``Model.set_node_frames``) the constraints act on node-
    frame components: a rigid body's slave follows ``Lam_s^T S Lam_m`` of its master. The
    global map is then ``Lam @ D`` with ``Lam`` block-diagonal. Everything is sparse: the
    cost grows with the number of constrained DOFs, never with ``n_dof^2``.
    """
    # Long: rigid bodies and linear constraints claim their dependent DOFs through one
    # shared record of ownership (so that a DOF claimed twice is named with both owners);
    # splitting the two loops out would pass that record and the row lists around.
    n_full = model.n_dof
    node_ids = model.node_ids
    xyz = model.xyz
    frames = model.node_frames() if hasattr(model, "node_frames") else None
    Lam = None if frames is None else frame_transform(frames)
    fixed_flat = np.asarray(fixed, bool).reshape(-1)
    dependent = np.zeros(n_full, bool)
    owner = np.full(n_full, "", dtype=object)  # label of the body owning each dependent DOF
    rows, cols, vals = [], [], []

    def claim(sd, what, body=None):
        taken = dependent[sd]
        if taken.any():
            d = int(sd[taken][0])
            if body is not None and isinstance(owner[d], int):
                raise ModelError(f"node {node_ids[d // 6]} is a slave of two rigid bodies "
                                 f"({owner[d]} and {body})")
            raise ModelError(f"node {node_ids[d // 6]} {DOF_NAMES[d % 6]} is dependent in two rigid "
                             f"elements or constraints ({owner[d]} and {what})")
        sup = fixed_flat[sd]
        if sup.any():
            d = int(sd[sup][0])
            if body is not None:
                raise ModelError(f"node {node_ids[d // 6]} is a slave of {what} and also supported in "
                                 f"{DOF_NAMES[d % 6]}: support its master instead")
            raise ModelError(f"node {node_ids[d // 6]} is dependent in {what} and also supported in "
                             f"{DOF_NAMES[d % 6]}: support an independent DOF instead")
        dependent[sd] = True
        owner[sd] = what if body is None else body

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
        claim(sd, what, body.id)
        S = rigid_transform(xyz[s] - xyz[m])  # (k, 6, 6)
        if Lam is not None:
            S = np.swapaxes(Lam[s], -1, -2) @ S @ Lam[m]
        Sk = S[:, comps, :]  # rows of the dependent components, (k, c, 6)
        r = np.broadcast_to(sd.reshape(len(s), len(comps))[:, :, None], Sk.shape)
        c = np.broadcast_to((6 * m + np.arange(6))[None, None, :], Sk.shape)
        nz = Sk != 0
        rows.append(r[nz])
        cols.append(c[nz])
        vals.append(Sk[nz])

    for con in getattr(model, "constraints", []):
        d = 6 * np.atleast_1d(model.index_of(con.dep_nodes, what=f"{con.label} (dependent)")) + con.dep_comps
        i = 6 * np.atleast_1d(model.index_of(con.ind_nodes, what=f"{con.label} (independent)")) + con.ind_comps
        uniq, counts = np.unique(d, return_counts=True)
        if (counts > 1).any():
            u = int(uniq[counts > 1][0])
            raise ModelError(f"{con.label}: node {node_ids[u // 6]} {DOF_NAMES[u % 6]} is dependent twice")
        if np.isin(d, i).any():
            u = int(d[np.isin(d, i)][0])
            raise ModelError(f"{con.label}: node {node_ids[u // 6]} {DOF_NAMES[u % 6]} is both dependent "
                             f"and independent")
        claim(d, con.label)
        r = np.broadcast_to(d[:, None], con.C.shape)
        c = np.broadcast_to(i[None, :], con.C.shape)
        nz = con.C != 0
        rows.append(r[nz])
        cols.append(c[nz])
        vals.append(con.C[nz])

    indep = np.flatnonzero(~dependent)
    if rows:
        # Full-to-full map: identity on independent DOFs, constraint rows on dependent ones.
        # Squaring substitutes dependent DOFs that appear on right-hand sides (chains).
        D = sp.csr_matrix((np.concatenate([np.ones(len(indep))] + vals),
                           (np.concatenate([indep] + rows), np.concatenate([indep] + cols))),
                          shape=(n_full, n_full))
        dep_cols = np.flatnonzero(dependent)
        n_links = len(model.rigid_bodies) + len(getattr(model, "constraints", []))
        for _ in range(n_links + 1):
            still = D[:, dep_cols].nnz
            if not still:
                break
            D = (D @ D).tocsr()
            D.eliminate_zeros()
        else:
            bad = dep_cols[np.asarray(abs(D[:, dep_cols]).sum(axis=0)).ravel() > 0][0]
            raise ModelError(f"rigid bodies form a cycle through {dof_label(node_ids, bad)}")
        D.eliminate_zeros()
    else:
        D = sp.identity(n_full, format="csr")
    keep = indep[~fixed_flat[indep]]
    T = D[:, keep].tocsr()
    if Lam is not None:
        n = len(node_ids)
        r = np.broadcast_to((6 * np.arange(n))[:, None, None] + np.arange(6)[None, :, None], (n, 6, 6))
        c = np.broadcast_to((6 * np.arange(n))[:, None, None] + np.arange(6)[None, None, :], (n, 6, 6))
        nz = Lam != 0
        L = sp.csr_matrix((Lam[nz], (r[nz], c[nz])), shape=(n_full, n_full))
        T = (L @ T).tocsr()
    return T, keep


def rigid_element(xyz: np.ndarray, frames: np.ndarray | None, independent, dependent,
                  label: str) -> np.ndarray:
    """Coefficients of a rigid element whose independent DOFs are any six that fix its motion.

    NASTRAN's RBAR, CRIGD1-3 and RBE2 all say: the grids move as one rigid body; the
    listed independent components determine that motion, the dependent ones follow.

    Parameters
    ----------
    xyz : (k, 3) float
        Positions of the element's grids (global) [m].
    frames : (k, 3, 3) float or None
        Their displacement frames (rows = axes), None for global.
    independent, dependent : sequences of (grid position 0..k-1, component 0..5)
    label : str
        For the error message.

    Returns
    -------
    C : (len(dependent), len(independent)) float
        ``u_dependent = C @ u_independent``.

    Raises
    ------
    ModelError
        When the independent components do not determine a rigid motion (not exactly six,
        or six that leave a motion free), naming ``label``.
    """
    xyz = np.asarray(xyz, float)
    G = rigid_transform(xyz - xyz[0])  # (k, 6, 6): grid DOFs from the rigid motion of grid 0
    if frames is not None:
        G = np.swapaxes(frame_transform(frames), -1, -2) @ G
    ind = np.array([G[g, c] for g, c in independent]).reshape(-1, 6)
    dep = np.array([G[g, c] for g, c in dependent]).reshape(-1, 6)
    sv = np.linalg.svd(ind, compute_uv=False) if len(ind) else np.zeros(0)
    if len(ind) != 6 or sv.min() <= 1e-10 * max(sv.max(), 1.0):
        raise ModelError(f"{label}: its {len(ind)} independent components do not determine a rigid "
                         f"motion (six independent ones are needed)")
    return dep @ np.linalg.inv(ind)


def rbe3_constraint(ref_xyz, ref_frame, xyz, frames, comps, weights, refc, label: str) -> np.ndarray:
    """Coefficients of an RBE3 (interpolation element), NASTRAN's weighting.

    The reference point moves as the weighted least-squares rigid-body fit of the
    independent grids' listed components: with ``S_i`` mapping the reference point's
    motion to grid i, ``u_ref = (S^T W S)^-1 S^T W u``. Translations are weighted by the
    grid's weight ``w_i``, rotations by ``w_i Lc^2`` with ``Lc`` the mean distance of the
    independent grids from the reference point (NASTRAN's default characteristic length,
    which makes the weights dimensionally consistent).

    Parameters
    ----------
    ref_xyz : (3,) float
    ref_frame : (3, 3) float or None
        Displacement frame of the reference grid (rows = axes).
    xyz : (k, 3) float
        Independent grids (one row per grid and component group; a grid may repeat).
    frames : (k, 3, 3) float or None
    comps : (k, 6) bool
        Components of each row that take part.
    weights : (k,) float
    refc : (6,) bool
        Reference components that are dependent.
    label : str

    Returns
    -------
    C : (refc.sum(), comps.sum()) float
        ``u_ref[refc] = C @ u[comps]`` (independent DOFs in row-major order of ``comps``).
    """
    xyz = np.atleast_2d(np.asarray(xyz, float))
    ref = np.asarray(ref_xyz, float)
    r = xyz - ref
    Lc = float(np.mean(np.linalg.norm(r, axis=1)))
    Lc = Lc if Lc > 0 else 1.0
    S = rigid_transform(r)  # (k, 6, 6) grid DOFs (global) from the reference motion (global)
    if frames is not None:
        S = np.swapaxes(frame_transform(frames), -1, -2) @ S
    comps = np.asarray(comps, bool)
    w = np.repeat(np.asarray(weights, float)[:, None], 6, axis=1) * np.array([1, 1, 1, Lc**2, Lc**2, Lc**2])
    A = S[comps]  # (p, 6)
    W = w[comps]
    N = A.T @ (W[:, None] * A)
    sv = np.linalg.svd(N, compute_uv=False)
    if sv.min() <= 1e-12 * sv.max():
        raise ModelError(f"{label}: the independent components do not determine the reference "
                         f"point's motion (add grids or components)")
    G = np.linalg.solve(N, A.T * W[None, :])  # (6, p): global reference motion
    if ref_frame is not None:
        G = frame_transform(ref_frame).T @ G
    return G[np.asarray(refc, bool)]


def rigid_body_modes(xyz: np.ndarray, origin=None) -> np.ndarray:
    """The six rigid-body motions of a set of nodes, (6 n_nodes, 6).

    Columns: unit translations along x, y, z, then unit rotations about x, y, z through
    ``origin`` (default: the nodes' centroid, which keeps the columns well scaled).
    """
    xyz = np.asarray(xyz, float)
    origin = xyz.mean(axis=0) if origin is None else np.asarray(origin, float)
    S = rigid_transform(xyz - origin)  # (n, 6, 6) node <- origin
    return S.reshape(-1, 6)
