"""A wall study of 10^5 designs on 2 local workers: completes, resumes, stays small (issue 26).

``python benchmarks/bench_study_scale.py [--points 100000] [--workers 2] [--json PATH]``

1. **Uninterrupted**: ``run_study`` in this process (the driver) on a LocalCluster of
   ``--workers`` processes: wall and CPU time (driver and workers), the driver's resident
   memory after 1 % of the points and at the end, its peak (``getrusage``), per-point and
   per-task costs (:meth:`trussid.study.StudyRun.costs`).
2. **Interrupted**: ``trussid study SPEC --out DIR2 --workers 2`` as a command, SIGINT
   once half the points are saved, then the same command again; the table (less timing and
   worker columns) must equal the uninterrupted run's, point by point, exactly.
3. The wall time of 10^6 designs on 64 workers, from the measured per-point and per-task
   costs (:func:`estimate_1e6`).

The study: the default testbed's six strut walls, Latin hypercube over 0.6 .. 1.7 mm,
20 modes and labels per design (``examples/wall_study.toml``'s evaluation). ``--quick``
runs 600 designs (seconds; CI's ``benchmarks/run.py --quick``). The full run on a quiet
2-core machine takes about 2 x 10^5 x 16 ms / 2 = 27 min (both runs). Writes ``--json`` and
``study_scale.md`` beside it (``--md``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq
import tomli_w

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from results_io import RESULTS, finish, rss_mb, stamp, write_json  # noqa: E402


def spec_dict(n: int) -> dict:
    return {"study": {"name": f"walls-{n}", "evaluate": "modes"}, "evaluate": {"n_modes": 20, "labels": True},
            "sample": {"method": "lhs", "n": n, "seed": 26},
            "parameters": {f"wall{i}": {"low": 0.0006, "high": 0.0017} for i in range(6)}}


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def saved_rows(out: Path) -> int:
    n = 0
    for p in out.glob("part-*.parquet"):
        try:
            n += pq.read_metadata(p).num_rows
        except OSError:  # a part renamed or being read while written: count it next time
            pass
    return n


def uninterrupted(spec, out: Path, workers: int) -> dict:
    """run_study in this process; CPU of the workers from their own clocks (client.run)."""
    from distributed import Client

    from trussid.study import run_study
    from trussid.study.engine import local_cluster

    mem = {}

    def progress(batch):
        done[0] += batch.points
        if "rss_1pct_mb" not in mem and done[0] >= 0.01 * spec.n:
            mem["rss_1pct_mb"] = rss_mb()

    done = [0]
    l0, t0 = os.getloadavg(), time.perf_counter()
    with local_cluster(workers) as cluster, Client(cluster) as client:
        start_s = time.perf_counter() - t0
        w0, c0 = client.run(time.process_time), time.process_time()
        run = run_study(spec, out, client=client, progress=progress)
        w1, c1 = client.run(time.process_time), time.process_time()
    wall = time.perf_counter() - t0
    return {"points": run.computed, "failed": run.failed, "wall_s": wall, "cluster_start_s": start_s,
            "run_s": run.seconds, "cpu_driver_s": c1 - c0, "cpu_workers_s": sum(w1[k] - w0[k] for k in w0 if k in w1),
            "eval_cpu_s": run.eval_cpu_s, "eval_s": run.eval_s, "task_cpu_s": run.task_cpu_s,
            "context_cpu_s": run.context_cpu_s, "engine_cpu_s": run.engine_cpu_s, "tasks": run.tasks,
            "batch_min": run.batch_min, "batch_max": run.batch_max, "driver_write_cpu_s": run.driver_write_cpu_s,
            "driver_run_cpu_s": run.driver_cpu_s, "peak_rss_mb": run.peak_rss_mb, "rss_end_mb": rss_mb(),
            **mem, "costs": run.costs(), "load_before": l0, "load_after": os.getloadavg()}


def interrupted(spec_file: Path, out: Path, workers: int, total: int, timeout: float) -> dict:
    """The CLI, SIGINT at half the points, then again to the end."""
    cmd = [sys.executable, "-m", "trussid", "study", str(spec_file), "--out", str(out), "--workers", str(workers),
           "--quiet"]
    t0, cpu0 = time.perf_counter(), children_cpu()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        while saved_rows(out) < total // 2:
            if proc.poll() is not None:
                raise RuntimeError(f"trussid study ended before the interruption: {proc.communicate()}")
            if time.perf_counter() - t0 > timeout:
                raise TimeoutError("half the points not saved in time")
            time.sleep(0.5)
        at = saved_rows(out)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=300)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=30)
    first = {"returncode": proc.returncode, "saved_at_sigint": at, "saved_after": saved_rows(out),
             "stderr": err.strip()[-400:], "wall_s": time.perf_counter() - t0}
    t1 = time.perf_counter()
    res = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    second = {"returncode": res.returncode, "stdout": res.stdout.strip()[-1500:], "wall_s": time.perf_counter() - t1}
    return {"first": first, "rerun": second, "cpu_all_s": children_cpu() - cpu0}


def compare(a: Path, b: Path) -> dict:
    import pandas as pd

    from trussid.study import read_study

    drop = ["seconds", "cpu_seconds", "worker"]
    ta = read_study(a)[1].drop(columns=drop)
    tb = read_study(b)[1].drop(columns=drop)
    equal = True
    try:
        pd.testing.assert_frame_equal(ta, tb, check_exact=True)
    except AssertionError:
        equal = False
    return {"rows_a": len(ta), "rows_b": len(tb), "unique_b": bool(tb["point"].is_unique), "equal": equal,
            "parts_a": len(list(a.glob("part-*.parquet"))), "parts_b": len(list(b.glob("part-*.parquet")))}


def estimate_1e6(u: dict, workers: int = 64, task_seconds: float | None = None) -> dict:
    """Wall time of 10^6 designs on ``workers`` from the measured costs (each worker a core).

    A point costs its evaluation plus the engine's per-point work on the worker; a task adds
    the engine's per-task work on the worker and, on the driver, receiving and writing it
    plus the scheduler's share. Tasks are ``TASK_SECONDS`` of work. The driver is one
    process: its CPU per task x tasks bounds the study whatever the number of workers.
    """
    from trussid.study.engine import TASK_SECONDS

    n = 1_000_000
    c_eval = u["eval_cpu_s"] / u["points"]
    c_engine_task = u["engine_cpu_s"] / u["tasks"]
    batch = math.floor((task_seconds or TASK_SECONDS) / c_eval)
    tasks = math.ceil(n / batch)
    # the driver's whole CPU during the run (scheduler, nannies, heartbeats, writes) per task
    c_driver_task = u["driver_run_cpu_s"] / u["tasks"]
    workers_s = (n * c_eval + tasks * c_engine_task) / workers
    driver_s = tasks * c_driver_task
    return {"points": n, "workers": workers, "eval_cpu_ms": c_eval * 1e3, "batch": batch, "tasks": tasks,
            "engine_ms_per_task_worker": c_engine_task * 1e3, "driver_ms_per_task": c_driver_task * 1e3,
            "workers_bound_h": workers_s / 3600, "driver_bound_h": driver_s / 3600,
            "hours": max(workers_s, driver_s) / 3600, "bound": "driver" if driver_s > workers_s else "workers",
            "one_core_h": n * c_eval / 3600}


def markdown(res: dict) -> str:
    st, u, i, c, e = res["stamp"], res["uninterrupted"], res.get("interrupted"), res.get("compare"), res["estimate"]
    m = st["machine"]
    lines = [f"# A wall study of {u['points']} designs on {res['workers']} local workers (issue 26)", "",
             f"`python benchmarks/bench_study_scale.py --points {res['points']}` at {st['commit']}, {st['date_utc']}; "
             f"{m['cpu']}, {m['nproc']} cores, {m['memory']}; load (1, 5, 15 min) {st['loadavg_start']} at the start, "
             f"{st['loadavg_end']} at the end. " + ("The machine was shared with other jobs: wall times are "
                                                     "inflated; CPU times are the work done." if
                                                     st["loadavg_start"][0] > 1.5 else ""), "",
             "## Uninterrupted run (run_study, this process the driver)", "",
             f"- wall {u['wall_s']:.0f} s ({u['cluster_start_s']:.1f} s cluster start); "
             f"{u['points'] / u['run_s']:.1f} designs/s; {u['failed']} failed;",
             f"- CPU: workers {u['cpu_workers_s']:.0f} s, driver {u['cpu_driver_s']:.0f} s "
             f"(evaluations {u['eval_cpu_s']:.0f} s = {u['eval_cpu_s'] / u['points'] * 1e3:.2f} ms a design);",
             f"- {u['tasks']} tasks (= Parquet parts) of {u['batch_min']}..{u['batch_max']} designs;",
             f"- driver memory: {u.get('rss_1pct_mb', float('nan')):.0f} MB after 1 % of the designs, "
             f"{u['rss_end_mb']:.0f} MB at the end, peak **{u['peak_rss_mb']:.0f} MB**;",
             "- costs as `trussid study` prints them:", "", "```", u["costs"], "```", ""]
    if i:
        lines += ["## SIGINT at half, then the same command again (`trussid study ... --workers 2`)", "",
                  f"- SIGINT with {i['first']['saved_at_sigint']} designs saved; exit status "
                  f"{i['first']['returncode']}; {i['first']['saved_after']} saved when it ended; "
                  f"message: `{i['first']['stderr'].splitlines()[-1] if i['first']['stderr'] else ''}`;",
                  f"- the rerun: exit status {i['rerun']['returncode']}, {i['rerun']['wall_s']:.0f} s: "
                  f"`{i['rerun']['stdout'].splitlines()[0] if i['rerun']['stdout'] else ''}`;",
                  f"- CPU of both commands and their workers: {i['cpu_all_s']:.0f} s;",
                  f"- table (less seconds, cpu_seconds, worker) equal to the uninterrupted run's, point by point: "
                  f"**{c['equal']}** ({c['rows_b']} rows, points unique: {c['unique_b']}; parts {c['parts_a']} / "
                  f"{c['parts_b']}).", ""]
    lines += [f"## 10^6 designs on {e['workers']} workers, from the measured costs", "",
              f"- evaluation {e['eval_cpu_ms']:.2f} ms CPU a design; tasks of {e['batch']} designs "
              f"(1 s of work): {e['tasks']} tasks; engine on the worker {e['engine_ms_per_task_worker']:.2f} ms a task; "
              f"driver (scheduler, transfers, Parquet, heartbeats) {e['driver_ms_per_task']:.1f} ms CPU a task "
              "(its whole CPU during the run over the tasks: an upper bound, since its event loops and "
              "heartbeats accrue with wall time, which a loaded machine stretches);",
              f"- workers: {e['workers_bound_h'] * 60:.1f} min; driver: {e['driver_bound_h'] * 60:.1f} min; "
              f"**{e['hours'] * 60:.1f} min** (bound by the {e['bound']}); one core: {e['one_core_h']:.2f} h.", ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="600 designs (seconds)")
    ap.add_argument("--no-interrupt", action="store_true", help="only the uninterrupted run")
    ap.add_argument("--timeout", type=float, default=6 * 3600, help="bound on each command [s]")
    ap.add_argument("--json", default=str(RESULTS / "study_scale.json"))
    ap.add_argument("--md", default=None, help="markdown summary (default: beside --json, unless --quick)")
    ap.add_argument("--table", action="store_true", help="rewrite the markdown from --json (no run)")
    args = ap.parse_args(argv)
    if args.table:
        res = json.loads(Path(args.json).read_text())
        res["estimate"] = estimate_1e6(res["uninterrupted"])
        write_json(Path(args.json), res)
        Path(args.md or Path(args.json).with_suffix(".md")).write_text(markdown(res) + "\n")
        return 0
    if args.quick:
        args.points = 600
    from trussid.study import spec_from_dict

    spec = spec_from_dict(spec_dict(args.points))
    st = stamp()
    scratch = Path(tempfile.mkdtemp(prefix="bench_study_scale_"))
    res = {"points": args.points, "workers": args.workers}
    try:
        print(f"[scale] uninterrupted: {args.points} designs on {args.workers} workers", flush=True)
        res["uninterrupted"] = uninterrupted(spec, scratch / "a", args.workers)
        print(res["uninterrupted"]["costs"], flush=True)
        if not args.no_interrupt:
            spec_file = scratch / "spec.toml"
            spec_file.write_text(tomli_w.dumps(spec_dict(args.points)))
            print("[scale] interrupted at half, then resumed", flush=True)
            res["interrupted"] = interrupted(spec_file, scratch / "b", args.workers, args.points, args.timeout)
            res["compare"] = compare(scratch / "a", scratch / "b")
            print(res["compare"], flush=True)
        res["estimate"] = estimate_1e6(res["uninterrupted"])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    res["stamp"] = finish(st)
    ok = (res["uninterrupted"]["points"] == args.points
          and (args.no_interrupt or (res["compare"]["equal"] and res["interrupted"]["first"]["returncode"] == 130
                                     and res["interrupted"]["rerun"]["returncode"] == 0)))
    res["guards"] = [{"name": "driver peak memory < 1 GB", "value": res["uninterrupted"]["peak_rss_mb"],
                      "bound": 1024, "ok": res["uninterrupted"]["peak_rss_mb"] < 1024},
                     {"name": "complete; interrupted + rerun equals uninterrupted", "value": ok, "bound": True,
                      "ok": ok}]
    write_json(Path(args.json), res)
    md = args.md or (None if args.quick else str(Path(args.json).with_suffix(".md")))
    if md:
        Path(md).write_text(markdown(res) + "\n")
    print(markdown(res))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
