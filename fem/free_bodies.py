"""Free bodies: parts of a model that no stiffness ties to the rest or to the ground.

A zero-frequency mode is either a *free-body* motion, legal and reported at 0 Hz (NASTRAN
does so too), or a *mechanism*, refused as a modelling error. The line between them is
drawn by kinematic connectivity:

- the model's points fall into *components*: points joined, directly or in a chain, by an
  element stiffness term (beam, spring, general element) or by a constraint (rigid body,
  MPC, RBE3...); mass coupling does not join points, since it cannot carry a static force;
- a zero-energy motion is a free-body motion when every component moves as one rigid body
  (a component may also stand still). A point mass joined to nothing is a component of its
  own, so any motion of it is a rigid motion: a 0 Hz mode. A point joined to a structure
  by elements that do not resist one of its components (a CONM2 rotation at a rod-only
  node, a hinge left free by pin flags) moves alone inside its component: a mechanism;
- scalar points have no position: any motion of theirs counts as rigid (a zero-energy
  motion of a scalar spring network is the same translation of each of its parts), so a
  scalar point tied by an MPC to a free point mass moves with it as a free body.

DOFs on which nothing acts at all (no stiffness, no mass) are left out of the test, as in
:func:`trussid.fem.modal.rigid_null_dimension`.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from trussid.fem.constraints import rigid_transform

__all__ = ["node_components", "component_rigid_fit", "RIGID_FIT_TOL"]

#: Relative residual of the rigid fit below which a motion is rigid on its components
#: (the same tolerance the whole-model test used before components were considered).
RIGID_FIT_TOL = 1e-5


def node_components(n_nodes: int, pairs: np.ndarray, T: sp.spmatrix) -> np.ndarray:
    """Component label of each node, (n_nodes,) int from 0.

    Parameters
    ----------
    n_nodes : int
    pairs : (m, 2) int
        Node index pairs that an element stiffness joins (a star of pairs for an element
        on more than two nodes).
    T : (6 n_nodes, n_red) sparse
        Constraint transformation: the nodes one reduced DOF drives are joined.
    """
    Tc = sp.coo_matrix(T)
    tk = Tc.data != 0
    n_red = Tc.shape[1]
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    # Bipartite graph: nodes 0..n-1, reduced DOFs n..n+n_red-1.
    rows = np.concatenate([pairs[:, 0], Tc.row[tk] // 6])
    cols = np.concatenate([pairs[:, 1], n_nodes + Tc.col[tk]])
    A = sp.coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n_nodes + n_red, n_nodes + n_red))
    _, labels = connected_components(A, directed=False)
    return np.unique(labels[:n_nodes], return_inverse=True)[1]


def component_rigid_fit(xyz: np.ndarray, labels: np.ndarray, free: np.ndarray, Z: np.ndarray,
                        tol: float = RIGID_FIT_TOL) -> tuple[np.ndarray, np.ndarray]:
    """Which columns of ``Z`` move every component rigidly, and the nearest such motions.

    Parameters
    ----------
    xyz : (n, 3) float
        Node coordinates [m].
    labels : (n,) int
        Component of each node (:func:`node_components`).
    free : (6 n,) bool
        DOFs left out of the fit (scalar points, DOFs nothing acts on): any value is
        accepted there, and the fitted motion keeps ``Z``'s value.
    Z : (6 n, k) float
        Motions on the full DOFs.
    tol : float
        Relative residual (rotations weighted by the model's size) accepted as rigid.

    Returns
    -------
    rigid : (k,) bool
    fitted : (6 n, k) float
        Per component, the least-squares rigid motion of ``Z`` (``Z`` itself on ``free``).
    """
    xyz = np.asarray(xyz, float)
    n = len(xyz)
    Z = np.asarray(Z, float).reshape(6 * n, -1)
    k = Z.shape[1]
    size = float(np.ptp(xyz, axis=0).max()) if n else 1.0
    size = size or 1.0
    nc = int(labels.max()) + 1 if n else 0
    count = np.bincount(labels, minlength=nc)
    centre = np.stack([np.bincount(labels, weights=xyz[:, j], minlength=nc) for j in range(3)], 1)
    centre /= np.maximum(count, 1)[:, None]
    S = rigid_transform(xyz - centre[labels])           # (n, 6, 6): node <- component centre
    w = np.r_[np.ones(3), np.full(3, size)]             # rotations in length units
    use = (~np.asarray(free, bool)).reshape(n, 6) * w   # (n, 6) weights, 0 where free
    Sw = S * use[:, :, None]
    Zn = Z.reshape(n, 6, k)
    Zw = Zn * use[:, :, None]
    G = np.zeros((nc, 6, 6))
    np.add.at(G, labels, np.einsum("nij,nik->njk", Sw, Sw))
    b = np.zeros((nc, 6, k))
    np.add.at(b, labels, np.einsum("nij,nik->njk", Sw, Zw))
    a = np.linalg.pinv(G, hermitian=True) @ b            # (nc, 6, k) rigid motion of each component
    fit = S @ a[labels]                                  # (n, 6, k)
    res = np.linalg.norm((Zw - fit * use[:, :, None]).reshape(6 * n, k), axis=0)
    scale = np.linalg.norm(Zw.reshape(6 * n, k), axis=0)
    rigid = res <= tol * scale
    fitted = np.where((use > 0)[:, :, None], fit, Zn).reshape(6 * n, k)
    return rigid, fitted
