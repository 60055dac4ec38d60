"""Assembly of the global stiffness and mass matrices (scipy.sparse), reduced by constraints.

Every element kind contributes a stack of small dense matrices plus the global DOF index of
each row; one COO -> CSR conversion sums them (no Python loop over elements). The full
matrices are then reduced to the independent DOFs, ``K = T^T K_full T``, by
:func:`trussid.fem.constraints.build_transformation` (supports by elimination, rigid bodies by DOF
transformation).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from trussid.fem.constraints import build_transformation, dof_label, rigid_mass
from trussid.fem.elements import check_beam_properties, frame_matrices, local_axes
from trussid.fem.errors import ModelError
from trussid.fem.free_bodies import component_rigid_fit, node_components
from trussid.fem.model import DOF_NAMES
from trussid.fem.reduction import craig_bampton, guyan

__all__ = ["System", "beam_matrices", "spring_matrices", "general_blocks", "mass_blocks",
           "sum_blocks", "assemble"]


@dataclass
class System:
    """Assembled, constrained system ``M q'' + K q = f`` on the independent DOFs ``q``.

    Attributes
    ----------
    K, M : (n_red, n_red) scipy.sparse.csr_matrix
        Symmetric stiffness [N/m ...] and mass [kg ...] on the reduced DOFs.
    T : (6 n_nodes, n_red) scipy.sparse.csr_matrix
        Full DOF vector in global axes = ``T @ q`` (supported DOFs zero, rigid-body slaves
        and constrained DOFs expanded, omitted DOFs recovered statically).
    node_ids : (n_nodes,) int
    xyz : (n_nodes, 3) float
        Node coordinates [m].
    n_dof : int
        Number of reduced DOFs ``n_red``.
    dofs : (n_red,) int
        Full DOF index (``6 * node_index + component``, components in the node's
        displacement frame) of each reduced DOF.
    autospc : list of (int, str)
        ``(node_id, component)`` removed because they had neither stiffness nor mass.
    mass_formulation : str
        "consistent" or "lumped".
    beam_theory : str
    has_supports : bool
        The model had supports (then zero-frequency modes are mechanisms).
    name : str
    inert : (6 n_nodes,) bool or None
        Full DOFs with neither stiffness nor mass before constraints: nothing acts on them,
        so a support there (NASTRAN GRID PS on an unconnected rotation) does not stop a
        rigid-body motion.
    components : (n_nodes,) int or None
        Kinematic component of each node (:func:`trussid.fem.free_bodies.node_components`).
    scalar : (n_nodes,) bool or None
        Scalar points (no position: any motion of theirs is rigid).
    """

    K: sp.csr_matrix
    M: sp.csr_matrix
    T: sp.csr_matrix
    node_ids: np.ndarray
    xyz: np.ndarray
    n_dof: int
    dofs: np.ndarray
    autospc: list = field(default_factory=list)
    mass_formulation: str = "consistent"
    beam_theory: str = "euler-bernoulli"
    has_supports: bool = False
    name: str = "model"
    inert: np.ndarray | None = None
    components: np.ndarray | None = None
    scalar: np.ndarray | None = None

    def free_dofs(self) -> np.ndarray:
        """(6 n_nodes,) bool: full DOFs the free-body test leaves out (scalar points and
        DOFs nothing acts on)."""
        n = len(self.node_ids)
        free = np.zeros(6 * n, bool) if self.inert is None else self.inert.copy()
        if self.scalar is not None:
            free |= np.repeat(self.scalar, 6)
        return free

    def free_body(self, Z) -> tuple[np.ndarray, np.ndarray]:
        """``(rigid, fitted)`` of full-DOF motions ``Z`` (6 n_nodes, k): whether each moves
        every component rigidly (:func:`trussid.fem.free_bodies.component_rigid_fit`)."""
        labels = self.components if self.components is not None else np.zeros(len(self.node_ids), np.int64)
        return component_rigid_fit(self.xyz, labels, self.free_dofs(), Z)

    def dof_label(self, j: int) -> str:
        """``"node 7 rz"`` for reduced DOF ``j``."""
        return dof_label(self.node_ids, int(self.dofs[j]))


def _element_dofs(node_index: np.ndarray) -> np.ndarray:
    """(n, 6 k) global DOF indices for elements joining ``k`` nodes (n, k)."""
    return (6 * node_index[:, :, None] + np.arange(6)).reshape(len(node_index), -1)


def beam_matrices(model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Global-axis element matrices of all beams and their DOF indices.

    Returns
    -------
    K, M : (n_elem, 12, 12) float
    dofs : (n_elem, 12) int
    """
    b = model.beams
    if len(b) == 0:
        return np.zeros((0, 12, 12)), np.zeros((0, 12, 12)), np.zeros((0, 12), np.int64)
    check_beam_properties(b, model.beam_theory)
    idx = model.index_of(b.nodes, what=lambda pos: f"element {b.ids[pos // 2]}")
    same = idx[:, 0] == idx[:, 1]
    if same.any():
        raise ModelError(f"element {b.ids[same][0]}: zero length (both ends are node {b.nodes[same][0, 0]})")
    xyz = model.xyz
    L, R = local_axes(xyz[idx[:, 0]], xyz[idx[:, 1]], b.orient, b.ids)
    K, M = frame_matrices(L, b.A, b.Iy, b.Iz, b.J, b.E, b.G, b.rho, nsm=b.nsm, Asy=b.Asy, Asz=b.Asz,
                          rod=b.rod, R=R, theory=model.beam_theory, mass=model.mass_formulation)
    return K, M, _element_dofs(idx)


