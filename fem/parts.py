"""The parts of a finite-element model as plain arrays: the records :class:`trussid.fem.Model`
holds and hands to the assembly (beams, point masses, springs, rigid bodies, linear
constraints, element matrices), and the DOF naming they share.

Global DOF ``6 * i + k`` is component ``k`` (:data:`DOF_NAMES`: ux, uy, uz, rx, ry, rz) of
the node at index ``i``. Everything is SI: m, kg, s, N, Pa.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable

import numpy as np

from trussid.fem.errors import ModelError

__all__ = ["DOF_NAMES", "parse_dofs", "Beams", "PointMasses", "Springs", "RigidBody",
           "LinearConstraint", "GeneralElements"]

DOF_NAMES = ("ux", "uy", "uz", "rx", "ry", "rz")


def parse_dofs(dofs: str | Iterable[int]) -> np.ndarray:
    """DOF components as a boolean mask of length 6.

    ``dofs`` is a NASTRAN-style digit string (``"123"`` = translations, ``"123456"`` = all)
    or an iterable of 0-based component indices.

    Examples
    --------
    >>> from trussid.fem import parse_dofs
    >>> parse_dofs("123")                         # NASTRAN digits: the translations
    array([ True,  True,  True, False, False, False])
    >>> parse_dofs([3, 4, 5])                     # 0-based components: the rotations
    array([False, False, False,  True,  True,  True])
    """
    mask = np.zeros(6, dtype=bool)
    if isinstance(dofs, str):
        for ch in dofs.strip():
            if ch not in "123456":
                raise ModelError(f"DOF string {dofs!r}: component {ch!r} is not one of 1-6")
            mask[int(ch) - 1] = True
    else:
        for k in dofs:
            if not 0 <= int(k) < 6:
                raise ModelError(f"DOF component {k!r} is not in 0..5")
            mask[int(k)] = True
    return mask


@dataclass
class Beams:
    """All 2-node frame elements, as arrays of length ``n``.

    Attributes
    ----------
    ids : (n,) int
        Element ids.
    nodes : (n, 2) int
        Node ids of ends A and B.
    orient : (n, 3) float
        Orientation vector in global axes: together with the axis it fixes the local x-y
        plane (NASTRAN's v vector). Must not be parallel to the element.
    A, Iy, Iz, J, Asy, Asz : (n,) float
        Section properties (see :class:`trussid.fem.sections.Section`) [m^2, m^4].
    E, G, rho : (n,) float
        Material [Pa, Pa, kg/m^3].
    nsm : (n,) float
        Non-structural mass per length [kg/m].
    rod : (n,) bool
        Axial and torsion only (CROD/CONROD): no bending stiffness, translational mass.
    labels : (n,) object
        Property label for messages and reports (e.g. ``"strut 3"``, ``"PBAR 12"``).
    """

    ids: np.ndarray
    nodes: np.ndarray
    orient: np.ndarray
    A: np.ndarray
    Iy: np.ndarray
    Iz: np.ndarray
    J: np.ndarray
    Asy: np.ndarray
    Asz: np.ndarray
    E: np.ndarray
    G: np.ndarray
    rho: np.ndarray
    nsm: np.ndarray
    rod: np.ndarray
    labels: np.ndarray

    def __len__(self) -> int:
        return len(self.ids)


@dataclass
class PointMasses:
    """Concentrated masses (CONM2-like), arrays of length ``n``.

    Attributes
    ----------
    nodes : (n,) int
        Node ids.
    mass : (n,) float
        Mass [kg].
    inertia : (n, 3, 3) float
        Inertia tensor about the mass's own centre of gravity, global axes [kg m^2].
    offset : (n, 3) float
        Centre of gravity relative to the node, global axes [m].
    """

    nodes: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    offset: np.ndarray

    def __len__(self) -> int:
        return len(self.nodes)


@dataclass
class Springs:
    """Uncoupled 6-DOF springs (CELAS/CBUSH-like), arrays of length ``n``.

    A spring joins node A to node B, or node A to ground when B is ``-1``. Its stiffness is
    diagonal in the frame whose rows are ``frame[i]`` (global axes by default).

    Attributes
    ----------
    ids : (n,) int
    nodes : (n, 2) int
        Node ids; ``-1`` in column 1 for grounded springs.
    k : (n, 6) float
        Stiffness per component [N/m for translations, N m/rad for rotations], >= 0.
    frame : (n, 3, 3) float
        Rows are the spring's axes in global coordinates (orthonormal).
    """

    ids: np.ndarray
    nodes: np.ndarray
    k: np.ndarray
    frame: np.ndarray

    def __len__(self) -> int:
        return len(self.ids)


@dataclass
class RigidBody:
    """A rigid body (RBE2-like) with optional mass.

    The dependent components ``dofs`` of every slave node follow the master node rigidly.
    The body's mass is attached at the master (its centre of gravity need not be there).
    Applied by DOF transformation, not penalty.

    Attributes
    ----------
    id : int
    master : int
        Master node id.
    slaves : (k,) int
        Slave node ids.
    dofs : (6,) bool
        Slave components that follow the master (all six for a fully rigid body).
    mass : float
        Mass [kg] (0 for a massless link).
    cg : (3,) float
        Centre of gravity, global coordinates [m] (ignored when mass is 0).
    inertia : (3, 3) float
        Inertia tensor about the centre of gravity, global axes [kg m^2].
    label : str
    """

    id: int
    master: int
    slaves: np.ndarray
    dofs: np.ndarray
    mass: float = 0.0
    cg: np.ndarray = field(default_factory=lambda: np.zeros(3))
    inertia: np.ndarray = field(default_factory=lambda: np.zeros((3, 3)))
    label: str = ""


@dataclass
class LinearConstraint:
    """Dependent DOFs as linear combinations of independent ones (MPC, RBAR, RBE3...).

    ``u[dependent] = C @ u[independent]``, every component in its node's displacement frame
    (:meth:`Model.set_node_frames`; global axes by default). Applied by DOF transformation
    together with the rigid bodies: a dependent DOF must not be supported or dependent in
    another constraint; independent DOFs may be dependent elsewhere (chains are composed).

    Attributes
    ----------
    id : int
    dep_nodes, dep_comps : (m,) int
        Node ids and 0-based components (0..5 = ux..rz) of the dependent DOFs.
    ind_nodes, ind_comps : (p,) int
        Node ids and components of the independent DOFs.
    C : (m, p) float
        Coefficients [m/m, m/rad, rad/m as the components dictate].
    label : str
        For messages (e.g. ``"RBE3 7"``).
    """

    id: int
    dep_nodes: np.ndarray
    dep_comps: np.ndarray
    ind_nodes: np.ndarray
    ind_comps: np.ndarray
    C: np.ndarray
    label: str = ""


@dataclass
class GeneralElements:
    """Element matrices given directly (NASTRAN GENEL/DMIG-like), one stack per call.

    Attributes
    ----------
    ids : (n,) int
    nodes : (n, k) int
        Node ids joined by each element.
    K, M : (n, 6k, 6k) float
        Stiffness and mass in global axes, DOF order ``ux..rz`` of each node in turn.
    label : str
    """

    ids: np.ndarray
    nodes: np.ndarray
    K: np.ndarray
    M: np.ndarray
    label: str = ""

    def __len__(self) -> int:
        return len(self.ids)
