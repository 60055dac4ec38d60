"""Study engine throughput: serial loop vs 1 and 2 Dask workers, in one run (issues 15, 26).

``python benchmarks/bench_study.py [--fits 30] [--out benchmarks/results] [--quick]`` times

- the wall study ``examples/wall_study.toml`` (343 testbed designs, 20 modes + labels each),
- an identification campaign: ``--fits`` PLID fits (subspace start, 24 states) of case (a)
  records, 1500 samples at 60 dB SNR, one per seed,

each as (1) a plain serial loop over the evaluator (no engine, no Dask: the comparator) in
a process of its own with the environment the engine gives its workers
(:data:`trussid.study.engine.WORKER_ENV`: the malloc thresholds change the evaluation's own
cost, so both sides get them), and the same loop in a plain process for reference;
(2) :func:`trussid.study.run_study` on a LocalCluster of 1 worker process, (3) of 2, (4) on
an external cluster of a ``dask scheduler`` and 2 ``dask worker`` processes started with
Dask's command line on 127.0.0.1 (docs/studies.md's recipe). For every run: wall time, CPU
time of this process (driver + the in-process scheduler) and of the workers, load average
before and after. The cluster is started, warmed (a 4-point study: imports and the
evaluator's context) and then timed, so that per-point figures exclude the one-off start,
which is reported separately. ``--quick`` (CI): 8 designs, no fits, no 1-worker run.

Engine overhead per point = (driver + worker CPU seconds of the timed run) / points minus
the serial loop's CPU seconds per point. The 1e6-design estimate scales the measured
per-point CPU cost. Writes ``study.json`` and ``study.md`` into ``--out``.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import resource
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
IDLE_S = 8.0  # seconds of idle cluster measured for its background CPU


def wall_spec(quick: bool = False):
    from trussid.study import load_spec, spec_from_dict

    spec = load_spec(ROOT / "examples" / "wall_study.toml")
    if not quick:
        return spec
    d = spec.to_dict()  # 2 x 2 x 2 = 8 designs over the same ranges
    d["parameters"] = {k: {**v, "num": 2} for k, v in d["parameters"].items()}
    return spec_from_dict(d)


def fit_spec(n_fits: int):
    from trussid.study import spec_from_dict

    return spec_from_dict({
        "study": {"name": f"plid-{n_fits}-fits", "evaluate": "identify"},
        "evaluate": {"plant": "case_a", "n_samples": 1500, "n_validation": 2000, "noise": "60dB",
                     "order": 24, "method": "plid-subspace"},
        "parameters": {"seed": {"values": list(range(1, n_fits + 1))}}})


def serial_loop_here(spec) -> dict:
    """The comparator: the evaluator called point by point in this process."""
    from trussid._util.threads import blas_threads
    from trussid.study.engine import plan
    from trussid.study.evaluators import get_evaluator

    ev = get_evaluator(spec.evaluate)
    names, points, _ = plan(spec)
    with blas_threads(1):
        ctx = ev.context(spec.options)  # built once, as every worker does: not timed
        ev.point(ctx, dict(zip(names, points[0])), spec.options)  # warm caches of imports
        l0, t0, c0 = os.getloadavg(), time.perf_counter(), time.process_time()
        f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        for p in points:
            ev.point(ctx, dict(zip(names, p)), spec.options)
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0
    return {"points": len(points), "wall_s": wall, "cpu_s": cpu, "points_per_s": len(points) / wall,
            "cpu_s_per_point": cpu / len(points), "page_faults_per_point": faults / len(points),
            "load_before": l0, "load_after": os.getloadavg()}


def serial_loop(spec, worker_env: bool) -> dict:
    """:func:`serial_loop_here` in a fresh process, with the workers' environment or a plain one."""
    from trussid.study.engine import WORKER_ENV

    env = {**os.environ, **(WORKER_ENV if worker_env else {})}
    if not worker_env:
        for k in ("MALLOC_TRIM_THRESHOLD_", "MALLOC_MMAP_THRESHOLD_"):
            env.pop(k, None)
    spec_json = json.dumps(spec.to_dict())
    res = subprocess.run([sys.executable, __file__, "--serial-spec", spec_json], env=env, capture_output=True,
                         text=True, timeout=3600)
    if res.returncode != 0:
        raise RuntimeError(res.stderr[-2000:])
    return json.loads(res.stdout.strip().splitlines()[-1])