def spring_matrices(model) -> tuple[list, list]:
    """Stiffness blocks and DOF indices of the springs: ``([K2, K1], [dofs2, dofs1])``.

    Two-node springs give (n, 12, 12) blocks, grounded ones (n, 6, 6).
    """
    s = model.springs
    if len(s) == 0:
        return [], []
    grounded = s.nodes[:, 1] == -1
    ia = model.index_of(s.nodes[:, 0], what=lambda pos: f"spring {s.ids[pos]}")
    ib = np.full(len(s), -1)
    if (~grounded).any():
        ib[~grounded] = model.index_of(s.nodes[~grounded, 1],
                                       what=lambda pos: f"spring {s.ids[~grounded][pos]}")
    same = ~grounded & (ia == ib)
    if same.any():
        raise ModelError(f"spring {s.ids[same][0]}: both ends are node {s.nodes[same][0, 0]}")
    # Diagonal in the spring frame F (rows = axes): K_global = F^T diag(k) F per 3x3 block.
    F = s.frame
    k6 = np.zeros((len(s), 6, 6))
    k6[:, :3, :3] = np.einsum("nki,nk,nkj->nij", F, s.k[:, :3], F)
    k6[:, 3:, 3:] = np.einsum("nki,nk,nkj->nij", F, s.k[:, 3:], F)
    blocks, dofs = [], []
    two = ~grounded
    if two.any():
        k = k6[two]
        k12 = np.concatenate([np.concatenate([k, -k], axis=2), np.concatenate([-k, k], axis=2)], axis=1)
        blocks.append(k12)
        dofs.append(_element_dofs(np.column_stack([ia[two], ib[two]])))
    if grounded.any():
        blocks.append(k6[grounded])
        dofs.append(_element_dofs(ia[grounded][:, None]))
    return blocks, dofs


def general_blocks(model) -> tuple[list, list, list]:
    """Stiffness blocks, mass blocks and DOF indices of ``Model.add_matrices`` elements."""
    K, M, dofs = [], [], []
    for g in getattr(model, "general", []):
        if len(g) == 0:
            continue
        idx = model.index_of(g.nodes, what=lambda pos, g=g: f"{g.label or 'element'} {g.ids[pos // g.nodes.shape[1]]}")
        K.append(g.K)
        M.append(g.M)
        dofs.append(_element_dofs(idx))
    return K, M, dofs


def mass_blocks(model) -> tuple[list, list]:
    """6x6 mass blocks (point masses and rigid-body masses at their masters) and DOFs."""
    blocks, dofs = [], []
    pm = model.point_masses
    if len(pm):
        idx = model.index_of(pm.nodes, what=lambda pos: f"point mass {pos + 1} (at node {pm.nodes[pos]})")
        blocks.append(rigid_mass(pm.mass, pm.offset, pm.inertia))
        dofs.append(_element_dofs(idx[:, None]))
    bodies = [b for b in model.rigid_bodies if b.mass > 0 or np.any(b.inertia)]
    if bodies:
        idx = model.index_of([b.master for b in bodies],
                             what=lambda pos: f"rigid body {bodies[pos].id} (master)")
        xyz = model.xyz[idx]
        cg = np.array([xyz[i] if b.cg is None else np.asarray(b.cg, float) for i, b in enumerate(bodies)])
        blocks.append(rigid_mass(np.array([b.mass for b in bodies]), cg - xyz,
                                 np.array([b.inertia for b in bodies])))
        dofs.append(_element_dofs(idx[:, None]))
    return blocks, dofs


