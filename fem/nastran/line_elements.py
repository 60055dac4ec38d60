"""Line elements of a deck: CBAR and CBEAM (pin flags, tapered beams, bars with A = 0 or
G = 0), CROD and CONROD, added to the model one property at a time.
"""

from __future__ import annotations

import dataclasses
import math
from collections import defaultdict

import numpy as np

from trussid.fem.elements import frame_matrices, local_axes, to_global
from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.nastran.grids import NodeTable
from trussid.fem.nastran.line_properties import LineProperty, material_of, rod_torsion
from trussid.fem.properties import MaterialArrays, SectionArrays
from trussid.fem.tapered import tapered_frame_matrices

__all__ = ["add_bars", "add_rods"]


def _group(items, key):
    groups = defaultdict(list)
    for item in items:
        groups[key(item)].append(item)
    return groups


def add_bars(bdf, model: Model, nodes: NodeTable, props: dict) -> None:
    """CBAR and CBEAM: one add_beams call per property."""
    elems = [e for e in bdf.elements.values() if e.type in ("CBAR", "CBEAM")]
    for e in elems:
        card = f"{e.type} {e.eid}"
        for flag in (e.pa, e.pb):
            if flag and any(ch not in "123456" for ch in str(flag)):
                raise ModelError(f"{card}: pin flags PA={e.pa or ''} PB={e.pb or ''} must be digits 1-6")
        if np.any(np.asarray(e.wa, float) != 0) or np.any(np.asarray(e.wb, float) != 0):
            raise ModelError(f"{card}: offsets WA={list(e.wa)} WB={list(e.wb)} are not supported "
                             f"(give the grids at the neutral axis)")
        if e.type == "CBEAM" and (getattr(e, "sa", 0) or getattr(e, "sb", 0)):
            raise ModelError(f"{card}: warping scalar points SA/SB are not supported")
        if getattr(e, "bit", None) is not None:
            raise ModelError(f"{card}: BIT (beam-in-time orientation) is not supported")
        if e.pid not in props:
            raise ModelError(f"{card}: property {e.pid} is not defined")
        if props[e.pid].kind != "bar":
            raise ModelError(f"{card}: property {e.pid} is a {props[e.pid].label.split()[0]}, "
                             f"not a bar/beam property")
    for (_card, pid), group in _group(elems, lambda e: (e.type, e.pid)).items():
        prop = props[pid]
        eids = np.array([e.eid for e in group], dtype=np.int64)
        ends = np.array([[e.ga, e.gb] if e.type == "CBAR" else e.nodes for e in group], dtype=np.int64)
        card = group[0].type
        xyz = nodes.coords(ends, card, eids)
        g0 = np.array([e.g0 if e.g0 not in (None, 0) else -1 for e in group], dtype=np.int64)
        orient = np.array([[np.nan] * 3 if e.x is None or e.x[0] is None else e.x for e in group],
                          dtype=float)
        use_g0 = g0 >= 0
        if use_g0.any():
            orient[use_g0] = nodes.coords(g0[use_g0], card, eids[use_g0]) - xyz[use_g0, 0]
        bad = ~np.isfinite(orient).all(axis=1)
        if bad.any():
            raise ModelError(f"{card} {eids[bad][0]}: no orientation (give X1-X3 or G0)")
        mat, nsm = prop.mat, prop.nsm
        if prop.taper is not None:
            _add_tapered(model, group, ends, xyz, orient, prop, eids)
            continue
        if prop.section.A == 0 or prop.mat.G == 0:
            _add_spring_bars(model, group, xyz, orient, prop, eids)
            continue
        if card == "CBAR" and model.mass_formulation == "consistent":
            # NASTRAN's coupled CBAR mass has no torsional (nor rotary) inertia: the structural
            # mass goes in as non-structural mass per length, which the element gives
            # translational inertia only (the same translational mass, exactly; MSC 2020 on
            # the pt145 deck: torsion modes 2.6e-4 high with it, 3e-7 without).
            mat, nsm = dataclasses.replace(prop.mat, rho=0.0), prop.nsm + prop.mat.rho * prop.section.A
        model.add_beams(eids, ends, prop.section, mat, orient, nsm=nsm, rod=False, label=prop.label)
        pinned = np.array([bool(e.pa or e.pb) for e in group])
        if pinned.any():
            _add_pin_flags(model, [e for e, p in zip(group, pinned) if p], xyz[pinned], orient[pinned], prop)


