"""A :class:`trussid.fem.Model` as a runnable SOL 103 deck (:func:`write_bdf`)."""

from __future__ import annotations

import math
import os

import numpy as np

from trussid._util.files import atomic_path
from trussid.fem.assembly import sum_blocks, beam_matrices, general_blocks, mass_blocks
from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.nastran.reader import read_bdf

__all__ = ['write_bdf']


# ======================================================================= deck text
def _real16(x: float) -> str:
    """A real in at most 16 characters, as NASTRAN reads it, with as many digits as fit.

    ``repr`` when it fits (exact round trip), else the implicit-exponent form
    ``-1.2345678901-5`` (11 significant digits, a relative rounding of 5e-12).
    """
    x = float(x)
    if not math.isfinite(x):
        raise ModelError(f"write_bdf: value {x!r} cannot be written in a deck")
    if x == 0.0:
        return "0."
    s = repr(x)
    if len(s) <= 16:
        if "." not in s:
            s = s.replace("e", ".e") if "e" in s else s + "."
            if len(s) <= 16:
                return s
        else:
            return s
    for digits in range(15, 0, -1):
        mant, exp = f"{x:.{digits}e}".split("e")
        t = f"{mant}{int(exp):+d}"
        if len(t) <= 16:
            return t
    raise AssertionError(x)


