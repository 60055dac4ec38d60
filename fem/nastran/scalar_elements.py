"""Springs, masses and general elements of a deck: CONM1, CONM2, CMASS1-4, CELAS1-4, CBUSH
and GENEL, on grid components (in any displacement frame) or scalar points.
"""

from __future__ import annotations

import math

import numpy as np

from trussid.fem.constraints import rigid_transform
from trussid.fem.errors import ModelError
from trussid.fem.general_element import general_element_stiffness, lower_by_columns
from trussid.fem.model import Model
from trussid.fem.nastran.cards import nastran_value
from trussid.fem.nastran.deck import raw_cards
from trussid.fem.nastran.grids import NodeTable, dof_matrix, rect_frame

__all__ = ["SCALAR_POINT_CARDS", "offset_spring_matrix", "add_conm2", "add_conm1", "add_springs",
           "add_scalar_masses", "add_scalar_point_elements", "add_genel", "genel_fields"]


def add_conm2(bdf, model: Model, nodes: NodeTable, wtmass: float) -> None:
    """CONM2: mass, cg offset and inertia tensor (minus signs on I21, I31, I32), times WTMASS."""
    conm2 = [m for m in bdf.masses.values() if m.type == "CONM2"]
    if not conm2:
        return
    eids = np.array([m.eid for m in conm2], dtype=np.int64)
    nids = np.array([m.nid for m in conm2], dtype=np.int64)
    xyz = nodes.coords(nids, "CONM2", eids)
    mass = np.array([m.mass for m in conm2], dtype=float)
    X = np.array([m.X for m in conm2], dtype=float)
    I = np.array([m.I for m in conm2], dtype=float)  # I11, I21, I22, I31, I32, I33
    tensor = np.empty((len(conm2), 3, 3))
    tensor[:, 0, 0], tensor[:, 1, 1], tensor[:, 2, 2] = I[:, 0], I[:, 2], I[:, 5]
    tensor[:, 0, 1] = tensor[:, 1, 0] = -I[:, 1]
    tensor[:, 0, 2] = tensor[:, 2, 0] = -I[:, 3]
    tensor[:, 1, 2] = tensor[:, 2, 1] = -I[:, 4]
    cid = np.array([m.cid for m in conm2], dtype=np.int64)
    offset = X.copy()
    absolute = cid == -1  # X is the cg in basic coordinates
    offset[absolute] = X[absolute] - xyz[absolute]
    for i in np.flatnonzero(cid > 0):
        R = rect_frame(bdf, int(cid[i]), f"CONM2 {eids[i]}")
        offset[i] = R.T @ X[i]
        tensor[i] = R.T @ tensor[i] @ R
    bad = mass < 0
    if bad.any():
        raise ModelError(f"CONM2 {eids[bad][0]}: mass must be >= 0, got {mass[bad][0]:g}")
    model.add_point_masses(nids, mass * wtmass, inertia=tensor * wtmass, offset=offset)


def _scalar_ends(e, card: str, nodes: NodeTable):
    """(g1, c1, g2, c2) of a CELAS1/2 or CMASS1/2, grounded end last (g2 = 0)."""
    g1, g2 = (n or 0 for n in (list(e.nodes) + [None, None])[:2])
    c1, c2 = e.c1 or 0, e.c2 or 0
    if g1 == 0 and g2 == 0:
        raise ModelError(f"{card}: no grid given")
    if g1 == 0:  # grounded at its first end: swap
        g1, g2, c1, c2 = g2, g1, c2, c1
    spoints = getattr(nodes, "spoints", set())
    # A scalar point's only DOF is its component 1 here (component 0 in the deck).
    if g1 in spoints and c1 == 0:
        c1 = 1
    if g2 in spoints and c2 == 0:
        c2 = 1
    if c1 == 0 or (g2 != 0 and c2 == 0):
        raise ModelError(f"{card}: component 0 is a scalar point's, but {g1 if c1 == 0 else g2} is no SPOINT")
    if not (1 <= c1 <= 6) or (g2 and not 1 <= c2 <= 6):
        raise ModelError(f"{card}: component must be 1-6, got {c1} / {c2}")
    if g2 == g1 and c1 == c2:
        raise ModelError(f"{card}: both ends are component {c1} of grid {g1}")
    return g1, c1, g2, c2


