"""DOF sets of a deck: supports (SPC, SPC1, SPCADD, GRID PS), condensed and boundary sets
(OMIT, ASET, QSET, BSET, SUPORT), and the scalar points they and the scalar elements use.
"""

from __future__ import annotations

from collections import defaultdict

import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.nastran.deck import BdfInfo, case_has, case_int, components, raw_cards
from trussid.fem.nastran.grids import NodeTable
from trussid.fem.nastran.scalar_elements import SCALAR_POINT_CARDS, genel_fields

__all__ = ["add_spcs", "add_dof_sets", "scalar_points", "qset_points", "component_mode_reduction"]


def add_dof_sets(bdf, model: Model, nodes: NodeTable, info: BdfInfo) -> None:
    """OMIT/OMIT1 and ASET/ASET1 (Guyan reduction); SUPORT/SUPORT1 (accepted, noted)."""
    n = len(nodes.ids)
    def mask_of(cards, what):
        mask = np.zeros((n, 6), bool)
        for c in cards:
            ids = np.asarray(c.ids, dtype=np.int64)
            # OMIT/ASET pairs carry a component per id; OMIT1/ASET1 one for all
            comps = c.components if isinstance(c.components, list) else [c.components] * len(ids)
            idx = nodes.index(ids, what, np.zeros(len(ids), dtype=np.int64))
            for g, i, cm in zip(ids.tolist(), np.atleast_1d(idx), comps):
                # component 0 (or blank) is a scalar point's only DOF
                on_spoint = g in nodes.spoints and str(cm).strip() in ("0", "", "None")
                mask[i, [0] if on_spoint else components(cm, what)] = True
        return mask

    omits, asets = bdf.omits, bdf.asets
    if omits or asets:
        omitted = mask_of(omits, "OMIT")
        if asets:
            omitted |= ~mask_of(asets, "ASET")
        qpoints = qset_points(bdf) if component_mode_reduction(bdf) else []
        if qpoints:
            omitted[nodes.index(qpoints, "QSET", np.zeros(len(qpoints), dtype=np.int64))] = False
            model.add_generalized_coordinates(qpoints)
        for c in range(6):
            sel = omitted[:, c]
            if sel.any():
                model.omit(nodes.ids[sel], str(c + 1))
        info.notes.append(f"OMIT/ASET: {int(omitted.sum())} DOFs condensed by "
                          + (f"Craig-Bampton reduction, the lowest {len(qpoints)} fixed-interface modes on the "
                             f"QSET scalar points, as NASTRAN does" if qpoints else
                             "Guyan reduction, as NASTRAN does (exact for DOFs without mass)"))
    spoints = bdf.spoints
    bsets, qsets = bdf.bsets, bdf.qsets
    for c in qsets:
        ids = [int(g) for g in c.ids]
        grids = [g for g in ids if g not in spoints]
        if grids:
            raise ModelError(f"{c.type} {grids[0]}: modal (Q-set) DOFs on grid points are not supported; "
                             f"the Craig-Bampton Q-set is read on scalar points only")
    if bsets:
        extseout = case_has(bdf, "EXTSEOUT")
        if not (qsets or extseout):
            g0 = bsets[0].ids[0]
            raise ModelError(f"{bsets[0].type} (grid {g0}): a boundary set without QSET or EXTSEOUT (residual-structure "
                             f"B-set analysis) is not supported")
        held = mask_of(bsets, bsets[0].type)
        for c in range(6):
            if held[:, c].any():
                model.fix(nodes.ids[held[:, c]], str(c + 1))
        info.notes.append(f"BSET: {int(held.sum())} boundary DOFs held: a component reduction (QSET/EXTSEOUT) "
                          f"prints its fixed-interface (Craig-Bampton) modes, which these are"
                          + (f"; QSET on {len(spoints)} scalar points: modal coordinates of the reduction, "
                             f"no part of these modes" if qsets else ""))
    suport = bdf.suport + list(bdf.suport1.values())
    sol = (bdf.solution[0] or "").split(",")[0]
    if suport and sol == "31":
        # MYSTRAN SOL 31 is a Craig-Bampton reduction whose boundary is the SUPORT set: its
        # printed eigenvalues are those of the structure with that boundary held.
        held = np.zeros((n, 6), bool)
        for c in suport:
            ids = np.asarray(c.ids, dtype=np.int64)
            comps = c.components if isinstance(c.components, list) else [c.components] * len(ids)
            idx = nodes.index(ids, "SUPORT", np.zeros(len(ids), dtype=np.int64))
            for i, cm in zip(np.atleast_1d(idx), comps):
                held[i, components(cm, "SUPORT")] = True
        for c in range(6):
            if held[:, c].any():
                model.fix(nodes.ids[held[:, c]], str(c + 1))
        info.notes.append(f"SOL 31 (MYSTRAN Craig-Bampton): the {int(held.sum())} SUPORT DOFs are the reduction "
                          f"boundary, held for the fixed-interface modes MYSTRAN prints")
    elif suport:
        info.notes.append("SUPORT accepted: it selects reference DOFs for NASTRAN's rigid-body modes, "
                          "which trussid computes anyway (they come first, at about 0 Hz)")