def _field16(v) -> str:
    if v is None:
        return ""
    if isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return str(int(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return _real16(v)


class _DeckText:
    """The cards of a deck being written, as large-field text (16-character fields, so that
    a re-read model matches to about 1e-11); written by :meth:`write`."""

    def __init__(self):
        self.lines: list[str] = []
        self.coords: set = {0}
        self.properties: set = set()

    def card(self, name: str, fields: list, comment: str = "") -> None:
        if comment:
            self.lines.extend(f"$ {ln}" for ln in comment.splitlines())
        f = [_field16(v) for v in fields]
        while f and f[-1] == "":
            f.pop()
        for k in range(0, max(len(f), 1), 4):
            chunk = "".join(f"{v:>16}" for v in f[k:k + 4])
            self.lines.append((f"{name + '*':<8}" if k == 0 else "*       ") + chunk)

    def add_grid(self, nid, xyz):
        self.card("GRID", [nid, None, *xyz])

    def add_mat1(self, mid, E, G, nu, rho=0.0):
        self.card("MAT1", [mid, E, G, nu, rho])

    def add_prod(self, pid, mid, A, j=0.0, nsm=0.0, comment=""):
        self.properties.add(pid)
        self.card("PROD", [pid, mid, A, j, None, nsm], comment)

    def add_pbar(self, pid, mid, A, i1, i2, j, nsm, k1=None, k2=None, comment=""):
        self.properties.add(pid)
        self.card("PBAR", [pid, mid, A, i1, i2, j, nsm, None] + [None] * 8 + [k1, k2], comment)

    def add_crod(self, eid, pid, nodes):
        self.card("CROD", [eid, pid, *nodes])

    def add_cbar(self, eid, pid, nodes, x):
        self.card("CBAR", [eid, pid, *nodes, *x])

    def add_conm2(self, eid, nid, mass, cid=0, X=(0.0, 0.0, 0.0), I=(0.0,) * 6, comment=""):
        self.card("CONM2", [eid, nid, cid, mass, *X, None, *I], comment)

    def add_celas2(self, eid, k, nodes, c1, c2):
        self.card("CELAS2", [eid, k, nodes[0], c1, nodes[1], c2 if nodes[1] is not None else None])

    def add_cmass2(self, eid, m, nodes, c1, c2, comment=""):
        self.card("CMASS2", [eid, m, nodes[0], c1, nodes[1], c2], comment)

    def add_cord2r(self, cid, origin, zpoint, xzpoint):
        self.coords.add(cid)
        self.card("CORD2R", [cid, 0, *origin, *zpoint, *xzpoint])

    def add_pbush(self, pid, k):
        self.properties.add(pid)
        self.card("PBUSH", [pid, "K", *k])

    def add_cbush(self, eid, pid, nodes, cid):
        self.card("CBUSH", [eid, pid, *nodes, None, None, None, cid])

    def add_rbe2(self, eid, gn, cm, gm, comment=""):
        self.card("RBE2", [eid, gn, cm, *gm], comment)

    def add_spc1(self, sid, comp, ids):
        self.card("SPC1", [sid, comp, *ids])

    def add_param(self, name, values):
        self.card("PARAM", [name, *values])

    def add_eigrl(self, sid, nd):
        self.card("EIGRL", [sid, None, None, nd])

    def write(self, path, head: list) -> None:
        with open(path, "w") as fh:
            fh.write("\n".join(head + self.lines + ["ENDDATA", ""]))


# ======================================================================= writing
def write_bdf(model: Model, path: str | os.PathLike, n_modes: int | None = 20,
              title: str | None = None) -> None:
    """Write ``model`` as a runnable SOL 103 NASTRAN deck.

    Parameters
    ----------
    model : fem.Model
    path : path-like
        Output deck; written atomically (no partial file on error).
    n_modes : int or None
        ND of the EIGRL written (with METHOD in the case control); None writes no EIGRL.
    title : str, optional
        Case-control TITLE (default: the model's name).

    Notes
    -----
    Cards written: GRID; CBAR + PBAR (``I1 = Iz``, ``I2 = Iy``, K1/K2 = shear areas / A only
    for a Timoshenko model, blank otherwise) or CROD + PROD for rods; MAT1 (E, G, RHO; NU
    left blank so NASTRAN derives it); CONM2 (mass, offset and inertia about the cg, products
    of inertia with NASTRAN's sign); CELAS2 per nonzero component of springs in global axes,
    CBUSH + PBUSH with a CORD2R for springs in other axes (grounded or between coincident
    grids only: elsewhere NASTRAN adds a lever arm the model's spring does not have); RBE2
    (a rigid body's mass as a CONM2 at its master, CID = 0, offset to its cg); SPC1 (set 1);
    PARAM,COUPMASS (1 consistent, -1 lumped); EIGRL. NASTRAN's coupled CROD and CBAR mass differ
    from the model's textbook consistent mass (see
    :func:`~trussid.fem.nastran.conventions.nastran_mass_conventions`): the difference is
    written as CMASS2 scalar masses, so that the deck NASTRAN solves is the model itself. Element ids that clash across kinds are
    renumbered above the largest id. Values are written in 16-character fields so that a
    re-read model matches to about 1e-12 (16-character fields).

    Examples
    --------
    A model built in Python, written as a deck and read back: the same modes.

    >>> import numpy as np
    >>> from trussid.fem import ALUMINIUM, Model, Section, read_bdf, solve_modes, write_bdf
    >>> m = Model(mass="lumped")
    >>> m.add_nodes([1, 2, 3], [[0, 0, 0], [0, 0, 0.5], [0, 0, 1.0]])
    >>> m.add_beams([1, 2], [[1, 2], [2, 3]], Section.tube(0.0125, 0.002), ALUMINIUM, orient=[1, 0, 0])
    >>> m.fix(1)
    >>> write_bdf(m, "mast.bdf", n_modes=4)
    >>> again, info = read_bdf("mast.bdf")
    >>> f0, f1 = solve_modes(m, 4).frequencies_hz, solve_modes(again, 4).frequencies_hz
    >>> print(np.round(f0, 2), np.allclose(f0, f1, rtol=1e-6), info.eigen.n_modes)
    [ 20.71  20.71 106.69 106.69] True 4
    """
    bdf = _DeckText()
    ids, xyz = model.node_ids, model.xyz
    if len(ids) == 0:
        raise ModelError("write_bdf: the model has no nodes")
    unwritable = [what for what, present in (
        ("element matrices (add_matrices)", bool(getattr(model, "general", None))),
        ("linear constraints (add_constraint)", bool(getattr(model, "constraints", None))),
        ("node displacement frames", model.node_frames() is not None if hasattr(model, "node_frames") else False),
        ("omitted DOFs", bool(model.omitted_mask().any()) if hasattr(model, "omitted_mask") else False),
        ("scalar points", bool(model.scalar_mask().any()) if hasattr(model, "scalar_mask") else False),
    ) if present]
    if unwritable:
        raise ModelError(f"write_bdf: the model has {', '.join(unwritable)}, which this writer does not "
                         f"translate back into NASTRAN entries")
    for nid, x in zip(ids.tolist(), xyz):
        bdf.add_grid(nid, x.tolist())

    used_eids: set[int] = set()
    next_id = [0]
    beams = model.beams
    all_ids = [beams.ids, model.springs.ids, np.array([b.id for b in model.rigid_bodies], dtype=np.int64)]
    next_id[0] = int(max([a.max() for a in all_ids if len(a)] + [0])) + 1

    def eid_for(wanted: int) -> int:
        if wanted > 0 and wanted not in used_eids:
            used_eids.add(wanted)
            return wanted
        new = next_id[0]
        next_id[0] += 1
        used_eids.add(new)
        return new

    _write_beams(bdf, model, eid_for)
    _write_masses(bdf, model, eid_for)
    _write_springs(bdf, model, eid_for)
    _write_rigid(bdf, model, eid_for)

    fixed = model.fixed_mask() if model.has_supports else np.zeros((len(ids), 6), bool)
    has_spc = bool(fixed.any())
    if has_spc:
        codes = np.array(["".join(str(k + 1) for k in np.flatnonzero(row)) for row in fixed])
        for comp in sorted(set(codes) - {""}):
            bdf.add_spc1(1, comp, ids[codes == comp].tolist())
    bdf.add_param("COUPMASS", [1 if model.mass_formulation == "consistent" else -1])
    if n_modes:
        bdf.add_eigrl(1, int(n_modes))

    lines = ["SOL 103", "CEND", f"TITLE = {title or model.name}", "ECHO = NONE", "SUBCASE 1"]
    if n_modes:
        lines.append("  METHOD = 1")
    if has_spc:
        lines.append("  SPC = 1")
    lines += ["  DISPLACEMENT = ALL", "BEGIN BULK"]
    with atomic_path(path) as tmp:
        bdf.write(tmp, lines)
        n_scalar = _write_mass_corrections(bdf, model, tmp, eid_for)
        if n_scalar:
            bdf.write(tmp, lines)


def _global_mass(model: Model):
    """The model's unconstrained mass matrix (6 DOFs per node, in node-id order) [kg, kg m^2]."""
    _, Mb, db = beam_matrices(model)
    ms, dm = mass_blocks(model)
    _, mg, dg = general_blocks(model)
    return sum_blocks([Mb] + ms + mg, [db] + dm + dg, model.n_dof)


#: Mass entries of the written deck's difference from the model below this fraction of
#: ``sqrt(M_ii M_jj)`` are the round-off of 16-character fields, not a convention: no card.
MASS_CORRECTION_FLOOR = 1e-11


def _write_mass_corrections(bdf, model: Model, deck, eid_for) -> int:
    """CMASS2 elements that make NASTRAN's mass of the written ``deck`` the model's own.

    NASTRAN's coupled CBAR mass has no torsional inertia, its coupled CROD mass is not the
    textbook rod's and its shear-flexible coupled mass drops the rotary inertia
    (:func:`~trussid.fem.nastran.conventions.nastran_mass_conventions`). The deck is read
    back as NASTRAN would run it and the difference ``dM`` from the model's mass is added as scalar masses: ``-dM_ij``
    between components ``i`` and ``j`` (a CMASS2 adds its value to both diagonals and
    subtracts it off the diagonal), and on each diagonal the rest, grounded. NASTRAN takes
    negative scalar masses; the sum is the model's positive semi-definite mass. Returns the
    number of cards added.
    """
    back, _ = read_bdf(deck)
    M0 = _global_mass(model).tocsr()
    # the read-back model's DOFs in the model's node order
    pos = {int(n): i for i, n in enumerate(back.node_ids)}
    perm = np.array([pos[int(n)] for n in model.node_ids])
    dof = (6 * perm[:, None] + np.arange(6)).ravel()
    M1 = _global_mass(back).tocsr()[dof][:, dof]
    dM = (M0 - M1).tocoo()
    d0 = np.abs(M0.diagonal())
    scale = np.sqrt(np.maximum(d0[dM.row] * d0[dM.col], 1e-300))
    big = np.abs(dM.data) > MASS_CORRECTION_FLOOR * scale
    if not big.any():
        return 0
    rows, cols, vals = dM.row[big], dM.col[big], dM.data[big]
    ids = model.node_ids
    diag = np.zeros(model.n_dof)
    n = 0
    for i, j, v in zip(rows.tolist(), cols.tolist(), vals.tolist()):
        if i < j:
            gi, gj = int(ids[i // 6]), int(ids[j // 6])
            bdf.add_cmass2(eid_for(0), -v, [gi, gj], i % 6 + 1, j % 6 + 1,
                           comment="" if n else "model mass minus NASTRAN's coupled element "
                           "mass (trussid write_bdf)")
            diag[i] += v
            diag[j] += v
            n += 1
        elif i == j:
            diag[i] += v
    for i in np.flatnonzero(np.abs(diag) > MASS_CORRECTION_FLOOR * np.maximum(d0, 1e-300)):
        bdf.add_cmass2(eid_for(0), float(diag[i]), [int(ids[i // 6]), None], int(i % 6 + 1), None)
        n += 1
    return n


def _unique_rows(arr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rows, inverse = np.unique(arr, axis=0, return_inverse=True)
    return rows, inverse.ravel()


def _write_beams(bdf, model: Model, eid_for) -> None:
    b = model.beams
    if len(b) == 0:
        return
    mats, mat_of = _unique_rows(np.column_stack([b.E, b.G, b.rho]))
    for mid, (E, G, rho) in enumerate(mats, start=1):
        bdf.add_mat1(mid, float(E), float(G), None, rho=float(rho))
    timo = model.beam_theory == "timoshenko"
    Asy = np.where(np.isfinite(b.Asy), b.Asy, 0.0)
    Asz = np.where(np.isfinite(b.Asz), b.Asz, 0.0)
    keys = np.column_stack([b.rod, b.A, b.Iy, b.Iz, b.J, Asy, Asz, b.nsm, mat_of])
    props, prop_of = _unique_rows(keys)
    for pid, (rod, A, Iy, Iz, J, asy, asz, nsm, mi) in enumerate(props, start=1):
        mid = int(mi) + 1
        label = str(b.labels[np.flatnonzero(prop_of == pid - 1)[0]])
        if rod:
            bdf.add_prod(pid, mid, float(A), j=float(J), nsm=float(nsm), comment=label)
        else:
            # Euler-Bernoulli: K1/K2 blank (no shear flexibility).
            k1 = float(asy / A) if timo and asy > 0 else None
            k2 = float(asz / A) if timo and asz > 0 else None
            bdf.add_pbar(pid, mid, A=float(A), i1=float(Iz), i2=float(Iy), j=float(J), nsm=float(nsm),
                         k1=k1, k2=k2, comment=label)
    for i in range(len(b)):
        eid = eid_for(int(b.ids[i]))
        pid = int(prop_of[i]) + 1
        ga, gb = (int(n) for n in b.nodes[i])
        if b.rod[i]:
            bdf.add_crod(eid, pid, [ga, gb])
        else:
            bdf.add_cbar(eid, pid, [ga, gb], b.orient[i].tolist())


def _tensor_to_conm2(I: np.ndarray) -> list[float]:
    """Tensor about the cg -> CONM2 I11, I21, I22, I31, I32, I33 (NASTRAN adds the minus)."""
    return [float(I[0, 0]), float(-I[1, 0]), float(I[1, 1]), float(-I[2, 0]), float(-I[2, 1]),
            float(I[2, 2])]


def _write_masses(bdf, model: Model, eid_for) -> None:
    pm = model.point_masses
    for i in range(len(pm)):
        bdf.add_conm2(eid_for(0), int(pm.nodes[i]), float(pm.mass[i]), cid=0,
                      X=pm.offset[i].tolist(), I=_tensor_to_conm2(pm.inertia[i]))


def _write_springs(bdf, model: Model, eid_for) -> None:
    s = model.springs
    if len(s) == 0:
        return
    ids, xyz = model.node_ids, model.xyz
    pos = {int(n): i for i, n in enumerate(ids)}
    next_cid = [max(bdf.coords) + 1]
    next_pid = [max(bdf.properties, default=0) + 1]
    for i in range(len(s)):
        ga, gb = int(s.nodes[i, 0]), int(s.nodes[i, 1])
        frame = s.frame[i]
        if np.array_equal(frame, np.eye(3)):
            for c in np.flatnonzero(s.k[i]):
                nodes = [ga, gb] if gb >= 0 else [ga, None]
                comps = [int(c) + 1, int(c) + 1] if gb >= 0 else [int(c) + 1, 0]
                bdf.add_celas2(eid_for(int(s.ids[i])), float(s.k[i, c]), nodes, c1=comps[0], c2=comps[1])
            continue
        if gb >= 0 and np.linalg.norm(xyz[pos[ga]] - xyz[pos[gb]]) > 0:
            raise ModelError(f"spring {s.ids[i]}: a spring in rotated axes between non-coincident nodes "
                             f"{ga} and {gb} has no exact NASTRAN equivalent (CBUSH adds a lever arm)")
        cid = next_cid[0]
        next_cid[0] += 1
        # CORD2R by origin, a point on z and a point in the x-z plane (basic coordinates).
        bdf.add_cord2r(cid, [0.0, 0.0, 0.0], frame[2].tolist(), frame[0].tolist())
        pid = next_pid[0]
        next_pid[0] += 1
        bdf.add_pbush(pid, s.k[i].tolist())
        bdf.add_cbush(eid_for(int(s.ids[i])), pid, [ga, gb if gb >= 0 else None], cid)


def _write_rigid(bdf, model: Model, eid_for) -> None:
    xyz_of = dict(zip(model.node_ids.tolist(), model.xyz))
    for rb in model.rigid_bodies:
        comps = "".join(str(k + 1) for k in np.flatnonzero(rb.dofs))
        bdf.add_rbe2(eid_for(rb.id), rb.master, comps, rb.slaves.tolist(), comment=rb.label)
        if rb.mass > 0 or np.any(rb.inertia):
            if rb.master not in xyz_of:
                raise ModelError(f"{rb.label}: master node {rb.master} is not defined")
            offset = np.zeros(3) if rb.cg is None else np.asarray(rb.cg, float) - xyz_of[rb.master]
            bdf.add_conm2(eid_for(0), rb.master, float(rb.mass), cid=0, X=offset.tolist(),
                          I=_tensor_to_conm2(rb.inertia), comment=f"mass of {rb.label}")