def _add_scalar_elements(model: Model, nodes: NodeTable, ends: list, values: np.ndarray, eids: np.ndarray,
                         card: str, kind: str) -> None:
    """Scalar springs (``kind`` "K") or masses ("M") between grid components, any frames.

    The element acts on ``u1 - u2`` with ``u`` the component along the grid's displacement
    frame, so its matrix is ``value * a a^T`` with ``a`` the two DOF directions (the second
    negated): a 12x12 block on the two grids, or 6x6 when grounded or on one grid.
    """
    if not ends:
        return
    g1, c1, g2, c2 = (np.array(col, dtype=np.int64) for col in zip(*ends))
    a = nodes.dof_vectors(g1, c1, card, eids)
    one = (g2 == 0) | (g2 == g1)
    two = ~one
    if one.any():
        v = a[one].copy()
        same = (g2[one] == g1[one])
        if same.any():
            v[same] -= nodes.dof_vectors(g1[one][same], c2[one][same], card, eids[one][same])
        blocks = values[one][:, None, None] * v[:, :, None] * v[:, None, :]
        model.add_matrices(eids[one], g1[one][:, None], **{kind: blocks}, label=card)
    if two.any():
        v = np.concatenate([a[two], -nodes.dof_vectors(g2[two], c2[two], card, eids[two])], axis=1)
        blocks = values[two][:, None, None] * v[:, :, None] * v[:, None, :]
        model.add_matrices(eids[two], np.column_stack([g1[two], g2[two]]), **{kind: blocks}, label=card)


def add_springs(bdf, model: Model, nodes: NodeTable) -> None:
    """CELAS1/CELAS2 and CBUSH/PBUSH.

    A CELAS on equal components of grids in the basic system is a model spring; any other
    (different components, displacement frames) a scalar element matrix.
    """
    ids, pairs, ks = [], [], []
    gen_ends, gen_k, gen_ids = [], [], []
    for e in bdf.elements.values():
        if e.type not in ("CELAS1", "CELAS2"):
            continue
        card = f"{e.type} {e.eid}"
        if e.type == "CELAS1":
            p = bdf.properties.get(e.pid)
            if p is None or p.type != "PELAS":
                raise ModelError(f"{card}: property {e.pid} is not a defined PELAS")
            k = float(p.k)
        else:
            k = float(e.k)
        if not (math.isfinite(k) and k >= 0):
            raise ModelError(f"{card}: stiffness must be finite and >= 0, got {k:g}")
        g1, c1, g2, c2 = _scalar_ends(e, card, nodes)
        framed = nodes.frames is not None and (
            np.any(nodes.frame([g1], card, [e.eid]) != np.eye(3))
            or (g2 and np.any(nodes.frame([g2], card, [e.eid]) != np.eye(3))))
        if (g2 and c1 != c2) or g2 == g1 or framed:
            gen_ends.append((g1, c1, g2, c2))
            gen_k.append(k)
            gen_ids.append(e.eid)
            continue
        kv = np.zeros(6)
        kv[c1 - 1] = k
        ids.append(e.eid)
        pairs.append([g1, g2 if g2 else -1])
        ks.append(kv)
    if ids:
        ids_a = np.array(ids, dtype=np.int64)
        pairs_a = np.array(pairs, dtype=np.int64)
        nodes.index(pairs_a[:, 0], "spring", ids_a)
        two = pairs_a[:, 1] >= 0
        nodes.index(pairs_a[two, 1], "spring", ids_a[two])
        model.add_springs(ids_a, pairs_a, np.array(ks))
    _add_scalar_elements(model, nodes, gen_ends, np.array(gen_k, float), np.array(gen_ids, dtype=np.int64),
                         "CELAS", "K")
    _add_bushes(bdf, model, nodes)


