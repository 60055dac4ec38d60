"""``trussid demo [MODEL] [--io IO.toml] [--lab LAB.toml] [--out DIR] [--quick]``: the main
job, end to end, on the default testbed or on any structure.

Structure -> modes -> plant (sample rate, converters, sensor noise from the lab) ->
simulated identification and validation records -> PLID (one SIMO model per actuator
channel and a MIMO model) -> comparison against the true plant and the H1 estimate -> LQG
on the MIMO model, closed on the true plant -> a report directory (``report.md``, PNG
figures, ``summary.json``, the data and model files). MODEL: none (the default testbed), a
testbed parameter file (.toml) or a NASTRAN deck with ``--io``; for a deck the experiment
(band, levels, record lengths, orders) is derived from its modes and sample rate
(:func:`trussid.campaign.demo.derived_settings`) and each can be given. The campaign is
:mod:`trussid.campaign.demo`; ``--quick`` is :func:`trussid.campaign.demo.demo_settings` ``(True)``.
"""

from __future__ import annotations

import sys
import time

DEFAULT_OUT = "trussid-report"


def add_parser(subparsers):
    p = subparsers.add_parser(
        "demo", help="the main job: identify a simulated structure and write a report",
        description="Run the simulated identification campaign on the default testbed (or "
        "on MODEL: a testbed file, or a NASTRAN deck with --io, whose experiment is derived "
        "from its modes and sample rate): one "
        "SIMO PLID model (30 states) per actuator channel and one MIMO model (36 states), "
        "each compared with the true plant, the H1 estimate and validation data. Writes "
        "report.md, report.html (the same report as one page to explore offline: the modes "
        "in 3-D, interactive Bode plots), PNG figures, summary.json and the data and model "
        "files into DIR. "
        "--quick keeps only the channel-1 SIMO model (30 states) and an 18-state MIMO "
        "model, on shorter records (6000 + 4000 samples instead of 16000 + 8000).")
    p.add_argument("model", nargs="?", metavar="MODEL",
                   help="a NASTRAN deck (with --io) or a testbed parameter file (.toml); "
                   "default: the default testbed")
    p.add_argument("--io", metavar="IO.toml",
                   help="actuators, sensors and [plant] sample rate and damping of a deck "
                   "(the format of trussid plant --io)")
    p.add_argument("--lab", metavar="LAB.toml",
                   help="the lab of a deck's campaign, a lab file (trussid.geometry.lab."
                   "LabSpec: [daq] sample_rate, bits, full_scale); default: the IO file's "
                   "[plant] fs with 12-bit +-10 converters; sensor noise 60 dB under each "
                   "output")
    p.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"),
                   help="excitation band [Hz] (default: the testbed's 0-400 Hz; a deck's "
                   "0 to 0.4 of the sample rate)")
    p.add_argument("--order", type=int, metavar="N",
                   help="MIMO (and SIMO) model order (default: the testbed's 36 / 30; a "
                   "deck's twice its modes in the excitation band)")
    p.add_argument("--samples", type=int, metavar="N",
                   help="samples of each identification record (validation: half)")
    p.add_argument("--out", default=DEFAULT_OUT, metavar="DIR",
                   help=f"report directory (default {DEFAULT_OUT}/)")
    p.add_argument("--quick", action="store_true",
                   help="reduced run (under 2 minutes): fewer models, lower MIMO order, "
                   "shorter records")
    p.add_argument("--adapt", action="store_true",
                   help="add closed-loop identification and adaptive LQG redesign: the "
                   "demo's controller runs on the FE truth with dither, the plant is "
                   "identified in closed loop (PLID beside N4SID), then the truth changes "
                   "(UDF mass -10 %%, +10 %%, strut E -5 %%) and the loop re-identifies, "
                   "redesigns and switches under a supervisor; writes adapt/ files and a "
                   "report section (about 1-2 CPU minutes more with --quick)")
    p.add_argument("--seed", type=int, metavar="S",
                   help="seed of the campaign (default 1997)")
    p.add_argument("--force", action="store_true",
                   help="replace an existing report directory (only once the new report is "
                   "complete: an interrupted run leaves the old one as it was)")
    p.set_defaults(func=run)
    return p


