"""``trussid control MODEL.npz --data ID.npz --out CONTROLLER.npz``: an LQG damping
controller from an identified model and its identification record.

The controller file is a model file (:mod:`trussid.plid.modelfile`): ``A, B, C, D, dt`` of
``u = controller(y)``, inputs the sensor names, outputs the actuator names, no hidden sign.
Beside them: ``design_json`` (the design's choices and target modes) and the gains of the
decentralised baselines tuned on the same model (``baseline_kinds``, ``baseline_gains``,
``baseline_bands``), which ``trussid closed-loop`` evaluates beside the LQG.
"""

from __future__ import annotations

import json
import math

#: Choices of --form (trussid.lqg.design.FORMS; repeated so that --help imports nothing).
FORMS = ("predictor", "filter")


def add_parser(subparsers):
    p = subparsers.add_parser(
        "control", help="design an LQG damping controller from an identified model",
        description="Design a discrete LQG that damps the identified model's dominant "
        "modes, from the model and its identification record only. Without options it "
        "targets the modes of largest input-output residue below a quarter of the sample "
        "rate (and in the band the record excited), on a design model reduced to them, "
        "asks 7 %% damping of each, and grades each design on the whole identified model: "
        "stable, a MIMO disk margin of at least 6 dB, every other mode keeping 80 %% of its "
        "damping. When that is out of reach it backs off (less damping, fewer modes) to the "
        "best design that passes, and prints per target mode what it reached and what "
        "limited it (exit 0, with a warning). Exit 2 only when no design is stable with the "
        "margin. --target-damping, --band and --modes override the defaults. Writes "
        "CONTROLLER.npz (u = controller(y); strictly proper).")
    p.add_argument("model", metavar="MODEL.npz", help="identified discrete model file")
    p.add_argument("--data", required=True, metavar="ID.npz",
                   help="the identification record of the model (.npz, .csv or .mat; "
                   "channels named as the model's)")
    p.add_argument("--out", required=True, metavar="CONTROLLER.npz", help="controller file")
    p.add_argument("--target-damping", type=float, default=None, metavar="ZETA",
                   help="damping ratio asked of each target mode, in (0, 1) (default 0.07; "
                   "the design backs off from it when the margins require)")
    p.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"),
                   help="choose the target modes in this band [Hz] (default: 0 to a quarter of "
                   "the sample rate, within the band the record excited; the targets are the "
                   "modes of residue >= 25 %% of the largest there, with each input at its "
                   "record's RMS, and at least the three largest)")
    p.add_argument("--modes", type=int, metavar="N",
                   help="target the N modes with the largest residue (in --band when given, "
                   "else in the band the record excited) instead of every dominant one")
    p.add_argument("--form", choices=FORMS, default="predictor",
                   help="predictor: u[k] from y up to k-1 (one sample to compute, as the "
                   "thesis's PC); filter: u[k] from y[k] (no computation time)")
    p.add_argument("--estimator", choices=("record", "model"), default="record",
                   help="estimator gain: a Kalman gain chosen on the record for the design "
                   "model (default), or the model file's own K projected on the target modes")
    p.add_argument("--no-baselines", action="store_true",
                   help="do not tune the decentralised baselines (they are tuned only when "
                   "the model has as many sensors as actuators)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    import numpy as np

    from trussid._util.errors import UserError
    from trussid.lqg.procedure import design_controller
    from trussid._util.jsonio import json_safe
    from trussid.plid.datafile import read_data
    from trussid.plid.modelfile import load_model, save_model

    if not str(args.out).lower().endswith(".npz"):
        raise UserError(f"--out {args.out}: the controller file must end in .npz")
    if args.target_damping is not None and not (math.isfinite(args.target_damping)
                                                and 0 < args.target_damping < 1):
        raise UserError(f"--target-damping must lie in (0, 1), got {args.target_damping:g}")
    if args.modes is not None and args.modes < 1:
        raise UserError(f"--modes must be a positive integer, got {args.modes}")
    model, meta = load_model(args.model, which="discrete")
    data = read_data(args.data, inputs=meta.input_names, outputs=meta.output_names)
    if not math.isclose(data.fs, 1.0 / meta.dt, rel_tol=1e-6):
        raise UserError(f"--data {args.data}: sampled at {data.fs:g} Hz, the model at "
                        f"{1.0 / meta.dt:g} Hz")
    des, base, timings = design_controller(
        model, data.u, data.y, K=meta.K, target_damping=args.target_damping,
        band=args.band, form=args.form, baselines=not args.no_baselines, progress=print,
        n_modes=args.modes)
    info = json_safe({"form": des.form, "target_modes": des.target_modes,
                      "info": {k: v for k, v in des.info.items() if k != "model_modes"},
                      "procedure": {"band_hz": des.procedure.band_hz,
                                    "asked": des.procedure.asked,
                                    "disk_gain_db": des.procedure.disk_gain_db,
                                    "outcomes": des.procedure.outcomes,
                                    "attempts": des.procedure.attempts},
                      "model": str(args.model), "data": str(args.data), "timings_s": timings})
    extra = {"design_json": np.array(json.dumps(info))}
    if base:
        kinds = list(base)
        extra.update(baseline_kinds=np.array(kinds),
                       baseline_gains=np.array([base[k].gain for k in kinds]),
                     baseline_bands=np.array([base[k].band for k in kinds]))
    c = des.controller
    save_model(args.out, c, input_names=list(c.input_labels), output_names=list(c.output_labels),
               extra=extra)
    print(f"controller: {c.nstates} states, {c.ninputs} sensors ({', '.join(c.input_labels)}) "
          f"-> {c.noutputs} actuators ({', '.join(c.output_labels)}), {des.form} form, "
          f"dt {c.dt:g} s")
    proc = des.procedure
    print(proc.choice_line())
    for line in proc.lines():
        print(line)
    if proc.short:
        import sys

        print(f"warning: {proc.warning()}", file=sys.stderr)
    print(f"written: {args.out}")
    return 0