def add_scalar_masses(bdf, model: Model, nodes: NodeTable, wtmass: float) -> None:
    """CMASS1 (mass from PMASS) and CMASS2: scalar masses on grid components, times WTMASS."""
    ends, values, eids = [], [], []
    for m in bdf.masses.values():
        if m.type not in ("CMASS1", "CMASS2"):
            continue
        card = f"{m.type} {m.eid}"
        if m.type == "CMASS1":
            p = bdf.properties_mass.get(m.pid)
            if p is None or p.type != "PMASS":
                raise ModelError(f"{card}: property {m.pid} is not a defined PMASS")
            value = float(p.mass)
        else:
            value = float(m.mass)
        if not math.isfinite(value):
            raise ModelError(f"{card}: mass must be finite, got {value:g}")
        # A negative scalar mass is legal in NASTRAN (a coupling term of a lumped mass matrix
        # given element by element, as NASTRAN-95's D11-03-1A wing); the assembled mass
        # matrix is what must be positive, and the eigensolver says so if it is not.
        ends.append(_scalar_ends(m, card, nodes))
        values.append(value * wtmass)
        eids.append(m.eid)
    _add_scalar_elements(model, nodes, ends, np.array(values, float), np.array(eids, dtype=np.int64),
                         "CMASS", "M")


def offset_spring_matrix(xa, xb, p, frame, k) -> np.ndarray:
    """12x12 global stiffness of a 6-DOF spring at point ``p`` joined rigidly to grids A and B.

    The spring sees the relative motion at ``p``: ``d = F6 (S_B u_B - S_A u_A)`` with
    ``S_X`` the rigid map from grid X to ``p`` and ``F6 = diag(F, F)`` (rows of ``frame``
    are the spring axes), so ``K = B^T F6^T diag(k) F6 B`` with ``B = [-S_A, S_B]``.
    """
    B = np.concatenate([-rigid_transform(np.asarray(p) - xa), rigid_transform(np.asarray(p) - xb)], axis=1)
    F6 = np.zeros((6, 6))
    F6[:3, :3] = F6[3:, 3:] = frame
    A = F6 @ B
    return A.T @ (np.asarray(k, float)[:, None] * A)


def _add_bushes(bdf, model: Model, nodes: NodeTable) -> None:
    bushes = [e for e in bdf.elements.values() if e.type == "CBUSH"]
    if not bushes:
        return
    ids, pairs, ks, frames = [], [], [], []
    offset_ids, offset_pairs, offset_K = [], [], []
    for e in bushes:
        card = f"CBUSH {e.eid}"
        p = bdf.properties.get(e.pid)
        if p is None or p.type != "PBUSH":
            raise ModelError(f"{card}: property {e.pid} is not a defined PBUSH")
        if "K" not in p.vars:
            raise ModelError(f"PBUSH {p.pid}: no K stiffness line")
        k = np.array([0.0 if v is None else float(v) for v in (list(p.Ki) + [None] * 6)[:6]])
        ga, gb = e.nodes[0], e.nodes[1] if len(e.nodes) > 1 else None
        xa = nodes.coords([ga], "CBUSH", [e.eid])[0]
        xb = nodes.coords([gb], "CBUSH", [e.eid])[0] if gb else xa
        d = xb - xa
        L = float(np.linalg.norm(d))
        coincident = L <= 1e-9 * max(1.0, float(np.abs(nodes.xyz).max()))
        if e.ocid not in (None, -1) and any(v not in (None, 0.0) for v in (e.si or [])):
            raise ModelError(f"{card}: spring offset OCID/S1-S3 is not supported (it adds a lever arm)")
        if e.cid is not None and e.cid >= 0:
            frame = rect_frame(bdf, int(e.cid), card)
        elif coincident:
            raise ModelError(f"{card}: element axes undefined (grounded or coincident grids need CID)")
        else:
            if e.g0 not in (None, 0):
                v = nodes.coords([e.g0], "CBUSH", [e.eid])[0] - xa
            elif e.x is not None and e.x[0] is not None:
                v = np.asarray(e.x, float)
            elif k[1] == k[2] and k[4] == k[5]:
                # No orientation: the axis is GA-GB, and a stiffness symmetric about it
                # (K2 = K3, K5 = K6, e.g. an axial spring) is the same for any y-z pair.
                v = np.eye(3)[np.argmin(np.abs(d))]
            else:
                raise ModelError(f"{card}: no orientation (give X1-X3, G0 or CID; without one, the "
                                 f"stiffness must be symmetric about GA-GB: K2 = K3 and K5 = K6)")
            x = d / L
            z = np.cross(x, v)
            if np.linalg.norm(z) <= 1e-9 * np.linalg.norm(v):
                raise ModelError(f"{card}: orientation vector is parallel to GA-GB")
            z /= np.linalg.norm(z)
            frame = np.vstack([x, np.cross(z, x), z])
        if not coincident:
            # NASTRAN puts the spring at the point S of GA-GB (S = 0.5 by default), joined
            # rigidly to both grids, so a translational stiffness across that line also
            # transmits a moment (lever arm): an element matrix of its own.
            across = np.linalg.norm(np.cross(frame, d / L), axis=1) > 1e-9
            if (across & (k[:3] != 0)).any():
                S = 0.5 if getattr(e, "s", None) is None else float(e.s)
                offset_ids.append(e.eid)
                offset_pairs.append([ga, gb])
                offset_K.append(offset_spring_matrix(xa, xb, xa + S * d, frame, k))
                continue
        ids.append(e.eid)
        pairs.append([ga, gb if gb else -1])
        ks.append(k)
        frames.append(frame)
    if ids:
        model.add_springs(np.array(ids, dtype=np.int64), np.array(pairs, dtype=np.int64), np.array(ks),
                          frame=np.array(frames))
    if offset_ids:
        model.add_matrices(np.array(offset_ids, dtype=np.int64), np.array(offset_pairs, dtype=np.int64),
                           K=np.array(offset_K), label="CBUSH")


