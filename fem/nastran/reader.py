"""Translation of a parsed deck into a :class:`trussid.fem.Model` (:func:`read_bdf`)."""

from __future__ import annotations

import math
import os
import warnings
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from trussid.fem.constraints import rbe3_constraint, rigid_element, rigid_transform
from trussid.fem.elements import frame_matrices, local_axes, to_global
from trussid.fem.errors import ModelError, UnitsWarning
from trussid.fem.general_element import general_element_stiffness, lower_by_columns
from trussid.fem.tapered import tapered_frame_matrices
from trussid.fem.materials import wave_speed_problem
from trussid.fem.model import Model
from trussid.fem.sections import Section
from trussid.fem.nastran.matrices import add_direct_matrices
from trussid.fem.nastran.preload import add_preload_stiffness
from trussid.fem.nastran.entries import SECTION_TYPES
from trussid.fem.nastran.conventions import (BAR_SHEAR_FACTOR, CONVENTIONS, ROD_SHEAR_FACTOR,
                                             _nastran_mass_conventions)
from trussid.fem.nastran.deck import (_is_preload_run, BdfInfo, _case_has, _case_int, _check_cards,
                                      _comps, _ints, _nastran_value, _parse, _raw_cards,
                                      _read_params, _select_eigen)

__all__ = ['read_bdf', 'coord_axes', 'offset_spring_matrix']


# ======================================================================= reading
def read_bdf(path: str | os.PathLike, beam_theory: str | None = None,
             conventions: str = "nx") -> tuple[Model, BdfInfo]:
    """Read a NASTRAN bulk-data deck into a :class:`trussid.fem.Model`.

    Parameters
    ----------
    path : path-like
        A deck (.bdf/.dat/.nas...), with or without executive and case control.
    beam_theory : {"euler-bernoulli", "timoshenko"}, optional
        Override the theory chosen from the shear factors (see the module notes).
    conventions : {"nx", "msc"}
        Whose element conventions to follow where NASTRAN builds differ: the PBARL/PBEAML
        ROD shear factor is 0.9 with "nx" (NX/Simcenter, and the newer MSC builds: the
        default) and 6/7 with "msc" (an MSC 2012 build). Recorded in ``info.conventions``.

    Returns
    -------
    model : fem.Model
        Nodes in the deck's basic coordinates, everything in the deck's units, masses
        multiplied by WTMASS.
    info : BdfInfo

    Raises
    ------
    ModelError
        A missing or unreadable file, any card this reader does not translate (all such
        cards are listed with their counts; element entries such as shells and solids
        first), or a card it cannot translate faithfully (offsets, pin flags, tapered beams,
        scalar points...), naming the card.

    Notes
    -----
    Entries without effect on real modes (loads, tables, damping, aero model, output
    requests: :data:`IGNORED_CARDS`) are accepted and listed with their counts in
    ``info.ignored``. NASTRAN's own element conventions are reproduced where they differ
    from the textbook elements of :mod:`trussid.fem.elements` (see
    :func:`_nastran_mass_conventions` and the PBARL/PBEAML ROD shear factor).

    Examples
    --------
    A deck of a 1 m steel cantilever (CBAR, 20 x 10 mm section), written here and read back;
    its first bending frequencies against Euler-Bernoulli (8.154 and 16.308 Hz):

    >>> import numpy as np
    >>> from pathlib import Path
    >>> from trussid.fem import read_bdf, solve_modes
    >>> grids = "".join(f"GRID,{i},,{0.25 * (i - 1)},0.,0.\\n" for i in range(1, 6))
    >>> bars = "".join(f"CBAR,{e},1,{e},{e + 1},0.,0.,1.\\n" for e in range(1, 5))
    >>> _ = Path("cantilever.bdf").write_text(
    ...     "SOL 103\\nCEND\\nBEGIN BULK\\nPARAM,COUPMASS,1\\nMAT1,1,200.+9,,0.3,7850.\\n"
    ...     "PBAR,1,1,2.-4,1.6667-9,6.6667-9,4.5776-9\\n" + grids + bars + "SPC1,1,123456,1\\nENDDATA\\n")
    >>> model, info = read_bdf("cantilever.bdf")
    >>> model.n_nodes, len(model.beams), info.mass, info.beam_theory
    (5, 4, 'consistent', 'euler-bernoulli')
    >>> print(np.round(solve_modes(model, n_modes=2).frequencies_hz, 3))
    [ 8.154 16.308]
    """
    path = Path(path)
    if conventions not in CONVENTIONS:
        raise ModelError(f"conventions must be one of {', '.join(CONVENTIONS)}, got {conventions!r}")
    bdf = _parse(path)
    info = BdfInfo(path=str(path), cards=dict(sorted(bdf.card_count.items())), conventions=conventions)
    info.notes.extend(bdf.parsed.notes)
    _check_cards(bdf, path, info)
    _read_params(bdf, info)

    node_ids, xyz, frames = _nodes(bdf)
    scalar = _scalar_points(bdf, set(node_ids.tolist()), info)
    if not len(node_ids) and not scalar:
        raise ModelError("the deck has no GRID cards (and no scalar points)")
    if scalar:
        # Scalar points become nodes of their own with only component 1 free (position and
        # frame are irrelevant: only scalar elements and MPCs join them).
        node_ids = np.concatenate([node_ids, np.array(scalar, dtype=np.int64)])
        xyz = np.concatenate([xyz, np.zeros((len(scalar), 3))])
        if frames is not None:
            frames = np.concatenate([frames, np.broadcast_to(np.eye(3), (len(scalar), 3, 3))])
    nodes = _NodeTable(node_ids, xyz, frames)
    nodes.spoints = set(scalar)
    mats = _materials(bdf, info.wtmass)
    _check_units(bdf, mats, info.wtmass)
    props = _properties(bdf, mats, info.wtmass, conventions)

    if beam_theory is None:
        used = {e.pid for e in bdf.elements.values() if e.type in ("CBAR", "CBEAM")}
        shear = sorted({props[pid].label for pid in used if pid in props and props[pid].shear})
        if shear:
            info.beam_theory = "timoshenko"
            info.beam_theory_reason = (f"shear flexibility given by {', '.join(shear[:5])}"
                                       f"{' ...' if len(shear) > 5 else ''} (NASTRAN includes it)")
        else:
            info.beam_theory = "euler-bernoulli"
            info.beam_theory_reason = "no property gives shear flexibility"
    elif beam_theory in ("euler-bernoulli", "timoshenko"):
        info.beam_theory = beam_theory
        info.beam_theory_reason = "requested by the caller"
    else:
        raise ModelError(f"beam_theory must be 'euler-bernoulli' or 'timoshenko', got {beam_theory!r}")

    model = Model(beam_theory=info.beam_theory, mass=info.mass, name=path.stem)
    n_grid = len(node_ids) - len(scalar)
    if n_grid:
        model.add_nodes(node_ids[:n_grid], xyz[:n_grid])
    if scalar:
        model.add_scalar_points(scalar)
    if nodes.frames is not None:
        model.set_node_frames(node_ids, nodes.frames)
    _add_bars(bdf, model, nodes, props)
    _add_rods(bdf, model, nodes, props, mats, info.wtmass)
    _nastran_mass_conventions(bdf, model, nodes, props, info)
    _add_masses(bdf, model, nodes, info.wtmass)
    _add_scalar_masses(bdf, model, nodes, info.wtmass)
    _add_scalar_point_elements(bdf, model, nodes, info.wtmass)
    _add_conm1(bdf, model, nodes, info.wtmass)
    _add_genel(bdf, model, nodes)
    add_direct_matrices(bdf, model, info, lambda dofs, card, eid: _dof_matrix(nodes, dofs, card, eid))
    _add_springs(bdf, model, nodes)
    _add_rigid(bdf, model, nodes)
    _add_raw_rigid(bdf, model, nodes)
    _add_mpcs(bdf, model, nodes, info)
    _add_spcs(bdf, model, nodes, info)
    _add_dof_sets(bdf, model, nodes, info)
    _select_eigen(bdf, info)
    if _is_preload_run(*bdf.solution):
        add_preload_stiffness(bdf, model, nodes, info, _rect_frame)
    return model, info