def _add_tapered(model: Model, elems: list, ends: np.ndarray, xyz: np.ndarray, orient: np.ndarray,
                 prop: LineProperty, eids: np.ndarray) -> None:
    """CBEAMs of a tapered PBEAM/PBEAML, integrated along the element
    (:func:`trussid.fem.tapered.tapered_frame_matrices`), added as element matrices."""
    card = f"{elems[0].type} {eids[0]}"
    if any(e.pa or e.pb for e in elems):
        raise ModelError(f"{card}: pin flags on a tapered beam ({prop.label}) are not supported")
    L, R = local_axes(xyz[:, 0], xyz[:, 1], orient, eids)
    taper = prop.taper
    K, M = tapered_frame_matrices(L, taper.stations, taper.section_at, prop.mat.E, prop.mat.G, prop.mat.rho,
                                  nsm_at=taper.nsm_at,
                                  theory=model.beam_theory, mass=model.mass_formulation,
                                  torsion_lumped=elems[0].type == "CBEAM", label=prop.label)
    model.add_matrices(eids, ends, K=to_global(K, R), M=to_global(M, R), label=f"{prop.label} (tapered)")


def _add_spring_bars(model: Model, elems: list, xyz: np.ndarray, orient: np.ndarray, prop: LineProperty,
                     eids: np.ndarray) -> None:
    """Bars with A = 0 (bending springs: no axial stiffness, no structural mass) or a MAT1
    with G = 0 (no torsional stiffness), legal in NASTRAN (MSC NAS120 problem F).

    Their stiffness is the frame element's with placeholders (A = 1, G = E / 2), the axial
    (and, for G = 0, torsion) rows and columns then set to zero in element axes: in a
    straight frame element these are uncoupled from bending, so this is exact.
    """

    sec, mat = prop.section, prop.mat
    card = f"{elems[0].type} {eids[0]}"
    if any(e.pa or e.pb for e in elems):
        raise ModelError(f"{card}: pin flags on a bar with A = 0 or G = 0 are not supported")
    G0 = mat.G == 0
    if G0 and model.beam_theory == "timoshenko" and (math.isfinite(sec.Asy) or math.isfinite(sec.Asz)):
        raise ModelError(f"{card}: {prop.label} has shear flexibility with G = 0 (infinite shear flexibility)")
    A0 = sec.A == 0
    L, R = local_axes(xyz[:, 0], xyz[:, 1], orient, eids)
    K, M = frame_matrices(L, 1.0 if A0 else sec.A, sec.Iy, sec.Iz, sec.J, mat.E,
                          mat.E / 2.0 if G0 else mat.G, 0.0 if A0 else mat.rho,
                          nsm=prop.nsm, Asy=sec.Asy, Asz=sec.Asz, theory=model.beam_theory,
                          mass=model.mass_formulation)
    zero = ([0, 6] if A0 else []) + ([3, 9] if G0 else [])
    K[:, zero, :] = 0.0
    K[:, :, zero] = 0.0
    ends = np.array([[e.ga, e.gb] if e.type == "CBAR" else e.nodes for e in elems], dtype=np.int64)
    model.add_matrices(eids, ends, K=to_global(K, R), M=to_global(M, R),
                       label=f"{prop.label} ({'A = 0' if A0 else 'G = 0'})")


