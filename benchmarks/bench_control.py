"""Benchmark: issue 14, the LQG from the demo's MIMO model on the nominal and perturbed FE truths.

Runs, in one process and in this order: the demo's MIMO record (same settings and seeds as
``trussid demo``), its identification (``identify_model``, timed: the comparator), the LQG
design, the evaluation on the 7 + 2 (stretch) truths and the decentralised baselines.
Writes the tables of :func:`trussid.campaign.control.report_markdown`, the timings (wall
and CPU), the machine, load and commit into the Markdown file, and the raw numbers as JSON
beside it. BLAS is limited to one thread before numpy loads (2-core shared machine).

    python benchmarks/bench_control.py [--quick] [--out benchmarks/results/control.md]

CI (``benchmarks/run.py --quick``) adds ``--samples 3000 --truths 2 --no-baselines``: a shorter
record, the nominal truth and one perturbed one, no decentralised baselines (minutes less; the
figures then say only that the script runs).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, cwd=Path(__file__).parent).stdout.strip()
    except OSError:
        return "unknown"


def timed(fn, *a, **k):
    w, c = time.perf_counter(), time.process_time()
    out = fn(*a, **k)
    return out, time.perf_counter() - w, time.process_time() - c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the --quick demo's 18-state model")
    ap.add_argument("--out", default=None, help="Markdown file to write (default: print)")
    ap.add_argument("--truths", type=int, default=None,
                    help="evaluate on the first N truths only (default: all 7 + 2 stretch)")
    ap.add_argument("--no-baselines", action="store_true", help="skip the decentralised baselines")
    ap.add_argument("--samples", type=int, default=None,
                    help="identification record length (default: the demo's); validation the same")
    args = ap.parse_args()

    import control

    from trussid.campaign.control import control_study
    from trussid.campaign.loop_report import closed_loop_markdown, closed_loop_summary
    from trussid.lqg.grading import LoopSettings
    from trussid.testbed.perturbed import truths
    from trussid._util.jsonio import json_safe
    from trussid.campaign.demo import build_plant, demo_settings, identify_model, run_experiments

    load0 = os.getloadavg()
    sizes = {} if args.samples is None else {"n_identification": args.samples, "n_validation": args.samples}
    settings = demo_settings(quick=args.quick, simo_channels=(), **sizes)
    tp = build_plant()
    rid, _ = run_experiments(tp, settings)["mimo"]
    d = rid.data
    fit, w_id, c_id = timed(identify_model, d.u, d.y, settings.mimo_order, d.dt,
                            block_rows=settings.block_rows)
    m = fit.model
    model = control.ss(m.A, m.B, m.C, m.D, m.dt, inputs=d.input_names, outputs=d.output_names)
    plants, w_tr, c_tr = timed(truths, stretch=args.truths is None)
    plants = plants[:args.truths]
    study, w_st, c_st = timed(control_study, model, d.u, d.y, K=fit.K, plants=plants,
                              baselines=not args.no_baselines,
                              settings=LoopSettings.for_lab(tp.lab), progress=print)
    load1 = os.getloadavg()
    t = study.timings_s
    kind = "quick (18 states)" if args.quick else "full (36 states)"
    L = [f"## {kind} MIMO model", "",
         f"Commit {commit()}, {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; "
         f"{machine()}; load average {load0[0]:.1f} before, {load1[0]:.1f} after "
         "(the machine is shared: wall times vary with the load, CPU times less).", "",
         "| step | wall [s] | CPU [s] |", "| --- | --- | --- |",
         f"| identification of the model (comparator: `identify_model`, the demo's recipe) "
         f"| {w_id:.1f} | {c_id:.1f} |",
         f"| {len(plants)} FE truths (plant builds) | {w_tr:.1f} | {c_tr:.1f} |",
         f"| LQG design (`design_lqg`) | {t['design']:.1f} | - |",
         f"| baseline tuning on the model (4 kinds) | {t.get('baselines_tuning', 0):.1f} | - |",
         f"| LQG evaluation on {len(plants)} truths (poles, margins, H2, 12-bit simulation) "
         f"| {t['evaluation']:.1f} | - |",
         f"| baselines on {len(plants)} truths | {t.get('baselines', 0):.1f} | - |",
         f"| design + evaluation + baselines, total | {w_st:.1f} | {c_st:.1f} |", "",
         closed_loop_markdown(closed_loop_summary(study), heading="###")]
    text = "\n".join(L) + "\n"
    print(text)
    if args.out:
        out = Path(args.out)
        tag = "quick" if args.quick else "full"
        out.with_name(f"control_{tag}.json").write_text(json.dumps(json_safe(
            {**json_safe(closed_loop_summary(study)), "identification_s": {"wall": w_id, "cpu": c_id},
             "study_s": {"wall": w_st, "cpu": c_st}, "load": [load0, load1]}), indent=1))
        part = out.with_name(f"control_{tag}.md")
        part.write_text(text)
        print(f"written {part} (control.md collects control_quick.md and control_full.md)")


if __name__ == "__main__":
    main()