class _NodeTable:
    """Node id -> index and coordinates, with lookups that name the referring card.

    ``frames`` holds each grid's displacement frame (rows = axes in basic), or None when
    every grid uses the basic system.
    """

    def __init__(self, ids: np.ndarray, xyz: np.ndarray, frames: np.ndarray | None = None):
        self.ids, self.xyz, self.frames = ids, xyz, frames
        self.order = np.argsort(ids, kind="stable")
        self.sorted = ids[self.order]

    def index(self, ids, card: str, eids) -> np.ndarray:
        ids = np.asarray(ids, dtype=np.int64)
        pos = np.searchsorted(self.sorted, ids.ravel())
        pos_c = np.minimum(pos, len(self.sorted) - 1)
        ok = self.sorted[pos_c] == ids.ravel()
        if not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            eid = np.broadcast_to(np.asarray(eids)[:, None] if ids.ndim == 2 else np.asarray(eids),
                                  ids.shape).ravel()[i]
            raise ModelError(f"{card} {eid}: grid {ids.ravel()[i]} is not defined")
        return self.order[pos_c].reshape(ids.shape)

    def coords(self, ids, card: str, eids) -> np.ndarray:
        return self.xyz[self.index(ids, card, eids)]

    def frame(self, ids, card: str, eids) -> np.ndarray:
        """(..., 3, 3) displacement frames of grids ``ids`` (identity for basic)."""
        idx = self.index(ids, card, eids)
        if self.frames is None:
            return np.broadcast_to(np.eye(3), idx.shape + (3, 3)).copy()
        return self.frames[idx]

    def dof_vectors(self, ids, comps, card: str, eids) -> np.ndarray:
        """(n, 6) global DOF direction of component ``comps`` (1-6) of each grid.

        A scalar element on component c of a grid with displacement frame F acts along
        row c of F (translation or rotation axis) in basic coordinates.
        """
        comps = np.asarray(comps, dtype=np.int64)
        F = self.frame(ids, card, eids)
        out = np.zeros((len(comps), 6))
        rows = F[np.arange(len(comps)), (comps - 1) % 3]
        rot = comps > 3
        out[~rot, :3] = rows[~rot]
        out[rot, 3:] = rows[rot]
        return out


def _nodes(bdf):
    """GRID ids, basic coordinates and displacement frames (GRDSET defaults applied and
    coordinate systems resolved by :func:`trussid.fem.nastran.bulk.build_bulk`).

    A displacement system CD gives the grid's DOFs along that system's axes at the grid (for
    cylindrical and spherical systems these depend on the position): returned as frames
    whose rows are the axes in basic.
    """
    if not bdf.nodes:  # scalar points only (checked by the caller)
        return np.zeros(0, dtype=np.int64), np.zeros((0, 3)), None
    if bdf.grdset is not None and bdf.grdset.seid:
        raise ModelError("GRDSET: superelements (SEID) are not supported")
    ids = np.fromiter(bdf.nodes.keys(), dtype=np.int64, count=len(bdf.nodes))
    cd = np.fromiter((g.cd for g in bdf.nodes.values()), dtype=np.int64, count=len(ids))
    seid = [g.nid for g in bdf.nodes.values() if g.seid]
    if seid:
        raise ModelError(f"GRID {seid[0]}: superelements (SEID) are not supported")
    for nid, c in zip(ids[cd > 0], cd[cd > 0]):
        if c not in bdf.coords:
            raise ModelError(f"GRID {nid}: coordinate system CD={c} is not defined")
    xyz = bdf.xyz_basic
    frames = None
    if (cd > 0).any():
        frames = np.broadcast_to(np.eye(3), (len(ids), 3, 3)).copy()
        for c in np.unique(cd[cd > 0]):
            sel = cd == c
            frames[sel] = coord_axes(bdf.coords[int(c)], xyz[sel], f"GRID {ids[sel][0]} (CD={c})")
    return ids, xyz, frames