def _add_pin_flags(model: Model, elems: list, xyz: np.ndarray, orient: np.ndarray, prop: LineProperty) -> None:
    """CBAR/CBEAM pin flags PA/PB: the released end DOFs (element axes) carry no force.

    The element's stiffness is condensed statically on the released DOFs, one at a time
    (a DOF already free after earlier releases is skipped), and the difference from the
    unpinned element is added as an element matrix, so the beam itself stays a plain beam.
    The mass is unchanged (NASTRAN's pin flags act on the stiffness).
    """
    eids = np.array([e.eid for e in elems], dtype=np.int64)
    L, R = local_axes(xyz[:, 0], xyz[:, 1], orient, eids)
    sec, mat = prop.section, prop.mat
    K = frame_matrices(L, sec.A, sec.Iy, sec.Iz, sec.J, mat.E, mat.G, mat.rho,
                       Asy=sec.Asy, Asz=sec.Asz, theory=model.beam_theory)[0]
    dK = np.zeros_like(K)
    for i, e in enumerate(elems):
        k = K[i].copy()
        released = [int(c) - 1 for c in str(e.pa or "")] + [6 + int(c) - 1 for c in str(e.pb or "")]
        for d in released:
            if k[d, d] <= 1e-12 * np.abs(k).max():
                continue
            k = k - np.outer(k[:, d], k[d, :]) / k[d, d]
            k[d, :] = k[:, d] = 0.0
        dK[i] = 0.5 * (k + k.T) - K[i]
    model.add_matrices(eids, np.array([[e.ga, e.gb] if e.type == "CBAR" else e.nodes for e in elems]),
                       K=to_global(dK, R), label=f"{elems[0].type} pin flags")


def add_rods(bdf, model: Model, nodes: NodeTable, props: dict, mats: dict, wtmass: float) -> None:
    """CROD (one call per property) and CONROD (one call with per-element arrays)."""
    crods = [e for e in bdf.elements.values() if e.type == "CROD"]
    for e in crods:
        if e.pid not in props:
            raise ModelError(f"CROD {e.eid}: property {e.pid} is not defined")
        if props[e.pid].kind != "rod":
            raise ModelError(f"CROD {e.eid}: property {e.pid} is not a PROD or PTUBE")
    for pid, group in _group(crods, lambda e: e.pid).items():
        prop = props[pid]
        eids = np.array([e.eid for e in group], dtype=np.int64)
        ends = np.array([e.nodes for e in group], dtype=np.int64)
        section, mat = rod_torsion(prop.section, prop.mat)
        model.add_beams(eids, ends, section, mat, _rod_orient(nodes, ends, "CROD", eids),
                        nsm=prop.nsm, rod=True, label=prop.label)
    conrods = [e for e in bdf.elements.values() if e.type == "CONROD"]
    if conrods:
        eids = np.array([e.eid for e in conrods], dtype=np.int64)
        ends = np.array([e.nodes for e in conrods], dtype=np.int64)
        m = [material_of(mats, e.mid, f"CONROD {e.eid}") for e in conrods]
        sec = SectionArrays(A=[e.A for e in conrods], Iy=1.0, Iz=1.0, J=[e.j or 0.0 for e in conrods],
                            name="CONROD").per_element(len(eids))
        mat = MaterialArrays(E=[mi.E for mi in m], G=[mi.G for mi in m], rho=[mi.rho for mi in m], name="CONROD")
        sec, mat = rod_torsion(sec, mat)
        nsm = np.array([e.nsm or 0.0 for e in conrods]) * wtmass
        model.add_beams(eids, ends, sec, mat, _rod_orient(nodes, ends, "CONROD", eids), nsm=nsm,
                        rod=True, label="CONROD")


def _rod_orient(nodes: NodeTable, ends: np.ndarray, card: str, eids: np.ndarray) -> np.ndarray:
    """Some vector not parallel to each rod (rods have no bending; the element wants axes)."""
    xyz = nodes.coords(ends, card, eids)
    d = np.abs(xyz[:, 1] - xyz[:, 0])
    return np.eye(3)[np.argmin(d, axis=1)]