def sum_blocks(blocks, dofs, n) -> sp.csr_matrix:
    """Sum dense element blocks into an (n, n) CSR matrix with one COO conversion.

    Exact zeros are dropped first so that they do not enter the sparsity pattern (and the
    fill-in of later factorisations).
    """
    if not any(len(b) for b in blocks):
        return sp.csr_matrix((n, n))
    idx = np.int32 if n < 2**31 - 1 else np.int64
    rows, cols, vals = [], [], []
    for b, d in zip(blocks, dofs):
        if len(b) == 0:
            continue
        d = d.astype(idx)
        k = d.shape[1]
        v = b.reshape(len(b), -1)
        nz = v != 0
        rows.append(np.broadcast_to(d[:, :, None], (len(d), k, k)).reshape(len(d), -1)[nz])
        cols.append(np.broadcast_to(d[:, None, :], (len(d), k, k)).reshape(len(d), -1)[nz])
        vals.append(v[nz])
    A = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)).tocsr()
    A.sum_duplicates()
    return A


def _zero(diag: np.ndarray, dofs: np.ndarray, rel: float = 1e-12) -> np.ndarray:
    """Diagonal entries that are zero relative to the largest of their kind.

    Translations and rotations are compared separately: their units (and magnitudes) differ.
    """
    out = np.zeros(len(diag), bool)
    rot = (dofs % 6) >= 3
    for sel in (rot, ~rot):
        if sel.any():
            d = np.abs(diag[sel])
            out[sel] = d <= rel * d.max() if d.max() > 0 else True
    return out


def _check_unique_element_ids(model) -> None:
    """Element ids (beams and springs share one id space, as NASTRAN's elements do) must be
    unique: a repeated id makes every message that names an element ambiguous."""
    b_ids = np.asarray(model.beams.ids, dtype=np.int64)
    s_ids = np.asarray(model.springs.ids, dtype=np.int64)
    ids = np.concatenate([b_ids, s_ids])
    if ids.size < 2:
        return
    uniq, counts = np.unique(ids, return_counts=True)
    if (counts > 1).any():
        dup = int(uniq[counts > 1][0])
        kinds = (["beam"] * int((b_ids == dup).sum())) + (["spring"] * int((s_ids == dup).sum()))
        raise ModelError(f"element {dup} is defined more than once ({' and '.join(kinds)})")


def _stiffness_pairs(model) -> np.ndarray:
    """(m, 2) node index pairs joined by an element stiffness: beams, two-node springs with a
    stiffness, general elements with a nonzero K (each node to the first); from the element
    lists, not from K (its entries are 150 per beam)."""
    out = []
    b = model.beams
    if len(b):
        out.append(model.index_of(b.nodes, what="a beam"))
    s = model.springs
    if len(s):
        two = (s.nodes[:, 1] >= 0) & (s.k > 0).any(axis=1)
        if two.any():
            out.append(model.index_of(s.nodes[two], what="a spring"))
    for g in model.general:
        live = np.abs(g.K).max(axis=(1, 2), initial=0.0) > 0
        if live.any() and g.nodes.shape[1] > 1:
            idx = model.index_of(g.nodes[live], what=g.label or "a general element")
            out.append(np.stack([np.repeat(idx[:, :1], idx.shape[1] - 1, axis=1).ravel(), idx[:, 1:].ravel()], 1))
    return np.concatenate(out) if out else np.zeros((0, 2), np.int64)


