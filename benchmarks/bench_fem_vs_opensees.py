"""FE benchmark: trussid against OpenSeesPy (and plain scipy) on the same structures (issues 2, 18).

Usage::

    python benchmarks/bench_fem_vs_opensees.py [--sizes small|all] [--repeat 3]
        [--tools trussid,opensees,scipy] [--json OUT.json] [--md OUT.md]

For every structure of :data:`fem_models.SIZES` (a truss boom of triangular section of
~1.5e4 and ~1.5e5 DOF, a cubic lattice frame of ~3e3, ~3e4 and ~1.4e5 DOF; ``--sizes
small`` runs the smaller boom and lattice) and every tool (plain scipy only on
:data:`SCIPY_CASES`), the lowest 20 modes are computed ``--repeat`` times,
each run in a fresh child process, and the best run is reported. Phases timed
(``time.perf_counter``):

- trussid: *setup* = the spec arrays -> :class:`trussid.fem.Model`; *assembly* =
  :func:`trussid.fem.assembly.assemble`; *modes* = :func:`trussid.fem.modal.solve_modes` (20 modes).
- scipy: trussid's setup and assembly, then *modes* = ``scipy.sparse.linalg.eigsh(K, 20,
  M, sigma=0)`` with scipy's own shift-invert (SuperLU with its defaults).
- OpenSeesPy: *setup* = the ``node``/``fix``/``geomTransf``/``element`` calls; *modes* =
  ``ops.eigen`` (20 modes), which forms K and M itself, so OpenSees' assembly is inside its
  modes time and cannot be timed apart from the Python side.

So the like-for-like comparisons are *total* (setup + assembly + modes) and
*assembly + modes* (from a defined model to 20 frequencies).

Peak memory is the child's peak resident set size (``ru_maxrss`` from ``os.wait4`` on that
child alone), so each tool is measured in isolation, imports included; the RSS right after
the imports is reported too (``base MB``), so the model's own share is the difference.
OpenSeesPy runs with LD_LIBRARY_PATH set to its wheel's bundled library folder
(:func:`fem_models.opensees_env`); its eigen-solver settings are chosen with
``--sweep-opensees`` (see the results file for the sweep).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from fem_models import SIZES, SMALL, opensees_env, spec_from_name  # noqa: E402
from results_io import RESULTS, finish, stamp, write_json  # noqa: E402

#: Cases on which plain scipy (``eigsh`` shift-invert on its default SuperLU) is timed too.
SCIPY_CASES = ("lattice-1.4e5",)

N_MODES = 20
#: OpenSeesPy settings per structure kind: the fastest combination that gives the right answer,
#: from ``--sweep-opensees`` (20 modes, ARPACK shift-invert ``-genBandArpack`` in every case;
#: ``-fullGenLapack`` took 415 s on the 2 688-DOF lattice and ``-symmBandLapack`` solves only
#: the standard problem K x = lambda x; ``system SparseSYM`` returned wrong frequencies).
#: Measured under load (see benchmarks/results/fem_vs_opensees.md): boom 1.5e4: SuperLU+AMD
#: 5.4 s, ProfileSPD+RCM (OpenSees' default) 7.4 s, Mumps 7.9 s, BandGeneral 11.7 s,
#: BandSPD 12.5 s, UmfPack 29.9 s; lattice 2.8e4: Mumps 227 s, SuperLU+AMD 251 s,
#: ProfileSPD and BandSPD > 300 s.
OPENSEES_SETTINGS = {
    "boom": {"solver": "-genBandArpack", "system": "SuperLU", "numberer": "AMD"},
    "lattice": {"solver": "-genBandArpack", "system": "Mumps", "numberer": "RCM"},
}


def opensees_settings(case: str) -> dict:
    """The OpenSeesPy settings used for ``case`` (by structure kind)."""
    kind = SIZES.get(case, case).partition(":")[0]
    return dict(OPENSEES_SETTINGS[kind])


# ------------------------------------------------------------------------------ workers
def _rss_mb(field: str = "VmRSS") -> float:
    """This process's resident set size (``VmRSS``) or its peak (``VmHWM``) [MB]."""
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith(field + ":"):
                return int(line.split()[1]) / 1024.0
    return float("nan")


