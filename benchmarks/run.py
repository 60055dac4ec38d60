"""Run the benchmarks in one command; ``--quick`` is the cheap form CI runs.

Usage::

    python benchmarks/run.py [--quick] [--only NAME[,NAME...]] [--out DIR]

Each benchmark runs as its own command (a crash is its non-zero exit) and writes one stamped
JSON file (``benchmarks/results_io.py``: commit, machine, date, load) to ``--out``
(default: ``benchmarks/results/`` for the full run, a temporary folder for ``--quick``, so a
quick run never replaces the recorded figures). The scaling guards
(``tests/fem/test_scaling.py``, ``tests/plid/test_scaling.py``: memory and operation counts
against model size and record length) run in both modes. The command exits 1 if any
benchmark crashed or any guard failed, and prints a one-line summary per benchmark.

Then ``python benchmarks/readme_tables.py`` writes the README's tables from the results.

Adding a benchmark: give its script ``--json PATH`` (write the result with
``results_io.write_json``, a ``"tables"`` entry for the README if it has one) and
``--quick``, and add a line to :data:`BENCHMARKS`.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

#: name -> (full arguments, quick arguments) of ``python benchmarks/<script>``; ``{json}``
#: is replaced by the result file. The FE comparison's full form takes ~30-60 min on the
#: shared 2-core machine (OpenSeesPy and plain scipy need minutes each on the 1.4e5-DOF
#: lattice); its quick form times trussid alone on the two small structures.
BENCHMARKS = {
    "fem_vs_opensees": (["bench_fem_vs_opensees.py", "--sizes", "all", "--json", "{json}"],
                        ["bench_fem_vs_opensees.py", "--cases", "boom-1.5e4,lattice-3e3", "--repeat", "1",
                         "--tools", "trussid", "--json", "{json}"]),
    "testbed": (["bench_testbed.py", "--json", "{json}"], ["bench_testbed.py", "--quick", "--json", "{json}"]),
    "plant": (["bench_plant.py", "--json", "{json}"], ["bench_plant.py", "--quick", "--json", "{json}"]),
    # study engine: serial loop vs local and command-line Dask clusters (~3 min quiet; quick
    # ~1 min); a 1e5-design study interrupted and resumed (~30 min quiet; quick: 600 designs)
    "study": (["bench_study.py", "--json", "{json}"], ["bench_study.py", "--quick", "--json", "{json}"]),
    "study_scale": (["bench_study_scale.py", "--json", "{json}"], ["bench_study_scale.py", "--quick", "--json", "{json}"]),
}

#: The scaling guards: pytest files run by both modes.
GUARDS = ["tests/fem/test_scaling.py", "tests/plid/test_scaling.py"]


def run_one(name: str, args: list[str], out: Path) -> dict:
    """Run one benchmark command; returns its name, exit status, seconds and result file."""
    path = out / f"{name}.json"
    cmd = [sys.executable, str(HERE / args[0])] + [a.replace("{json}", str(path)) for a in args[1:]]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    res = {"name": name, "status": proc.returncode, "seconds": time.perf_counter() - t0, "json": str(path)}
    if proc.returncode != 0:
        res["stderr"] = proc.stderr[-3000:]
    else:
        guards = json.loads(path.read_text()).get("guards", []) if path.exists() else []
        res["failed_guards"] = [g for g in guards if not g.get("ok")]
    return res


def run_guards() -> dict:
    """The scaling guards through pytest (same assertions as the test suite)."""
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *GUARDS], cwd=ROOT,
                          capture_output=True, text=True)
    res = {"name": "scaling guards", "status": proc.returncode, "seconds": time.perf_counter() - t0}
    if proc.returncode != 0:
        res["stderr"] = proc.stdout[-3000:]
    return res


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="cheap form for CI (under ~2 min)")
    p.add_argument("--only", default=None, help="comma-separated benchmark names (and/or 'guards')")
    p.add_argument("--out", default=None, help="folder for the result files")
    args = p.parse_args(argv)
    names = list(BENCHMARKS) + ["guards"]
    only = args.only.split(",") if args.only else names
    unknown = [n for n in only if n not in names]
    if unknown:
        print(f"run.py: unknown benchmark {unknown[0]!r} (known: {', '.join(names)})", file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else (Path(tempfile.mkdtemp(prefix="trussid-bench-")) if args.quick
                                          else HERE / "results")
    out.mkdir(parents=True, exist_ok=True)
    results = []
    for name in only:
        r = run_guards() if name == "guards" else run_one(name, BENCHMARKS[name][1 if args.quick else 0], out)
        ok = r["status"] == 0 and not r.get("failed_guards")
        print(f"{'ok  ' if ok else 'FAIL'} {r['name']:18s} {r['seconds']:7.1f} s  {r.get('json', '')}", flush=True)
        if not ok:
            print(r.get("stderr", "") or json.dumps(r.get("failed_guards")), file=sys.stderr)
        results.append(ok)
    return 0 if all(results) else 1


if __name__ == "__main__":
    raise SystemExit(main())
