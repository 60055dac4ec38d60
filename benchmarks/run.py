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
``results_io.write_json``, a ``"tables"`` entry for the README if it has one) or an output
folder, and a quick form, and add a line to :data:`BENCHMARKS`; a new file in ``benchmarks/``
that is in neither :data:`BENCHMARKS` nor :data:`HELPERS` stops the runner (and fails
``tests/benchmarks_smoke/test_run.py``).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent

#: name -> (full arguments, quick arguments) of ``python benchmarks/<script>``; ``{json}``
#: is replaced by the result file, ``{out}`` by the result folder. Every script of
#: ``benchmarks/`` is here or in :data:`HELPERS` (the runner refuses to start otherwise), so
#: the quick run in ``.ci/run`` exercises each one and none can rot unseen. The quick forms
#: are smoke runs at small sizes (their figures say only that the script works); the FE
#: comparison's full form takes ~30-60 min on the shared 2-core machine (OpenSeesPy and plain
#: scipy need minutes each on the 1.4e5-DOF lattice); its quick form times trussid alone on
#: the two small structures.
BENCHMARKS = {
    "fem_vs_opensees": (["bench_fem_vs_opensees.py", "--sizes", "all", "--json", "{json}"],
                        ["bench_fem_vs_opensees.py", "--cases", "boom-1.5e4,lattice-3e3", "--repeat", "1",
                         "--tools", "trussid", "--json", "{json}"]),
    "testbed": (["bench_testbed.py", "--json", "{json}"], ["bench_testbed.py", "--quick", "--json", "{json}"]),
    # dense LAPACK vs shift-invert around fem.modal.DENSE_MAX_DOF (issue 31)
    "dense_crossover": (["bench_dense_crossover.py", "--json", "{json}", "--out", "benchmarks/results/dense_crossover.md"],
                        ["bench_dense_crossover.py", "--quick", "--json", "{json}"]),
    "plant": (["bench_plant.py", "--json", "{json}"], ["bench_plant.py", "--quick", "--json", "{json}"]),
    "adapt": (["bench_adapt.py", "--json", "{json}", "--out", "benchmarks/results/adapt.md"],
              ["bench_adapt.py", "--quick", "--json", "{json}"]),
    "nastran_parse": (["bench_nastran_parse.py"],
                      ["bench_nastran_parse.py", "--elements", "3000", "--modes", "10",
                       "--out", "{out}/nastran_parse"]),
    "plid": (["bench_plid.py", "--json", "{json}"], ["bench_plid.py", "--quick", "--json", "{json}"]),
    "plid_thesis": (["bench_plid_thesis.py"], ["bench_plid_thesis.py", "--quick", "--out", "{out}"]),
    "plid_seeds": (["bench_plid_seeds.py"],
                   ["bench_plid_seeds.py", "--quick", "--seeds", "11-11", "--workers", "1", "--out", "{out}"]),
    "plid36": (["research_plid36.py"], ["research_plid36.py", "60dB", "11", "--quick", "--out", "{out}"]),
    "realdata": (["bench_realdata.py"],
                 ["bench_realdata.py", "--sets", "robotarm", "--methods", "PLID,N4SID", "--out", "{out}/realdata"]),
    "subframe_modal": (["subframe_modal.py", "--out", "docs/images"],
                       ["subframe_modal.py", "--orders", "6:9:3", "--order", "6", "--out", "{out}"]),
    "control": (["bench_control.py", "--out", "benchmarks/results/control.md"],
                ["bench_control.py", "--quick", "--samples", "3000", "--truths", "2", "--no-baselines",
                 "--out", "{out}/control.md"]),
    "render": (["bench_render.py"], ["bench_render.py", "--quick", "--out", "{out}/render.md"]),
    # report.html: size, the demo's time writing it against its total, load time offline
    "report_html": (["bench_report_html.py", "--json", "{json}"],
                    ["bench_report_html.py", "--quick", "--opens", "1", "--json", "{json}"]),
    # study engine: serial loop vs local and `dask` command-line clusters (~4 min quiet); a
    # 1e5-design study uninterrupted, then interrupted and resumed (~30 min quiet; quick: 600)
    "study": (["bench_study.py"], ["bench_study.py", "--quick", "--out", "{out}"]),
    "study_scale": (["bench_study_scale.py", "--json", "{json}"],
                    ["bench_study_scale.py", "--quick", "--json", "{json}"]),
    "threads": (["bench_threads.py"], ["bench_threads.py", "--repeats", "1", "--out", "{out}/threads.md"]),
    # the PLID prior with D against N4SID with D on three feed-through plants (issue 34)
    "feedthrough": (["bench_feedthrough.py", "--json", "{json}", "--out",
                     "benchmarks/results/plid_feedthrough.md"],
                    ["bench_feedthrough.py", "--quick", "--json", "{json}"]),
    "closedloop": (["bench_closedloop.py"], ["bench_closedloop.py", "--quick", "--out", "{out}"]),
    "predictor": (["bench_predictor.py", "--json", "{json}"],
                  ["bench_predictor.py", "--quick", "--json", "{json}"]),
    # identify against N4SID, CPU, paired with another checkout (--before; issue 34 item 1)
    "gain_ab": (["bench_gain_ab.py", "--json", "{json}"],
                ["bench_gain_ab.py", "--quick", "--json", "{json}"]),
    "uncertainty": (["bench_uncertainty.py"],
                    ["bench_uncertainty.py", "--records", "2", "--out", "{out}/uncertainty"]),
    # Not a measurement: the README's tables from the results; the quick run checks that the
    # README shows what benchmarks/results holds.
    "readme_tables": (["readme_tables.py"], ["readme_tables.py", "--check"]),
}