@contextlib.contextmanager
def command_line_cluster(workers: int, timeout: float = 120):
    """``dask scheduler`` + ``workers`` x ``dask worker --nthreads 1`` on 127.0.0.1, with the
    environment docs/studies.md gives them; every process killed on exit (bounded waits)."""
    from distributed import Client

    from trussid.study.cluster import worker_exports

    env = dict(os.environ)
    env.update(line.removeprefix("export ").split("=", 1) for line in worker_exports())
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, "start_new_session": True, "env": env}
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1", "--port", str(port),
                               "--no-dashboard"], **quiet)]
    try:
        procs += [subprocess.Popen([sys.executable, "-m", "dask", "worker", address, "--host", "127.0.0.1",
                                    "--nthreads", "1", "--no-dashboard", "--name", f"w{k}"], **quiet)
                  for k in range(workers)]
        with Client(address, timeout=timeout) as client:
            client.wait_for_workers(workers, timeout=timeout)
        yield address
    finally:
        for p in procs:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                pass
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGKILL)
            p.wait(timeout=10)


def engine_run(spec, workers: int, scratch: Path, external: bool = False) -> dict:
    """run_study on a fresh cluster of ``workers`` processes: start, warm, then timed.

    ``external``: a scheduler and workers started with Dask's command line, the study
    connecting by address (``scheduler=``), as ``trussid study --scheduler`` does.
    """
    from distributed import Client

    from trussid.study import read_study, run_study, spec_from_dict
    from trussid.study.engine import local_cluster

    tag = f"ext{workers}" if external else f"w{workers}"
    t_start = time.perf_counter()
    with contextlib.ExitStack() as stack:
        if external:
            address = stack.enter_context(command_line_cluster(workers))
            client = stack.enter_context(Client(address))
        else:
            client = stack.enter_context(Client(stack.enter_context(local_cluster(workers))))
        d = spec.to_dict()
        d["sample"] = {"method": "list"}
        d["parameters"] = {k: ({"values": [v] * 4} if not isinstance(v, dict) else {"values": _first(v, 4)})
                           for k, v in spec.to_dict()["parameters"].items()}
        run_study(spec_from_dict(d), scratch / f"warm-{tag}", client=client)
        start_s = time.perf_counter() - t_start
        # The cluster's background CPU (event loops, heartbeats) while idle, per second:
        # it accrues with wall time, not with points, so a loaded machine inflates it.
        # (external: the scheduler's own process is not counted here, nor in the run)
        i0, j0, k0 = client.run(time.process_time), time.process_time(), time.perf_counter()
        time.sleep(IDLE_S)
        i1, j1, idle_wall = client.run(time.process_time), time.process_time(), time.perf_counter() - k0
        idle_driver = (j1 - j0) / idle_wall
        idle_workers = sum(i1[k] - i0[k] for k in i0) / idle_wall
        w0 = client.run(time.process_time)
        l0, t0, c0 = os.getloadavg(), time.perf_counter(), time.process_time()
        if external:
            run = run_study(spec, scratch / f"run-{tag}", scheduler=address)
        else:
            run = run_study(spec, scratch / f"run-{tag}", client=client)
        wall, cpu_driver = time.perf_counter() - t0, time.process_time() - c0
        w1 = client.run(time.process_time)
    cpu_workers = sum(w1[k] - w0[k] for k in w0 if k in w1)
    n = run.computed
    background = (idle_driver + idle_workers) * wall
    eval_cpu = float(read_study(scratch / f"run-{tag}")[1]["cpu_seconds"].sum())
    return {"workers": workers, "external": external, "points": n, "failed": run.failed, "start_and_warm_s": start_s,
            "wall_s": wall, "points_per_s": n / wall, "cpu_driver_s": cpu_driver, "cpu_workers_s": cpu_workers,
            "cpu_s_per_point": (cpu_driver + cpu_workers) / n, "tasks": run.tasks, "batch_min": run.batch_min,
            "batch_max": run.batch_max, "costs": run.costs(), "engine_worker_cpu_s": run.engine_cpu_s,
            "driver_write_cpu_s": run.driver_write_cpu_s,
            "eval_cpu_in_workers_s": eval_cpu, "idle_cpu_per_s_driver": idle_driver, "idle_cpu_per_s_workers": idle_workers,
            "background_cpu_s": background, "cpu_s_per_point_less_background": (cpu_driver + cpu_workers
                                                                               - background) / n,
            "load_before": l0, "load_after": os.getloadavg()}


