"""``trussid closed-loop CONTROLLER.npz [PLANT] --out DIR``: a controller on a plant.

Without PLANT, on the default testbed's FE truth and the seven perturbed truths of issue 14
(UDF mass +-5 %, strut Young's modulus +-5 %, amplifier low-pass at 100 Hz, amplifier gain
x1.5, modal damping 0.1 %; ``--stretch`` adds UDF mass +-10 %). With PLANT (a discrete
model file whose inputs and outputs carry the controller's names), on that plant alone,
behind the converters of the lab the plant file records (``trussid plant`` and the demo's
``plant_true.npz`` record theirs; for a plant file without one, the default testbed's lab at
the plant's rate, said on stderr).
Writes ``report.md`` (damping table, robustness table, margins, baselines), ``sigma.png``,
``bode_<channel>.png``, ``impulse.png``, ``poles.png`` and ``summary.json``. Everything is
computed before the first file is written.
"""

from __future__ import annotations

from pathlib import Path


def add_parser(subparsers):
    p = subparsers.add_parser(
        "closed-loop", help="evaluate a controller on the FE truth (or a plant file)",
        description="Close the loop u = controller(y) around PLANT (default: the default "
        "testbed's FE truth and 7 perturbed truths) and write a report into DIR: damping "
        "per mode (counting visible controller poles), disk margins, H2 and command RMS "
        "in a simulation with the lab's converters (those PLANT records; the default "
        "testbed's otherwise), open- vs closed-loop responses, pole map, the "
        "decentralised baselines stored in the controller file.")
    p.add_argument("controller", metavar="CONTROLLER.npz", help="controller file "
                   "(trussid control)")
    p.add_argument("plant", metavar="PLANT", nargs="?",
                   help="discrete plant model file (default: the FE truths)")
    p.add_argument("--out", required=True, metavar="DIR", help="report directory")
    p.add_argument("--stretch", action="store_true",
                   help="add the UDF mass +-10 %% truths (default truths only)")
    p.add_argument("--no-baselines", action="store_true",
                   help="leave out the baselines stored in the controller file")
    p.add_argument("--samples", type=int, default=8000, metavar="N",
                   help="length of the closed-loop time simulation (default 8000)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    import numpy as np
    from tqdm import tqdm

    from trussid._util.errors import UserError
    from trussid.campaign.control import LoopSettings, robustness, truths, write_report
    from trussid.geometry.lab import recorded_lab
    from trussid.geometry.spec import Testbed
    from trussid.plid.modelfile import load_model

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out} exists and is not a directory")
    if args.samples < 100:
        raise UserError(f"--samples must be at least 100, got {args.samples}")
    ctrl, meta = load_model(args.controller, which="discrete")
    if args.plant:
        plant, pmeta = load_model(args.plant, which="discrete")
        plants = [(Path(args.plant).stem, plant)]
        lab = recorded_lab(pmeta["extra"], args.plant)
    else:
        lab = Testbed().lab
        plants = truths(stretch=args.stretch)
    from trussid.lqg.evaluate import check_pair

    for label, plant in plants:  # every mismatch before any work
        check_pair(plant, ctrl, label)
    if lab is None:  # a plant file that records no lab (an identified model, a deck's plant)
        import sys

        lab = Testbed().lab.at_rate(1.0 / plants[0][1].dt)
        print(f"trussid closed-loop: warning: {args.plant} records no lab; its loop runs "
              f"behind the default testbed's {lab.daq.bits}-bit +-{lab.daq.full_scale:g} V "
              "converters", file=sys.stderr)
    ex = meta["extra"]
    base = {}
    if not args.no_baselines and "baseline_kinds" in ex:
        for k, g, b in zip(ex["baseline_kinds"], ex["baseline_gains"], ex["baseline_bands"]):
            base[str(k)] = {"gain": float(g), "band": [float(v) for v in np.ravel(b)]}
    bar = tqdm(total=len(plants) + len(base), desc="closed loops", unit="step")
    study = robustness(ctrl, plants, base, LoopSettings.for_lab(lab, n_samples=args.samples),
                       progress=lambda msg: bar.update(1))
    bar.close()
    if "design_json" in ex:
        import json

        study["design_info"] = json.loads(str(ex["design_json"]))
    files = write_report(out, study)
    for label, ok in study["checks"].items():
        r = study["rows"][label]
        failed = [k for k, v in ok.items() if not v]
        dom = ", ".join(f"{100 * d['worst']:.2f}" for d in r["dominant"])
        print(f"{label:28s} stable {'yes' if r['stable'] else 'NO '}  dominant worst "
              f"[{dom}] %  {'pass' if not failed else 'FAIL ' + ', '.join(failed)}")
    print(f"report: {out}/{files[0]} ({len(files)} files)")
    return 0
