"""MAT1 materials and the line-element properties (PBAR, PBEAM, PBARL, PBEAML, PROD, PTUBE)
of a deck, resolved to per-element section and material arrays with NASTRAN's shear factors
and defaults, tapered beams as a section along the element.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from trussid.fem.errors import ModelError, UnitsWarning
from trussid.fem.materials import wave_speed_problem
from trussid.fem.nastran.conventions import BAR_SHEAR_FACTOR, ROD_SHEAR_FACTOR
from trussid.fem.nastran.entries import SECTION_TYPES
from trussid.fem.properties import SECTION_FIELDS, MaterialArrays, SectionArrays
from trussid.fem.sections import Section

__all__ = ["DeckMaterial", "Taper", "LineProperty", "deck_materials", "check_units", "line_properties",
           "material_of", "rod_torsion"]


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
        why = wave_speed_problem(m.E, m.rho, wtmass)
        if why:
            warnings.warn(f"MAT1 {mid}: {why}", UnitsWarning, stacklevel=3)
            return


@dataclass(frozen=True)
class DeckMaterial:
    """A MAT1 as the elements use it: E, G [Pa], NU and the density times WTMASS, in the
    deck's units."""

    label: str
    E: float
    G: float
    nu: float
    rho: float

    def arrays(self) -> MaterialArrays:
        """E, G and density as the model's :class:`~trussid.fem.MaterialArrays`."""
        return MaterialArrays(self.E, self.G, self.rho, name=self.label)

    def nu_for_shear(self) -> float:
        """Poisson's ratio for Cowper's shear factors (0.3 when the MAT1 gives E alone, NU = 0
        then, or a NU no solid has)."""
        return self.nu if -1.0 < self.nu < 0.5 else 0.3


def deck_materials(bdf, wtmass: float) -> dict[int, DeckMaterial]:
    """MAT1 id -> :class:`DeckMaterial`; NASTRAN's rule for a blank E, G or NU is applied when
    the card is read (:func:`trussid.fem.nastran.bulk._mat1`)."""
    return {mid: DeckMaterial(f"MAT1 {mid}", float(mat.e or 0.0), float(mat.g or 0.0), float(mat.nu or 0.0),
                              float(mat.rho or 0.0) * wtmass)
            for mid, mat in bdf.materials.items()}


@dataclass(frozen=True)
class Taper:
    """A tapered PBEAM/PBEAML: stations ``x / L`` (0 ... 1) and the section and non-structural
    mass per length at any ``xi`` (:func:`trussid.fem.tapered.tapered_frame_matrices`)."""

    stations: np.ndarray
    section_at: Callable[[np.ndarray], SectionArrays]
    nsm_at: Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class LineProperty:
    """A line property resolved to section arrays, material and mass per length."""

    label: str
    kind: str  # "bar" (bending) or "rod"
    section: SectionArrays
    mat: MaterialArrays
    nsm: float
    shear: bool
    taper: Taper | None = None


def material_of(mats: dict, mid: int, label: str) -> DeckMaterial:
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


def _sec(A, Iy, Iz, J, Asy=math.inf, Asz=math.inf, name: str = "section") -> SectionArrays:
    return SectionArrays(float(A), float(Iy), float(Iz), float(J), float(Asy), float(Asz), name=name)


def line_properties(bdf, mats: dict, wtmass: float, conventions: str = "nx") -> dict:
    props = {}
    for pid, p in bdf.properties.items():
        label = f"{p.type} {pid}"
        if p.type in ("PELAS", "PBUSH"):
            continue
        full = material_of(mats, p.mid, label)
        mat = full.arrays()
        if p.type == "PBAR":
            if p.i12:
                raise ModelError(f"{label}: I12 = {p.i12:g} (non-principal axes) is not supported")
            # NASTRAN: K1/K2 blank (or 0.0) means no shear flexibility.
            k1 = math.inf if p.k1 is None or p.k1 == 0 else p.k1
            k2 = math.inf if p.k2 is None or p.k2 == 0 else p.k2
            sec = _sec(p.A, p.i2, p.i1, p.j, k1 * p.A, k2 * p.A, label)
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
            sec = _sec(A, p.i2[0], p.i1[0], p.j[0], k1 * A, k2 * A, label)
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
                    taper = pbeaml_taper(p, shape, full.nu_for_shear(), conventions, wtmass, label)
                dims, nsm = dims[0], float(nsm[0])
            else:
                dims, nsm = p.dim, float(p.nsm or 0.0)
            props[pid] = LineProperty(label, "bar", shape_section(shape, dims, full.nu_for_shear(), conventions, label),
                               mat, nsm * wtmass, True, taper)
        elif p.type == "PROD":
            props[pid] = LineProperty(label, "rod", rod_section(p.A, p.j, label), mat, float(p.nsm) * wtmass, False)
        elif p.type == "PTUBE":
            if p.OD2 is not None and p.OD2 != p.OD1:
                raise ModelError(f"{label}: tapered tube (OD2 != OD1) is not supported")
            r = p.OD1 / 2.0
            t = p.t if p.t else r
            s = Section.circle(r, name=label) if t >= r else Section.tube(r, t, name=label)
            props[pid] = LineProperty(label, "rod", rod_section(s.A, s.J, label), mat, float(p.nsm) * wtmass, False)
    return props