def _first(axis: dict, k: int):
    import numpy as np

    if "values" in axis:
        return list(axis["values"])[:1] * k
    return [float(v) for v in np.linspace(axis["low"], axis["high"], axis.get("num", 2))[:1]] * k


RUNS = {"workers1": (1, False), "workers2": (2, False), "external2": (2, True)}


def measure(name, spec, scratch, quick: bool = False) -> dict:
    print(f"[{name}] serial loop (workers' environment, own process)", flush=True)
    out = {"serial": serial_loop(spec, worker_env=True)}
    print(f"[{name}] serial loop (plain process)", flush=True)
    out["serial_plain"] = serial_loop(spec, worker_env=False)
    for key, (w, external) in RUNS.items():
        if quick and key == "workers1":
            continue
        print(f"[{name}] {key}", flush=True)
        out[key] = engine_run(spec, w, scratch / name, external=external)
    derive(out)
    print(json.dumps(out, indent=1, default=float), flush=True)
    return out


def derive(out: dict) -> None:
    """Speed-ups and overheads from the raw figures of :func:`measure` (in place)."""
    s = out["serial"]
    for key in RUNS:
        if key not in out:
            continue
        r = out[key]
        w = r["workers"]
        r["speedup_wall"] = r["points_per_s"] / s["points_per_s"]
        r["overhead_cpu_s_per_point"] = r["cpu_s_per_point"] - s["cpu_s_per_point"]
        r["overhead_fraction"] = r["overhead_cpu_s_per_point"] / s["cpu_s_per_point"]
        # Split: the cluster's background (idle rate x wall time of the run) and the rest,
        # the engine's per-point work (tasks, transfers, Parquet parts). On a loaded machine
        # the background rate in the run is not the idle one, so the rest is noisy; a
        # negative rest means "below what this run can resolve" and counts as 0 below.
        rate = r["idle_cpu_per_s_driver"] + r["idle_cpu_per_s_workers"]
        r["background_cpu_s"] = rate * r["wall_s"]
        r["work_overhead_s_per_point"] = ((r["cpu_driver_s"] + r["cpu_workers_s"] - r["background_cpu_s"])
                                          / r["points"] - s["cpu_s_per_point"])
        r["work_overhead_fraction"] = r["work_overhead_s_per_point"] / s["cpu_s_per_point"]
        # Unloaded (each worker on a core of its own): a point lasts CPU / w of wall per
        # worker, during which the background costs rate x that.
        r["unloaded_overhead_fraction"] = max(r["work_overhead_fraction"], 0.0) + rate / w
        r["speedup_cpu_bound"] = w / (1.0 + r["unloaded_overhead_fraction"])
        if "eval_cpu_in_workers_s" in r:
            r["eval_cpu_per_point_in_workers"] = r["eval_cpu_in_workers_s"] / r["points"]
        if "engine_worker_cpu_s" in r:
            # the engine's own work (batch tables on the workers, receiving and writing on
            # the driver), as the engine measures it: what batching is meant to make small
            r["engine_own_fraction"] = ((r["engine_worker_cpu_s"] + r["driver_write_cpu_s"]) / r["points"]
                                        / s["cpu_s_per_point"])
    if "external2" in out and "workers2" in out:
        out["external2"]["rate_vs_local"] = out["external2"]["points_per_s"] / out["workers2"]["points_per_s"]