def worker_trussid(case: str, n_modes: int, method: str) -> dict:
    from trussid.fem.assembly import assemble
    from trussid.fem.modal import solve_modes
    import scipy.sparse.linalg  # noqa: F401  (import cost is not part of the measurement)

    from fem_models import to_trussid

    base = _rss_mb()
    spec = spec_from_name(case)
    c0, t0 = time.process_time(), time.perf_counter()
    model = to_trussid(spec)
    t1 = time.perf_counter()
    system = assemble(model)
    t2 = time.perf_counter()
    modes = solve_modes(system, n_modes=n_modes, method=method)
    t3 = time.perf_counter()
    return {"setup": t1 - t0, "assembly": t2 - t1, "modes": t3 - t2, "cpu": time.process_time() - c0,
            "n_dof": int(system.n_dof), "base_mb": base, "method": modes.method,
            "frequencies_hz": np.asarray(modes.frequencies_hz).tolist()}


def worker_opensees(case: str, n_modes: int, solver: str, system: str | None, numberer: str | None) -> dict:
    import openseespy.opensees as ops

    from fem_models import build_opensees, opensees_eigen

    base = _rss_mb()
    spec = spec_from_name(case)
    c0, t0 = time.process_time(), time.perf_counter()
    build_opensees(spec, ops)
    t1 = time.perf_counter()
    f = opensees_eigen(ops, n_modes, solver, system, numberer)
    t2 = time.perf_counter()
    return {"setup": t1 - t0, "assembly": 0.0, "modes": t2 - t1, "cpu": time.process_time() - c0,
            "n_dof": spec.n_free_dof, "base_mb": base, "frequencies_hz": np.sort(f).tolist()}


def worker_scipy(case: str, n_modes: int) -> dict:
    """Plain scipy: trussid's assembly, then ``eigsh(K, M=M, sigma=0)`` with scipy's own
    shift-invert operator (``splu`` with its defaults: COLAMD ordering, partial pivoting)."""
    import scipy.sparse.linalg as sla

    from trussid.fem.assembly import assemble

    from fem_models import to_trussid

    base = _rss_mb()
    spec = spec_from_name(case)
    c0, t0 = time.process_time(), time.perf_counter()
    model = to_trussid(spec)
    t1 = time.perf_counter()
    system = assemble(model)
    t2 = time.perf_counter()
    lam = sla.eigsh(system.K.tocsc(), k=n_modes, M=system.M.tocsc(), sigma=0.0, which="LM",
                    return_eigenvectors=False)
    t3 = time.perf_counter()
    f = np.sqrt(np.maximum(np.sort(lam), 0.0)) / (2 * np.pi)
    return {"setup": t1 - t0, "assembly": t2 - t1, "modes": t3 - t2, "cpu": time.process_time() - c0,
            "n_dof": int(system.n_dof), "base_mb": base, "frequencies_hz": f.tolist()}


def _worker_main(args) -> int:
    if args.worker == "trussid":
        out = worker_trussid(args.case, args.modes, args.method)
    elif args.worker == "scipy":
        out = worker_scipy(args.case, args.modes)
    else:
        out = worker_opensees(args.case, args.modes, args.os_solver or "-genBandArpack",
                              args.os_system, args.os_numberer)
    out["peak_mb_self"] = _rss_mb("VmHWM")
    print("RESULT " + json.dumps(out), flush=True)
    return 0


