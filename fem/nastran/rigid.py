"""Rigid elements and multipoint constraints of a deck: RBE2, RBAR, RBE3, NASTRAN-95's
CRIGD1/2/3 and CRIGDR, and the MPC set the case control selects.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.constraints import rbe3_constraint, rigid_element
from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.nastran.deck import BdfInfo, case_int, components, grid_ids
from trussid.fem.nastran.dof_sets import qset_points
from trussid.fem.nastran.grids import NodeTable

__all__ = ["add_rigid", "add_raw_rigid", "add_mpcs"]


def _add_rigid_element(model: Model, nodes: NodeTable, eid: int, grids, independent, dependent,
                       label: str) -> None:
    """A rigid element given by (grid, component) lists: a linear constraint of the model."""
    grids = list(dict.fromkeys(grids))
    pos = {g: i for i, g in enumerate(grids)}
    xyz = nodes.coords(grids, label.split()[0], [eid] * len(grids))
    frames = None if nodes.frames is None else nodes.frame(grids, label.split()[0], [eid] * len(grids))
    C = rigid_element(xyz, frames, [(pos[g], c) for g, c in independent],
                      [(pos[g], c) for g, c in dependent], label)
    dep = np.array(dependent, dtype=np.int64).reshape(-1, 2)
    ind = np.array(independent, dtype=np.int64).reshape(-1, 2)
    model.add_constraint(eid, (dep[:, 0], dep[:, 1]), (ind[:, 0], ind[:, 1]), C, label=label)


def add_rigid(bdf, model: Model, nodes: NodeTable) -> None:
    """RBE2 (rigid body), RBAR (rigid bar, any independent set) and RBE3 (interpolation)."""
    for eid, e in sorted(bdf.rigid_elements.items()):
        card = f"{e.type} {eid}"
        if e.type == "RBE2":
            nodes.index([e.gn], "RBE2", [eid])
            nodes.index(np.asarray(e.Gmi, dtype=np.int64), "RBE2", [eid] * len(e.Gmi))
            dofs = "".join(str(c + 1) for c in components(e.cm, card))
            model.add_rigid_body(eid, e.gn, e.Gmi, dofs=dofs, mass=0.0, label=card)
        elif e.type == "RBAR":
            ind = [(e.ga, c) for c in components(e.cna, card)] + [(e.gb, c) for c in components(e.cnb, card)]
            cma, cmb = components(e.cma, card), components(e.cmb, card)
            if not cma and not cmb:  # NASTRAN: blank CMA and CMB = every DOF not independent
                cma = [c for c in range(6) if (e.ga, c) not in ind]
                cmb = [c for c in range(6) if (e.gb, c) not in ind]
            dep = [(e.ga, c) for c in cma] + [(e.gb, c) for c in cmb]
            if set(dep) & set(ind):
                raise ModelError(f"{card}: a component is both independent and dependent")
            _add_rigid_element(model, nodes, eid, [e.ga, e.gb], ind, dep, card)
        elif e.type == "RBE3":
            if e.Gmi:
                raise ModelError(f"{card}: UM (alternative dependent DOFs) is not supported")
            rows, comps, weights = [], [], []
            for w, c, grids in zip(e.weights, e.comps, e.Gijs):
                mask = np.zeros(6, bool)
                mask[components(c, card)] = True
                for g in grids:
                    rows.append(int(g))
                    comps.append(mask)
                    weights.append(float(w))
            rows_a = np.array(rows, dtype=np.int64)
            comps_a = np.array(comps, dtype=bool).reshape(-1, 6)
            refc = np.zeros(6, bool)
            refc[components(e.refc, card)] = True
            ref_xyz = nodes.coords([e.refgrid], "RBE3", [eid])[0]
            xyz = nodes.coords(rows_a, "RBE3", [eid] * len(rows_a))
            frames = None if nodes.frames is None else nodes.frame(rows_a, "RBE3", [eid] * len(rows_a))
            ref_frame = None if nodes.frames is None else nodes.frame([e.refgrid], "RBE3", [eid])[0]
            C = rbe3_constraint(ref_xyz, ref_frame, xyz, frames, comps_a, weights, refc, card)
            ind_nodes = np.repeat(rows_a, comps_a.sum(axis=1))
            ind_comps = np.nonzero(comps_a)[1]
            dep_comps = np.flatnonzero(refc)
            model.add_constraint(eid, (np.full(len(dep_comps), e.refgrid), dep_comps), (ind_nodes, ind_comps),
                                 C, label=card)
        else:
            raise ModelError(f"{card}: not supported")


def add_raw_rigid(bdf, model: Model, nodes: NodeTable) -> None:
    """NASTRAN-95's rigid elements CRIGD1, CRIGD2, CRIGD3 and CRIGDR (from their fields).

    CRIGD1 EID GI GM...: every component of each GM follows GI rigidly. CRIGD2 EID GI
    (GM CM)...: the listed components. CRIGD3 EID (GI CI)... MSET (GM CM)...: six
    independent components anywhere on the element determine the rigid motion. CRIGDR EID
    GI GM CM: a rigid pin-ended rod, component CM of GM keeps the distance GI-GM.
    """
    cards = [c for n in ("CRIGD1", "CRIGD2", "CRIGD3", "CRIGDR") for c in bdf.raw.get(n, [])]
    for c in sorted(cards, key=lambda c: (c.file, c.line)):
        name = c.name
        f = list(c.fields)
        try:
            eid = int(f[1])
        except (IndexError, ValueError):
            raise ModelError(f"{name}: no element id") from None
        card = f"{name} {eid}"
        try:
            if name == "CRIGD1":
                gi, gms = int(f[2]), grid_ids(f[3:], card)
                nodes.index([gi] + gms, name, [eid] * (1 + len(gms)))
                model.add_rigid_body(eid, gi, gms, dofs="123456", label=card)
            elif name == "CRIGD2":
                gi = int(f[2])
                vals = [x for x in f[3:] if x]
                pairs = list(zip(vals[0::2], vals[1::2]))
                grids = [gi] + [int(g) for g, _ in pairs]
                ind = [(gi, c) for c in range(6)]
                dep = [(int(g), c) for g, cm in pairs for c in components(cm, card)]
                _add_rigid_element(model, nodes, eid, grids, ind, dep, card)
            elif name == "CRIGD3":
                vals = [x for x in f[2:] if x]
                if "MSET" not in vals:
                    raise ModelError(f"{card}: no MSET (dependent components) given")
                k = vals.index("MSET")
                ind = [(int(g), c) for g, cm in zip(vals[:k:2], vals[1:k:2]) for c in components(cm, card)]
                dep = [(int(g), c) for g, cm in zip(vals[k + 1::2], vals[k + 2::2]) for c in components(cm, card)]
                grids = [g for g, _ in ind + dep]
                _add_rigid_element(model, nodes, eid, grids, ind, dep, card)
            else:  # CRIGDR
                gi, gm, cm = int(f[2]), int(f[3]), int(f[4])
                _add_rigid_rod(model, nodes, eid, gi, gm, cm, card)
        except (IndexError, ValueError):
            raise ModelError(f"{card}: malformed entry") from None


def _add_rigid_rod(model: Model, nodes: NodeTable, eid: int, gi: int, gm: int, cm: int, card: str) -> None:
    """CRIGDR: ``e . (u_M - u_I) = 0`` solved for translation ``cm`` of GM (frames honoured)."""
    if cm not in (1, 2, 3):
        raise ModelError(f"{card}: dependent component must be a translation 1-3, got {cm}")
    x = nodes.coords([gi, gm], "CRIGDR", [eid, eid])
    d = x[1] - x[0]
    if not np.linalg.norm(d) > 0:
        raise ModelError(f"{card}: grids {gi} and {gm} coincide")
    e = d / np.linalg.norm(d)
    F = nodes.frame([gi, gm], "CRIGDR", [eid, eid])
    a, b = F[1] @ e, F[0] @ e  # the rod direction in each grid's displacement frame
    c = cm - 1
    if abs(a[c]) <= 1e-6:
        raise ModelError(f"{card}: component {cm} of grid {gm} is normal to the rod; it cannot be dependent")
    others = [k for k in range(3) if k != c]
    ind_nodes = [gi, gi, gi] + [gm, gm]
    ind_comps = [0, 1, 2] + others
    C = np.concatenate([b, -a[others]])[None, :] / a[c]
    model.add_constraint(eid, ([gm], [c]), (ind_nodes, ind_comps), C, label=card)


def add_mpcs(bdf, model: Model, nodes: NodeTable, info: BdfInfo) -> None:
    """MPC (through MPCADD) of the case control's MPC set: the first term is dependent."""
    chosen = case_int(bdf, "MPC")
    if not chosen:
        if bdf.mpcs or bdf.mpcadds:
            info.notes.append(f"MPC sets {sorted(set(bdf.mpcs) | set(bdf.mpcadds))} present but not "
                              f"selected by the case control: not applied (as NASTRAN)")
        return
    top = int(chosen[0])
    if len(chosen) > 1:
        info.notes.append(f"subcases select different MPC sets {chosen}; using the first, {top}")
    sets, stack = [], [top]
    while stack:
        sid = stack.pop()
        if sid in sets:
            continue
        if sid not in bdf.mpcs and sid not in bdf.mpcadds:
            raise ModelError(f"case control MPC = {top}: MPC set {sid} is not defined")
        sets.append(sid)
        for add in bdf.mpcadds.get(sid, []):
            stack.extend(add.sets)
    qpoints = set(qset_points(bdf)) & bdf.spoints
    for sid in sets:
        for k, c in enumerate(bdf.mpcs.get(sid, [])):
            card = f"MPC {sid}"
            g = np.asarray(c.nodes, dtype=np.int64)
            comps_raw = [str(x).strip() for x in c.components]
            onq = np.array([int(n) in qpoints and cm in ("0", "") for n, cm in zip(g, comps_raw)])
            if onq.any():
                # A Q-set scalar point is a modal coordinate of the component reduction,
                # held at zero with the boundary in the fixed-interface modes: its term drops.
                if onq[0]:
                    raise ModelError(f"{card}: dependent term on Q-set scalar point {g[0]} is not supported")
                keep = ~onq
                g = g[keep]
                c = type("MPCTerms", (), {"components": [x for x, k in zip(c.components, keep) if k],
                                          "coefficients": [x for x, k in zip(c.coefficients, keep) if k]})
                if len(g) == 1:
                    model.fix([int(g[0])], str(components(c.components[0], card)[0] + 1))
                    continue
            comp = [[0] if int(gi) in nodes.spoints and str(x).strip() in ("0", "") else components(x, card)
                    for gi, x in zip(g, c.components)]
            if any(len(x) != 1 for x in comp):
                raise ModelError(f"{card}: each term needs exactly one component (scalar points are "
                                 f"not supported)")
            comp = np.array([x[0] for x in comp])
            a = np.asarray(c.coefficients, float)
            if a[0] == 0:
                raise ModelError(f"{card}: the dependent term's coefficient is 0")
            nodes.index(g, "MPC", [sid] * len(g))
            model.add_constraint(sid, ([g[0]], [comp[0]]), (g[1:], comp[1:]), -a[1:][None, :] / a[0],
                                 label=card)