def coord_axes(coord, xyz: np.ndarray, label: str) -> np.ndarray:
    """Local axes (rows, in basic) of a NASTRAN coordinate system at basic points ``xyz``.

    ``coord`` has ``cid``, ``Type`` ("R", "C", "S"), ``origin`` and axes ``i``, ``j``, ``k``
    in basic (:class:`trussid.fem.nastran.bulk.Coord`).

    Rectangular: the system's axes. Cylindrical (r, theta, z) and spherical (r, theta,
    phi): the unit vectors of the coordinate directions at the point, which NASTRAN uses as
    the displacement directions of a grid with that CD. On the axis (cylindrical) or at the
    origin (spherical) those directions are undefined and the grid is refused.
    """
    R = np.vstack([coord.i, coord.j, coord.k]).astype(float)  # rows: system axes in basic
    n = len(xyz)
    if coord.Type == "R":
        return np.broadcast_to(R, (n, 3, 3)).copy()
    p = (np.asarray(xyz, float) - np.asarray(coord.origin, float)) @ R.T  # local rectangular
    rho = np.hypot(p[:, 0], p[:, 1])
    scale = max(float(np.abs(p).max(initial=0.0)), 1.0)
    if coord.Type == "C":
        if (rho <= 1e-12 * scale).any():
            raise ModelError(f"{label}: grid on the axis of cylindrical system {coord.cid}: radial "
                             f"and tangential directions are undefined")
        c, s = p[:, 0] / rho, p[:, 1] / rho
        loc = np.stack([np.stack([c, s, 0 * c], 1), np.stack([-s, c, 0 * c], 1),
                        np.broadcast_to([0.0, 0.0, 1.0], (n, 3))], axis=1)
    else:
        r = np.linalg.norm(p, axis=1)
        if (rho <= 1e-12 * scale).any():
            raise ModelError(f"{label}: grid on the polar axis of spherical system {coord.cid}: "
                             f"its directions are undefined")
        ct, st = p[:, 2] / r, rho / r
        cp_, sp_ = p[:, 0] / rho, p[:, 1] / rho
        loc = np.stack([np.stack([st * cp_, st * sp_, ct], 1), np.stack([ct * cp_, ct * sp_, -st], 1),
                        np.stack([-sp_, cp_, 0 * cp_], 1)], axis=1)
    return loc @ R


def _check_units(bdf, mats: dict, wtmass: float) -> None:
    """Warn (:class:`UnitsWarning`, once per deck) when a material used by an element has an
    E and a density that no consistent unit system gives a solid (:func:`wave_speed_problem`):
    NASTRAN would run such a deck too, with frequencies off by orders of magnitude."""
    used = set()
    for p in bdf.properties.values():
        mid = getattr(p, "mid", None)
        if mid is not None:
            used.add(int(mid))
    for mid in sorted(used & set(mats)):
        m = mats[mid]
        why = wave_speed_problem(m["E"], m["rho"], wtmass)
        if why:
            warnings.warn(f"MAT1 {mid}: {why}", UnitsWarning, stacklevel=3)
            return


def _materials(bdf, wtmass: float) -> dict:
    """MAT1 id -> dict(E, G, nu, rho); NASTRAN's rule for a blank E, G or NU is applied when
    the card is read (:func:`trussid.fem.nastran.bulk._mat1`)."""
    mats = {}
    for mid, mat in bdf.materials.items():
        mats[mid] = {"E": float(mat.e or 0.0), "G": float(mat.g or 0.0), "nu": float(mat.nu or 0.0),
                     "rho": float(mat.rho or 0.0) * wtmass, "label": f"MAT1 {mid}"}
    return mats


@dataclass
class _Prop:
    """A line property resolved to section arrays, material and mass per length."""

    label: str
    kind: str  # "bar" (bending) or "rod"
    section: dict
    mat: dict
    nsm: float
    shear: bool
    taper: tuple | None = None  # (stations x/L, section_at(xi) -> dict): a tapered PBEAM/PBEAML


def _material(mats: dict, mid: int, label: str) -> dict:
    if mid not in mats:
        raise ModelError(f"{label}: material {mid} is not defined (MAT1 expected)")
    return mats[mid]


def _section_from_shape(shape: str, dims, nu: float, label: str) -> Section:
    """A :class:`Section` for a PBARL/PBEAML shape.

    NASTRAN's element axes for these shapes (QRG PBARL figure): DIM1
    runs along element z, DIM2 along element y, so for BAR ``I1 = Izz = DIM1 DIM2^3 / 12``.
    """
    d = [float(x) for x in dims]
    need = {"ROD": 1, "TUBE": 2, "BAR": 2, "BOX": 4}[shape]
    if len(d) < need:
        raise ModelError(f"{label}: {shape} needs {need} dimensions, got {len(d)}")
    if shape == "ROD":
        return Section.circle(d[0], nu=nu, name=label)
    if shape == "TUBE":
        if not d[1] < d[0]:
            raise ModelError(f"{label}: TUBE inner radius DIM2={d[1]:g} must be less than the outer "
                             f"radius DIM1={d[0]:g}")
        return Section.tube(d[0], d[0] - d[1], nu=nu, name=label)
    if shape == "BAR":
        return Section.rectangle(b=d[1], h=d[0], nu=nu, name=label)
    if d[2] != d[3]:
        raise ModelError(f"{label}: BOX with unequal wall thicknesses (DIM3={d[2]:g}, DIM4={d[3]:g}) "
                         f"is not supported")
    return Section.box(b=d[1], h=d[0], t=d[2], nu=nu, name=label)


