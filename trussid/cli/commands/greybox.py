"""``trussid greybox``: grey-box identification of physical parameters from data.

``trussid greybox dc-motor DATA (--inertia J | --flywheel DIMS) [--resistance R] [--json]``
fits a DC motor (see :mod:`trussid.plid.dcmotor`) to a CSV with columns ``t`` [s], ``u`` [V] and
``y`` [rad/s].

JSON output (``--json``)::

    {"T": s, "G": rad/s/V, "T_interval": [lo, hi], "G_interval": [lo, hi],
     "parameters": {"J": .., "b": .., "R": .., "k": ..},   # null when undetermined
     "intervals": {"J": null, "b": [lo, hi], ...},          # 95 %; null for given or
                                                            # undetermined parameters
     "given": ["J", ...], "undetermined": ["R*k", ...],     # [] when all are determined
     "representative": {...},   # one best-fitting full set (e.g. to simulate with)
     "initial_speed": rad/s,    # fitted speed at t[0]; null with --initial-state zero
     "spread": {"b": [min, max], ...},  # over multi-start fits as good as the best
     "n_starts": 8, "rms": ..}

A parameter the data do not determine is reported as ``null`` rather than as a number
with a flag: any single value would be one arbitrary point of a curve of equally good
fits. ``representative`` still gives one such point, clearly labelled.
"""

from __future__ import annotations

import csv
import json
import math
import sys

import numpy as np

from trussid.plid.errors import DataError

DIMS_HELP = (
    "flywheel as comma-separated numbers: disc radius, disc thickness, shaft radius, "
    "shaft length [m] and optionally density [kg/m^3] (default 7850, steel), e.g. "
    "--flywheel 0.1,0.02,0.01,0.2; the disc is centred on the shaft and J is computed "
    "from their trimesh solid"
)


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "greybox",
        help="fit physical parameters of a grey-box model to data",
        description="Grey-box identification: fit the physical parameters of a "
        "parametric model to measured data, and say which ones the data cannot determine.",
    )
    models = p.add_subparsers(dest="model", metavar="MODEL")
    p.set_defaults(func=_no_model, _parser=p)

    m = models.add_parser(
        "dc-motor",
        help="DC motor speed response: T, G, then J, b, R, k",
        description="Identify a DC motor from its speed response (armature inductance "
        "neglected): first the time constant T and gain G of G/(T s + 1) (63.2 % rule "
        "start, least-squares refinement over any input), then the damping b, resistance "
        "R and motor constant k, with the inertia J given. With only J given the data "
        "cannot determine b, R and k (only T = J R/(b R + k^2) and G = k/(b R + k^2)); "
        "the output names the undetermined combination. Give --resistance too to get all "
        "four.",
    )
    m.add_argument("data", metavar="DATA",
                   help="CSV with a header row and columns t [s], u [V], y [rad/s]")
    src = m.add_mutually_exclusive_group(required=True)
    src.add_argument("--inertia", type=float, metavar="J",
                     help="total rotating inertia J [kg m^2]")
    src.add_argument("--flywheel", metavar="DIMS", help=DIMS_HELP)
    m.add_argument("--resistance", type=float, metavar="R",
                   help="armature resistance R [ohm], if measured separately")
    m.add_argument("--hold", choices=("zoh", "foh"), default="zoh",
                   help="input between samples: held (zoh, default: square waves, DACs) "
                   "or linear (foh)")
    m.add_argument("--initial-state", choices=("fit", "zero"), default="fit",
                   help="estimate the speed at the first sample (fit, default) or assume "
                   "the record starts at rest (zero)")
    m.add_argument("--starts", type=int, default=8, metavar="N",
                   help="multi-start count for the physical stage (default 8)")
    m.add_argument("--seed", type=int, default=0, help="seed of the multi-start (default 0)")
    m.add_argument("--json", action="store_true", help="print JSON instead of a summary")
    m.set_defaults(func=run_dc_motor)


def _no_model(args) -> int:
    args._parser.print_help(sys.stderr)
    return 2


def read_tuy_csv(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns ``t``, ``u``, ``y`` of a CSV with a header row (other columns ignored)."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise DataError(f"{path}: empty file")
    header = [c.strip() for c in rows[0]]
    cols = {}
    for name in ("t", "u", "y"):
        if name not in header:
            raise DataError(f"{path}: column {name!r} missing (found: {', '.join(header)})")
        cols[name] = header.index(name)
    body = rows[1:]
    if len(body) < 10:
        raise DataError(f"{path}: data too short: {len(body)} sample row(s), need at least 10")
    out = {n: np.empty(len(body)) for n in cols}
    for i, row in enumerate(body):
        for n, j in cols.items():
            try:
                v = float(row[j])
            except (IndexError, ValueError):
                cell = row[j] if j < len(row) else ""
                raise DataError(f"{path}: row {i + 2}, column {n!r}: not a number: "
                                f"{cell!r}") from None
            if not math.isfinite(v):
                raise DataError(f"{path}: row {i + 2}, column {n!r}: not finite: {row[j]!r}")
            out[n][i] = v
    return out["t"], out["u"], out["y"]


def run_dc_motor(args) -> int:
    # Imported here so that `trussid --help` stays fast.
    from trussid.plid.dcmotor import identify_dc_motor

    if args.flywheel is not None:
        from trussid.geometry.flywheel import flywheel_inertia, parse_flywheel

        J = flywheel_inertia(parse_flywheel(args.flywheel))
    else:
        J = args.inertia
    if args.starts < 1:
        raise DataError(f"--starts must be at least 1, got {args.starts}")
    t, u, y = read_tuy_csv(args.data)
    res = identify_dc_motor(t, u, y, J=J, R=args.resistance, hold=args.hold,
                            initial_state=args.initial_state, n_starts=args.starts,
                            seed=args.seed)
    if args.json:
        print(json.dumps(res.to_dict(), indent=2))
    else:
        if args.flywheel is not None:
            print(f"J from the flywheel solid: {J:.5g} kg m^2")
        print(res.summary())
    return 0
