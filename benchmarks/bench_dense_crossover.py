"""Where dense LAPACK stops paying against sparse shift-invert: the one ``DENSE_MAX_DOF``.

For the testbed meshed with 2..10 elements per bare tube segment (174 to ~750 reduced DOFs)
it times, in one process and in alternation, the two paths that
:data:`trussid.fem.modal.DENSE_MAX_DOF` chooses between, for 30 modes (what the testbed, its
plant and the wall study ask for):

- ``solve_modes``: :func:`trussid.fem.modal.solve_modes` with ``method="dense"`` against
  ``method="sparse"`` on the assembled system (the testbed's eigen solution);
- ``wall sweep``: :func:`trussid.fem.modal.dense_modes` on the dense pair a wall sweep forms
  (:func:`trussid.testbed.walls.wall_matrices`) against ``solve_modes(method="sparse")`` on
  the same pair as sparse matrices (what :func:`trussid.testbed.walls.wall_modes` does on
  either side of the constant).

CPU seconds (``time.process_time``, one BLAS thread), median of ``--repeat``; the load average
and commit are recorded. Writes a Markdown table to ``--out`` and the stamped JSON to ``--json``.

    python benchmarks/bench_dense_crossover.py [--quick] [--repeat 5] [--json PATH] [--out PATH]
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from results_io import finish, stamp, write_json  # noqa: E402
from trussid.fem.assembly import assemble  # noqa: E402
from trussid.fem.modal import DENSE_MAX_DOF, dense_modes, solve_modes  # noqa: E402
from trussid.geometry.spec import Testbed  # noqa: E402
from trussid.testbed.model import build_testbed  # noqa: E402
from trussid.testbed.walls import wall_basis, wall_matrices  # noqa: E402

N_MODES = 30


def cpu(fn, repeat: int) -> float:
    """Median CPU seconds of ``fn()`` over ``repeat`` calls."""
    out = []
    for _ in range(repeat):
        c = time.process_time()
        fn()
        out.append(time.process_time() - c)
    return statistics.median(out)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="two mesh sizes, one repeat (CI smoke run)")
    ap.add_argument("--repeat", type=int, default=5, help="timings per point (median)")
    ap.add_argument("--json", default=None, help="write the stamped results here")
    ap.add_argument("--out", default=None, help="Markdown file to write (default: print only)")
    args = ap.parse_args()
    st = stamp()
    meshes = (2, 4) if args.quick else (2, 3, 4, 5, 6, 7, 8, 10)
    repeat = 1 if args.quick else args.repeat
    load0 = os.getloadavg()[0]
    rows = []
    for eps in meshes:
        tbm = build_testbed(Testbed(), eps)
        system = assemble(tbm.model)
        basis = wall_basis(tbm, system)
        walls = 1.2 * np.asarray(tbm.testbed.struts.walls)
        sweep_sys = replace(system, **dict(zip(("K", "M"), (basis.sparse(d) for d in basis.data(walls)))))
        solve_modes(system, N_MODES, method="sparse")  # warm-up (imports, first factorisation)
        t = {
            "solve dense": cpu(lambda: solve_modes(system, N_MODES, method="dense"), repeat),
            "solve sparse": cpu(lambda: solve_modes(system, N_MODES, method="sparse"), repeat),
            "sweep dense": cpu(lambda: dense_modes(*wall_matrices(basis, walls), N_MODES, overwrite=True), repeat),
            "sweep sparse": cpu(lambda: solve_modes(sweep_sys, N_MODES, method="sparse"), repeat),
        }
        rows.append({"elements_per_segment": eps, "n_dof": int(system.n_dof), **{k: float(v) for k, v in t.items()}})
        print(rows[-1], flush=True)
    load1 = os.getloadavg()[0]
    lines = [
        "# Dense LAPACK vs sparse shift-invert: the crossover (issue 31, acceptance 4)",
        "",
        f"Commit {st['commit']}, {st['date_utc']}; load average (1 min) {load0:.1f} before, {load1:.1f} after, "
        f"2 logical CPUs shared with other jobs; one BLAS thread. {N_MODES} modes of the default testbed "
        f"meshed with n elements per bare tube segment; CPU seconds (time.process_time), median of {repeat}. "
        f"`python benchmarks/bench_dense_crossover.py`. DENSE_MAX_DOF at this commit: {DENSE_MAX_DOF}.",
        "",
        "| n | reduced DOFs | solve_modes dense [ms] | solve_modes sparse [ms] | sweep dense [ms] | sweep sparse [ms] |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        lines.append(f"| {r['elements_per_segment']} | {r['n_dof']} | {1e3 * r['solve dense']:.1f} | "
                     f"{1e3 * r['solve sparse']:.1f} | {1e3 * r['sweep dense']:.1f} | {1e3 * r['sweep sparse']:.1f} |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.json:
        write_json(args.json, {"stamp": finish(st), "n_modes": N_MODES, "dense_max_dof": DENSE_MAX_DOF,
                               "load_before": load0, "load_after": load1, "rows": rows})
    if args.out:
        with open(args.out, "w") as fh:
            fh.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
