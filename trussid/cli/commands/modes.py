"""``trussid modes [MODEL] [--n N] [--json]``: natural frequencies of a model.

MODEL is a NASTRAN bulk-data deck (.bdf/.dat/.nas/.blk/.bulk), a testbed parameter file
(.toml) or omitted (the default testbed). :func:`load_model` turns any of these into a
:class:`LoadedModel`; other commands that take a MODEL (render, plant) can use it too.
For a testbed the table has a label column (:mod:`trussid.testbed.labels`) and ``--json`` a ``labels``
list (``null`` for decks).
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

from trussid._util.errors import UserError

#: File suffixes read as NASTRAN bulk data.
BULK_SUFFIXES = (".bdf", ".dat", ".nas", ".blk", ".bulk")
#: Modes computed when neither --n nor the model asks for a number.
DEFAULT_N_MODES = 20


@dataclass
class LoadedModel:
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
    """

    model: object
    source: str
    autospc: bool = False
    n_modes: int | None = None
    units: str = "SI"
    notes: list = field(default_factory=list)
    info: object | None = None


def load_model(path: str | os.PathLike | None) -> LoadedModel:
    """Load MODEL as the command line gives it: None, a .toml testbed file or a bulk-data deck."""
    if path is None:
        return load_testbed(None)
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".toml":
        return load_testbed(p)
    if suffix in BULK_SUFFIXES:
        return load_bulk_data(p)
    raise UserError(f"{p}: unknown model file type {suffix or '(no suffix)'!r}; give a NASTRAN deck "
                    f"({', '.join(BULK_SUFFIXES)}) or a testbed parameter file (.toml)")


def load_testbed(path: Path | None) -> LoadedModel:
    """The testbed model from a parameter file, or the default testbed when ``path`` is None.

    ``info`` is the :class:`trussid.testbed.model.TestbedModel` (model, map of nodes and elements, the
    parameters), so that commands can label modes or find actuators and sensors.
    """
    from trussid.testbed.model import build_testbed
    from trussid.geometry.params_toml import load_testbed as read_testbed
    from trussid.geometry.spec import INCH, Testbed

    tb = Testbed() if path is None else read_testbed(path)
    tbm = build_testbed(tb)
    s = tb.struts
    ends = " / ".join("clamped" if k == float("inf") else f"flexure {k:g} N m/rad"
                      for k in (s.base_rotational_stiffness, s.top_rotational_stiffness))
    notes = [f"testbed: tube OD {s.outer_diameter / INCH:.4g} in, walls "
             f"{', '.join(f'{t / INCH:.3f}' for t in s.walls)} in; strut ends (base / top): {ends}; "
             f"base {tb.base.support}",
             f"mass: {tbm.model.mass_formulation}; beam theory: {tbm.model.beam_theory}",
             "labels: where each mode's kinetic and strain energy sits (fem.labels)"]
    return LoadedModel(model=tbm.model, source="default testbed" if path is None else str(path),
                       notes=notes, info=tbm)


def load_bulk_data(path: Path) -> LoadedModel:
    """A NASTRAN deck through :func:`trussid.fem.nastran.read_bdf`."""
    from trussid.fem.nastran import read_bdf

    model, info = read_bdf(path)
    notes = [f"mass: {info.mass} ({info.mass_reason})",
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
    return LoadedModel(model=model, source=str(path), autospc=info.autospc,
                       n_modes=info.eigen.n_modes if info.eigen is not None else None,
                       units="the deck's units (frequencies in Hz if its time unit is s)",
                       notes=notes, info=info)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "modes", help="natural frequencies of a model",
        description="Compute the lowest natural frequencies of MODEL: a NASTRAN bulk-data deck "
        f"({', '.join(BULK_SUFFIXES)}), a testbed parameter file (.toml), or, when omitted, "
        "the default testbed. Decks are read as NASTRAN would: PARAM,WTMASS scales every mass, "
        "PARAM,COUPMASS > 0 selects consistent mass (lumped otherwise), AUTOSPC removes DOFs "
        "with neither stiffness nor mass.")
    p.add_argument("model", nargs="?", metavar="MODEL", help="bulk-data deck or testbed .toml file")
    p.add_argument("--n", type=int, default=None, metavar="N",
                   help=f"number of modes (default: the deck's EIGRL ND, else {DEFAULT_N_MODES})")
    p.add_argument("--json", action="store_true", help="print a JSON object instead of a table")
    p.add_argument("--op2", metavar="OUT.op2", default=None,
                   help="also write the eigenvalues and mass-normalised eigenvectors as a NASTRAN "
                   "OP2 file (OUGV1 eigenvector table, each grid in its CD system; 32-bit reals)")
    p.set_defaults(func=run)


def run(args) -> int:
    from trussid.fem.assembly import assemble
    from trussid.fem.modal import solve_modes

    if args.n is not None and args.n < 1:
        raise UserError(f"--n must be at least 1, got {args.n}")
    from trussid.testbed.model import TestbedModel

    loaded = load_model(args.model)
    n = args.n or loaded.n_modes or DEFAULT_N_MODES
    system = assemble(loaded.model, autospc=loaded.autospc)
    labels = None
    if isinstance(loaded.info, TestbedModel):
        from trussid.testbed.labels import label_testbed_modes
        from trussid.testbed.model import solve_testbed_modes

        # The testbed's own solver keeps the sub-hertz suspension modes (solve_modes rounds
        # eigenvalues below 1e-11 of max K_ii/M_ii to zero, which catches them here).
        modes = solve_testbed_modes(loaded.info, n, system=system)
        labels = label_testbed_modes(loaded.info, modes).labels
    else:
        modes = solve_modes(system, n_modes=n)
    freqs = [float(f) for f in modes.frequencies_hz]
    model = loaded.model
    if args.op2:
        from trussid.fem.op2 import write_op2

        frames = model.node_frames() if hasattr(model, "node_frames") else None
        write_op2(args.op2, modes, frames=frames, title=f"trussid modes of {loaded.source}")
        loaded.notes.append(f"OP2 written: {args.op2} ({len(freqs)} modes)")
    if args.json:
        print(json.dumps({
            "model": loaded.source,
            "frequencies_hz": freqs,
            "labels": labels,
            "n_dof": int(system.n_dof),
            "mass": model.mass_formulation,
            "beam_theory": model.beam_theory,
            "units": loaded.units,
            "autospc_removed": len(system.autospc),
            "notes": loaded.notes,
        }, indent=2))
        return 0
    print(f"model: {loaded.source}: {len(model.node_ids)} nodes, {len(model.beams)} beams, "
          f"{len(model.point_masses)} point masses, {len(model.springs)} springs, "
          f"{len(model.rigid_bodies)} rigid bodies")
    removed = f" ({len(system.autospc)} removed by AUTOSPC)" if system.autospc else ""
    print(f"DOF: {system.n_dof} free{removed}")
    for note in loaded.notes:
        print(note)
    if len(freqs) < n:
        print(f"only {len(freqs)} modes exist (asked for {n})")
    print(f"units: {loaded.units}")
    print()
    print(f"{'mode':>5}  {'frequency [Hz]':>16}" + ("  label" if labels else ""))
    for i, f in enumerate(freqs, start=1):
        print(f"{i:>5}  {f:>16.6g}" + (f"  {labels[i - 1]}" if labels else ""))
    return 0