def add_conm1(bdf, model: Model, nodes: NodeTable, wtmass: float) -> None:
    """CONM1: a 6x6 mass matrix at a grid (lower triangle by rows, in system CID), times WTMASS.

    Read from its fields, so that a blank is NASTRAN's 0.0 and a malformed entry is named.
    """
    for eid, f in raw_cards(bdf, "CONM1"):
        card = f"CONM1 {eid}"
        try:
            g = int(f[2])
            cid = int(f[3]) if f[3] else 0
            vals = [float(nastran_value(v)) if v else 0.0 for v in (f[4:25] + [""] * 21)[:21]]
        except (IndexError, ValueError, TypeError):
            raise ModelError(f"{card}: malformed entry (GRID, CID and 21 mass terms expected)") from None
        M = np.zeros((6, 6))
        M[np.tril_indices(6)] = vals  # row-wise lower triangle: M11, M21, M22, M31, ...
        M = M + np.tril(M, -1).T
        if cid:
            R = rect_frame(bdf, cid, card)
            R6 = np.kron(np.eye(2), R)
            M = R6.T @ M @ R6
        nodes.index([g], "CONM1", [eid])
        model.add_matrices([eid], [[g]], M=[M * wtmass], label="CONM1")


def genel_fields(f: list, card: str) -> tuple[list, list, str, list, list | None]:
    """``(ui, ud, kind, terms, s_terms)`` of a GENEL from its flat fields (``f[1]`` = EID).

    Positional, as the QRG lays the entry out: (grid or scalar point, component) pairs from
    field 4 of the first line and from field 2 of each continuation (a blank component is a
    scalar point's 0, a pair of blanks is padding); the keywords UD, K or Z, and S start a
    continuation (field 2, flat index 1 + 8 j); UD pairs start after one blank field, the
    K/Z and S terms right after their keyword, running on over continuations. A term list
    may end with blank padding, but a blank inside it is refused (not silently 0.0).
    """
    f = [x.strip().upper() for x in f] + [""] * 2
    keyword = lambda k, names: k < len(f) and f[k] in names and (k - 1) % 8 == 0

    def pairs(k: int, stop: tuple) -> tuple[list, int]:
        out = []
        while k < len(f) - 2 and not keyword(k, stop):
            g, c = f[k], f[k + 1]
            if g:
                out.append((int(g), int(c) if c else 0))
            elif c:
                raise ModelError(f"{card}: component {c} without a grid or scalar point")
            k += 2
        return out, k

    def terms(seg: list, name: str) -> list:
        while seg and not seg[-1]:
            seg = seg[:-1]
        if "" in seg:
            raise ModelError(f"{card}: a blank field inside the {name} terms (write 0.0)")
        return [float(nastran_value(v)) for v in seg]

    ui, k = pairs(3, ("UD", "K", "Z", "S"))
    ud = []
    if keyword(k, ("UD",)):
        ud, k = pairs(k + 2, ("K", "Z", "S"))
    if not keyword(k, ("K", "Z")):
        raise ModelError(f"{card}: no K or Z matrix given (a continuation starting with K or Z)")
    kind = f[k]
    s_at = next((j for j in range(k + 1, len(f)) if keyword(j, ("S",))), None)
    kz = terms(f[k + 1:s_at], kind)
    s_terms = terms(f[s_at + 1:], "S") if s_at is not None else None
    return ui, ud, kind, kz, s_terms