def _sec(A, Iy, Iz, J, Asy=math.inf, Asz=math.inf) -> dict:
    return {"A": float(A), "Iy": float(Iy), "Iz": float(Iz), "J": float(J),
            "Asy": float(Asy), "Asz": float(Asz)}


def _properties(bdf, mats: dict, wtmass: float, conventions: str = "nx") -> dict:
    props = {}
    for pid, p in bdf.properties.items():
        label = f"{p.type} {pid}"
        if p.type in ("PELAS", "PBUSH"):
            continue
        full = _material(mats, p.mid, label)
        mat = {k: full[k] for k in ("E", "G", "rho")}
        if p.type == "PBAR":
            if p.i12:
                raise ModelError(f"{label}: I12 = {p.i12:g} (non-principal axes) is not supported")
            # NASTRAN: K1/K2 blank (or 0.0) means no shear flexibility.
            k1 = math.inf if p.k1 is None or p.k1 == 0 else p.k1
            k2 = math.inf if p.k2 is None or p.k2 == 0 else p.k2
            sec = _sec(p.A, p.i2, p.i1, p.j, k1 * p.A, k2 * p.A)
            props[pid] = _Prop(label, "bar", sec, mat, float(p.nsm) * wtmass,
                               math.isfinite(k1) or math.isfinite(k2))
        elif p.type == "PBEAM":
            if np.any(np.asarray(p.i12, float) != 0):
                raise ModelError(f"{label}: I12 (non-principal axes) is not supported")
            for key in ("m1a", "m2a", "m1b", "m2b", "n1a", "n2a", "n1b", "n2b", "nsia", "nsib",
                        "cwa", "cwb"):
                if getattr(p, key, 0.0) not in (None, 0.0):
                    raise ModelError(f"{label}: {key.upper()} = {getattr(p, key):g} is not supported "
                                     f"(offsets, non-structural inertia and warping must be 0)")
            # PBEAM: K default 1.0; K = 0.0 means no shear flexibility.
            k1 = math.inf if not p.k1 else p.k1
            k2 = math.inf if not p.k2 else p.k2
            A = float(p.A[0])
            sec = _sec(A, p.i2[0], p.i1[0], p.j[0], k1 * A, k2 * A)
            props[pid] = _Prop(label, "bar", sec, mat, float(p.nsm[0]) * wtmass,
                               math.isfinite(k1) or math.isfinite(k2), _pbeam_taper(p, k1, k2, wtmass, label))
        elif p.type in ("PBARL", "PBEAML"):
            shape = str(p.beam_type).strip().upper()
            if shape not in SECTION_TYPES:
                raise ModelError(f"{label}: section type {shape} is not supported "
                                 f"(supported: {', '.join(SECTION_TYPES)})")
            taper = None
            if p.type == "PBEAML":
                dims = np.atleast_2d(np.asarray(p.dim, float))
                nsm = np.atleast_1d(np.asarray(p.nsm, float))
                if (dims != dims[0]).any() or (nsm != nsm[0]).any():
                    taper = _pbeaml_taper(p, shape, _nu_for_shear(full), conventions, wtmass, label)
                dims, nsm = dims[0], float(nsm[0])
            else:
                dims, nsm = p.dim, float(p.nsm or 0.0)
            props[pid] = _Prop(label, "bar", _shape_section(shape, dims, _nu_for_shear(full), conventions, label),
                               mat, nsm * wtmass, True, taper)
        elif p.type == "PROD":
            props[pid] = _Prop(label, "rod", _rod_sec(p.A, p.j), mat, float(p.nsm) * wtmass, False)
        elif p.type == "PTUBE":
            if p.OD2 is not None and p.OD2 != p.OD1:
                raise ModelError(f"{label}: tapered tube (OD2 != OD1) is not supported")
            r = p.OD1 / 2.0
            t = p.t if p.t else r
            s = Section.circle(r, name=label) if t >= r else Section.tube(r, t, name=label)
            props[pid] = _Prop(label, "rod", _rod_sec(s.A, s.J), mat, float(p.nsm) * wtmass, False)
    return props


def _shape_section(shape: str, dims, nu: float, conventions: str, label: str) -> dict:
    """Section arrays of a PBARL/PBEAML shape with NASTRAN's shear factors."""
    s = _section_from_shape(shape, dims, nu, label)
    asy, asz = s.Asy, s.Asz
    if shape == "ROD":
        # NASTRAN converts PBARL/PBEAML ROD to PBAR/PBEAM with K1 = K2 = 0.9 in the
        # newest builds (Simcenter 2019.2, NX 2022 ~0.898, MSC 2012-13 OP2s); one
        # MSC 2012 build used 6/7. Cowper's 6(1+nu)/(7+6nu) (0.886 at nu = 0.33)
        # sits between them; 0.9 is what the recent decks of the corpus were run with.
        asy = asz = ROD_SHEAR_FACTOR[conventions] * s.A
    elif shape == "BAR":
        asy = asz = BAR_SHEAR_FACTOR * s.A
    return _sec(s.A, s.Iy, s.Iz, s.J, asy, asz)


def _stations(xxb, label: str) -> np.ndarray:
    """Station positions x/L of a tapered PBEAM/PBEAML: 0 (end A) ... 1 (end B), ascending."""
    x = np.asarray(xxb, float).ravel()
    if len(x) < 2 or x[0] != 0.0 or x[-1] != 1.0 or not (np.diff(x) > 0).all():
        raise ModelError(f"{label}: stations X/XB must ascend from 0 to 1.0 (end B), got {x.tolist()}")
    return x