# ------------------------------------------------------------------------------ driver
def run_worker(tool: str, case: str, n_modes: int = N_MODES, timeout: float = 600.0,
               method: str = "auto", opensees: dict | None = None, blas_threads: int | None = None) -> dict:
    """Run one measurement in a fresh child process; returns its figures.

    The child's peak RSS comes from ``os.wait4`` on that child (its own ``ru_maxrss``), not
    from RUSAGE_CHILDREN, which would mix all children.
    """
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", tool, "--case", case,
           "--modes", str(n_modes), "--method", method]
    env = dict(os.environ)
    o = None
    if tool == "opensees":
        o = {**opensees_settings(case), **{k: v for k, v in (opensees or {}).items() if v}}
        # "--opt=value": the OpenSees flags start with "-", which argparse would take for options.
        cmd += [f"--os-solver={o['solver']}"]
        if o.get("system"):
            cmd += [f"--os-system={o['system']}"]
        if o.get("numberer"):
            cmd += [f"--os-numberer={o['numberer']}"]
        env = opensees_env()
    if blas_threads:
        # OpenBLAS (numpy/scipy) and OpenMP (OpenSees' MUMPS) thread pools.
        env.update(OPENBLAS_NUM_THREADS=str(blas_threads), OMP_NUM_THREADS=str(blas_threads))
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, env=env, text=True)
        timed_out = False
        while True:
            pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() - t0 > timeout:
                proc.kill()
                pid, status, usage = os.wait4(proc.pid, 0)
                timed_out = True
                break
            time.sleep(0.02)
        wall = time.perf_counter() - t0
        proc.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        stdout, stderr = out.read(), err.read()
    result = {"tool": tool, "case": case, "wall": wall, "blas_threads": blas_threads, "settings": o, "peak_mb": usage.ru_maxrss / 1024.0,
              "cpu_rusage": usage.ru_utime + usage.ru_stime,  # the child's CPU, also when killed
              "load_before": load_before, "load_after": os.getloadavg()[0]}
    lines = [ln for ln in stdout.splitlines() if ln.startswith("RESULT ")]
    if timed_out:
        result["status"] = f"timeout after {timeout:.0f} s"
    elif proc.returncode != 0 or not lines:
        result["status"] = f"failed (exit {proc.returncode}): {stderr.strip().splitlines()[-1] if stderr.strip() else ''}"
    else:
        result.update(json.loads(lines[-1][len("RESULT "):]))
        result["status"] = "ok"
        result["total"] = result["setup"] + result["assembly"] + result["modes"]
    return result


def machine_info() -> dict:
    """nproc, CPU model, memory and load average, for the results file."""
    model = platform.processor() or "?"
    try:
        lscpu = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        model = next((ln.split(":", 1)[1].strip() for ln in lscpu.splitlines() if ln.startswith("Model name")), model)
    except OSError:
        pass
    mem = "?"
    with open("/proc/meminfo") as fh:
        for line in fh:
            if line.startswith("MemTotal:"):
                mem = f"{int(line.split()[1]) / 1024**2:.1f} GiB"
    from trussid import fem

    fem_dir = Path(fem.__file__).resolve().parent
    git = subprocess.run(["git", "-C", str(fem_dir), "log", "-1", "--format=%h", "--", "."],
                         capture_output=True, text=True)
    dirty = subprocess.run(["git", "-C", str(fem_dir), "status", "--porcelain", "--", "."],
                           capture_output=True, text=True).stdout.strip()
    fem_version = (git.stdout.strip() + (" + uncommitted changes" if dirty else "")) if git.returncode == 0 \
        else os.environ.get("TRUSSID_FEM_VERSION", "unknown")
    return {"nproc": len(os.sched_getaffinity(0)), "cpu": model, "memory": mem,
            "fem": f"{fem_dir} ({fem_version})",
            "loadavg": os.getloadavg(), "python": platform.python_version(),
            "numpy": np.__version__, "scipy": __import__("scipy").__version__,
            "date_utc": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}


def best_of(runs: list[dict]) -> dict:
    ok = [r for r in runs if r["status"] == "ok"]
    if not ok:
        return runs[-1]
    best = dict(min(ok, key=lambda r: r["total"]))
    best["n_runs"] = len(ok)
    best["totals"] = [round(r["total"], 3) for r in ok]
    best["peak_mb"] = min(r["peak_mb"] for r in ok)
    return best


def _fmt(x, spec=".2f"):
    return "—" if x is None else format(x, spec)


