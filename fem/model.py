"""The finite-element model as plain data: nodes, beams, point masses, springs, rigid bodies,
supports.

A :class:`Model` is a builder: ``add_*`` calls append, each accepting many items at once.
Elements refer to nodes by *node id* (the user's numbering, e.g. NASTRAN GRID ids), so
elements may be added before their nodes; ids are resolved to indices, and checked, when the
model is assembled (:func:`Model.index_of`). Global DOF ``6 * i + k`` is component ``k``
(ux, uy, uz, rx, ry, rz) of the node at index ``i`` (the order nodes were added). The parts
it holds are the records of :mod:`trussid.fem.parts`.

Everything is SI: m, kg, s, N, Pa.
"""

from __future__ import annotations

import copy
import dataclasses
from typing import Literal

import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.materials import Material
from trussid.fem.parts import (DOF_NAMES, Beams, GeneralElements, LinearConstraint, PointMasses, RigidBody,
                               Springs, parse_dofs)
from trussid.fem.properties import MaterialArrays, SectionArrays
from trussid.fem.sections import Section

# The parts are re-exported: code and users import them from here (fem.model).
__all__ = ["DOF_NAMES", "parse_dofs", "Beams", "PointMasses", "Springs", "RigidBody",
           "LinearConstraint", "GeneralElements", "Model"]


def _ids(values, what: str) -> np.ndarray:
    """Integer ids from ``values``; a non-whole or non-finite number is a ModelError naming
    it (``np.asarray(.., dtype=int64)`` would store node 4.5 as 4 without a word)."""
    a = np.asarray(values)
    if a.dtype.kind in "iu":
        return a.astype(np.int64)
    if a.dtype.kind == "b" or a.dtype.kind not in "f":
        try:
            a = a.astype(float)
        except (TypeError, ValueError):
            raise ModelError(f"{what} must be whole numbers, got {values!r}") from None
    bad = ~np.isfinite(a) | (a != np.round(a))
    if bad.any():
        raise ModelError(f"{what} must be whole numbers, got {a[bad].ravel()[0].item()!r}")
    return a.astype(np.int64)


def _inertia_tensors(inertia, n: int, nodes) -> np.ndarray:
    """(n, 3, 3) inertia tensors from the forms :meth:`Model.add_point_masses` takes,
    checked symmetric and positive semi-definite (a negative moment is no body's)."""
    if inertia is None:
        return np.zeros((n, 3, 3))
    a = np.asarray(inertia, dtype=float)
    if a.shape == (3,) or a.shape == (n, 3) and a.shape != (3, 3):
        a = np.einsum("...i,ij->...ij", a, np.eye(3))
    if a.shape not in ((3, 3), (n, 3, 3)):
        raise ModelError(f"add_point_masses: inertia must be 3 principal moments, a (3, 3) "
                         f"tensor or one per mass, got shape {a.shape}")
    a = np.broadcast_to(a, (n, 3, 3)).copy()
    scale = np.maximum(np.abs(a).max(axis=(1, 2)), 1e-300)
    for k in range(n):
        t = a[k]
        if not np.all(np.isfinite(t)):
            raise ModelError(f"point mass at node {nodes[k]}: inertia is not finite")
        if np.abs(t - t.T).max() > 1e-12 * scale[k]:
            raise ModelError(f"point mass at node {nodes[k]}: inertia tensor is not symmetric")
        low = np.linalg.eigvalsh(t).min()
        if low < -1e-12 * scale[k]:
            raise ModelError(f"point mass at node {nodes[k]}: inertia tensor has a negative "
                             f"principal moment ({low:.3g} kg m^2)")
    return a