def add_spcs(bdf, model: Model, nodes: NodeTable, info: BdfInfo) -> None:
    """SPC/SPC1 (through SPCADD) of the case control's SPC set, else of all sets; GRID PS."""
    all_sets = set(bdf.spcs) | set(bdf.spcadds)
    chosen = case_int(bdf, "SPC")
    if chosen:
        if len(chosen) > 1:
            info.notes.append(f"subcases select different SPC sets {chosen}; using the first, {chosen[0]}")
        top = int(chosen[0])
        if top not in all_sets:
            # NASTRAN only warns (and runs without the set); said loudly in the notes.
            info.spc_reason = f"SPC = {top} in the case control, but no SPC, SPC1 or SPCADD has set {top}: no SPC applied, as NASTRAN"
            info.notes.append(f"WARNING: case control SPC = {top} names no SPC/SPC1/SPCADD set: run without it, "
                              f"as NASTRAN does (it warns too)")
            roots = []
        else:
            info.spc_reason = f"SPC = {top} in the case control"
            roots = [top]
    elif all_sets:
        roots = sorted(all_sets)
        info.spc_reason = "no SPC request in the case control: all SPC sets applied"
    else:
        roots = []
        info.spc_reason = "no SPC cards"
    used = []
    stack = list(roots)
    while stack:
        sid = stack.pop()
        if sid in used:
            continue
        used.append(sid)
        for add in bdf.spcadds.get(sid, []):
            for s in add.sets:
                if s not in all_sets:
                    raise ModelError(f"SPCADD {sid}: SPC set {s} is not defined")
                stack.append(s)
    info.spc_sets = sorted(used) if used else None
    by_comp = defaultdict(list)
    for sid in used:
        for c in bdf.spcs.get(sid, []):
            if c.type == "SPC1":
                ids = np.asarray(c.nodes, dtype=np.int64)
                nodes.index(ids, "SPC1", np.full(len(ids), sid))
                by_comp[str(c.components)].append(ids)
            elif c.type == "SPC":
                for nid, comp, d in zip(c.nodes, c.components, c.enforced):
                    if d:
                        info.notes.append(f"SPC {sid}: enforced displacement {d:g} at grid {nid} "
                                          f"(irrelevant to modes) treated as a support")
                    nodes.index([nid], "SPC", [sid])
                    by_comp[str(comp)].append(np.array([nid], dtype=np.int64))
            else:
                raise ModelError(f"{c.type} {sid}: not supported")
    for g in bdf.nodes.values():
        if g.ps:
            by_comp[str(g.ps)].append(np.array([g.nid], dtype=np.int64))
    for comp, chunks in sorted(by_comp.items()):
        ids = np.unique(np.concatenate(chunks))
        if "0" in comp or not comp.strip():  # component 0 (or blank): a scalar point's only DOF
            held = [i for i in ids.tolist() if i in nodes.spoints]
            if held:
                model.fix(held, "1")
        comp = comp.replace("0", "")
        if comp.strip():
            model.fix(ids, comp)