def assemble(model, autospc: bool = False) -> System:
    """Assemble and constrain a :class:`trussid.fem.Model`.

    Parameters
    ----------
    model : fem.Model
    autospc : bool
        Remove (and list in ``System.autospc``) every independent DOF with neither
        stiffness nor mass, like NASTRAN's AUTOSPC: e.g. the rotations of nodes joined
        only by rods. Without it such a DOF is an error.

    Returns
    -------
    System

    Raises
    ------
    ModelError
        Bad element data or references (naming the element, spring, mass or body), a DOF
        without stiffness when the model has supports (``"mechanism: node 7 rz has no
        stiffness"``), or a DOF with neither stiffness nor mass when ``autospc`` is off.

    Examples
    --------
    >>> from trussid.fem import ALUMINIUM, Model, Section, assemble
    >>> m = Model()
    >>> m.add_nodes([1, 2, 3], [[0, 0, 0], [0.5, 0, 0], [1, 0, 0]])
    >>> m.add_beams([1, 2], [[1, 2], [2, 3]], Section.tube(0.01, 0.001), ALUMINIUM, orient=[0, 0, 1])
    >>> m.fix(1)
    >>> system = assemble(m)
    >>> system.K.shape                            # 18 DOFs less the 6 clamped ones
    (12, 12)
    """
    node_ids = model.node_ids
    if len(node_ids) == 0:
        raise ModelError("the model has no nodes")
    model.index_of(node_ids[:1], what="the node list")  # duplicate node ids are an error
    _check_unique_element_ids(model)
    n = model.n_dof
    Kb, Mb, db = beam_matrices(model)
    ks, ds = spring_matrices(model)
    ms, dm = mass_blocks(model)
    kg, mg, dg = general_blocks(model)
    K_full = sum_blocks([Kb] + ks + kg, [db] + ds + dg, n)
    M_full = sum_blocks([Mb] + ms + mg, [db] + dm + dg, n)

    fixed = model.fixed_mask()
    T, dofs = build_transformation(model, fixed)
    if model.rigid_bodies or getattr(model, "constraints", None) or model.node_frames() is not None:
        Tt = T.T.tocsr()
        K = (Tt @ K_full @ T).tocsr()
        M = (Tt @ M_full @ T).tocsr()
    else:
        K = K_full[dofs][:, dofs].tocsr()
        M = M_full[dofs][:, dofs].tocsr()

    generalized = model.generalized_mask() if hasattr(model, "generalized_mask") else None
    q_full = np.zeros(n, bool)
    if generalized is not None and generalized.any():
        # Component-mode amplitudes live on scalar points that no element touches: taken out
        # here (they are empty DOFs), put back by the Craig-Bampton reduction below.
        q_full[6 * np.flatnonzero(generalized)] = True
        touched = q_full & ((abs(K_full).sum(axis=1).A1 != 0) | (abs(M_full).sum(axis=1).A1 != 0))
        if touched.any():
            raise ModelError(f"generalized coordinate {dof_label(node_ids, int(np.flatnonzero(touched)[0]))}: "
                             f"an element acts on it (component-mode amplitudes must be free scalar points)")
        keep = np.flatnonzero(~q_full[dofs])
        T, dofs = T[:, keep].tocsr(), dofs[keep]
        K, M = K[keep][:, keep].tocsr(), M[keep][:, keep].tocsr()
    zk = _zero(K.diagonal(), dofs)
    zm = _zero(M.diagonal(), dofs)
    removed: list[tuple[int, str]] = []
    empty = zk & zm
    if empty.any():
        if not autospc:
            j = int(np.flatnonzero(empty)[0])
            raise ModelError(f"mechanism: {dof_label(node_ids, dofs[j])} has no stiffness (and no mass); "
                             f"support it, or use AUTOSPC to remove such DOFs")
        keep = np.flatnonzero(~empty)
        removed = [(int(node_ids[d // 6]), DOF_NAMES[d % 6]) for d in dofs[empty]]
        T, dofs = T[:, keep].tocsr(), dofs[keep]
        K, M = K[keep][:, keep].tocsr(), M[keep][:, keep].tocsr()
        zk = zk[keep]
    if K.shape[0] == 0:
        raise ModelError("the model has no free DOF left after supports and constraints")
    K.sort_indices()
    M.sort_indices()
    inert = (K_full.diagonal() == 0) & (M_full.diagonal() == 0)
    scalar = model.scalar_mask() if hasattr(model, "scalar_mask") else np.zeros(len(node_ids), bool)
    system = System(K=K, M=M, T=T, node_ids=node_ids, xyz=model.xyz, n_dof=K.shape[0], dofs=dofs,
                    autospc=removed, mass_formulation=model.mass_formulation,
                    beam_theory=model.beam_theory, has_supports=model.has_supports, name=model.name,
                    inert=inert, components=node_components(len(node_ids), _stiffness_pairs(model), T),
                    scalar=scalar)
    if model.has_supports and zk.any():
        # A DOF with mass and no stiffness: a free body when moving it moves its whole
        # component rigidly (a point mass joined to nothing), else a mechanism.
        cols = np.flatnonzero(zk)
        rigid, _ = system.free_body(T[:, cols].toarray())
        if not rigid.all():
            j = int(cols[~rigid][0])
            raise ModelError(f"mechanism: {dof_label(node_ids, dofs[j])} has no stiffness")
    omitted = model.omitted_mask().reshape(-1) if hasattr(model, "omitted_mask") else None
    if q_full.any():
        omit = np.zeros(len(dofs), bool) if omitted is None else omitted[dofs]
        system = craig_bampton(system, omit, np.flatnonzero(q_full))
    elif omitted is not None and omitted.any():
        # Omitted DOFs that were supported, dependent or removed by AUTOSPC are not in the
        # system any more: only the remaining ones are condensed.
        system = guyan(system, omitted[dofs])
    return system