#: Benchmarks that read the measured data beside the repository (``../shared/realdata``):
#: without it they are skipped, and the summary says so.
NEEDS = {"realdata": Path(os.environ.get("TRUSSID_REALDATA", ROOT.parent / "shared" / "realdata")),
         "subframe_modal": ROOT.parent / "shared" / "realdata" / "flexibleStructure.mat",
         "predictor": Path(os.environ.get("TRUSSID_REALDATA", ROOT.parent / "shared" / "realdata")),
         "gain_ab": Path(os.environ.get("TRUSSID_REALDATA", ROOT.parent / "shared" / "realdata"))}

#: The modules of ``benchmarks/`` that are not benchmarks, and what runs them.
HELPERS = {
    "run.py": "this runner",
    "results_io.py": "stamped result files, imported by the benchmarks",
    "plid_cases.py": "the simulated PLID plants, imported by bench_plid*.py and research_plid36.py",
    "fem_models.py": "the FE structures of bench_fem_vs_opensees.py, bench_nastran_parse.py and "
                     "bench_render.py (and their OpenSeesPy worker)",
}


def unregistered(folder: Path = HERE) -> list[str]:
    """Python files of ``folder`` that are neither a registered benchmark nor a helper."""
    known = {args[0] for pair in BENCHMARKS.values() for args in pair} | set(HELPERS)
    return sorted(p.name for p in folder.glob("*.py") if p.name not in known)


#: The scaling guards: pytest files run by both modes.
GUARDS = ["tests/fem/test_scaling.py", "tests/plid/test_scaling.py"]


def run_one(name: str, args: list[str], out: Path) -> dict:
    """Run one benchmark command; returns its name, exit status, seconds and result file."""
    path = out / f"{name}.json"
    cmd = [sys.executable, str(HERE / args[0])] + [a.replace("{json}", str(path)).replace("{out}", str(out))
                                                   for a in args[1:]]
    need = NEEDS.get(name)
    if need is not None and not need.exists():
        return {"name": name, "status": 0, "seconds": 0.0, "skipped": f"no {need}"}
    t0, c0 = time.perf_counter(), _children_cpu()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    res = {"name": name, "status": proc.returncode, "seconds": time.perf_counter() - t0,
           "cpu_seconds": _children_cpu() - c0, "json": str(path) if "{json}" in args else ""}
    if proc.returncode != 0:
        res["stderr"] = proc.stderr[-3000:]
    else:
        guards = json.loads(path.read_text()).get("guards", []) if path.exists() else []
        res["failed_guards"] = [g for g in guards if not g.get("ok")]
    return res


def _children_cpu() -> float:
    """CPU seconds (user + system) of the finished child processes so far: on the shared
    machine the wall time measures the load as much as the benchmark."""
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_guards() -> dict:
    """The scaling guards through pytest (same assertions as the test suite)."""
    t0, c0 = time.perf_counter(), _children_cpu()
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *GUARDS], cwd=ROOT,
                          capture_output=True, text=True)
    res = {"name": "scaling guards", "status": proc.returncode, "seconds": time.perf_counter() - t0,
           "cpu_seconds": _children_cpu() - c0}
    if proc.returncode != 0:
        res["stderr"] = proc.stdout[-3000:]
    return res


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true", help="cheap form of every benchmark, for CI (a few minutes)")
    p.add_argument("--only", default=None, help="comma-separated benchmark names (and/or 'guards')")
    p.add_argument("--out", default=None, help="folder for the result files")
    args = p.parse_args(argv)
    stray = unregistered()
    if stray:
        print(f"run.py: {', '.join(stray)} in benchmarks/ is neither a benchmark nor a helper: add it "
              "to BENCHMARKS (with a quick form) or HELPERS", file=sys.stderr)
        return 2
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
    t0, c0 = time.perf_counter(), _children_cpu()
    for name in only:
        r = run_guards() if name == "guards" else run_one(name, BENCHMARKS[name][1 if args.quick else 0], out)
        ok = r["status"] == 0 and not r.get("failed_guards")
        tag = "skip" if r.get("skipped") else "ok  " if ok else "FAIL"
        print(f"{tag} {r['name']:18s} {r['seconds']:7.1f} s wall {r.get('cpu_seconds', 0.0):7.1f} s CPU  "
              f"{r.get('skipped') or r.get('json', '')}", flush=True)
        if not ok:
            print(r.get("stderr", "") or json.dumps(r.get("failed_guards")), file=sys.stderr)
        results.append(ok)
    print(f"total {time.perf_counter() - t0:.0f} s wall, {_children_cpu() - c0:.0f} s CPU, load average "
          f"{os.getloadavg()[0]:.1f} at the end", flush=True)
    return 0 if all(results) else 1


if __name__ == "__main__":
    raise SystemExit(main())
