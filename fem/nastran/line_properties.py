"""MAT1 materials and the line-element properties (PBAR, PBEAM, PBARL, PBEAML, PROD, PTUBE)
of a deck, resolved to per-element section and material arrays with NASTRAN's shear factors
and defaults, tapered beams as a section along the element.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

from trussid.fem.errors import ModelError, UnitsWarning
from trussid.fem.materials import wave_speed_problem
from trussid.fem.nastran.conventions import BAR_SHEAR_FACTOR, ROD_SHEAR_FACTOR
from trussid.fem.nastran.entries import SECTION_TYPES
from trussid.fem.sections import Section

__all__ = ["LineProperty", "deck_materials", "check_units", "line_properties", "material_of",
           "rod_torsion"]


def check_units(bdf, mats: dict, wtmass: float) -> None:
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


def deck_materials(bdf, wtmass: float) -> dict:
    """MAT1 id -> dict(E, G, nu, rho); NASTRAN's rule for a blank E, G or NU is applied when
    the card is read (:func:`trussid.fem.nastran.bulk._mat1`)."""
    mats = {}
    for mid, mat in bdf.materials.items():
        mats[mid] = {"E": float(mat.e or 0.0), "G": float(mat.g or 0.0), "nu": float(mat.nu or 0.0),
                     "rho": float(mat.rho or 0.0) * wtmass, "label": f"MAT1 {mid}"}
    return mats


@dataclass
class LineProperty:
    """A line property resolved to section arrays, material and mass per length."""

    label: str
    kind: str  # "bar" (bending) or "rod"
    section: dict
    mat: dict
    nsm: float
    shear: bool
    taper: tuple | None = None  # (stations x/L, section_at(xi) -> dict): a tapered PBEAM/PBEAML


def material_of(mats: dict, mid: int, label: str) -> dict:
    if mid not in mats:
        raise ModelError(f"{label}: material {mid} is not defined (MAT1 expected)")
    return mats[mid]


def section_from_shape(shape: str, dims, nu: float, label: str) -> Section:
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


def line_properties(bdf, mats: dict, wtmass: float, conventions: str = "nx") -> dict:
    props = {}
    for pid, p in bdf.properties.items():
        label = f"{p.type} {pid}"
        if p.type in ("PELAS", "PBUSH"):
            continue
        full = material_of(mats, p.mid, label)
        mat = {k: full[k] for k in ("E", "G", "rho")}
        if p.type == "PBAR":
            if p.i12:
                raise ModelError(f"{label}: I12 = {p.i12:g} (non-principal axes) is not supported")
            # NASTRAN: K1/K2 blank (or 0.0) means no shear flexibility.
            k1 = math.inf if p.k1 is None or p.k1 == 0 else p.k1
            k2 = math.inf if p.k2 is None or p.k2 == 0 else p.k2
            sec = _sec(p.A, p.i2, p.i1, p.j, k1 * p.A, k2 * p.A)
            props[pid] = LineProperty(label, "bar", sec, mat, float(p.nsm) * wtmass,
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
            props[pid] = LineProperty(label, "bar", sec, mat, float(p.nsm[0]) * wtmass,
                               math.isfinite(k1) or math.isfinite(k2), pbeam_taper(p, k1, k2, wtmass, label))
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
                    taper = pbeaml_taper(p, shape, nu_for_shear(full), conventions, wtmass, label)
                dims, nsm = dims[0], float(nsm[0])
            else:
                dims, nsm = p.dim, float(p.nsm or 0.0)
            props[pid] = LineProperty(label, "bar", shape_section(shape, dims, nu_for_shear(full), conventions, label),
                               mat, nsm * wtmass, True, taper)
        elif p.type == "PROD":
            props[pid] = LineProperty(label, "rod", rod_section(p.A, p.j), mat, float(p.nsm) * wtmass, False)
        elif p.type == "PTUBE":
            if p.OD2 is not None and p.OD2 != p.OD1:
                raise ModelError(f"{label}: tapered tube (OD2 != OD1) is not supported")
            r = p.OD1 / 2.0
            t = p.t if p.t else r
            s = Section.circle(r, name=label) if t >= r else Section.tube(r, t, name=label)
            props[pid] = LineProperty(label, "rod", rod_section(s.A, s.J), mat, float(p.nsm) * wtmass, False)
    return props


def shape_section(shape: str, dims, nu: float, conventions: str, label: str) -> dict:
    """Section arrays of a PBARL/PBEAML shape with NASTRAN's shear factors."""
    s = section_from_shape(shape, dims, nu, label)
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


def taper_stations(xxb, label: str) -> np.ndarray:
    """Station positions x/L of a tapered PBEAM/PBEAML: 0 (end A) ... 1 (end B), ascending."""
    x = np.asarray(xxb, float).ravel()
    if len(x) < 2 or x[0] != 0.0 or x[-1] != 1.0 or not (np.diff(x) > 0).all():
        raise ModelError(f"{label}: stations X/XB must ascend from 0 to 1.0 (end B), got {x.tolist()}")
    return x


def pbeam_taper(p, k1: float, k2: float, wtmass: float, label: str):
    """``(stations, section_at)`` of a PBEAM whose properties vary (NASTRAN: linearly between
    stations), or None for a uniform one. I2 bends about element y, I1 about z."""
    cols = {key: np.asarray(getattr(p, key), float).ravel() for key in ("A", "i1", "i2", "j", "nsm")}
    if all((v == v[0]).all() for v in cols.values()):
        return None
    x = taper_stations(p.xxb, label)

    def at(xi):
        f = {key: np.interp(xi, x, v) for key, v in cols.items()}
        return {"A": f["A"], "Iy": f["i2"], "Iz": f["i1"], "J": f["j"], "Asy": k1 * f["A"],
                "Asz": k2 * f["A"], "nsm": f["nsm"] * wtmass}
    return x, at


def pbeaml_taper(p, shape: str, nu: float, conventions: str, wtmass: float, label: str):
    """``(stations, section_at)`` of a PBEAML whose dimensions vary: dimensions and NSM linear
    between stations, the section computed from the dimensions at each point."""
    x = taper_stations(p.xxb, label)
    dims = np.atleast_2d(np.asarray(p.dim, float))
    nsm = np.asarray(p.nsm, float).ravel()

    def at(xi):
        d = np.stack([np.interp(xi, x, dims[:, k]) for k in range(dims.shape[1])], 1)
        rows = [shape_section(shape, di, nu, conventions, label) for di in d]
        out = {key: np.array([r[key] for r in rows]) for key in ("A", "Iy", "Iz", "J", "Asy", "Asz")}
        out["nsm"] = np.interp(xi, x, nsm) * wtmass
        return out
    return x, at


def nu_for_shear(mat: dict) -> float:
    # Cowper's shear factors need Poisson's ratio; MAT1 with E alone has NU = 0.
    nu = mat["nu"]
    return nu if -1.0 < nu < 0.5 else 0.3


def rod_section(A, J) -> dict:
    # Rods have no bending: Iy, Iz are placeholders the element ignores for rods.
    return _sec(A, 1.0, 1.0, J or 0.0)


def rod_torsion(section: dict, mat: dict) -> tuple[dict, dict]:
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
