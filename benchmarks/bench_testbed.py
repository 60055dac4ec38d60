"""Benchmark: build + 30 lowest modes of the default testbed, and a wall-thickness sweep.

Issue 3, acceptance 7: at least 50 designs per second on one core for a sweep of 200 random
wall-thickness designs (build + 30 lowest modes each).

Three ways to get a design's 30 lowest modes are timed side by side in one run:

- ``rebuild``: what a user without the sweep API would do: ``build_testbed(tb.with_walls(w))``,
  ``assemble`` and the dense subset eigensolver (:func:`trussid.testbed.walls.solve_testbed_modes`);
- ``rebuild (fem.modal)``: the same with the general :func:`trussid.fem.modal.solve_modes`;
- ``sweep``: the model built once, :func:`trussid.testbed.walls.wall_basis`, then per design only
  :func:`trussid.testbed.walls.wall_modes` (strut terms of K and M re-formed from precomputed data on
  a fixed sparse pattern, dense ``scipy.linalg.eigh(..., subset_by_index=[0, 29])``).

One core: the BLAS/LAPACK thread pools are limited to one thread by setting
``OMP_NUM_THREADS``, ``OPENBLAS_NUM_THREADS`` and ``MKL_NUM_THREADS`` to 1 *before* numpy is
imported (threadpoolctl is not installed); the script prints the BLAS configuration it ran
with.

Usage::

    python benchmarks/bench_testbed.py [--designs 200] [--repeat 5] [--out benchmarks/results/testbed.md]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import scipy  # noqa: E402


def _timeit(fn, repeat: int) -> list[float]:
    out = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t)
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description="testbed build/modes/sweep benchmark")
    p.add_argument("--designs", type=int, default=200)
    p.add_argument("--rebuild-designs", type=int, default=40, help="designs timed with the rebuild paths")
    p.add_argument("--repeat", type=int, default=5)
    p.add_argument("--out", default=None, help="also write the results as Markdown here")
    p.add_argument("--json", default=None, help="write the stamped results (README table) here")
    p.add_argument("--quick", action="store_true", help="20 designs, 5 rebuilds, 2 repeats (CI)")
    args = p.parse_args(argv)
    if args.quick:
        args.designs, args.rebuild_designs, args.repeat = 20, 5, 2
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from results_io import finish, stamp, write_json

    st = stamp()

    from trussid.fem.assembly import assemble
    from trussid.fem.modal import solve_modes
    from trussid.testbed.model import build_testbed
    from trussid.testbed.walls import solve_testbed_modes, wall_basis, wall_modes
    from trussid.geometry.spec import Testbed

    tb = Testbed()
    build_testbed(tb)  # warm-up: imports, the UDF solid (memoised), first BLAS calls

    def build_and_solve():
        tbm = build_testbed(tb)
        return solve_testbed_modes(tbm, 30)

    single = _timeit(build_and_solve, args.repeat)
    tbm = build_testbed(tb)
    system = assemble(tbm.model)
    n_dof = system.n_dof
    t_build = _timeit(lambda: build_testbed(tb), args.repeat)
    t_asm = _timeit(lambda: assemble(tbm.model), args.repeat)
    t_eig = _timeit(lambda: solve_testbed_modes(tbm, 30, system=system), args.repeat)

    rng = np.random.default_rng(12345)
    nominal = np.array(tb.struts.walls)
    designs = nominal * rng.uniform(0.7, 1.3, size=(args.designs, 6))

    t0, c0 = time.perf_counter(), time.process_time()
    basis = wall_basis(tbm, system)
    t_basis, c_basis = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    f_sweep = np.array([wall_modes(basis, w, 30)[0] for w in designs])
    t_sweep, c_sweep = time.perf_counter() - t0, time.process_time() - c0

    nr = min(args.rebuild_designs, args.designs)
    t0, c0 = time.perf_counter(), time.process_time()
    f_rebuild = np.array([solve_testbed_modes(build_testbed(tb.with_walls(tuple(w))), 30).frequencies_hz
                          for w in designs[:nr]])
    t_rebuild, c_rebuild = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    for w in designs[:nr]:
        solve_modes(build_testbed(tb.with_walls(tuple(w))).model, 30)
    t_rebuild_fm, c_rebuild_fm = time.perf_counter() - t0, time.process_time() - c0
    flex = f_sweep[:nr, 6:]
    agree = float(np.max(np.abs(flex - f_rebuild[:, 6:]) / f_rebuild[:, 6:]))

    blas = "unknown"
    try:
        cfg = np.show_config(mode="dicts")
        blas = f"{cfg['Build Dependencies']['blas']['name']} {cfg['Build Dependencies']['blas']['version']}"
    except Exception:  # older numpy: no dict mode
        pass
    try:
        load = " ".join(f"{x:.1f}" for x in os.getloadavg())
    except OSError:
        load = "n/a"
    med = statistics.median
    lines = [
        "# Testbed benchmark (issue 3, acceptance 7)",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} logical CPUs (shared; other jobs were running: "
        f"load average at the end {load}); Python {platform.python_version()}, numpy {np.__version__}, "
        f"scipy {scipy.__version__}, BLAS {blas}, one thread (OMP/OPENBLAS/MKL_NUM_THREADS=1).",
        f"Model: default testbed, {len(tbm.model.node_ids)} nodes, {len(tbm.model.beams)} beams, "
        f"{n_dof} free DOF; 30 lowest modes.",
        "",
        "| step | time (median of %d) |" % args.repeat,
        "| --- | --- |",
        f"| build_testbed | {1e3 * med(t_build):.1f} ms |",
        f"| assemble | {1e3 * med(t_asm):.1f} ms |",
        f"| 30 modes (dense subset eigh) | {1e3 * med(t_eig):.1f} ms |",
        f"| **build + assemble + 30 modes** | **{1e3 * med(single):.1f} ms** |",
        "",
        f"Sweep of random wall designs (each wall uniform in 0.7..1.3 x nominal, seed 12345):",
        "",
        "| method | designs | wall time | designs/s (wall) | CPU time | designs per CPU-second |",
        "| --- | --- | --- | --- | --- | --- |",
        f"| sweep: wall_basis once ({1e3 * t_basis:.0f} ms, included) + wall_modes | {args.designs} | "
        f"{t_sweep + t_basis:.2f} s | **{args.designs / (t_sweep + t_basis):.1f}** | {c_sweep + c_basis:.2f} s | "
        f"**{args.designs / (c_sweep + c_basis):.1f}** |",
        f"| rebuild: build_testbed + assemble + dense subset eigh | {nr} | {t_rebuild:.2f} s | "
        f"{nr / t_rebuild:.1f} | {c_rebuild:.2f} s | {nr / c_rebuild:.1f} |",
        f"| rebuild with fem.modal.solve_modes | {nr} | {t_rebuild_fm:.2f} s | {nr / t_rebuild_fm:.1f} | "
        f"{c_rebuild_fm:.2f} s | {nr / c_rebuild_fm:.1f} |",
        "",
        "Wall time is what a user waits on this shared machine; CPU time (``time.process_time`` of "
        "this single-threaded process) is the time the one core actually spent, the better estimate "
        "of a dedicated core when other jobs compete for the CPUs.",
        "",
        f"Sweep vs rebuild frequencies (modes 7-30, first {nr} designs): max relative difference {agree:.1e}.",
        "Target: at least 50 designs/s on one core.",
        "",
        f"Verdict: {args.designs / (c_sweep + c_basis):.0f} designs per CPU-second of the one core used "
        f"({'meets' if args.designs / (c_sweep + c_basis) >= 50 else 'misses'} the target); "
        f"{args.designs / (t_sweep + t_basis):.0f} designs per wall-clock second on this shared machine "
        f"({'meets' if args.designs / (t_sweep + t_basis) >= 50 else 'misses'} it: the process got only a "
        f"fraction of a core at load average {load.split()[0] if load != 'n/a' else 'n/a'} on "
        f"{os.cpu_count()} CPUs).",
        "The first build in a process also pays the imports and the UDF solid's boolean union "
        "(about 1 s, memoised), excluded above by a warm-up build.",
    ]
    text = "\n".join(lines) + "\n"
    print(text)
    if args.json:
        la = f"{os.getloadavg()[0]:.1f}"
        rows = [["build + assemble + 30 modes", f"{1e3 * med(single):.1f} ms", f"median of {args.repeat}", la,
                 st["commit"]],
                ["wall-thickness sweep (wall_basis + wall_modes)",
                 f"{args.designs / (c_sweep + c_basis):.0f} designs per CPU-s",
                 f"{args.designs / (t_sweep + t_basis):.0f} per wall-s, {args.designs} designs", la, st["commit"]]]
        write_json(args.json, {"stamp": finish(st), "n_dof": n_dof, "sweep_vs_rebuild_max_rel_diff": agree,
                               "tables": {"testbed": {
                                   "columns": ["testbed (default, %d DOF)" % n_dof, "figure", "how", "load (1-min)",
                                               "commit"],
                                   "rows": rows,
                                   "notes": f"`python benchmarks/bench_testbed.py`, {st['date_utc']}, one BLAS "
                                            "thread; details: benchmarks/results/testbed.md."}}})
    if args.out:
        from trussid._util.files import atomic_path

        with atomic_path(args.out) as tmp:
            tmp.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