def markdown(results: dict, info: dict) -> str:
    """Results as a markdown table, one row per tool and size plus a ratio row."""
    lines = [
        f"Machine: {info['nproc']} cores ({info['cpu']}), {info['memory']}, load average at start "
        f"{info['loadavg'][0]:.2f}/{info['loadavg'][1]:.2f}/{info['loadavg'][2]:.2f}; Python {info['python']}, "
        f"numpy {info['numpy']}, scipy {info['scipy']}; {info['date_utc']}; fem from {info['fem']}.",
        "",
        "| structure | DOF | tool | setup s | assembly s | modes s | assembly+modes s | total s | CPU s | peak MB (base) | runs: totals s | load 1-min |",
        "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---|---:|",
    ]
    for case, per_tool in results.items():
        for tool, r in per_tool.items():
            if r.get("settings"):
                tool = f"{tool} ({r['settings']['system']}, {r['settings']['numberer']})"
            if r["status"] != "ok":
                lines.append(f"| {case} | {r.get('n_dof', '')} | {tool} | | | | | {r['status']} | | {r['peak_mb']:.0f} | | {r['load_before']:.2f} |")
                continue
            asm = "(in eigen)" if tool.startswith("opensees") else _fmt(r["assembly"])
            lines.append(
                f"| {case} | {r['n_dof']} | {tool} | {_fmt(r['setup'])} | {asm} | {_fmt(r['modes'])} | "
                f"{_fmt(r['assembly'] + r['modes'])} | {_fmt(r['total'])} | {_fmt(r['cpu'])} | {r['peak_mb']:.0f} ({r['base_mb']:.0f}) | "
                f"{', '.join(map(str, r['totals']))} | {r['load_before']:.2f} |")
        t = per_tool.get("trussid")
        for tool, label in (("opensees", "OpenSees"), ("scipy", "scipy")):
            o = per_tool.get(tool)
            if not (t and o and t["status"] == "ok" and o["status"] == "ok"):
                continue
            ft, fo = np.asarray(t["frequencies_hz"]), np.asarray(o["frequencies_hz"])
            k = min(len(ft), len(fo))
            dev = np.max(np.abs(ft[:k] - fo[:k]) / fo[:k])
            lines.append(
                f"| {case} | | **{label} / trussid** | {o['setup'] / max(t['setup'], 1e-9):.1f}x | | | "
                f"**{(o['assembly'] + o['modes']) / (t['assembly'] + t['modes']):.1f}x** | **{o['total'] / t['total']:.1f}x** | {o['cpu'] / t['cpu']:.1f}x | "
                f"{o['peak_mb'] / t['peak_mb']:.2f}x | max rel. freq. diff {dev:.1e} | |")
    return "\n".join(lines)


def readme_tables(results: dict, st: dict) -> dict:
    """The README's FE table: per case, trussid against each comparator (best runs)."""
    rows = []
    for case, per_tool in results.items():
        t = per_tool.get("trussid")
        if not t or t["status"] != "ok":
            continue
        for tool, r in per_tool.items():
            name = tool if not r.get("settings") else f"OpenSeesPy ({r['settings']['system']})"
            name = {"trussid": "trussid", "scipy": "scipy eigsh shift-invert"}.get(tool, name)
            if r["status"] != "ok":
                rows.append([case, r.get("n_dof", t["n_dof"]), name, r["status"], "", f"{r['peak_mb']:.0f}", "",
                             f"{r['load_before']:.1f}", st["commit"]])
                continue
            speed = "" if tool == "trussid" else f"{(r['assembly'] + r['modes']) / (t['assembly'] + t['modes']):.1f}x"
            rows.append([case, r["n_dof"], name, f"{r['assembly'] + r['modes']:.2f}", f"{r['cpu']:.2f}",
                         f"{r['peak_mb']:.0f}", speed, f"{r['load_before']:.1f}", st["commit"]])
    return {"fem": {"columns": ["structure", "DOF", "tool", "assembly + 20 modes s", "CPU s", "peak MB",
                                "tool / trussid time", "load (1-min)", "commit"],
                    "rows": rows,
                    "notes": (f"`python benchmarks/bench_fem_vs_opensees.py --sizes all`, {st['date_utc']}, "
                              f"{st['machine']['nproc']} cores ({st['machine']['cpu']}), shared and loaded; "
                              "best of up to 3 runs (runs over 2 min are not repeated), each in a fresh "
                              "process; peak MB is that process's peak RSS, imports included. "
                              "Details: benchmarks/results/fem_vs_opensees.md.")}}