def _overrides(args) -> dict:
    from trussid._util.errors import UserError

    kw = {} if args.seed is None else {"seed": args.seed}
    if args.band is not None:
        lo, hi = args.band
        if not 0 <= lo < hi:
            raise UserError(f"--band needs 0 <= LO < HI [Hz], got {lo:g} {hi:g}")
        kw["excitation_band"] = (lo, hi)
    if args.order is not None:
        if args.order < 1:
            raise UserError(f"--order must be a positive integer, got {args.order}")
        kw.update(mimo_order=args.order, simo_order=args.order)
    if args.samples is not None:
        if args.samples < 500:
            raise UserError(f"--samples must be at least 500, got {args.samples}")
        kw.update(n_identification=args.samples, n_validation=max(args.samples // 2, 500))
    return kw


def run(args) -> int:
    from pathlib import Path

    from trussid._util.errors import UserError
    from trussid.campaign.demo import demo_settings, derived_settings, run_demo

    overrides = _overrides(args)
    out = Path(args.out)  # refused before any computation (run_demo checks it again)
    if out.exists() and (not out.is_dir() or not args.force):
        raise UserError(f"--out {out} exists" + (" and is not a directory" if not out.is_dir()
                        else "; give --force to replace it (it is replaced only once the "
                        "new report is complete)"))
    t0 = time.perf_counter()

    def say(msg):
        print(f"[{time.perf_counter() - t0:6.1f} s] {msg}", flush=True)

    plant = testbed = None
    suffix = Path(args.model).suffix.lower() if args.model else ""
    if args.model and suffix != ".toml":
        from trussid.campaign.structure import deck_campaign_plant
        from trussid.cli.loaders import BULK_SUFFIXES

        if suffix not in BULK_SUFFIXES:
            raise UserError(f"{args.model}: give a NASTRAN deck ({', '.join(BULK_SUFFIXES)}) "
                            f"with --io, or a testbed parameter file (.toml)")
        if not args.io:
            raise UserError(f"{args.model}: a deck needs --io IO.toml (its actuators and "
                            f"sensors)")
        if getattr(args, "adapt", False):
            raise UserError(f"{args.model}: --adapt changes the testbed (UDF mass, strut "
                            f"stiffness) under a running controller; it needs a testbed "
                            f"MODEL (.toml or none), not a deck")
        say(f"reading {args.model} with {args.io} ...")
        plant = deck_campaign_plant(args.model, args.io, args.lab)
        settings = derived_settings(plant, args.quick, **overrides)
    else:
        if args.io or args.lab:
            raise UserError("--io and --lab apply to a NASTRAN deck MODEL; the testbed's lab "
                            "is in its parameter file")
        if args.model:
            from trussid.cli.loaders import testbed_spec

            testbed = testbed_spec(args.model)
        settings = demo_settings(args.quick, **overrides)

    import shlex

    summary = run_demo(args.out, settings, progress=say, force=args.force, plant=plant,
                       testbed=testbed, adapt=getattr(args, "adapt", False),
                       command="trussid " + " ".join(
                           shlex.quote(a) for a in getattr(args, "argv", sys.argv[1:])))
    print()
    print(f"report: {args.out}/report.md (figures, summary.json, data and model files "
          f"beside it); to explore: {args.out}/report.html (open it in a browser, offline)")
    print(f"{'model':<10} {'kind':<5} {'states':>6} {'SPE [dB]':>9} {'per output [dB]':>17} "
          f"{'FRF max':>8} {'FRF RMS':>8} {'seconds':>8}")
    for m in summary.models:
        def f(x, w=8, d=2):
            return f"{x:{w}.{d}f}" if x is not None else f"{'-':>{w}}"
        print(f"{m.name:<10} {m.kind:<5} {m.states:>6} "
              f"{f(m.signal_to_prediction_error_db, 9)} "
              f"{', '.join(f'{v:.1f}' for v in m.signal_to_prediction_error_db_per_output):>17} "
              f"{f(m.frf_max_error_db)} {f(m.frf_rms_error_db)} {f(m.seconds, 8, 1)}")
    lo, hi = summary.settings.frf_band
    print(f"(SPE: one-step signal-to-prediction-error ratio on validation data; FRF errors "
          f"in dB against the true plant over {lo:g}-{hi:g} Hz)")
    if summary.adapt is not None:
        _print_adapt(summary.adapt.summary)
    print(f"total {summary.timings_s['total']:.1f} s", file=sys.stdout)
    return 0


def _print_adapt(a: dict) -> None:
    """The adaptive section's one line per change (report.md has the tables)."""
    nom = a["nominal"]["frf_rms_db"]
    print(f"closed-loop model: FRF RMS {nom['plid']:.2f} dB (N4SID {nom['n4sid']:.2f} dB, "
          f"open-loop model {nom['open_loop']:.2f} dB)")
    for name, c in a["changes"].items():
        det = ("not detected" if c["detected_at_s"] is None else
               f"detected at {c['detected_at_s']:.2f} s ({c['detect_cpu_seconds']:.1f} s CPU)")
        sw = ("nominal controller kept" if c["switched_at_s"] is None else
              f"new controller at {c['switched_at_s']:.2f} s")
        after = ", ".join(f"{100 * z:.1f}" for z in c["damping_after"])
        ok = [v["ok"] for k, v in a["checks"].items() if k.endswith(name)]
        print(f"{c['label']:<16} {det}; {sw}; dominant modes {after} %"
              f"{'' if not ok else ('  (acceptance: pass)' if ok[0] else '  (acceptance: FAIL)')}")