def add_genel(bdf, model: Model, nodes: NodeTable) -> None:
    """GENEL: a general element given by its stiffness K or flexibility Z with rigid-body
    matrix S (:func:`trussid.fem.general_element.general_element_stiffness`), on grid
    components or scalar points."""
    for eid, f in raw_cards(bdf, "GENEL"):
        card = f"GENEL {eid}"
        try:
            ui, ud, kind, kz, s_terms = genel_fields(f, card)
        except ModelError:
            raise
        except (ValueError, TypeError):
            raise ModelError(f"{card}: malformed entry (a grid or component that is not an integer, "
                             f"or a term that is not a number)") from None
        m, n = len(ui), len(ud)
        if not m:
            raise ModelError(f"{card}: no UI (independent) DOFs given")
        matrix = lower_by_columns(kz, m, card, kind)
        S = None
        if n:
            if s_terms is None:
                raise ModelError(f"{card}: UD DOFs given without the S matrix")
            if len(s_terms) != m * n:
                raise ModelError(f"{card}: S needs {m * n} terms ({m} UI x {n} UD), got {len(s_terms)}")
            S = np.asarray(s_terms, float).reshape(m, n)  # by rows: S11, S12, ..., S21, ...
        elif s_terms:
            raise ModelError(f"{card}: S given without UD DOFs")
        full = general_element_stiffness(matrix, kind, S, card)
        grids, A = dof_matrix(nodes, ui + ud, card, eid)
        Kg = A.T @ full @ A
        model.add_matrices([eid], [grids], K=[0.5 * (Kg + Kg.T)], label="GENEL")


#: Scalar elements between scalar points, read from their raw fields (two elements may share
#: one entry: EID, PID or value, S1, S2, then a second EID...).
SCALAR_POINT_CARDS = ("CELAS3", "CELAS4", "CMASS3", "CMASS4")


def add_scalar_point_elements(bdf, model: Model, nodes: NodeTable, wtmass: float) -> None:
    """CELAS3/CELAS4 springs and CMASS3/CMASS4 masses between scalar points (or to ground)."""
    for name in SCALAR_POINT_CARDS:
        kind = "K" if name.startswith("CELAS") else "M"
        ends, values, eids = [], [], []
        for _eid, f in raw_cards(bdf, name):
            f = f + [""] * 9
            for base in (1, 5):  # a second element on the same entry starts in field 5
                if not f[base]:
                    continue
                try:
                    eid = int(f[base])
                    ref = int(f[base + 1]) if name.endswith("3") else float(nastran_value(f[base + 1]))
                    s1, s2 = (int(x) if x else 0 for x in f[base + 2:base + 4])
                except (ValueError, TypeError):
                    raise ModelError(f"{name} {f[base]}: malformed entry") from None
                if name.endswith("3"):
                    table = bdf.properties if kind == "K" else bdf.properties_mass
                    p = table.get(ref)
                    if p is None or p.type != ("PELAS" if kind == "K" else "PMASS"):
                        raise ModelError(f"{name} {eid}: property {ref} is not a defined "
                                         f"{'PELAS' if kind == 'K' else 'PMASS'}")
                    value = float(p.k if kind == "K" else p.mass)
                else:
                    value = ref
                if not (s1 or s2):
                    raise ModelError(f"{name} {eid}: no scalar point given")
                for sp in (s1, s2):
                    if sp and sp not in nodes.spoints:
                        raise ModelError(f"{name} {eid}: {sp} is not a scalar point (SPOINT)")
                if not s1:
                    s1, s2 = s2, 0
                ends.append((s1, 1, s2, 1 if s2 else 0))
                values.append(value * (wtmass if kind == "M" else 1.0))
                eids.append(eid)
        _add_scalar_elements(model, nodes, ends, np.array(values, float), np.array(eids, dtype=np.int64),
                             name, kind)