def _scalar_point_refs(bdf) -> tuple[set, set]:
    """Scalar points that scalar elements, and selected MPCs, reference (besides Q-set points).

    A scalar element's points need no SPOINT entry (QRG, CELASi/CMASSi remarks): they are
    defined by the reference. An MPC's are not.
    """
    refs = set()
    for e in list(bdf.elements.values()) + list(bdf.masses.values()):
        if e.type in ("CELAS1", "CELAS2", "CMASS1", "CMASS2"):
            refs |= {int(n) for n, c in zip(list(e.nodes), (e.c1, e.c2)) if n and not c}
    for name in SCALAR_POINT_CARDS:
        for eid, f in raw_cards(bdf, name):
            for k in (3, 4, 7, 8):
                if k < len(f) and f[k]:
                    try:
                        refs.add(int(f[k]))
                    except ValueError:
                        raise ModelError(f"{name} {eid}: scalar point field {k} is {f[k]!r}, not a point id") from None
    mpc_refs = set()
    for sid in case_int(bdf, "MPC")[:1]:
        for c in bdf.mpcs.get(int(sid), []):
            mpc_refs |= {int(n) for n, cm in zip(c.nodes, c.components) if str(cm).strip() in ("0", "")}
    for eid, f in raw_cards(bdf, "GENEL"):  # a GENEL's scalar points need their SPOINT, like an MPC's
        try:
            ui, ud, *_ = genel_fields(f, f"GENEL {eid}")
        except (ModelError, ValueError, TypeError):
            continue  # reported, naming the entry, when the element is built
        mpc_refs |= {g for g, c in ui + ud if c == 0}
    return refs, mpc_refs


def qset_points(bdf) -> list:
    """Ids on QSET/QSET1 entries, in deck order (each once)."""
    ids = []
    for q in bdf.qsets:
        ids.extend(int(n) for n in q.ids)
    return list(dict.fromkeys(ids))


def component_mode_reduction(bdf) -> bool:
    """QSET with ASET/OMIT and no BSET: a Craig-Bampton reduction whose modes are solved (the
    B-set case prints the fixed-interface modes instead, see :func:`add_dof_sets`)."""
    return bool(bdf.qsets) and bool(bdf.asets or bdf.omits) and not bdf.bsets


def scalar_points(bdf, grids: set, info: BdfInfo) -> list:
    """Ids of the SPOINTs that something connects (sorted); the others are noted and ignored."""
    spoints = set(bdf.spoints)
    qset = set(qset_points(bdf))
    elem_refs, mpc_refs = _scalar_point_refs(bdf)
    if component_mode_reduction(bdf) and (elem_refs | mpc_refs) & qset:
        q = min((elem_refs | mpc_refs) & qset)
        raise ModelError(f"QSET {q}: scalar point {q} holds a component mode's amplitude (Craig-Bampton with "
                         f"ASET/OMIT), but a scalar element, MPC or GENEL also references it")
    elem_refs, mpc_refs = elem_refs - qset, mpc_refs - qset
    missing = sorted(mpc_refs - spoints - grids - elem_refs)
    if missing:
        raise ModelError(f"scalar point {missing[0]} is referenced by an MPC or GENEL (component 0) but no "
                         f"SPOINT or scalar element defines it")
    clash = sorted(spoints & grids)
    if clash:
        raise ModelError(f"SPOINT {clash[0]}: the id is also a GRID")
    implicit = sorted(elem_refs - spoints - grids)
    if implicit:
        info.notes.append(f"scalar point(s) {', '.join(map(str, implicit[:5]))}{' ...' if len(implicit) > 5 else ''} "
                          f"defined by the scalar elements that reference them (no SPOINT needed, as NASTRAN)")
    spoints = spoints | set(implicit)
    refs = elem_refs | mpc_refs
    if component_mode_reduction(bdf):
        refs |= qset  # the generalized coordinates of the reduction
    used = sorted(refs & spoints)
    idle = sorted(spoints - refs - qset)
    if idle:
        info.notes.append(f"SPOINT {', '.join(map(str, idle[:5]))}{' ...' if len(idle) > 5 else ''}: unconnected "
                          f"scalar point(s), no effect on the modes: ignored")
    return used
