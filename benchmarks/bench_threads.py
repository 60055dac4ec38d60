"""Time ``trussid plant`` and ``trussid compare`` with one BLAS thread (the default since
issue 19) and with the BLAS libraries' own default (``--threads 0``: one thread per core),
alternating in the same run so that both see the same machine load.

Each run is a fresh ``python -m trussid`` process (what a user pays), with the BLAS
environment variables removed so that ``--threads 0`` really gets the libraries' default.
Wall time from ``time.perf_counter``; CPU time (user + sys) of the child from
``resource.getrusage``. The load average is read before and after every run.

The compare case: a 36-state model of the default testbed plant (balanced truncation of
the plant, ``plid.balanced_truncation``: a stand-in for an identified 36-state model, which
the audit compared) against the 141-state plant, band 50-350 Hz.

Usage::

    python benchmarks/bench_threads.py [--repeats 3]   # writes benchmarks/results/threads.md
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "threads.md"
SETTINGS = {"1 thread (default)": [], "library default (--threads 0)": ["--threads", "0"]}


def _env():
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                        "TRUSSID_THREADS")}
    return env


def _load() -> float:
    return os.getloadavg()[0]


def timed(args: list[str]) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    l0 = _load()
    t0 = time.perf_counter()
    res = subprocess.run([sys.executable, "-m", "trussid", *args], capture_output=True,
                         text=True, env=_env())
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode:
        raise SystemExit(f"trussid {' '.join(args)} failed:\n{res.stderr}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall": wall, "cpu": cpu, "load": (l0, _load())}


def setup(work: Path) -> None:
    """The plant file and the 36-state model (made once, not timed)."""
    subprocess.run([sys.executable, "-m", "trussid", "plant", "--out", str(work / "plant.npz")],
                   check=True, capture_output=True, env=_env())
    code = (
        "import sys; from trussid.plid.modelfile import load_model, save_model; "
        "from trussid.plid.reduce import balanced_truncation; "
        "p, meta = load_model(sys.argv[1]); "
        "r = balanced_truncation(p, 36).model; "
        "save_model(sys.argv[2], r, input_names=meta.input_names, "
        "output_names=meta.output_names)")
    subprocess.run([sys.executable, "-c", code, str(work / "plant.npz"),
                    str(work / "m36.npz")], check=True, env=_env())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=RESULTS)
    a = ap.parse_args()
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                            capture_output=True, text=True).stdout.strip() or "unknown"
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--", "trussid",
                            "plid", "fem"], capture_output=True, text=True).stdout.strip()
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        setup(work)
        cases = {
            "trussid plant": ["plant", "--out", str(work / "p.npz")],
            "trussid compare": ["compare", str(work / "m36.npz"), str(work / "plant.npz"),
                                "--out", str(work / "cmp"), "--band", "50", "350"],
        }
        rows = {(c, s): [] for c in cases for s in SETTINGS}
        start = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
        for _ in range(a.repeats):
            for c, args in cases.items():
                for s, extra in SETTINGS.items():
                    r = timed([*extra, *args])
                    rows[(c, s)].append(r)
                    print(f"{c:16s} {s:32s} wall {r['wall']:6.2f} s  cpu {r['cpu']:6.2f} s  "
                          f"load {r['load'][0]:.2f}->{r['load'][1]:.2f}", flush=True)
    lines = [
        "# BLAS threads in `trussid plant` and `trussid compare` (issue 19, acceptance 5)",
        "",
        f"Measured by `python benchmarks/bench_threads.py --repeats {a.repeats}` at commit "
        f"`{commit}`{' (with uncommitted changes)' if dirty else ''}, {start}.",
        f"Machine: {platform.node()}, {os.cpu_count()} cores, {platform.processor() or platform.machine()}, "
        f"Python {platform.python_version()}; shared with other jobs (load average below).",
        "Each run is a fresh process; the two settings alternate run by run, so both see the "
        "same load. The BLAS environment variables were removed for every run.",
        "",
        "| command | BLAS threads | wall [s] median (runs) | CPU user+sys [s] median | load average during the runs |",
        "| --- | --- | --- | --- | --- |",
    ]
    for (c, s), rs in rows.items():
        walls = ", ".join(f"{r['wall']:.1f}" for r in rs)
        loads = [x for r in rs for x in r["load"]]
        lines.append(f"| `{c}` | {s} | {statistics.median(r['wall'] for r in rs):.2f} ({walls}) "
                     f"| {statistics.median(r['cpu'] for r in rs):.2f} | "
                     f"{min(loads):.1f}-{max(loads):.1f} |")
    for c in cases:
        one = statistics.median(r["wall"] for r in rows[(c, "1 thread (default)")])
        lib = statistics.median(r["wall"] for r in rows[(c, "library default (--threads 0)")])
        lines.append("")
        lines.append(f"- `{c}`: median wall {lib:.2f} s with the libraries' default threads, "
                     f"{one:.2f} s with one thread ({lib / one:.2f} x).")
    lines += ["", "Why: both commands spend their time in many small dense products (frequency "
              "responses of a 141-state plant at thousands of frequencies, simulation), where "
              "BLAS threads only add synchronisation, and on a loaded machine wait for a core.",
              ""]
    a.out.write_text("\n".join(lines))
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
