"""MODEL arguments of the command line: a NASTRAN deck, a testbed .toml file, or nothing.

:func:`load_structure` turns any of these into a :class:`LoadedStructure` for ``trussid
modes``, ``render`` and ``plant``; :func:`testbed_spec` reads a testbed parameter file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from trussid._util.errors import UserError

#: File suffixes read as NASTRAN bulk data.
BULK_SUFFIXES = (".bdf", ".dat", ".nas", ".blk", ".bulk")
@dataclass
class LoadedStructure:
    """A model ready to assemble, with what a report should say about it.

    Attributes
    ----------
    model : fem.Model
    source : str
        The file it came from, or "default testbed".
    autospc : bool
        Remove DOFs with neither stiffness nor mass when assembling (NASTRAN's AUTOSPC).
    n_modes : int or None
        Number of modes the source asks for (a deck's EIGRL ND), if any.
    units : str
        How to read the numbers ("SI", or the deck's own units).
    notes : list of str
        One-line facts for the report (mass formulation and why, beam theory, WTMASS...).
    info : object or None
        Source-specific details (:class:`trussid.fem.nastran.BdfInfo` for decks).
    testbed : trussid.testbed.model.TestbedModel or None
        The testbed behind the model (for labels, solids, actuators and sensors), or None.
    """

    model: object
    source: str
    autospc: bool = False
    n_modes: int | None = None
    units: str = "SI"
    notes: list = field(default_factory=list)
    info: object | None = None
    testbed: object | None = None


def load_structure(path: str | os.PathLike | None, conventions: str | None = None) -> LoadedStructure:
    """Load MODEL as the command line gives it: None, a .toml testbed file or a bulk-data deck.

    ``conventions`` ("nx" or "msc", default "nx") is the NASTRAN build whose element
    conventions a deck is read with (:func:`trussid.fem.nastran.read_bdf`); it has no
    meaning for a testbed and is refused there.
    """
    if path is None:
        if conventions is not None:
            raise UserError("--conventions applies to NASTRAN decks, not to the default testbed")
        return testbed_structure(None)
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix in BULK_SUFFIXES:
        return deck_structure(p, conventions)
    if conventions is not None:
        raise UserError(f"--conventions applies to NASTRAN decks ({', '.join(BULK_SUFFIXES)}), not to {p}")
    if suffix == ".toml":
        return testbed_structure(p)
    raise UserError(f"{p}: unknown model file type {suffix or '(no suffix)'!r}; give a NASTRAN deck "
                    f"({', '.join(BULK_SUFFIXES)}) or a testbed parameter file (.toml)")


def testbed_spec(path: str | os.PathLike | None):
    """The :class:`trussid.geometry.Testbed` of a parameter file (.toml), or the default."""
    from trussid.geometry.params_toml import load_testbed
    from trussid.geometry.spec import Testbed

    if path is None:
        return Testbed()
    p = Path(path)
    if p.suffix.lower() != ".toml":
        raise UserError(f"{p}: give a testbed parameter file (.toml), or no MODEL for the "
                        "default testbed")
    return load_testbed(p)


def testbed_structure(path: Path | None) -> LoadedStructure:
    """The testbed model from a parameter file, or the default testbed when ``path`` is None.

    ``testbed`` is the :class:`trussid.testbed.model.TestbedModel` (model, map of nodes and
    elements, the parameters), so that commands can label modes or find actuators and sensors.
    """
    from trussid.geometry.spec import INCH
    from trussid.testbed.model import build_testbed

    tb = testbed_spec(path)
    tbm = build_testbed(tb)
    s = tb.struts
    ends = " / ".join("clamped" if k == float("inf") else f"flexure {k:g} N m/rad"
                      for k in (s.base_rotational_stiffness, s.top_rotational_stiffness))
    notes = [f"testbed: tube OD {s.outer_diameter / INCH:.4g} in, walls "
             f"{', '.join(f'{t / INCH:.3f}' for t in s.walls)} in; strut ends (base / top): {ends}; "
             f"base {tb.base.support}",
             f"mass: {tbm.model.mass_formulation}; beam theory: {tbm.model.beam_theory}",
             "labels: where each mode's kinetic and strain energy sits (trussid.testbed.labels)"]
    return LoadedStructure(model=tbm.model, source="default testbed" if path is None else str(path),
                           notes=notes, testbed=tbm)


def deck_structure(path: Path, conventions: str | None = None) -> LoadedStructure:
    """A NASTRAN deck through :func:`trussid.fem.nastran.read_bdf` (conventions default "nx")."""
    from trussid.fem.nastran import read_bdf

    model, info = read_bdf(path, conventions=conventions or "nx")
    notes = [f"conventions: {info.conventions} ({'given' if conventions else 'the default'}; "
             f"PBARL/PBEAML ROD shear factor {'6/7' if info.conventions == 'msc' else '0.9'})",
             f"mass: {info.mass} ({info.mass_reason})",
             f"beam theory: {info.beam_theory} ({info.beam_theory_reason})",
             f"supports: {info.spc_reason}"]
    if info.wtmass != 1.0:
        notes.append(f"PARAM,WTMASS,{info.wtmass:g} applied to every mass")
    if info.eigen is not None:
        e = info.eigen
        rng = ""
        if e.f_low is not None or e.f_high is not None:
            lo = "" if e.f_low is None else f"{e.f_low:g}"
            hi = "" if e.f_high is None else f"{e.f_high:g}"
            rng = f", range {lo}..{hi} Hz (not applied: the lowest N modes are listed)"
        notes.append(f"eigenvalue request: {e.card} {e.sid}, ND={e.n_modes}{rng}")
    if info.ignored:
        notes.append(f"ignored (no effect on the modes): {', '.join(info.ignored)}")
    notes += info.notes
    return LoadedStructure(model=model, source=str(path), autospc=info.autospc,
                           n_modes=info.eigen.n_modes if info.eigen is not None else None,
                           units="the deck's units (frequencies in Hz if its time unit is s)",
                           notes=notes, info=info)
