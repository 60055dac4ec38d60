"""``trussid demo [--out DIR] [--quick]``: the main job, end to end on the default testbed.

Default testbed -> modes -> plant (1600 Hz, 12-bit converters, sensor noise) -> simulated
identification and validation records -> PLID (one SIMO model per actuator channel and a
MIMO model) -> comparison against the true plant and the H1 estimate -> a report directory
(``report.md``, PNG figures, ``summary.json``, the data and model files). The campaign is
:mod:`trussid.campaign.demo`; ``--quick`` is :func:`trussid.campaign.demo.demo_settings` ``(True)``.
"""

from __future__ import annotations

import sys
import time

DEFAULT_OUT = "trussid-report"


def add_parser(subparsers):
    p = subparsers.add_parser(
        "demo", help="the main job: identify the simulated testbed and write a report",
        description="Run the simulated identification campaign on the default testbed: one "
        "SIMO PLID model (30 states) per actuator channel and one MIMO model (36 states), "
        "each compared with the true plant, the H1 estimate and validation data. Writes "
        "report.md, PNG figures, summary.json and the data and model files into DIR. "
        "--quick keeps only the channel-1 SIMO model (30 states) and an 18-state MIMO "
        "model, on shorter records (6000 + 4000 samples instead of 16000 + 8000).")
    p.add_argument("--out", default=DEFAULT_OUT, metavar="DIR",
                   help=f"report directory (default {DEFAULT_OUT}/)")
    p.add_argument("--quick", action="store_true",
                   help="reduced run (under 2 minutes): fewer models, lower MIMO order, "
                   "shorter records")
    p.add_argument("--seed", type=int, metavar="S",
                   help="seed of the campaign (default 1997)")
    p.add_argument("--force", action="store_true",
                   help="replace an existing report directory (only once the new report is "
                   "complete: an interrupted run leaves the old one as it was)")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from trussid.campaign.demo import demo_settings, run_demo

    overrides = {} if args.seed is None else {"seed": args.seed}
    settings = demo_settings(args.quick, **overrides)
    t0 = time.perf_counter()

    def say(msg):
        print(f"[{time.perf_counter() - t0:6.1f} s] {msg}", flush=True)

    import shlex

    summary = run_demo(args.out, settings, progress=say, force=args.force,
                       command="trussid " + " ".join(
                           shlex.quote(a) for a in getattr(args, "argv", sys.argv[1:])))
    print()
    print(f"report: {args.out}/report.md (figures, summary.json, data and model files "
          f"beside it)")
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
    print(f"total {summary.timings_s['total']:.1f} s", file=sys.stdout)
    return 0
