"""Benchmark: build the default testbed plant (model, modes, actuators, sensors, lab chain, ZOH).

Issue 4, acceptance 6: the whole build, modes included, under 0.1 s. BLAS is limited to one
thread before numpy loads (on this 2-core shared machine several threads only contend).

    python benchmarks/bench_plant.py [--repeat N] [--out benchmarks/results/plant.md]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
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
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, load average {load:.1f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--out", default=None, help="append a markdown row to this file")
    ap.add_argument("--json", default=None, help="write the stamped results (README table) here")
    ap.add_argument("--quick", action="store_true", help="3 repeats (CI)")
    args = ap.parse_args()
    if args.quick:
        args.repeat = 3
    import sys

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from results_io import finish, stamp, write_json

    st = stamp()

    from trussid.testbed.plant import testbed_plant

    first = time.perf_counter()
    plant = testbed_plant()                        # includes imports' first-use costs
    first = time.perf_counter() - first
    times, cpu = [], []
    for _ in range(args.repeat):
        t, c = time.perf_counter(), time.process_time()
        plant = testbed_plant()
        times.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    best, median = min(times), statistics.median(times)
    row = (f"| {time.strftime('%Y-%m-%d %H:%M')} | {plant.discrete.nstates} states, "
           f"{len(plant.modes.omega)} modes | {first:.3f} | {best:.3f} | {median:.3f} | "
           f"{'yes' if best < 0.1 else 'no'} | {machine()} |")
    print("first call [s], best [s], median [s]:", f"{first:.3f} {best:.3f} {median:.3f}")
    print(row)
    if args.json:
        write_json(args.json, {"stamp": finish(st), "tables": {"plant": {
            "columns": ["testbed plant build (modes included)", "best of %d (wall)" % args.repeat, "median (wall)",
                        "best CPU", "first call", "load (1-min)", "commit"],
            "rows": [[f"{plant.discrete.nstates} states, {len(plant.modes.omega)} modes", f"{1e3 * best:.0f} ms",
                      f"{1e3 * median:.0f} ms", f"{1e3 * min(cpu):.0f} ms", f"{first:.2f} s",
                      f"{os.getloadavg()[0]:.1f}", st["commit"]]],
            "notes": f"`python benchmarks/bench_plant.py`, {st['date_utc']}, one BLAS thread; the first call "
                     "pays imports and first-use costs."}}})
    if args.out:
        path = Path(args.out)
        if not path.exists():
            path.write_text("# Testbed plant build time (issue 4, acceptance 6: under 0.1 s)\n\n"
                            "Model build, assembly, all modes below Nyquist (dense by value), PZT loads, "
                            "accelerometers, modal plant, electronics, ZOH at 1600 Hz. One BLAS thread.\n\n"
                            "| when | plant | first call [s] | best of N [s] | median [s] | < 0.1 s | machine |\n"
                            "|---|---|---|---|---|---|---|\n")
        with path.open("a") as fh:
            fh.write(row + "\n")


if __name__ == "__main__":
    main()
