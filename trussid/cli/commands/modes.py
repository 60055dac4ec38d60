"""``trussid modes [MODEL] [--n N] [--json]``: natural frequencies of a model.

MODEL is a NASTRAN bulk-data deck (.bdf/.dat/.nas/.blk/.bulk), a testbed parameter file
(.toml) or omitted (the default testbed), read by :func:`trussid.cli.loaders.load_structure`.
For a testbed the table has a label column (:mod:`trussid.testbed.labels`) and ``--json`` a ``labels``
list (``null`` for decks).
"""

from __future__ import annotations

import json

from trussid._util.errors import UserError
from trussid.cli.loaders import BULK_SUFFIXES, load_structure

#: Modes computed when neither --n nor the model asks for a number.
DEFAULT_N_MODES = 20


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
    p.add_argument("--conventions", choices=("nx", "msc"), default=None,
                   help="NASTRAN build whose element conventions a deck follows where builds "
                   "differ (PBARL/PBEAML ROD shear factor: nx 0.9, msc 6/7); default nx")
    p.add_argument("--op2", metavar="OUT.op2", default=None,
                   help="also write the eigenvalues and mass-normalised eigenvectors as a NASTRAN "
                   "OP2 file (OUGV1 eigenvector table, each grid in its CD system; 32-bit reals)")
    p.set_defaults(func=run)


def run(args) -> int:
    from trussid.fem.assembly import assemble
    from trussid.fem.modal import solve_modes

    if args.n is not None and args.n < 1:
        raise UserError(f"--n must be at least 1, got {args.n}")
    loaded = load_structure(args.model, args.conventions)
    n = args.n or loaded.n_modes or DEFAULT_N_MODES
    system = assemble(loaded.model, autospc=loaded.autospc)
    labels = None
    if loaded.testbed is not None:
        from trussid.testbed.labels import label_testbed_modes
        from trussid.testbed.walls import solve_testbed_modes

        # The testbed's own solver keeps the sub-hertz suspension modes (solve_modes rounds
        # eigenvalues below 1e-11 of max K_ii/M_ii to zero, which catches them here).
        modes = solve_testbed_modes(loaded.testbed, n, system=system)
        labels = label_testbed_modes(loaded.testbed, modes).labels
    else:
        modes = solve_modes(system, n_modes=n)
    freqs = [float(f) for f in modes.frequencies_hz]
    model = loaded.model
    if args.op2:
        from trussid.fem.op2 import write_op2

        write_op2(args.op2, modes, frames=model.node_frames(), title=f"trussid modes of {loaded.source}")
        loaded.notes.append(f"OP2 written: {args.op2} ({len(freqs)} modes)")
    if args.json:
        print(json.dumps({
            "model": loaded.source,
            "frequencies_hz": freqs,
            "labels": labels,
            "n_dof": int(system.n_dof),
            "mass": model.mass_formulation,
            "beam_theory": model.beam_theory,
            "conventions": getattr(loaded.info, "conventions", None),
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