class Model:
    """A 3-D frame model under construction.

    Parameters
    ----------
    beam_theory : {"euler-bernoulli", "timoshenko"}
        Timoshenko adds shear deformation (and rotary inertia) using the sections' shear
        areas.
    mass : {"consistent", "lumped"}
        Beam mass matrix formulation.
    name : str
        For reports.

    Examples
    --------
    A 1 m aluminium tube clamped at node 1 (12 DOFs, 6 of them supported):

    >>> from trussid.fem import ALUMINIUM, Model, Section
    >>> m = Model()
    >>> m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    >>> m.add_beams([1], [[1, 2]], Section.tube(0.00635, 0.001), ALUMINIUM, orient=[0, 0, 1])
    >>> m.fix(1)
    >>> m.n_nodes, m.n_dof
    (2, 12)
    """

    def __init__(self, beam_theory: Literal["euler-bernoulli", "timoshenko"] = "euler-bernoulli",
                 mass: Literal["consistent", "lumped"] = "consistent", name: str = "model"):
        if beam_theory not in ("euler-bernoulli", "timoshenko"):
            raise ModelError(f"beam_theory must be 'euler-bernoulli' or 'timoshenko', got {beam_theory!r}")
        if mass not in ("consistent", "lumped"):
            raise ModelError(f"mass must be 'consistent' or 'lumped', got {mass!r}")
        self.beam_theory = beam_theory
        self.mass_formulation = mass
        self.name = name
        self._node_ids: list[np.ndarray] = []
        self._xyz: list[np.ndarray] = []
        # index_of's sorted node ids, (number of add_nodes calls it was built from, order,
        # sorted ids): rebuilt when nodes were added since, not re-sorted on every call.
        self._node_index: tuple[int, np.ndarray, np.ndarray] | None = None
        self._beams: list[Beams] = []
        self._masses: list[PointMasses] = []
        self._springs: list[Springs] = []
        self.rigid_bodies: list[RigidBody] = []
        self._fixed: list[tuple[np.ndarray, np.ndarray]] = []
        self._omitted: list[tuple[np.ndarray, np.ndarray]] = []
        self._frames: list[tuple[np.ndarray, np.ndarray]] = []
        self.constraints: list[LinearConstraint] = []
        self.general: list[GeneralElements] = []
        self._scalar: list[np.ndarray] = []
        self._generalized: list[np.ndarray] = []

    # ------------------------------------------------------------------ nodes
    def add_nodes(self, ids, xyz) -> None:
        """Add nodes with integer ``ids`` (n,) at coordinates ``xyz`` (n, 3) [m]."""
        ids = np.atleast_1d(_ids(ids, "add_nodes: node ids"))
        xyz = np.atleast_2d(np.asarray(xyz, dtype=float))
        if xyz.shape != (len(ids), 3):
            raise ModelError(f"add_nodes: xyz must have shape ({len(ids)}, 3), got {xyz.shape}")
        bad = ~np.isfinite(xyz).all(axis=1)
        if bad.any():
            raise ModelError(f"node {ids[bad][0]}: coordinates are not finite")
        self._node_ids.append(ids)
        self._xyz.append(xyz)

    def add_node(self, id: int, xyz) -> None:
        """Add one node."""
        self.add_nodes([id], [xyz])

    def add_scalar_points(self, ids) -> None:
        """Add scalar points (NASTRAN SPOINT): points with one DOF and no position.

        A scalar point is a node whose only DOF is component 0 (``ux``); the other five are
        held (they are no support: :attr:`has_supports` does not count them). Scalar
        elements, general elements and constraints join it; it has no geometry, so the
        free-body test (:mod:`trussid.fem.free_bodies`) accepts any motion of it.
        """
        ids = np.atleast_1d(_ids(ids, "add_scalar_points: ids"))
        self.add_nodes(ids, np.zeros((len(ids), 3)))
        self._scalar.append(ids)

    def scalar_mask(self) -> np.ndarray:
        """(n_nodes,) bool: scalar points, in node index order."""
        mask = np.zeros(self.n_nodes, bool)
        if self._scalar:
            mask[np.atleast_1d(self.index_of(np.concatenate(self._scalar), what="a scalar point"))] = True
        return mask

    def add_generalized_coordinates(self, ids) -> None:
        """Make scalar points ``ids`` the generalized coordinates of component modes
        (NASTRAN QSET on SPOINTs).

        With omitted DOFs (:meth:`omit`), the static (Guyan) condensation becomes a
        Craig-Bampton reduction: the omitted DOFs follow the retained ones statically plus
        the lowest ``len(ids)`` modes of the omitted DOFs with the retained ones held, whose
        amplitudes are these points' DOFs (:func:`trussid.fem.reduction.craig_bampton`).
        Points beyond the number of such modes are left out, as NASTRAN's AUTOSPC does.
        """
        ids = np.atleast_1d(_ids(ids, "add_generalized_coordinates: ids"))
        self._generalized.append(ids)

    def generalized_mask(self) -> np.ndarray:
        """(n_nodes,) bool: scalar points holding component-mode amplitudes."""
        mask = np.zeros(self.n_nodes, bool)
        if self._generalized:
            ids = np.concatenate(self._generalized)
            idx = np.atleast_1d(self.index_of(ids, what="a generalized coordinate"))
            if not self.scalar_mask()[idx].all():
                bad = ids[~self.scalar_mask()[idx]][0]
                raise ModelError(f"generalized coordinate {bad}: not a scalar point")
            mask[idx] = True
        return mask

    def set_node_frames(self, ids, frames) -> None:
        """Give nodes a displacement frame (NASTRAN's GRID CD).

        The six DOFs of such a node are its translations and rotations along the frame's
        axes; supports (:meth:`fix`), rigid-body and linear-constraint components and
        :meth:`omit` refer to them. Element matrices stay in global axes; the assembled
        ``System.T`` maps the reduced DOFs to global displacements.

        Parameters
        ----------
        ids : (n,) int
            Node ids.
        frames : (3, 3) or (n, 3, 3) float
            Rows are the frame's axes in global coordinates (orthonormal).
        """
        ids = np.atleast_1d(np.asarray(ids, dtype=np.int64))
        fr = np.broadcast_to(np.asarray(frames, float), (len(ids), 3, 3)).copy()
        err = np.abs(fr @ fr.transpose(0, 2, 1) - np.eye(3)).max(axis=(1, 2)) if len(ids) else np.zeros(0)
        if (err > 1e-9).any():
            raise ModelError(f"node {ids[err > 1e-9][0]}: displacement frame axes are not orthonormal")
        self._frames.append((ids, fr))

    def node_frames(self) -> np.ndarray | None:
        """(n_nodes, 3, 3) displacement frames in node index order, or None if all global."""
        if not self._frames:
            return None
        out = np.broadcast_to(np.eye(3), (self.n_nodes, 3, 3)).copy()
        for ids, fr in self._frames:
            out[np.atleast_1d(self.index_of(ids, what="a displacement frame"))] = fr
        return out

    @property
    def node_ids(self) -> np.ndarray:
        """Node ids in index order, (n,)."""
        return np.concatenate(self._node_ids) if self._node_ids else np.zeros(0, np.int64)

    @property
    def xyz(self) -> np.ndarray:
        """Node coordinates in index order, (n, 3) [m]."""
        return np.concatenate(self._xyz) if self._xyz else np.zeros((0, 3))

    @property
    def n_nodes(self) -> int:
        return sum(len(a) for a in self._node_ids)

    @property
    def n_dof(self) -> int:
        """Number of DOFs before supports and rigid links are applied."""
        return 6 * self.n_nodes

    def _sorted_node_ids(self) -> tuple[np.ndarray, np.ndarray]:
        """(order, sorted ids) of the node ids, cached until the next :meth:`add_nodes`."""
        if self._node_index is None or self._node_index[0] != len(self._node_ids):
            node_ids = self.node_ids
            order = np.argsort(node_ids, kind="stable")
            sorted_ids = node_ids[order]
            dup = sorted_ids[1:][sorted_ids[1:] == sorted_ids[:-1]]
            if dup.size:
                raise ModelError(f"node {dup[0]} is defined more than once")
            self._node_index = (len(self._node_ids), order, sorted_ids)
        return self._node_index[1], self._node_index[2]

    def index_of(self, ids, what: str = "element") -> np.ndarray:
        """Node indices for node ``ids`` (any shape); unknown ids raise naming ``what``.

        ``what`` may be a callable ``what(position) -> str`` describing the referrer of the
        flat position that failed (e.g. ``"beam 12"``).
        """
        order, sorted_ids = self._sorted_node_ids()
        ids = np.asarray(ids, dtype=np.int64)
        pos = np.searchsorted(sorted_ids, ids.ravel())
        pos_c = np.minimum(pos, max(len(sorted_ids) - 1, 0))
        ok = (pos < len(sorted_ids)) & (sorted_ids[pos_c] == ids.ravel()) if len(sorted_ids) else np.zeros(ids.size, bool)
        if not ok.all():
            first = int(np.flatnonzero(~ok)[0])
            who = what(first) if callable(what) else what
            raise ModelError(f"undefined node {ids.ravel()[first]} (referenced by {who})")
        return order[pos_c].reshape(ids.shape)

    # ------------------------------------------------------------------ elements
    def add_beams(self, ids, nodes, section: Section | SectionArrays, material: Material | MaterialArrays,
                  orient, nsm=0.0, rod: bool = False, label: str | None = None) -> None:
        """Add frame elements sharing one section and material.

        Parameters
        ----------
        ids : (n,) int
            Element ids.
        nodes : (n, 2) int
            Node ids of the two ends.
        section : Section or SectionArrays
            Cross-section, or per-element section arrays (a mapping with the keys A, Iy, Iz,
            J and optionally Asy, Asz is read as :meth:`SectionArrays.of` reads it).
        material : Material or MaterialArrays
            Material, or per-element material arrays (or a mapping with the keys E, G, rho).
        orient : (3,) or (n, 3) float
            Orientation vector(s), global axes.
        nsm : float or (n,) float
            Non-structural mass per length [kg/m].
        rod : bool
            Axial and torsion only.
        label : str, optional
            Property label for messages (defaults to the section's name).
        """
        ids = np.atleast_1d(_ids(ids, "add_beams: element ids"))
        n = len(ids)
        nodes = _ids(nodes, "add_beams: nodes")
        if nodes.size != 2 * n:
            raise ModelError(f"add_beams: nodes must be {n} pairs of node ids (shape ({n}, 2)), "
                             f"got shape {nodes.shape}")
        nodes = nodes.reshape(n, 2)
        orient = np.asarray(orient, dtype=float)
        if orient.shape not in ((3,), (n, 3)):
            raise ModelError(f"add_beams: orient must be a 3-vector or ({n}, 3), got shape "
                             f"{orient.shape}")
        orient = np.broadcast_to(orient, (n, 3)).copy()
        name = label if label is not None else getattr(section, "name", "section")
        sec = SectionArrays.of(section, name).per_element(n)
        mat = MaterialArrays.of(material, name).per_element(n)
        try:
            nsm = np.broadcast_to(np.asarray(nsm, dtype=float), (n,)).copy()
        except (TypeError, ValueError):
            raise ModelError(f"add_beams ({name}): nsm must be one number or {n} (one per element), "
                             f"got {nsm!r}") from None
        self._beams.append(Beams(ids=ids, nodes=nodes, orient=orient, A=sec.A, Iy=sec.Iy, Iz=sec.Iz, J=sec.J,
                                 Asy=sec.Asy, Asz=sec.Asz, E=mat.E, G=mat.G, rho=mat.rho, nsm=nsm,
                                 rod=np.full(n, bool(rod)), labels=np.full(n, name, dtype=object)))

    @property
    def beams(self) -> Beams:
        """All beams as one :class:`Beams` of arrays."""
        keys = Beams.__dataclass_fields__.keys()
        if not self._beams:
            shapes = {"nodes": (0, 2), "orient": (0, 3)}
            return Beams(**{k: np.zeros(shapes.get(k, (0,)),
                                         dtype=np.int64 if k in ("ids", "nodes") else bool if k == "rod"
                                         else object if k == "labels" else float) for k in keys})
        return Beams(**{k: np.concatenate([getattr(c, k) for c in self._beams]) for k in keys})

    def with_beam_sections(self, A, Iy, Iz, J) -> "Model":
        """A copy of the model whose beams have the section properties ``A`` [m^2], ``Iy``,
        ``Iz``, ``J`` [m^4] (arrays over the beams in :attr:`beams` order); everything else
        is the same. For design sweeps that move sections without rebuilding a model.

        Raises
        ------
        ModelError
            If an array is not one finite value per beam.
        """
        b = self.beams
        n = len(b.ids)
        new = {k: np.asarray(v, dtype=float) for k, v in (("A", A), ("Iy", Iy), ("Iz", Iz), ("J", J))}
        for k, v in new.items():
            if v.shape != (n,) or not np.isfinite(v).all():
                raise ModelError(f"with_beam_sections: {k} must be {n} finite values (one per beam), "
                                 f"got shape {v.shape}")
        out = copy.copy(self)
        for key, value in vars(self).items():  # the copy's own lists: adding to one leaves the other
            if isinstance(value, list):
                setattr(out, key, list(value))
        out._beams = [dataclasses.replace(b, **new)]
        return out

    def add_point_masses(self, nodes, mass, inertia=None, offset=None) -> None:
        """Add point masses at node ids ``nodes``.

        Parameters
        ----------
        nodes : (n,) int
        mass : float or (n,) float
            [kg], >= 0.
        inertia : (3,), (n, 3), (3, 3) or (n, 3, 3) float, optional
            About each mass's centre of gravity, global axes [kg m^2]; default zero. Three
            numbers are the principal moments about the global axes (a diagonal tensor).
            Each tensor must be symmetric and positive semi-definite.
        offset : (3,) or (n, 3) float, optional
            Centre of gravity relative to the node [m]; default zero.
        """
        nodes = np.atleast_1d(_ids(nodes, "add_point_masses: nodes"))
        n = len(nodes)
        inertia = _inertia_tensors(inertia, n, nodes)
        try:
            chunk = PointMasses(
                nodes=nodes,
                mass=np.broadcast_to(np.asarray(mass, dtype=float), (n,)).copy(),
                inertia=inertia,
                offset=np.broadcast_to(np.zeros(3) if offset is None else np.asarray(offset, float), (n, 3)).copy(),
            )
        except ValueError as exc:
            raise ModelError(f"add_point_masses: mass must be one number or {n}, and offset a "
                             f"3-vector or ({n}, 3) ({exc})") from None
        bad = (chunk.mass < 0) | ~np.isfinite(chunk.mass)
        if bad.any():
            raise ModelError(f"point mass at node {nodes[bad][0]}: mass must be >= 0, got {float(chunk.mass[bad][0])!r}")
        self._masses.append(chunk)

    @property
    def point_masses(self) -> PointMasses:
        if not self._masses:
            return PointMasses(np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 3, 3)), np.zeros((0, 3)))
        return PointMasses(**{k: np.concatenate([getattr(c, k) for c in self._masses]) for k in PointMasses.__dataclass_fields__})

    def add_springs(self, ids, nodes, k, frame=None) -> None:
        """Add 6-DOF springs.

        Parameters
        ----------
        ids : (n,) int
        nodes : (n, 2) int or (n,) int
            Node id pairs; a 1-D array (or ``-1`` in the second column) grounds the spring.
        k : (6,) or (n, 6) float
            Stiffnesses [N/m, N m/rad], >= 0.
        frame : (3, 3) or (n, 3, 3) float, optional
            Rows are the spring axes in global coordinates; default global axes.
        """
        ids = np.atleast_1d(_ids(ids, "add_springs: spring ids"))
        n = len(ids)
        nodes = _ids(nodes, "add_springs: nodes")
        if nodes.ndim == 1:
            nodes = np.column_stack([nodes, np.full(n, -1)])
        nodes = nodes.reshape(n, 2)
        kk = np.broadcast_to(np.asarray(k, dtype=float), (n, 6)).copy()
        bad = ~(np.isfinite(kk) & (kk >= 0)).all(axis=1)
        if bad.any():
            raise ModelError(f"spring {ids[bad][0]}: stiffness must be finite and >= 0, got {kk[bad][0].tolist()}")
        fr = np.broadcast_to(np.eye(3) if frame is None else np.asarray(frame, float), (n, 3, 3)).copy()
        err = np.abs(fr @ fr.transpose(0, 2, 1) - np.eye(3)).max(axis=(1, 2))
        if (err > 1e-9).any():
            raise ModelError(f"spring {ids[err > 1e-9][0]}: frame axes are not orthonormal")
        self._springs.append(Springs(ids=ids, nodes=nodes, k=kk, frame=fr))

    @property
    def springs(self) -> Springs:
        if not self._springs:
            return Springs(np.zeros(0, np.int64), np.zeros((0, 2), np.int64), np.zeros((0, 6)), np.zeros((0, 3, 3)))
        return Springs(**{k: np.concatenate([getattr(c, k) for c in self._springs]) for k in Springs.__dataclass_fields__})

    def add_rigid_body(self, id: int, master: int, slaves, dofs: str = "123456", mass: float = 0.0,
                       cg=None, inertia=None, label: str = "") -> None:
        """Add a rigid body: ``slaves`` (node ids) follow ``master`` in components ``dofs``.

        ``mass`` [kg] with centre of gravity ``cg`` (global, m; default the master node) and
        ``inertia`` about the cg (3, 3) [kg m^2] is attached to the master.
        """
        if not (np.isfinite(mass) and mass >= 0):
            raise ModelError(f"rigid body {id}: mass must be >= 0, got {mass!r}")
        inertia = np.zeros((3, 3)) if inertia is None else np.asarray(inertia, dtype=float)
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T, rtol=0, atol=1e-12 * max(1.0, abs(inertia).max())):
            raise ModelError(f"rigid body {id}: inertia must be a symmetric 3x3 tensor")
        self.rigid_bodies.append(RigidBody(
            id=int(id), master=int(master), slaves=np.atleast_1d(np.asarray(slaves, dtype=np.int64)),
            dofs=parse_dofs(dofs), mass=float(mass),
            cg=None if cg is None else np.asarray(cg, dtype=float), inertia=inertia, label=label or f"rigid body {id}",
        ))

    def add_constraint(self, id: int, dependent, independent, C, label: str = "") -> None:
        """Add linear constraints ``u[dependent] = C @ u[independent]``.

        Parameters
        ----------
        id : int
        dependent, independent : ((m,) int, (m,) int) and ((p,) int, (p,) int)
            Node ids and 0-based components (0..5) of the dependent and independent DOFs, in
            the nodes' displacement frames.
        C : (m, p) float
        label : str
        """
        dn, dc = (np.atleast_1d(np.asarray(a, dtype=np.int64)) for a in dependent)
        inn, ic = (np.atleast_1d(np.asarray(a, dtype=np.int64)) for a in independent)
        C = np.asarray(C, float).reshape(len(dn), len(inn))
        name = label or f"constraint {id}"
        if len(dc) != len(dn) or len(ic) != len(inn):
            raise ModelError(f"{name}: nodes and components differ in length")
        if ((dc < 0) | (dc > 5)).any() or ((ic < 0) | (ic > 5)).any():
            raise ModelError(f"{name}: components must be 0..5")
        if not np.isfinite(C).all():
            raise ModelError(f"{name}: coefficients are not finite")
        self.constraints.append(LinearConstraint(int(id), dn, dc, inn, ic, C, name))

    def add_matrices(self, ids, nodes, K=None, M=None, label: str = "") -> None:
        """Add elements given by their matrices in global axes (GENEL/DMIG-like).

        Parameters
        ----------
        ids : (n,) int
        nodes : (n, k) int
            Node ids joined by each element.
        K, M : (n, 6k, 6k) float, optional
            Symmetric stiffness and mass [SI per DOF pair]; default zero.
        label : str
        """
        ids = np.atleast_1d(np.asarray(ids, dtype=np.int64))
        nodes = np.asarray(nodes, dtype=np.int64).reshape(len(ids), -1)
        size = 6 * nodes.shape[1]
        mats = []
        for name, A in (("K", K), ("M", M)):
            A = np.zeros((len(ids), size, size)) if A is None else np.asarray(A, float).reshape(len(ids), size, size)
            bad = ~np.isfinite(A).all(axis=(1, 2)) | (np.abs(A - A.transpose(0, 2, 1)).max(axis=(1, 2), initial=0.0)
                                                     > 1e-9 * np.abs(A).max(axis=(1, 2), initial=0.0))
            if bad.any():
                raise ModelError(f"{label or 'element'} {ids[bad][0]}: {name} must be finite and symmetric")
            mats.append(A)
        self.general.append(GeneralElements(ids, nodes, mats[0], mats[1], label))

    # ------------------------------------------------------------------ supports
    def omit(self, nodes, dofs: str = "123456") -> None:
        """Condense components ``dofs`` of node ids ``nodes`` statically (Guyan, NASTRAN OMIT).

        See :func:`trussid.fem.reduction.guyan`: exact for DOFs without mass, an
        approximation otherwise.
        """
        nodes = np.atleast_1d(np.asarray(nodes, dtype=np.int64))
        self._omitted.append((nodes, parse_dofs(dofs)))

    def omitted_mask(self) -> np.ndarray:
        """(n_nodes, 6) bool: DOFs to condense (:meth:`omit`), in node index order."""
        mask = np.zeros((self.n_nodes, 6), dtype=bool)
        for nodes, comps in self._omitted:
            idx = self.index_of(nodes, what="an omitted DOF")
            mask[np.ix_(np.atleast_1d(idx), comps.nonzero()[0])] = True
        return mask

    def fix(self, nodes, dofs: str = "123456") -> None:
        """Support (eliminate) components ``dofs`` at node ids ``nodes`` (in their frames)."""
        nodes = np.atleast_1d(np.asarray(nodes, dtype=np.int64))
        self._fixed.append((nodes, parse_dofs(dofs)))

    def fixed_mask(self) -> np.ndarray:
        """(n_nodes, 6) bool: supported DOFs, in node index order (and the five components
        a scalar point does not have)."""
        mask = np.zeros((self.n_nodes, 6), dtype=bool)
        mask[self.scalar_mask(), 1:] = True
        for nodes, comps in self._fixed:
            idx = self.index_of(nodes, what="a support")
            mask[np.ix_(np.atleast_1d(idx), comps.nonzero()[0])] = True
        return mask

    @property
    def has_supports(self) -> bool:
        return bool(self._fixed)

    def __repr__(self) -> str:
        return (f"Model({self.name!r}: {self.n_nodes} nodes, {len(self.beams)} beams, "
                f"{len(self.point_masses)} point masses, {len(self.springs)} springs, "
                f"{len(self.rigid_bodies)} rigid bodies, {self.beam_theory}, {self.mass_formulation} mass)")
