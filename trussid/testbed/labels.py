"""Mode labels from where the kinetic and strain energy of each mode sits.

:func:`element_energies` splits ``phi^T M phi`` and ``phi^T K phi`` of every mode over the
model's parts (each beam, point mass, rigid-body mass, spring), for any :class:`trussid.fem.Model`.
:func:`label_testbed_modes` groups them into the testbed's components (``strut 0`` ..
``strut 5`` with their flexure springs, ``UDF`` with its accelerometers, ``base``,
``bungees``) and names each mode.

Rules (in this order; fractions are of the mode's total kinetic or strain energy)
-------------------------------------------------------------------------------------
1. ``"suspension"``: the bungees hold at least :data:`DOMINANT` of the strain energy (or
   the mode has zero frequency: rigid-body motion of a free model).
2. Otherwise the component with the largest *kinetic* energy fraction dominates if that
   fraction is at least :data:`DOMINANT` (one half: "more than everything else together");
   else the label is ``"mixed (A 0.42, B 0.31)"``, the top two kinetic fractions.
   Exception: the ``UDF`` and ``base`` rigid bodies *together* holding at least
   :data:`DOMINANT` give ``"UDF rigid-body"`` (rule 3).
3. ``"UDF rigid-body"``: the rigid bodies carry the kinetic energy while the struts act
   as springs. With a suspended base the plate (three times the UDF's mass) recoils
   against the UDF in these modes and may hold most of their kinetic energy; they are
   still the six modes of the UDF on its struts (with a clamped base the same six modes
   remain, with the plate still), so both bodies count together.
4. ``strut k`` dominant: that strut's strain energy is split, per element in local axes,
   into axial, torsion, and bending with deflection along local ``y`` or ``z`` (the
   Euler-Bernoulli element has no coupling between these). The largest part names the
   mode: ``"strut k axial"``, ``"strut k torsion"``, or ``"strut k bending n (plane y)"``
   where the plane is the *direction of the deflection* in the strut's frame
   (:mod:`trussid.geometry.layout`: ``y`` horizontal, normal to the bipod plane; ``z`` in it).
   The order ``n`` is one more than the number of sign changes, along the strut, of the
   deflection relative to the chord through the strut's end points (rigid motion of the
   ends removed), counting only nodes whose deflection exceeds :data:`NODE_THRESHOLD` of
   the largest: first bending has no interior zero, second one, third two. This is local
   to the mode (it does not need the strut's other modes to be in the computed set) and
   ignores the near-zero values around a node of the shape. A strut's ``y`` and ``z``
   bending modes of one order are close in frequency and may combine into an oblique
   plane; the label then names the larger part (both may carry the same plane).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trussid.fem.assembly import beam_matrices, mass_blocks, spring_matrices
from trussid.fem.elements import frame_matrices, local_axes
from trussid.testbed.model import N_STRUTS

#: A component dominates a mode when it holds at least this fraction of the energy.
DOMINANT = 0.5
#: Nodes whose deflection is below this fraction of the strut's largest are skipped when
#: counting sign changes.
NODE_THRESHOLD = 0.1

_AXIAL = np.array([0, 6])
_TORSION = np.array([3, 9])
_DEFL_Y = np.array([1, 5, 7, 11])  # v, rz: deflection along local y
_DEFL_Z = np.array([2, 4, 8, 10])  # w, ry: deflection along local z


@dataclass
class Energies:
    """Per-part energies of a set of modes (``phi^T X phi`` contributions, not halved).

    Attributes
    ----------
    beam_kinetic, beam_strain : (n_beams, n_modes) float
    beam_strain_parts : (n_beams, 4, n_modes) float
        Beam strain energy split into axial, torsion, deflection along local y, along local z.
    mass_kinetic : (n_point_masses, n_modes) float
    body_kinetic : (n_bodies_with_mass, n_modes) float
        In the order of ``body_ids``.
    body_ids : list of int
    spring_strain : (n_springs, n_modes) float
    """

    beam_kinetic: np.ndarray
    beam_strain: np.ndarray
    beam_strain_parts: np.ndarray
    mass_kinetic: np.ndarray
    body_kinetic: np.ndarray
    body_ids: list
    spring_strain: np.ndarray


def _quad(blocks: np.ndarray, dofs: np.ndarray, shapes_full: np.ndarray) -> np.ndarray:
    """``u_e^T B_e u_e`` per element and mode: (n_elem, n_modes)."""
    if len(blocks) == 0:
        return np.zeros((0, shapes_full.shape[1]))
    u = shapes_full[dofs]  # (n, d, k)
    return np.einsum("nik,nij,njk->nk", u, blocks, u)


def element_energies(model, shapes_full: np.ndarray) -> Energies:
    """Kinetic (``phi^T M_e phi``) and strain (``phi^T K_e phi``) energy of every part.

    Parameters
    ----------
    model : fem.Model
    shapes_full : (6 n_nodes, n_modes) float
        Mode shapes on all DOFs (``Modes.shapes_full``).

    Returns
    -------
    Energies
    """
    X = np.asarray(shapes_full, float)
    K, M, dofs = beam_matrices(model)
    b = model.beams
    beam_kin, beam_str = _quad(M, dofs, X), _quad(K, dofs, X)
    parts = np.zeros((len(b), 4, X.shape[1]))
    if len(b):
        idx = model.index_of(b.nodes)
        xyz = model.xyz
        L, R = local_axes(xyz[idx[:, 0]], xyz[idx[:, 1]], b.orient, b.ids)
        Kl, _ = frame_matrices(L, b.A, b.Iy, b.Iz, b.J, b.E, b.G, b.rho, nsm=b.nsm, Asy=b.Asy, Asz=b.Asz,
                               rod=b.rod, theory=model.beam_theory, mass=model.mass_formulation)
        u = X[dofs].reshape(len(b), 4, 3, -1)  # (n, 4 triads, 3, k) global
        ul = np.einsum("npi,naik->napk", R, u).reshape(len(b), 12, -1)
        for j, sel in enumerate((_AXIAL, _TORSION, _DEFL_Y, _DEFL_Z)):
            parts[:, j] = np.einsum("nik,nij,njk->nk", ul[:, sel], Kl[:, sel[:, None], sel[None, :]], ul[:, sel])
    mb, md = mass_blocks(model)
    pm = model.point_masses
    mass_kin = _quad(mb[0], md[0], X) if len(pm) else np.zeros((0, X.shape[1]))
    bodies = [rb for rb in model.rigid_bodies if rb.mass > 0 or np.any(rb.inertia)]
    body_kin = _quad(mb[-1], md[-1], X) if bodies else np.zeros((0, X.shape[1]))
    sk, sd = spring_matrices(model)
    s = model.springs
    spring_str = np.zeros((len(s), X.shape[1]))
    if len(s):
        grounded = s.nodes[:, 1] == -1
        pieces = []
        if (~grounded).any():
            pieces.append((np.flatnonzero(~grounded), _quad(sk[0], sd[0], X)))
        if grounded.any():
            pieces.append((np.flatnonzero(grounded), _quad(sk[-1], sd[-1], X)))
        for where, val in pieces:
            spring_str[where] = val
    return Energies(beam_kinetic=beam_kin, beam_strain=beam_str, beam_strain_parts=parts, mass_kinetic=mass_kin,
                    body_kinetic=body_kin, body_ids=[rb.id for rb in bodies], spring_strain=spring_str)


@dataclass
class ModeLabels:
    """Labels of a set of modes and the energy fractions they rest on.

    Attributes
    ----------
    labels : list of str
    components : list of str
        Names of the columns of ``kinetic`` and ``strain``.
    kinetic, strain : (n_modes, n_components) float
        Fractions of each mode's kinetic and strain energy in each component (rows sum to 1;
        strain is all zero for a zero-frequency mode).
    strut : (n_modes,) int
        Strut of a strut-dominated mode, else -1.
    order : (n_modes,) int
        Bending order of a strut bending mode, else 0.
    plane : list of str
        ``"y"`` or ``"z"`` for strut bending modes, else ``""``.
    kind : list of str
        ``"bending"``, ``"axial"``, ``"torsion"``, ``"udf"``, ``"base"``, ``"suspension"`` or
        ``"mixed"``.
    """

    labels: list
    components: list
    kinetic: np.ndarray
    strain: np.ndarray
    strut: np.ndarray
    order: np.ndarray
    plane: list
    kind: list


def _fractions(parts: np.ndarray) -> np.ndarray:
    tot = parts.sum(axis=0)
    return np.divide(parts, tot, out=np.zeros_like(parts), where=tot > 0).T


def bending_order(deflection: np.ndarray, s: np.ndarray, threshold: float = NODE_THRESHOLD) -> np.ndarray:
    """Bending order of deflections along a member: 1 + sign changes relative to the chord.

    Parameters
    ----------
    deflection : (n_nodes, n_modes) float
        Lateral deflection at the member's nodes, in order along it.
    s : (n_nodes,) float
        Node positions along the member [m].
    threshold : float
        Nodes below this fraction of the largest relative deflection are skipped.

    Returns
    -------
    (n_modes,) int
    """
    d = np.asarray(deflection, float)
    xi = (s - s[0]) / (s[-1] - s[0])
    rel = d - (d[:1] + (d[-1:] - d[:1]) * xi[:, None])
    big = np.abs(rel) >= threshold * np.abs(rel).max(axis=0, keepdims=True)
    out = np.zeros(d.shape[1], dtype=int)
    for k in range(d.shape[1]):  # a loop over modes (tens), not elements
        sig = np.sign(rel[big[:, k], k])
        out[k] = 1 + int(np.count_nonzero(sig[1:] != sig[:-1]))
    return out


def label_testbed_modes(tbm, modes) -> ModeLabels:
    """Name each mode of a testbed model by where its energy sits (module docstring).

    Parameters
    ----------
    tbm : trussid.testbed.TestbedModel
    modes : fem.modal.Modes
        Modes of ``tbm.model`` (``shapes_full`` and ``frequencies_hz`` are used).

    Returns
    -------
    ModeLabels
    """
    model, mp = tbm.model, tbm.map
    X = np.asarray(modes.shapes_full, float)
    freqs = np.asarray(modes.frequencies_hz, float)
    e = element_energies(model, X)
    b, s = model.beams, model.springs
    strut_of_beam = mp.strut_of_element(b.ids)
    components = [f"strut {k}" for k in range(N_STRUTS)] + ["UDF", "base", "bungees"]
    nm = X.shape[1]
    kin = np.zeros((len(components), nm))
    strain = np.zeros((len(components), nm))
    for k in range(N_STRUTS):
        kin[k] = e.beam_kinetic[strut_of_beam == k].sum(axis=0)
        strain[k] = e.beam_strain[strut_of_beam == k].sum(axis=0)
        flex = mp.flexure_springs[k][mp.flexure_springs[k] >= 0]
        if len(flex):
            strain[k] += e.spring_strain[np.isin(s.ids, flex)].sum(axis=0)
    pm = model.point_masses
    pm_strut = np.full(len(pm), -1)
    for k in range(N_STRUTS):
        pm_strut[np.isin(pm.nodes, mp.strut_nodes[k])] = k
    for k in range(N_STRUTS):
        kin[k] += e.mass_kinetic[pm_strut == k].sum(axis=0)
    kin[6] = e.mass_kinetic[pm_strut < 0].sum(axis=0)  # the accelerometers ride on the UDF
    for bid, val in zip(e.body_ids, e.body_kinetic):
        kin[6 if bid == mp.udf_body else 7] += val
    strain[8] = e.spring_strain[np.isin(s.ids, mp.bungee_springs)].sum(axis=0)
    K, S = _fractions(kin), _fractions(strain)

    idx = model.index_of(mp.strut_nodes)  # (6, n)
    labels, kinds, planes = [], [], []
    strut = np.full(nm, -1)
    order = np.zeros(nm, dtype=int)
    for j in range(nm):  # a loop over modes
        top = np.argsort(K[j])[::-1]
        c = int(top[0])
        rigid = K[j, 6] + K[j, 7]
        if S[j, 8] >= DOMINANT or freqs[j] == 0.0:
            labels.append("suspension"), kinds.append("suspension"), planes.append("")
        elif rigid >= DOMINANT:
            labels.append("UDF rigid-body"), kinds.append("udf"), planes.append("")
        elif K[j, c] < DOMINANT:
            a, b2 = int(top[0]), int(top[1])
            labels.append(f"mixed ({components[a]} {K[j, a]:.2f}, {components[b2]} {K[j, b2]:.2f})")
            kinds.append("mixed"), planes.append("")
        else:
            strut[j] = c
            part = e.beam_strain_parts[strut_of_beam == c, :, j].sum(axis=0)
            which = int(np.argmax(part))
            if which == 0:
                labels.append(f"strut {c} axial"), kinds.append("axial"), planes.append("")
            elif which == 1:
                labels.append(f"strut {c} torsion"), kinds.append("torsion"), planes.append("")
            else:
                plane = "y" if which == 2 else "z"
                axis = mp.strut_frames[c, 1 if plane == "y" else 2]
                u = X[(6 * idx[c])[:, None] + np.arange(3), j] @ axis
                order[j] = bending_order(u[:, None], mp.strut_s)[0]
                labels.append(f"strut {c} bending {order[j]} (plane {plane})")
                kinds.append("bending"), planes.append(plane)
    return ModeLabels(labels=labels, components=components, kinetic=K, strain=S, strut=strut, order=order,
                      plane=planes, kind=kinds)


__all__ = ["Energies", "ModeLabels", "element_energies", "bending_order", "label_testbed_modes",
           "DOMINANT", "NODE_THRESHOLD"]