def estimate(res: dict) -> dict:
    """Wall time of a 1e6-design wall grid from the measured per-point CPU costs.

    Each worker has a core to itself (no other load): a point costs its evaluation CPU plus
    the engine's per-point work, plus the background CPU of the cluster's event loops
    (measured idle, per second) spread over the points of that second. The driver (one
    process: scheduler, result collection, one Parquet part per chunk) does work per point
    too; its rate bounds the study whatever the number of workers.
    """
    s, w2 = res["serial"], res["workers2"]
    c_eval = s["cpu_s_per_point"]
    c_work = max(w2["work_overhead_s_per_point"], 0.0)
    worker_idle = w2["idle_cpu_per_s_workers"] / 2
    n = 1_000_000
    out = {"points": n, "cpu_s_per_point_eval": c_eval, "cpu_s_per_point_engine_work": c_work,
           "idle_cpu_per_s_per_worker": worker_idle, "idle_cpu_per_s_driver": w2["idle_cpu_per_s_driver"]}
    out["one_core_serial_h"] = n * c_eval / 3600
    per_point = (c_eval + c_work) * (1 + worker_idle)
    out["two_cores_h"] = n * per_point / 2 / 3600
    # driver work per point (less its idle background), measured in the 2-worker run
    driver = max(w2["cpu_driver_s"] - w2["idle_cpu_per_s_driver"] * w2["wall_s"], 0.0) / w2["points"]
    out["driver_cpu_s_per_point"] = driver
    out["sixty_four_workers_h"] = max(n * per_point / 64, n * driver) / 3600
    out["sixty_four_workers_bound"] = "driver" if n * driver > n * per_point / 64 else "workers"
    return out


LABELS = {"serial": "serial loop (workers' environment)", "serial_plain": "serial loop (plain process)",
          "workers1": "1 local worker", "workers2": "2 local workers", "external2": "2 workers, `dask` command line"}


