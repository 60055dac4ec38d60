"""``trussid export MODEL.npz --to FILE.mat|FILE.py`` (or ``--python``): models out to the
controls toolchain (:mod:`trussid.plid.export`).

``.mat``: MATLAB/Octave (``A, B, C, D, Ts, K, InputName, OutputName``; a plant file's
continuous model as ``Ac .. Dc``). ``.py``: Python code building a ``control.ss`` with the
channel names, needing only numpy and python-control. ``--python`` prints that code.
"""

from __future__ import annotations

import sys
from pathlib import Path

from trussid._util.errors import UserError

SUFFIXES = (".mat", ".py")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "export", help="export a model file to MATLAB (.mat) or python-control (.py)",
        description="Export MODEL.npz (from 'trussid identify' or 'trussid plant') for "
        "control design. FILE.mat holds A, B, C, D, Ts (0: continuous), K (the one-step "
        "predictor gain, when the model has one), InputName and OutputName; a plant's "
        "continuous model goes in as Ac, Bc, Cc, Dc. In MATLAB or Octave: "
        "s = load('FILE.mat'); G = ss(s.A, s.B, s.C, s.D, s.Ts, 'InputName', s.InputName, "
        "'OutputName', s.OutputName). FILE.py is Python code that builds model = "
        "control.ss(...) with the channel names (needs numpy and python-control only): "
        "'from FILE import model, K', or exec it. --python prints that code instead.")
    p.add_argument("model", metavar="MODEL.npz", help="model file")
    target = p.add_mutually_exclusive_group(required=True)
    target.add_argument("--to", metavar="FILE", help="output file: .mat (MATLAB) or .py "
                        "(python-control code)")
    target.add_argument("--python", action="store_true",
                        help="print python-control code on stdout")
    p.add_argument("--continuous", action="store_true",
                   help="export the file's continuous model (a plant's c_A .. c_D) instead "
                   "of its main (discrete) one")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from trussid.plid.export import MATLAB_LOAD, python_code, write_mat, write_python
    from trussid.plid.modelfile import load_model

    out = Path(args.to) if args.to else None
    if out is not None and out.suffix.lower() not in SUFFIXES:
        raise UserError(f"--to {out}: give a .mat (MATLAB) or .py (python-control) file")
    model, meta = load_model(args.model, which="continuous" if args.continuous else "auto")
    note = meta.stability.message(f"the model {args.model}")
    names = dict(input_names=meta.input_names, output_names=meta.output_names)
    if args.python:
        sys.stdout.write(python_code(model, meta.K, source=str(args.model), **names))
    elif out.suffix.lower() == ".mat":
        continuous = None
        if meta.has_continuous and not args.continuous and meta.dt > 0:
            continuous = load_model(args.model, which="continuous")[0]
        write_mat(out, model, K=meta.K, continuous=continuous, **names)
        print(f"wrote {out}: {model.nstates} states, {model.ninputs} input(s), "
              f"{model.noutputs} output(s), Ts = {meta.dt:g} s"
              + (", K" if meta.K is not None else "")
              + (", continuous model as Ac..Dc" if continuous is not None else ""))
        print("in MATLAB/Octave: " + MATLAB_LOAD.format(name=out.name))
    else:
        write_python(out, model, meta.K, source=str(args.model), **names)
        print(f"wrote {out}: python-control code; use: from {out.stem} import model, K "
              f"(or exec(open('{out}').read()))")
    if note:
        print(f"trussid export: warning: {note}", file=sys.stderr)
    return 0
