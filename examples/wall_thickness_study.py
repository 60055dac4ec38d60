"""Wall-thickness study of the testbed: how each strut's wall moves the natural frequencies.

Sweeps one strut's wall thickness at a time (the others at their nominal values) from
``--low`` to ``--high`` times nominal, plots the lowest modes' frequencies against the
thickness (one panel per strut) and prints the analytic sensitivities ``df/dt`` at the
nominal design with each mode's label. The model is built once; every design of the
sweep only re-forms the strut terms of K and M (:func:`trussid.testbed.model.wall_basis`).

Usage::

    python examples/wall_thickness_study.py --out study.png
    python examples/wall_thickness_study.py --params examples/testbed.toml --points 21
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="wall_thickness_study.png", help="output PNG (default %(default)s)")
    p.add_argument("--params", default=None, help="testbed parameter file (.toml); default: the default testbed")
    p.add_argument("--points", type=int, default=15, help="designs per strut (default %(default)s)")
    p.add_argument("--low", type=float, default=0.6, help="lowest wall / nominal (default %(default)s)")
    p.add_argument("--high", type=float, default=1.4, help="highest wall / nominal (default %(default)s)")
    p.add_argument("--modes", type=int, default=30, help="modes computed (default %(default)s)")
    p.add_argument("--fmax", type=float, default=400.0, help="plot frequencies up to this [Hz] (default %(default)s)")
    p.add_argument("--study", default=None,
                   help="study output directory (Parquet, resumable; default: OUT without suffix + _study)")
    p.add_argument("--workers", type=int, default=0,
                   help="0: in this process (default); N: a local Dask cluster of N worker processes")
    p.add_argument("--quiet", action="store_true", help="no progress dots")
    return p.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    if args.points < 2:
        print(f"wall_thickness_study: error: --points {args.points} must be at least 2", file=sys.stderr)
        return 2
    if not 0 < args.low < args.high:
        print(f"wall_thickness_study: error: need 0 < --low < --high, got {args.low}, {args.high}", file=sys.stderr)
        return 2

    from trussid._util.errors import UserError
    from trussid.geometry.params_toml import load_testbed, testbed_to_dict
    from trussid.geometry.spec import INCH, Testbed
    from trussid.plots import save_figure
    from trussid.study import read_study, run_study, spec_from_dict
    from trussid.study.report import modes_figure
    from trussid.testbed.labels import label_testbed_modes
    from trussid.testbed.model import build_testbed, solve_testbed_modes, wall_basis
    from trussid.testbed.sensitivity import wall_sensitivities

    try:
        tb = load_testbed(args.params) if args.params else Testbed()
    except UserError as exc:
        print(f"wall_thickness_study: error: {exc}", file=sys.stderr)
        return 2
    nominal = np.array(tb.struts.walls)
    r_out = tb.struts.outer_radius

    # The sweep as a study (trussid.study): one strut's wall at a time, the others nominal,
    # listed point by point; each design's modes and labels come from the wall basis.
    factors = np.linspace(args.low, args.high, args.points)
    designs = np.repeat(nominal[None, :], 6 * args.points, axis=0)
    for i in range(6):
        # a wall must stay inside the tube
        designs[i * args.points:(i + 1) * args.points, i] = np.minimum(factors * nominal[i], 0.95 * r_out)
    spec = spec_from_dict({
        "study": {"name": "wall-thickness-sweeps", "evaluate": "modes"},
        "evaluate": {"n_modes": args.modes, **({"testbed": testbed_to_dict(tb)} if args.params else {})},
        "sample": {"method": "list"},
        "parameters": {f"wall{i}": [float(v) for v in designs[:, i]] for i in range(6)}})
    study_dir = args.study or str(Path(args.out).with_suffix("")) + "_study"
    try:
        run = run_study(spec, study_dir, workers=args.workers,
                        progress=None if args.quiet else lambda rows: print(".", end="", flush=True))
    except UserError as exc:
        print(f"wall_thickness_study: error: {exc}", file=sys.stderr)
        return 2
    if not args.quiet:
        print()
    _, df = read_study(study_dir)
    if run.failed:
        print(f"wall_thickness_study: {run.failed} designs failed: {sorted(run.reasons)}", file=sys.stderr)

    fig = modes_figure(df, [f"wall{i}" for i in range(6)], args.modes, fmax=args.fmax,
                       slice_at={f"wall{i}": nominal[i] for i in range(6)},
                       title="Testbed frequencies vs one strut's wall thickness, the others nominal\n"
                             "(red: that strut's modes, blue: UDF rigid-body, grey: others)")
    save_figure(fig, args.out)

    # Nominal modes, their labels and analytic sensitivities.
    tbm = build_testbed(tb)
    basis = wall_basis(tbm)
    modes = solve_testbed_modes(tbm, args.modes, system=basis.system)
    labels = label_testbed_modes(tbm, modes).labels
    f0, dfdt = wall_sensitivities(basis, nominal, args.modes)

    print(f"wrote {args.out}: {6 * args.points} designs, {len(f0)} modes each (table: {study_dir})")
    print()
    print("sensitivities df/dt at the nominal walls [Hz per 0.001 in of wall]")
    header = "".join(f"{f'strut {i}':>11}" for i in range(6))
    print(f"{'mode':>4} {'f [Hz]':>9}  {'label':<34}{header}")
    for k in range(len(f0)):
        row = "".join(f"{v:>11.3g}" for v in dfdt[k] * 0.001 * INCH)
        print(f"{k + 1:>4} {f0[k]:>9.3f}  {labels[k]:<34}{row}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
