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
    args = ap.parse_args()

    from trussid.testbed.plant import testbed_plant

    first = time.perf_counter()
    plant = testbed_plant()                        # includes imports' first-use costs
    first = time.perf_counter() - first
    times = []
    for _ in range(args.repeat):
        t = time.perf_counter()
        plant = testbed_plant()
        times.append(time.perf_counter() - t)
    best, median = min(times), statistics.median(times)
    row = (f"| {time.strftime('%Y-%m-%d %H:%M')} | {plant.discrete.nstates} states, "
           f"{len(plant.modes.omega)} modes | {first:.3f} | {best:.3f} | {median:.3f} | "
           f"{'yes' if best < 0.1 else 'no'} | {machine()} |")
    print("first call [s], best [s], median [s]:", f"{first:.3f} {best:.3f} {median:.3f}")
    print(row)
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