def _pbeam_taper(p, k1: float, k2: float, wtmass: float, label: str):
    """``(stations, section_at)`` of a PBEAM whose properties vary (NASTRAN: linearly between
    stations), or None for a uniform one. I2 bends about element y, I1 about z."""
    cols = {key: np.asarray(getattr(p, key), float).ravel() for key in ("A", "i1", "i2", "j", "nsm")}
    if all((v == v[0]).all() for v in cols.values()):
        return None
    x = _stations(p.xxb, label)

    def at(xi):
        f = {key: np.interp(xi, x, v) for key, v in cols.items()}
        return {"A": f["A"], "Iy": f["i2"], "Iz": f["i1"], "J": f["j"], "Asy": k1 * f["A"],
                "Asz": k2 * f["A"], "nsm": f["nsm"] * wtmass}
    return x, at


def _pbeaml_taper(p, shape: str, nu: float, conventions: str, wtmass: float, label: str):
    """``(stations, section_at)`` of a PBEAML whose dimensions vary: dimensions and NSM linear
    between stations, the section computed from the dimensions at each point."""
    x = _stations(p.xxb, label)
    dims = np.atleast_2d(np.asarray(p.dim, float))
    nsm = np.asarray(p.nsm, float).ravel()

    def at(xi):
        d = np.stack([np.interp(xi, x, dims[:, k]) for k in range(dims.shape[1])], 1)
        rows = [_shape_section(shape, di, nu, conventions, label) for di in d]
        out = {key: np.array([r[key] for r in rows]) for key in ("A", "Iy", "Iz", "J", "Asy", "Asz")}
        out["nsm"] = np.interp(xi, x, nsm) * wtmass
        return out
    return x, at


def _nu_for_shear(mat: dict) -> float:
    # Cowper's shear factors need Poisson's ratio; MAT1 with E alone has NU = 0.
    nu = mat["nu"]
    return nu if -1.0 < nu < 0.5 else 0.3


def _rod_sec(A, J) -> dict:
    # Rods have no bending: Iy, Iz are placeholders the element ignores for rods.
    return _sec(A, 1.0, 1.0, J or 0.0)


def _rod_torsion(section: dict, mat: dict) -> tuple[dict, dict]:
    """Rods whose G is 0 (a MAT1 with E alone): no torsional stiffness, as in NASTRAN.

    The element checks G > 0 for every element, so such a rod gets J = 0 and a placeholder
    G = E / 2: its torsional stiffness G J is 0 either way, and nothing else uses G.
    """
    G = np.asarray(mat["G"], float)
    zero = G == 0
    if not zero.any():
        return section, mat
    J = np.where(zero, 0.0, np.asarray(section["J"], float))
    return {**section, "J": J}, {**mat, "G": np.where(zero, np.asarray(mat["E"], float) / 2.0, G)}


def _group(items, key):
    groups = defaultdict(list)
    for item in items:
        groups[key(item)].append(item)
    return groups


def _add_bars(bdf, model: Model, nodes: _NodeTable, props: dict) -> None:
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
        if prop.section["A"] == 0 or prop.mat["G"] == 0:
            _add_spring_bars(model, group, xyz, orient, prop, eids)
            continue
        if card == "CBAR" and model.mass_formulation == "consistent":
            # NASTRAN's coupled CBAR mass has no torsional (nor rotary) inertia: the structural
            # mass goes in as non-structural mass per length, which the element gives
            # translational inertia only (the same translational mass, exactly; MSC 2020 on
            # the pt145 deck: torsion modes 2.6e-4 high with it, 3e-7 without).
            mat, nsm = {**prop.mat, "rho": 0.0}, prop.nsm + prop.mat["rho"] * prop.section["A"]
        model.add_beams(eids, ends, prop.section, mat, orient, nsm=nsm, rod=False, label=prop.label)
        pinned = np.array([bool(e.pa or e.pb) for e in group])
        if pinned.any():
            _add_pin_flags(model, [e for e, p in zip(group, pinned) if p], xyz[pinned], orient[pinned], prop)


def _add_tapered(model: Model, elems: list, ends: np.ndarray, xyz: np.ndarray, orient: np.ndarray,
                 prop: _Prop, eids: np.ndarray) -> None:
    """CBEAMs of a tapered PBEAM/PBEAML, integrated along the element
    (:func:`trussid.fem.tapered.tapered_frame_matrices`), added as element matrices."""
    card = f"{elems[0].type} {eids[0]}"
    if any(e.pa or e.pb for e in elems):
        raise ModelError(f"{card}: pin flags on a tapered beam ({prop.label}) are not supported")
    L, R = local_axes(xyz[:, 0], xyz[:, 1], orient, eids)
    breaks, at = prop.taper
    K, M = tapered_frame_matrices(L, breaks, at, prop.mat["E"], prop.mat["G"], prop.mat["rho"],
                                  theory=model.beam_theory, mass=model.mass_formulation,
                                  torsion_lumped=elems[0].type == "CBEAM", label=prop.label)
    model.add_matrices(eids, ends, K=to_global(K, R), M=to_global(M, R), label=f"{prop.label} (tapered)")