def shape_section(shape: str, dims, nu: float, conventions: str, label: str) -> SectionArrays:
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
    return _sec(s.A, s.Iy, s.Iz, s.J, asy, asz, label)


def taper_stations(xxb, label: str) -> np.ndarray:
    """Station positions x/L of a tapered PBEAM/PBEAML: 0 (end A) ... 1 (end B), ascending."""
    x = np.asarray(xxb, float).ravel()
    if len(x) < 2 or x[0] != 0.0 or x[-1] != 1.0 or not (np.diff(x) > 0).all():
        raise ModelError(f"{label}: stations X/XB must ascend from 0 to 1.0 (end B), got {x.tolist()}")
    return x


def pbeam_taper(p, k1: float, k2: float, wtmass: float, label: str) -> Taper | None:
    """The :class:`Taper` of a PBEAM whose properties vary (NASTRAN: linearly between
    stations), or None for a uniform one. I2 bends about element y, I1 about z."""
    A, i1, i2, j, nsm = (np.asarray(getattr(p, key), float).ravel() for key in ("A", "i1", "i2", "j", "nsm"))
    if all((v == v[0]).all() for v in (A, i1, i2, j, nsm)):
        return None
    x = taper_stations(p.xxb, label)

    def at(xi):
        a = np.interp(xi, x, A)
        return SectionArrays(a, np.interp(xi, x, i2), np.interp(xi, x, i1), np.interp(xi, x, j), k1 * a, k2 * a,
                             name=label)
    return Taper(x, at, lambda xi: np.interp(xi, x, nsm) * wtmass)


def pbeaml_taper(p, shape: str, nu: float, conventions: str, wtmass: float, label: str) -> Taper:
    """The :class:`Taper` of a PBEAML whose dimensions vary: dimensions and NSM linear between
    stations, the section computed from the dimensions at each point."""
    x = taper_stations(p.xxb, label)
    dims = np.atleast_2d(np.asarray(p.dim, float))
    nsm = np.asarray(p.nsm, float).ravel()

    def at(xi):
        d = np.stack([np.interp(xi, x, dims[:, k]) for k in range(dims.shape[1])], 1)
        rows = [shape_section(shape, di, nu, conventions, label) for di in d]
        return SectionArrays(*(np.array([getattr(r, key) for r in rows]) for key in SECTION_FIELDS), name=label)
    return Taper(x, at, lambda xi: np.interp(xi, x, nsm) * wtmass)


def rod_section(A, J, label: str = "rod") -> SectionArrays:
    # Rods have no bending: Iy, Iz are placeholders the element ignores for rods.
    return _sec(A, 1.0, 1.0, J or 0.0, name=label)


def rod_torsion(section: SectionArrays, mat: MaterialArrays) -> tuple[SectionArrays, MaterialArrays]:
    """Rods whose G is 0 (a MAT1 with E alone): no torsional stiffness, as in NASTRAN.

    The element checks G > 0 for every element, so such a rod gets J = 0 and a placeholder
    G = E / 2: its torsional stiffness G J is 0 either way, and nothing else uses G.
    """
    zero = mat.G == 0
    if not zero.any():
        return section, mat
    return (dataclasses.replace(section, J=np.where(zero, 0.0, section.J)),
            dataclasses.replace(mat, G=np.where(zero, mat.E / 2.0, mat.G)))