def markdown(results: dict) -> str:
    """The results as the tables of study.md."""
    m = results["meta"]
    lines = ["# Study engine: serial loop vs Dask workers (issues 15, 26)", "",
             f"`python benchmarks/bench_study.py{' --quick' if m.get('quick') else ''}` at commit {m['commit']}, "
             f"{m['started']} to {m['finished']}; {m['machine']}; Python {m['python']}. Load averages (1 min) "
             "before/after each run are in the table: on a shared machine wall-clock rates depend on what else "
             "ran; CPU seconds much less.", ""]
    for key, title in (("wall_study", "Wall study (examples/wall_study.toml: 20 modes + labels per design)"),
                       ("fit_campaign", "Identification campaign (PLID subspace, case (a), 24 states, 1500 samples, "
                                        "60 dB; one fit per seed)")):
        if key not in results:
            continue
        r = results[key]
        lines += [f"## {title}", "",
                  "| run | points | wall s | points/s | speed-up (wall) | CPU / point, all processes | "
                  "engine overhead (CPU) | less the idle background | engine's own work | tasks (points) | "
                  "cluster start + warm s | load 1-min before/after |",
                  "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---|"]
        for run in ("serial", "serial_plain"):
            s = r[run]
            lines.append(f"| {LABELS[run]} | {s['points']} | {s['wall_s']:.1f} | {s['points_per_s']:.3g} | "
                         f"{s['points_per_s'] / r['serial']['points_per_s']:.2f} | {s['cpu_s_per_point'] * 1e3:.1f} ms "
                         f"({s['page_faults_per_point']:.0f} page faults) | - | - | - | - | - | "
                         f"{s['load_before'][0]:.1f} / {s['load_after'][0]:.1f} |")
        for run in RUNS:
            if run not in r:
                continue
            x = r[run]
            lines.append(
                f"| {LABELS[run]} | {x['points']} | {x['wall_s']:.1f} | {x['points_per_s']:.3g} | "
                f"**{x['speedup_wall']:.2f}** | {x['cpu_s_per_point'] * 1e3:.1f} ms | "
                f"{x['overhead_fraction'] * 100:+.1f} % | {x['work_overhead_fraction'] * 100:+.1f} % | "
                f"{x.get('engine_own_fraction', float('nan')) * 100:.2f} % | {x.get('tasks', '-')} "
                f"({x.get('batch_min', '-')}..{x.get('batch_max', '-')}) | "
                f"{x['start_and_warm_s']:.1f} | {x['load_before'][0]:.1f} / {x['load_after'][0]:.1f} |")
        lines += ["", "Background CPU of an idle cluster (event loops, heartbeats), per wall second: "
                  + "; ".join(f"{LABELS[k]}: driver {r[k]['idle_cpu_per_s_driver'] * 100:.1f} %, "
                              f"workers {r[k]['idle_cpu_per_s_workers'] * 100:.1f} % of a core"
                              for k in RUNS if k in r) + ".",
                  "Unloaded figures from the CPU costs (each worker on a core of its own): engine overhead "
                  + ", ".join(f"{LABELS[k]} {r[k]['unloaded_overhead_fraction'] * 100:.1f} %" for k in RUNS if k in r)
                  + f"; 2-worker speed-up {r['workers2']['speedup_cpu_bound']:.2f}x.",
                  (f"External cluster against local workers: {r['external2']['rate_vs_local']:.2f}x the rate."
                   if "rate_vs_local" in r.get("external2", {}) else ""), ""]
    if "estimate_1e6" in results:
        e = results["estimate_1e6"]
        lines += ["## 10^6-design wall grid, estimated from the measured per-point costs", "",
                  f"- evaluation {e['cpu_s_per_point_eval'] * 1e3:.2f} ms CPU per design (20 modes + labels), "
                  f"engine per-point work {e['cpu_s_per_point_engine_work'] * 1e3:.3f} ms, worker background "
                  f"{e['idle_cpu_per_s_per_worker'] * 100:.1f} % of a core, driver "
                  f"{e['driver_cpu_s_per_point'] * 1e3:.3f} ms per design;",
                  f"- 1 core, serial loop: 1e6 x {e['cpu_s_per_point_eval'] * 1e3:.2f} ms = "
                  f"**{e['one_core_serial_h']:.2f} h**;",
                  f"- 2 cores, 2 workers: **{e['two_cores_h']:.2f} h**;",
                  f"- 64 workers: **{e['sixty_four_workers_h']:.3f} h** "
                  f"({e['sixty_four_workers_h'] * 60:.1f} min; bound by the {e['sixty_four_workers_bound']}). "
                  "The 10^5-design run and its estimate from per-task costs: study_scale.md.", ""]
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fits", type=int, default=30)
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    ap.add_argument("--json", default=None, help="result file (default: OUT/study.json; the markdown beside it)")
    ap.add_argument("--only", choices=("wall", "fits"), default=None)
    ap.add_argument("--quick", action="store_true",
                    help="CI form: the wall study on a 2 x 2 x 2 grid, 2 s of idle cluster, no fits, no 1-worker "
                         "run (give --out a scratch folder)")
    ap.add_argument("--table", action="store_true", help="rewrite study.md from study.json (no run)")
    ap.add_argument("--serial-spec", default=None, help=argparse.SUPPRESS)  # the serial loop's own process
    args = ap.parse_args(argv)
    if args.serial_spec:
        from trussid.study import spec_from_dict

        print(json.dumps(serial_loop_here(spec_from_dict(json.loads(args.serial_spec))), default=float))
        return 0
    json_path = Path(args.json) if args.json else Path(args.out) / "study.json"
    md_path = json_path.with_suffix(".md")
    if args.table:
        results = json.loads(json_path.read_text())
        for key in ("wall_study", "fit_campaign"):
            if key in results:
                derive(results[key])
        if "wall_study" in results:
            results["estimate_1e6"] = estimate(results["wall_study"])
        json_path.write_text(json.dumps(results, indent=1, default=float))
        md_path.write_text(markdown(results) + "\n")
        return 0
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    meta = {"machine": f"{platform.machine()} {os.cpu_count()} cpus, shared with other agents",
            "python": platform.python_version(), "commit": commit, "quick": args.quick,
            "started": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}
    scratch = Path(tempfile.mkdtemp(prefix="bench_study_"))
    results = {"meta": meta}
    try:
        if args.quick:
            global IDLE_S
            IDLE_S = 2.0
        if args.only in (None, "wall"):
            results["wall_study"] = measure("wall", wall_spec(args.quick), scratch, args.quick)
            results["estimate_1e6"] = estimate(results["wall_study"])
        if args.only in (None, "fits") and not args.quick:
            results["fit_campaign"] = measure("fits", fit_spec(args.fits), scratch, args.quick)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    meta["finished"] = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    json_path.parent.mkdir(parents=True, exist_ok=True)
    tmp = json_path.with_name("." + json_path.name + ".tmp")
    tmp.write_text(json.dumps(results, indent=1, default=float))
    os.replace(tmp, json_path)
    if args.only is None and not args.quick:
        tmp = md_path.with_name("." + md_path.name + ".tmp")
        tmp.write_text(markdown(results) + "\n")
        os.replace(tmp, md_path)
    print(f"wrote {json_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
