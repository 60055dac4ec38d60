"""``trussid closed-loop CONTROLLER.npz [PLANT] --out DIR``: a controller on a plant.

Without PLANT, on the default testbed's FE truth and the seven perturbed truths of issue 14
(UDF mass +-5 %, strut Young's modulus +-5 %, amplifier low-pass at 100 Hz, amplifier gain
x1.5, modal damping 0.1 %; ``--stretch`` adds UDF mass +-10 %), graded by issue 14's
thresholds. With PLANT (a discrete model file whose inputs and outputs carry the
controller's names, or those names without the ``u_``/``y_`` prefix of a CSV record), on
that plant alone, graded in its own units (:func:`trussid.lqg.grading.
plant_loop_settings`): every mode up to Nyquist, excitation white to 0.4 of the sample rate
at the identification record's levels, behind the converters of the lab the plant file
records (``trussid plant`` and the demo's ``plant_true.npz`` record theirs; ideal
converters for a plant file without one, said on stderr), feed-through allowed.
Writes ``report.md`` (damping table, robustness table, margins, baselines), ``sigma.png``,
``bode_<channel>.png``, ``impulse.png``, ``poles.png`` and ``summary.json``. Everything is
computed before the first file is written.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path


def add_parser(subparsers):
    p = subparsers.add_parser(
        "closed-loop", help="evaluate a controller on the FE truth (or a plant file)",
        description="Close the loop u = controller(y) around PLANT (default: the default "
        "testbed's FE truth and 7 perturbed truths, 12-bit +-10 V converters, issue 14's "
        "thresholds) and write a report into DIR: damping per mode (counting visible "
        "controller poles), disk margins, H2 and command RMS in a closed-loop simulation, "
        "open- vs closed-loop responses, pole map, the decentralised baselines stored in "
        "the controller file. A PLANT file is graded in its own units: every mode up to "
        "Nyquist, white excitation to 0.4 of its sample rate at the identification "
        "record's levels, ideal converters; a controller named after a CSV record "
        "(u_/y_ prefixes) is matched to the plant's names.")
    p.add_argument("controller", metavar="CONTROLLER.npz", help="controller file "
                   "(trussid control)")
    p.add_argument("plant", metavar="PLANT", nargs="?",
                   help="discrete plant model file (default: the FE truths)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="report directory (written also when a loop is unstable; the exit "
                   "status is then 1)")
    p.add_argument("--stretch", action="store_true",
                   help="add the UDF mass +-10 %% truths (default truths only)")
    p.add_argument("--no-baselines", action="store_true",
                   help="leave out the baselines stored in the controller file")
    p.add_argument("--samples", type=int, default=8000, metavar="N",
                   help="length of the closed-loop time simulation (default 8000)")
    p.set_defaults(func=run)
    return p


def _check_pairs(plants, ctrl, designed: bool, path) -> None:
    """Refuse a controller that does not fit a plant; without a design record of `trussid
    control` say that it may be a model (the newcomer's mistake in audit 3 read "controller
    input 'ch1' is not a plant output", naming the wrong cause)."""
    from trussid._util.errors import UserError
    from trussid.lqg.loop import check_pair

    for label, plant in plants:
        try:
            check_pair(plant, ctrl, label)
        except UserError as exc:
            if designed:
                raise
            raise UserError(f"{exc}; {path} has no design record of `trussid control`: is it a "
                            "model rather than a controller? (make one with trussid control "
                            "MODEL.npz --data ID.npz --out CONTROLLER.npz)") from None


def run(args) -> int:
    import dataclasses

    import numpy as np
    from tqdm import tqdm

    from trussid._util.errors import UserError
    from trussid.campaign.loop_report import write_report
    from trussid.lqg.grading import Baseline, LoopSettings, plant_loop_settings, robustness
    from trussid.testbed.perturbed import truths
    from trussid.geometry.lab import recorded_lab
    from trussid.geometry.spec import Testbed
    from trussid.plid.modelfile import load_model

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out} exists and is not a directory")
    if args.samples < 100:
        raise UserError(f"--samples must be at least 100, got {args.samples}")
    import json

    from trussid.lqg.loop import match_names

    ctrl, meta = load_model(args.controller, which="discrete")
    ex = meta.extra
    design = json.loads(str(ex["design_json"])) if "design_json" in ex else {}
    if args.plant:
        plant, pmeta = load_model(args.plant, which="discrete")
        plants = [(Path(args.plant).stem, plant)]
        ctrl, renamed = match_names(plant, ctrl)
        if renamed:
            print("controller channels matched to the plant's by dropping the record's u_/y_ "
                  "prefix: " + ", ".join(f"{a} -> {b}" for a, b in renamed))
        lab = recorded_lab(pmeta.extra, args.plant)
        di = design.get("info", {})
        settings = plant_loop_settings(plant, input_rms=di.get("input_rms"),
                                       output_rms=di.get("output_rms"),
                                       target_damping=di.get("target_damping"),
                                       targets_hz=[t["frequency_hz"] for t in
                                                   design.get("target_modes", [])],
                                       n_samples=args.samples, lab=lab)
    else:
        dt_tb = 1.0 / Testbed().daq.sample_rate
        if not math.isclose(ctrl.dt, dt_tb, rel_tol=1e-9):
            raise UserError(f"no PLANT given, so the controller runs on the default testbed "
                            f"(sampled at {1 / dt_tb:g} Hz), but it is sampled at "
                            f"{1 / ctrl.dt:g} Hz: give the plant file it was designed for")
        plants = truths(stretch=args.stretch)
        settings = LoopSettings.for_lab(Testbed().lab, n_samples=args.samples)
    _check_pairs(plants, ctrl, bool(design), args.controller)  # every mismatch before any work
    if args.plant and lab is None:  # a plant file that records no lab (a model, a deck's)
        print(f"trussid closed-loop: note: {args.plant} records no lab; its loop runs behind "
              "ideal converters", file=sys.stderr)
    base = {}
    if not args.no_baselines and "baseline_kinds" in ex:
        for k, g, b in zip(ex["baseline_kinds"], ex["baseline_gains"], ex["baseline_bands"]):
            base[str(k)] = Baseline(float(g), [float(v) for v in np.ravel(b)])
    bar = tqdm(total=len(plants) + len(base), desc="closed loops", unit="step")
    study = robustness(ctrl, plants, base, settings, progress=lambda msg: bar.update(1))
    bar.close()
    if design:
        study = dataclasses.replace(study, design_info=design)
    files = write_report(out, study)
    for label, ok in study.checks.items():
        r = study.rows[label]
        failed = ok.failed
        dom = ", ".join(f"{100 * d.worst:.2f}" for d in r.dominant)
        print(f"{label:28s} stable {'yes' if r.stable else 'NO '}  dominant worst "
              f"[{dom}] %  {'pass' if not failed else 'FAIL ' + ', '.join(failed)}")
    print(f"report: {out}/{files[0]} ({len(files)} files)")
    unstable = [label for label, r in study.rows.items() if not r.stable]
    if unstable:
        # said loudly, not only in a table row: the controller must not go on the structure
        print(f"trussid closed-loop: the closed loop is UNSTABLE on {', '.join(unstable)} "
              f"(report written: {out}/report.md)", file=sys.stderr)
        return 1
    return 0