def _add_spring_bars(model: Model, elems: list, xyz: np.ndarray, orient: np.ndarray, prop: _Prop,
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
    G0 = mat["G"] == 0
    if G0 and model.beam_theory == "timoshenko" and (math.isfinite(sec["Asy"]) or math.isfinite(sec["Asz"])):
        raise ModelError(f"{card}: {prop.label} has shear flexibility with G = 0 (infinite shear flexibility)")
    A0 = sec["A"] == 0
    L, R = local_axes(xyz[:, 0], xyz[:, 1], orient, eids)
    K, M = frame_matrices(L, 1.0 if A0 else sec["A"], sec["Iy"], sec["Iz"], sec["J"], mat["E"],
                          mat["E"] / 2.0 if G0 else mat["G"], 0.0 if A0 else mat["rho"],
                          nsm=prop.nsm, Asy=sec["Asy"], Asz=sec["Asz"], theory=model.beam_theory,
                          mass=model.mass_formulation)
    zero = ([0, 6] if A0 else []) + ([3, 9] if G0 else [])
    K[:, zero, :] = 0.0
    K[:, :, zero] = 0.0
    ends = np.array([[e.ga, e.gb] if e.type == "CBAR" else e.nodes for e in elems], dtype=np.int64)
    model.add_matrices(eids, ends, K=to_global(K, R), M=to_global(M, R),
                       label=f"{prop.label} ({'A = 0' if A0 else 'G = 0'})")


def _add_pin_flags(model: Model, elems: list, xyz: np.ndarray, orient: np.ndarray, prop: _Prop) -> None:
    """CBAR/CBEAM pin flags PA/PB: the released end DOFs (element axes) carry no force.

    The element's stiffness is condensed statically on the released DOFs, one at a time
    (a DOF already free after earlier releases is skipped), and the difference from the
    unpinned element is added as an element matrix, so the beam itself stays a plain beam.
    The mass is unchanged (NASTRAN's pin flags act on the stiffness).
    """
    eids = np.array([e.eid for e in elems], dtype=np.int64)
    L, R = local_axes(xyz[:, 0], xyz[:, 1], orient, eids)
    sec, mat = prop.section, prop.mat
    K = frame_matrices(L, sec["A"], sec["Iy"], sec["Iz"], sec["J"], mat["E"], mat["G"], mat["rho"],
                       Asy=sec["Asy"], Asz=sec["Asz"], theory=model.beam_theory)[0]
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


def _add_rods(bdf, model: Model, nodes: _NodeTable, props: dict, mats: dict, wtmass: float) -> None:
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
        section, mat = _rod_torsion(prop.section, prop.mat)
        model.add_beams(eids, ends, section, mat, _rod_orient(nodes, ends, "CROD", eids),
                        nsm=prop.nsm, rod=True, label=prop.label)
    conrods = [e for e in bdf.elements.values() if e.type == "CONROD"]
    if conrods:
        eids = np.array([e.eid for e in conrods], dtype=np.int64)
        ends = np.array([e.nodes for e in conrods], dtype=np.int64)
        m = [_material(mats, e.mid, f"CONROD {e.eid}") for e in conrods]
        sec = {"A": [e.A for e in conrods], "Iy": 1.0, "Iz": 1.0, "J": [e.j or 0.0 for e in conrods],
               "Asy": math.inf, "Asz": math.inf}
        sec = {k: np.broadcast_to(np.asarray(v, float), (len(eids),)) for k, v in sec.items()}
        sec, mat = _rod_torsion(sec, {k: np.array([mi[k] for mi in m]) for k in ("E", "G", "rho")})
        nsm = np.array([e.nsm or 0.0 for e in conrods]) * wtmass
        model.add_beams(eids, ends, sec, mat, _rod_orient(nodes, ends, "CONROD", eids), nsm=nsm,
                        rod=True, label="CONROD")


def _rod_orient(nodes: _NodeTable, ends: np.ndarray, card: str, eids: np.ndarray) -> np.ndarray:
    """Some vector not parallel to each rod (rods have no bending; the element wants axes)."""
    xyz = nodes.coords(ends, card, eids)
    d = np.abs(xyz[:, 1] - xyz[:, 0])
    return np.eye(3)[np.argmin(d, axis=1)]


def _rect_frame(bdf, cid: int, card: str) -> np.ndarray:
    """Rows = axes of rectangular coordinate system ``cid`` in basic coordinates."""
    if cid == 0:
        return np.eye(3)
    if cid not in bdf.coords:
        raise ModelError(f"{card}: coordinate system {cid} is not defined")
    coord = bdf.coords[cid]
    if coord.Type != "R":
        raise ModelError(f"{card}: coordinate system {cid} is not rectangular (only CORD1R/CORD2R "
                         f"are supported here)")
    return np.vstack([coord.i, coord.j, coord.k]).astype(float)


def _add_masses(bdf, model: Model, nodes: _NodeTable, wtmass: float) -> None:
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
        R = _rect_frame(bdf, int(cid[i]), f"CONM2 {eids[i]}")
        offset[i] = R.T @ X[i]
        tensor[i] = R.T @ tensor[i] @ R
    bad = mass < 0
    if bad.any():
        raise ModelError(f"CONM2 {eids[bad][0]}: mass must be >= 0, got {mass[bad][0]:g}")
    model.add_point_masses(nids, mass * wtmass, inertia=tensor * wtmass, offset=offset)


def _scalar_ends(e, card: str, nodes: _NodeTable):
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


def _add_scalar_elements(model: Model, nodes: _NodeTable, ends: list, values: np.ndarray, eids: np.ndarray,
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


def _add_springs(bdf, model: Model, nodes: _NodeTable) -> None:
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


def _add_scalar_masses(bdf, model: Model, nodes: _NodeTable, wtmass: float) -> None:
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


def _add_bushes(bdf, model: Model, nodes: _NodeTable) -> None:
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
            frame = _rect_frame(bdf, int(e.cid), card)
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


def _add_rigid_element(model: Model, nodes: _NodeTable, eid: int, grids, independent, dependent,
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


def _add_rigid(bdf, model: Model, nodes: _NodeTable) -> None:
    """RBE2 (rigid body), RBAR (rigid bar, any independent set) and RBE3 (interpolation)."""
    for eid, e in sorted(bdf.rigid_elements.items()):
        card = f"{e.type} {eid}"
        if e.type == "RBE2":
            nodes.index([e.gn], "RBE2", [eid])
            nodes.index(np.asarray(e.Gmi, dtype=np.int64), "RBE2", [eid] * len(e.Gmi))
            dofs = "".join(str(c + 1) for c in _comps(e.cm, card))
            model.add_rigid_body(eid, e.gn, e.Gmi, dofs=dofs, mass=0.0, label=card)
        elif e.type == "RBAR":
            ind = [(e.ga, c) for c in _comps(e.cna, card)] + [(e.gb, c) for c in _comps(e.cnb, card)]
            cma, cmb = _comps(e.cma, card), _comps(e.cmb, card)
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
                mask[_comps(c, card)] = True
                for g in grids:
                    rows.append(int(g))
                    comps.append(mask)
                    weights.append(float(w))
            rows_a = np.array(rows, dtype=np.int64)
            comps_a = np.array(comps, dtype=bool).reshape(-1, 6)
            refc = np.zeros(6, bool)
            refc[_comps(e.refc, card)] = True
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


def _add_raw_rigid(bdf, model: Model, nodes: _NodeTable) -> None:
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
                gi, gms = int(f[2]), _ints(f[3:], card)
                nodes.index([gi] + gms, name, [eid] * (1 + len(gms)))
                model.add_rigid_body(eid, gi, gms, dofs="123456", label=card)
            elif name == "CRIGD2":
                gi = int(f[2])
                vals = [x for x in f[3:] if x]
                pairs = list(zip(vals[0::2], vals[1::2]))
                grids = [gi] + [int(g) for g, _ in pairs]
                ind = [(gi, c) for c in range(6)]
                dep = [(int(g), c) for g, cm in pairs for c in _comps(cm, card)]
                _add_rigid_element(model, nodes, eid, grids, ind, dep, card)
            elif name == "CRIGD3":
                vals = [x for x in f[2:] if x]
                if "MSET" not in vals:
                    raise ModelError(f"{card}: no MSET (dependent components) given")
                k = vals.index("MSET")
                ind = [(int(g), c) for g, cm in zip(vals[:k:2], vals[1:k:2]) for c in _comps(cm, card)]
                dep = [(int(g), c) for g, cm in zip(vals[k + 1::2], vals[k + 2::2]) for c in _comps(cm, card)]
                grids = [g for g, _ in ind + dep]
                _add_rigid_element(model, nodes, eid, grids, ind, dep, card)
            else:  # CRIGDR
                gi, gm, cm = int(f[2]), int(f[3]), int(f[4])
                _add_rigid_rod(model, nodes, eid, gi, gm, cm, card)
        except (IndexError, ValueError):
            raise ModelError(f"{card}: malformed entry") from None


def _dof_matrix(nodes: _NodeTable, dofs: list, card: str, eid: int) -> tuple[list, np.ndarray]:
    """(grids, A): A maps the grids' 6-DOF vectors (basic) to the listed (grid, component) DOFs."""
    grids = list(dict.fromkeys(g for g, _ in dofs))
    pos = {g: i for i, g in enumerate(grids)}
    spoints = getattr(nodes, "spoints", set())
    dofs = [(g, 1 if g in spoints and c == 0 else c) for g, c in dofs]  # a scalar point's DOF
    for g, c in dofs:
        if g in spoints and c != 1:
            raise ModelError(f"{card}: scalar point {g} has component 0 only, got {c}")
        if not 1 <= c <= 6:
            raise ModelError(f"{card}: component {c} of grid {g} must be 1-6 (0 or blank only on a scalar point)")
    vec = nodes.dof_vectors([g for g, _ in dofs], [c for _, c in dofs], card.split()[0], [eid] * len(dofs))
    A = np.zeros((len(dofs), 6 * len(grids)))
    for k, (g, _c) in enumerate(dofs):
        A[k, 6 * pos[g]:6 * pos[g] + 6] = vec[k]
    return grids, A


def _add_conm1(bdf, model: Model, nodes: _NodeTable, wtmass: float) -> None:
    """CONM1: a 6x6 mass matrix at a grid (lower triangle by rows, in system CID), times WTMASS.

    Read from its fields, so that a blank is NASTRAN's 0.0 and a malformed entry is named.
    """
    for eid, f in _raw_cards(bdf, "CONM1"):
        card = f"CONM1 {eid}"
        try:
            g = int(f[2])
            cid = int(f[3]) if f[3] else 0
            vals = [float(_nastran_value(v)) if v else 0.0 for v in (f[4:25] + [""] * 21)[:21]]
        except (IndexError, ValueError, TypeError):
            raise ModelError(f"{card}: malformed entry (GRID, CID and 21 mass terms expected)") from None
        M = np.zeros((6, 6))
        M[np.tril_indices(6)] = vals  # row-wise lower triangle: M11, M21, M22, M31, ...
        M = M + np.tril(M, -1).T
        if cid:
            R = _rect_frame(bdf, cid, card)
            R6 = np.kron(np.eye(2), R)
            M = R6.T @ M @ R6
        nodes.index([g], "CONM1", [eid])
        model.add_matrices([eid], [[g]], M=[M * wtmass], label="CONM1")


def _genel_fields(f: list, card: str) -> tuple[list, list, str, list, list | None]:
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
        return [float(_nastran_value(v)) for v in seg]

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


def _add_genel(bdf, model: Model, nodes: _NodeTable) -> None:
    """GENEL: a general element given by its stiffness K or flexibility Z with rigid-body
    matrix S (:func:`trussid.fem.general_element.general_element_stiffness`), on grid
    components or scalar points."""
    for eid, f in _raw_cards(bdf, "GENEL"):
        card = f"GENEL {eid}"
        try:
            ui, ud, kind, kz, s_terms = _genel_fields(f, card)
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
        grids, A = _dof_matrix(nodes, ui + ud, card, eid)
        Kg = A.T @ full @ A
        model.add_matrices([eid], [grids], K=[0.5 * (Kg + Kg.T)], label="GENEL")


def _add_rigid_rod(model: Model, nodes: _NodeTable, eid: int, gi: int, gm: int, cm: int, card: str) -> None:
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


def _add_mpcs(bdf, model: Model, nodes: _NodeTable, info: BdfInfo) -> None:
    """MPC (through MPCADD) of the case control's MPC set: the first term is dependent."""
    chosen = _case_int(bdf, "MPC")
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
    qpoints = set(_qset_points(bdf)) & bdf.spoints
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
                    model.fix([int(g[0])], str(_comps(c.components[0], card)[0] + 1))
                    continue
            comp = [[0] if int(gi) in nodes.spoints and str(x).strip() in ("0", "") else _comps(x, card)
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


def _add_dof_sets(bdf, model: Model, nodes: _NodeTable, info: BdfInfo) -> None:
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
                mask[i, [0] if on_spoint else _comps(cm, what)] = True
        return mask

    omits, asets = bdf.omits, bdf.asets
    if omits or asets:
        omitted = mask_of(omits, "OMIT")
        if asets:
            omitted |= ~mask_of(asets, "ASET")
        qpoints = _qset_points(bdf) if _component_mode_reduction(bdf) else []
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
        extseout = _case_has(bdf, "EXTSEOUT")
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
                held[i, _comps(cm, "SUPORT")] = True
        for c in range(6):
            if held[:, c].any():
                model.fix(nodes.ids[held[:, c]], str(c + 1))
        info.notes.append(f"SOL 31 (MYSTRAN Craig-Bampton): the {int(held.sum())} SUPORT DOFs are the reduction "
                          f"boundary, held for the fixed-interface modes MYSTRAN prints")
    elif suport:
        info.notes.append("SUPORT accepted: it selects reference DOFs for NASTRAN's rigid-body modes, "
                          "which trussid computes anyway (they come first, at about 0 Hz)")


#: Scalar elements between scalar points, read from their raw fields (two elements may share
#: one entry: EID, PID or value, S1, S2, then a second EID...).
SCALAR_POINT_CARDS = ("CELAS3", "CELAS4", "CMASS3", "CMASS4")


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
        for eid, f in _raw_cards(bdf, name):
            for k in (3, 4, 7, 8):
                if k < len(f) and f[k]:
                    try:
                        refs.add(int(f[k]))
                    except ValueError:
                        raise ModelError(f"{name} {eid}: scalar point field {k} is {f[k]!r}, not a point id") from None
    mpc_refs = set()
    for sid in _case_int(bdf, "MPC")[:1]:
        for c in bdf.mpcs.get(int(sid), []):
            mpc_refs |= {int(n) for n, cm in zip(c.nodes, c.components) if str(cm).strip() in ("0", "")}
    for eid, f in _raw_cards(bdf, "GENEL"):  # a GENEL's scalar points need their SPOINT, like an MPC's
        try:
            ui, ud, *_ = _genel_fields(f, f"GENEL {eid}")
        except (ModelError, ValueError, TypeError):
            continue  # reported, naming the entry, when the element is built
        mpc_refs |= {g for g, c in ui + ud if c == 0}
    return refs, mpc_refs


def _qset_points(bdf) -> list:
    """Ids on QSET/QSET1 entries, in deck order (each once)."""
    ids = []
    for q in bdf.qsets:
        ids.extend(int(n) for n in q.ids)
    return list(dict.fromkeys(ids))


def _component_mode_reduction(bdf) -> bool:
    """QSET with ASET/OMIT and no BSET: a Craig-Bampton reduction whose modes are solved (the
    B-set case prints the fixed-interface modes instead, see :func:`_add_dof_sets`)."""
    return bool(bdf.qsets) and bool(bdf.asets or bdf.omits) and not bdf.bsets


def _scalar_points(bdf, grids: set, info: BdfInfo) -> list:
    """Ids of the SPOINTs that something connects (sorted); the others are noted and ignored."""
    spoints = set(bdf.spoints)
    qset = set(_qset_points(bdf))
    elem_refs, mpc_refs = _scalar_point_refs(bdf)
    if _component_mode_reduction(bdf) and (elem_refs | mpc_refs) & qset:
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
    if _component_mode_reduction(bdf):
        refs |= qset  # the generalized coordinates of the reduction
    used = sorted(refs & spoints)
    idle = sorted(spoints - refs - qset)
    if idle:
        info.notes.append(f"SPOINT {', '.join(map(str, idle[:5]))}{' ...' if len(idle) > 5 else ''}: unconnected "
                          f"scalar point(s), no effect on the modes: ignored")
    return used


def _add_scalar_point_elements(bdf, model: Model, nodes: _NodeTable, wtmass: float) -> None:
    """CELAS3/CELAS4 springs and CMASS3/CMASS4 masses between scalar points (or to ground)."""
    for name in SCALAR_POINT_CARDS:
        kind = "K" if name.startswith("CELAS") else "M"
        ends, values, eids = [], [], []
        for _eid, f in _raw_cards(bdf, name):
            f = f + [""] * 9
            for base in (1, 5):  # a second element on the same entry starts in field 5
                if not f[base]:
                    continue
                try:
                    eid = int(f[base])
                    ref = int(f[base + 1]) if name.endswith("3") else float(_nastran_value(f[base + 1]))
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


def _add_spcs(bdf, model: Model, nodes: _NodeTable, info: BdfInfo) -> None:
    """SPC/SPC1 (through SPCADD) of the case control's SPC set, else of all sets; GRID PS."""
    all_sets = set(bdf.spcs) | set(bdf.spcadds)
    chosen = _case_int(bdf, "SPC")
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