def sweep_opensees(case: str, timeout: float, repeat: int) -> list[dict]:
    """Time OpenSeesPy's eigen on ``case`` for each linear system and numberer."""
    combos = [(s, n) for s in ("ProfileSPD", "BandSPD", "BandGeneral", "SuperLU", "UmfPack", "Mumps")
              for n in ("RCM", "AMD")]
    rows = []
    for system, numberer in combos:
        runs = [run_worker("opensees", case, timeout=timeout,
                           opensees={"solver": "-genBandArpack", "system": system, "numberer": numberer})
                for _ in range(repeat)]
        r = best_of(runs)
        r.update(system=system, numberer=numberer)
        rows.append(r)
        print(f"{case:12s} {system:12s} {numberer:6s} "
              f"{r['modes'] if r['status'] == 'ok' else float('nan'):8.2f} s  {r['peak_mb']:7.0f} MB  "
              f"f1 {r.get('frequencies_hz', [np.nan])[0]:.6g} Hz  {r['status']}", flush=True)
    return rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", choices=("small", "all"), default="small")
    p.add_argument("--cases", default=None, help="comma-separated cases (keys of SIZES or boom:<n>/lattice:<n>)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--tools", default="trussid,opensees,scipy",
                   help="comma-separated; scipy runs only on --scipy-cases")
    p.add_argument("--scipy-cases", default=",".join(SCIPY_CASES),
                   help="cases on which plain scipy shift-invert is also timed")
    p.add_argument("--timeout", type=float, default=1800.0, help="per run [s]")
    p.add_argument("--json", default=None, help="write the stamped results to this JSON file "
                   "(default with --sizes all: benchmarks/results/fem_vs_opensees.json)")
    p.add_argument("--md", default=None, help="also write the markdown table to this file")
    p.add_argument("--blas-threads", type=int, default=None,
                   help="set OPENBLAS_NUM_THREADS and OMP_NUM_THREADS in both tools' processes")
    p.add_argument("--sweep-opensees", default=None, metavar="CASE",
                   help="time OpenSeesPy's linear-system/numberer options on CASE and exit")
    # worker mode (internal)
    p.add_argument("--worker", choices=("trussid", "opensees", "scipy"), help=argparse.SUPPRESS)
    p.add_argument("--case", help=argparse.SUPPRESS)
    p.add_argument("--modes", type=int, default=N_MODES, help=argparse.SUPPRESS)
    p.add_argument("--method", default="auto", help="trussid solve_modes method")
    p.add_argument("--os-solver", default=None, help="OpenSees eigen solver flag (default: by structure)")
    p.add_argument("--os-system", default=None, help="OpenSees system (default: by structure)")
    p.add_argument("--os-numberer", default=None, help="OpenSees numberer (default: by structure)")
    args = p.parse_args(argv)

    if args.worker:
        return _worker_main(args)
    info = machine_info()
    st = stamp()
    if args.sweep_opensees:
        rows = sweep_opensees(args.sweep_opensees, args.timeout, args.repeat)
        if args.json:
            Path(args.json).write_text(json.dumps({"machine": info, "sweep": rows}, indent=1))
        return 0

    cases = args.cases.split(",") if args.cases else (list(SMALL) if args.sizes == "small" else list(SIZES))
    tools = args.tools.split(",")
    opensees = {"solver": args.os_solver, "system": args.os_system, "numberer": args.os_numberer}
    results: dict[str, dict] = {}
    all_runs = []
    for case in cases:
        results[case] = {}
        for tool in tools:
            if tool == "scipy" and case not in args.scipy_cases.split(","):
                continue
            runs = []
            for i in range(args.repeat):
                r = run_worker(tool, case, timeout=args.timeout, method=args.method, opensees=opensees,
                               blas_threads=args.blas_threads)
                runs.append(r)
                print(f"# {case} {tool} run {i + 1}: {r['status']} "
                      f"total {r.get('total', float('nan')):.2f} s, wall {r['wall']:.2f} s, "
                      f"peak {r['peak_mb']:.0f} MB, load {r['load_before']:.2f}", file=sys.stderr, flush=True)
                # A run that timed out or takes minutes is not repeated: the bound is the figure.
                if r["status"] != "ok" or r["wall"] > 120:
                    break
            results[case][tool] = best_of(runs)
            all_runs += runs
    info["loadavg_end"] = os.getloadavg()
    md = markdown(results, info)
    print(md)
    out = args.json or (str(RESULTS / "fem_vs_opensees.json") if args.sizes == "all" and not args.cases else None)
    if out:
        write_json(Path(out), {"stamp": finish(st), "machine": info, "opensees": opensees,
                               "results": results, "runs": all_runs, "tables": readme_tables(results, st)})
    if args.md:
        Path(args.md).write_text(md + "\n")
    # A trussid run that failed is a crash of the code under test: fail the command.
    bad = [case for case, per_tool in results.items() if per_tool.get("trussid", {}).get("status", "ok") != "ok"]
    if bad:
        print(f"trussid failed on: {', '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
