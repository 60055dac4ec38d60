"""Study engine throughput: serial loop vs Dask workers, in one run (issues 15, 26, 35).

``python benchmarks/bench_study.py [--grid 20] [--fits 30] [--out benchmarks/results] [--quick]``
times

- the wall study ``examples/wall_study.toml`` on a ``--grid`` ^ 3 grid (default 20: 8000
  testbed designs, 20 modes + labels each),
- an identification campaign: ``--fits`` PLID fits (subspace start, 24 states) of case (a)
  records, 1500 samples at 60 dB SNR, one per seed,

each as (1) a plain serial loop over the evaluator (no engine, no Dask: the comparator) in
a process of its own with the environment the engine gives its workers
(:data:`trussid.study.engine.WORKER_ENV`: the malloc thresholds change the evaluation's own
cost, so both sides get them; the fits also in a plain process for reference);
(2) :func:`trussid.study.run_study` on a LocalCluster of 1 worker process (fits only),
(3) of 2, (4) of 2 with the Dask settings the engine had before issue 35
(:data:`BEFORE_CONFIG`: Dask's default timers), (5) on an external cluster of a ``dask
scheduler`` and 2 ``dask worker`` processes started with Dask's command line on 127.0.0.1
(docs/studies.md's recipe). Every cluster is started, then *every* worker is warmed
(:func:`warm_worker`: imports, the evaluator's context, one point; before issue 35 only
the worker that got the 4-point warm-up study was, and the other paid its imports inside
the timed run), then timed. For every run: wall time, CPU of this process (driver: with a
local cluster also its scheduler and nannies) and of each worker, per thread
(:func:`thread_times`: the evaluating thread, the event loop, time waiting for a CPU), the
cluster's idle background CPU, load average before and after.

The guard (``guards`` in the JSON; ``benchmarks/run.py`` fails on it): the CPU per design
on the 2 local workers, less the cluster's idle background over the run's wall time plus
that background at the rate an unloaded machine gives it, over the CPU per design of the
same evaluations in a bare loop in each worker's own process (:func:`own_baseline`, timed
before and after the run), at most ``1 + ALLOWED`` (``1 + ALLOWED_QUICK`` for ``--quick``,
a small study on a busy CI machine). The ratio against the serial loop's separate process
is recorded beside it: on this host identical work runs up to 1.6x faster in one process
than in another, which moved that ratio between 0.76 and 1.44 for one commit. The 1e6-design estimate for 64 workers uses the measured per-point and per-task
costs. Writes ``study.json`` and ``study.md`` into ``--out`` (study.md keeps its
hand-written diagnosis section below :data:`KEEP_MARK`). ``--quick`` (CI): a 6^3 = 216
design grid, no fits, no 1-worker or before run, no whole-command runs. The full run
takes about 8-9 min on the quiet 2-core machine (serial 8000 x 10.5 ms = 84 s, three
2-worker runs of ~45 s, the whole ``trussid study`` command serial and on 2 workers ~2.3
min, the fits ~2 min, cluster starts, warm-ups and idle measurements).
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
import threading
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
IDLE_S = 5.0  # seconds of idle cluster measured for its background CPU
#: The Dask settings of the study's processes before issue 35 (Dask's default timers).
BEFORE_CONFIG = {"distributed.worker.profile.enabled": False}
#: Allowed CPU per design on the workers above the serial loop's (issue 35: 10 %).
ALLOWED = 0.10
#: The same for ``--quick``: 216 designs on a busy CI machine (per-task costs weigh more).
ALLOWED_QUICK = 0.25
#: study.md below this line is hand-written (the diagnosis) and kept by every rewrite.
KEEP_MARK = "<!-- kept by bench_study.py: hand-written below -->"


def wall_spec(grid: int = 20):
    """``examples/wall_study.toml`` on a ``grid`` x ``grid`` x ``grid`` grid over its ranges."""
    from trussid.study import load_spec, spec_from_dict

    spec = load_spec(ROOT / "examples" / "wall_study.toml")
    d = spec.to_dict()
    d["parameters"] = {k: {**v, "num": grid} for k, v in d["parameters"].items()}
    return spec_from_dict(d)


def fit_spec(n_fits: int):
    from trussid.study import spec_from_dict

    return spec_from_dict({
        "study": {"name": f"plid-{n_fits}-fits", "evaluate": "identify"},
        "evaluate": {"plant": "case_a", "n_samples": 1500, "n_validation": 2000, "noise": "60dB",
                     "order": 24, "method": "plid-subspace"},
        "parameters": {"seed": {"values": list(range(1, n_fits + 1))}}})


def thread_times() -> dict:
    """CPU run time and time waiting for a CPU of each thread of this process [s].

    ``{thread id: [name, run_s, runqueue_wait_s]}`` from ``/proc/self/task/*/schedstat``
    (Linux; empty elsewhere). The evaluating thread of a Dask worker is named
    ``...-Dask-Default-Threads-...``, its event loop ``MainThread``.
    """
    names = {t.native_id: t.name for t in threading.enumerate()}
    out = {}
    with contextlib.suppress(FileNotFoundError):
        for tid in os.listdir("/proc/self/task"):
            with contextlib.suppress(FileNotFoundError, ValueError):
                run_ns, wait_ns, _ = open(f"/proc/self/task/{tid}/schedstat").read().split()
                out[int(tid)] = [names.get(int(tid), "other"), int(run_ns) / 1e9, int(wait_ns) / 1e9]
    return out


def thread_split(before: dict, after: dict) -> dict:
    """CPU of the evaluating thread, the event loop and the rest, and the wait for a CPU [s]."""
    out = {"eval_s": 0.0, "event_loop_s": 0.0, "other_s": 0.0, "wait_s": 0.0}
    for tid, (name, run, wait) in after.items():
        _, run0, wait0 = before.get(tid, [name, 0.0, 0.0])
        key = "eval_s" if "Dask-Default-Threads" in name else "event_loop_s" if name == "MainThread" else "other_s"
        out[key] += run - run0
        out["wait_s"] += wait - wait0
    return out


def warm_worker(spec_dict: dict) -> float:
    """On a worker: import the evaluator's modules, build its context, evaluate one point.

    Returns the CPU it took [s]: the one-off cost of a worker, which otherwise lands on its
    first task (the imports in the event loop, as the task is unpickled). ``spec_dict``, not
    a spec: unpickling a spec would import trussid before the clock starts."""
    c0 = time.process_time()
    from trussid.study import spec_from_dict
    from trussid.study.engine import evaluate_batch, plan

    spec = spec_from_dict(spec_dict)
    names, points, schema = plan(spec)
    evaluate_batch(spec.evaluate, spec.options, names, [(0, points[0])], schema)
    return time.process_time() - c0


#: Points of the study each worker evaluates in a bare loop, before and after the timed run,
#: as its own serial baseline (a strided sample of the plan; all of it for ``--quick``).
BASELINE_POINTS = 216


def own_baseline(spec_dict: dict, max_points: int = BASELINE_POINTS) -> dict:
    """On a worker: CPU per point of the evaluator called in a bare loop in this process.

    The guard's comparator taken in the worker process itself. This host's speed differs
    by up to 1.6x between processes running identical work (measured for the PLID kernel,
    ``plid_speed_i35.md``), so a serial loop in another process measures that difference as
    much as the engine's overhead; in the same process the two see the same speed. Thread CPU
    (``time.thread_time``) of the loop: the worker's event loop runs beside it."""
    import socket

    from trussid._util.threads import blas_threads
    from trussid.study import spec_from_dict
    from trussid.study.engine import plan
    from trussid.study.evaluators import get_evaluator

    spec = spec_from_dict(spec_dict)
    ev = get_evaluator(spec.evaluate)
    names, points, _ = plan(spec)
    sample = points[::max(1, -(-len(points) // max_points))]
    with blas_threads(1):
        ctx = ev.context(spec.options)
        ev.point(ctx, dict(zip(names, sample[0])), spec.options)
        c0 = time.thread_time()
        for p in sample:
            ev.point(ctx, dict(zip(names, p)), spec.options)
        cpu = time.thread_time() - c0
    return {"worker": f"{socket.gethostname()}:{os.getpid()}", "points": len(sample),
            "cpu_s_per_point": cpu / len(sample)}


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


def _scheduler_cpu(client) -> float:
    return client.run_on_scheduler(time.process_time)


def engine_run(spec, workers: int, scratch: Path, external: bool = False, config: dict | None = None,
               tag: str = "", warm_all: bool = True, own: bool = True) -> dict:
    """run_study on a fresh cluster of ``workers`` processes: start, warm every worker, then timed.

    ``external``: a scheduler and workers started with Dask's command line, the study
    connecting by address (``scheduler=``), as ``trussid study --scheduler`` does (the
    scheduler's own CPU is then measured on it and added to the driver's). ``config``: the
    local cluster's Dask settings (default the engine's). ``warm_all``: warm every worker
    (:func:`warm_worker`); False is the benchmark before issue 35 (a 4-point study only).
    ``own``: time each worker's own bare loop before and after (:func:`own_baseline`).
    """
    from distributed import Client

    from trussid.study import read_study, run_study, spec_from_dict
    from trussid.study.engine import local_cluster

    tag = tag or (f"ext{workers}" if external else f"w{workers}")
    t_start = time.perf_counter()
    with contextlib.ExitStack() as stack:
        if external:
            address = stack.enter_context(command_line_cluster(workers))
            client = stack.enter_context(Client(address))
        else:
            client = stack.enter_context(Client(stack.enter_context(local_cluster(workers, config))))
        # every worker, in parallel (before issue 35 only the 4-point study below warmed
        # the cluster: one task, so one worker; the other imported inside the timed run)
        warm_cpu = client.run(warm_worker, spec.to_dict()) if warm_all else {}
        d = spec.to_dict()
        d["sample"] = {"method": "list"}
        d["parameters"] = {k: ({"values": [v] * 4} if not isinstance(v, dict) else {"values": _first(v, 4)})
                           for k, v in spec.to_dict()["parameters"].items()}
        run_study(spec_from_dict(d), scratch / f"warm-{tag}", client=client)
        start_s = time.perf_counter() - t_start
        # The cluster's background CPU (event loops, heartbeats) while idle, per second:
        # it accrues with wall time, not with points, so a loaded machine inflates it.
        sched = _scheduler_cpu if external else (lambda c: 0.0)
        i0, j0, s0, k0 = client.run(time.process_time), time.process_time(), sched(client), time.perf_counter()
        time.sleep(IDLE_S)
        i1, j1, s1 = client.run(time.process_time), time.process_time(), sched(client)
        idle_wall = time.perf_counter() - k0
        idle_driver = (j1 - j0 + s1 - s0) / idle_wall
        idle_workers = sum(i1[k] - i0[k] for k in i0) / idle_wall
        base0 = client.run(own_baseline, spec.to_dict()) if own else {}
        w0, th0, dth0 = client.run(time.process_time), client.run(thread_times), thread_times()
        l0, t0, c0, s0 = os.getloadavg(), time.perf_counter(), time.process_time(), sched(client)
        if external:
            run = run_study(spec, scratch / f"run-{tag}", scheduler=address)
        else:
            run = run_study(spec, scratch / f"run-{tag}", client=client)
        wall, cpu_driver = time.perf_counter() - t0, time.process_time() - c0 + sched(client) - s0
        w1, th1, dth1 = client.run(time.process_time), client.run(thread_times), thread_times()
        base1 = client.run(own_baseline, spec.to_dict()) if own else {}
    cpu_workers = sum(w1[k] - w0[k] for k in w0 if k in w1)
    threads = {"eval_s": 0.0, "event_loop_s": 0.0, "other_s": 0.0, "wait_s": 0.0}
    for k in th1:
        for key, v in thread_split(th0.get(k, {}), th1[k]).items():
            threads[key] += v
    n = run.computed
    table = read_study(scratch / f"run-{tag}")[1]
    eval_cpu = float(table["cpu_seconds"].sum())
    # each worker's own serial CPU per point (mean of before and after the run), and the
    # serial CPU the run's designs would have cost on the workers that evaluated them
    baseline = {b["worker"]: (b["cpu_s_per_point"] + base1[k]["cpu_s_per_point"]) / 2
                for k, b in base0.items() if k in base1}
    done = table["worker"].value_counts().to_dict() if "worker" in table else {}
    own_serial = (sum(baseline[k] * v for k, v in done.items() if k in baseline)
                  if baseline and set(done) <= set(baseline) else None)
    return {"workers": workers, "external": external, "points": n, "failed": run.failed, "start_and_warm_s": start_s,
            "warm_cpu_s_per_worker": sorted(warm_cpu.values()),
            "wall_s": wall, "points_per_s": n / wall, "cpu_driver_s": cpu_driver, "cpu_workers_s": cpu_workers,
            "cpu_s_per_point": (cpu_driver + cpu_workers) / n, "tasks": run.tasks, "batch_min": run.batch_min,
            "batch_max": run.batch_max, "costs": run.costs(), "engine_worker_cpu_s": run.engine_cpu_s,
            "driver_write_cpu_s": run.driver_write_cpu_s, "worker_threads": threads,
            "driver_threads": thread_split(dth0, dth1),
            "eval_cpu_in_workers_s": eval_cpu, "own_baseline_s_per_point": baseline,
            "own_serial_cpu_s": own_serial, "idle_cpu_per_s_driver": idle_driver, "idle_cpu_per_s_workers": idle_workers,
            "load_before": l0, "load_after": os.getloadavg()}


def _first(axis: dict, k: int):
    import numpy as np

    if "values" in axis:
        return list(axis["values"])[:1] * k
    return [float(v) for v in np.linspace(axis["low"], axis["high"], axis.get("num", 2))[:1]] * k


#: run name -> (workers, external, Dask settings: None for the engine's, every worker warmed).
RUNS = {"workers1": (1, False, None, True), "workers2": (2, False, None, True),
        "workers2_before": (2, False, BEFORE_CONFIG, False), "external2": (2, True, None, True)}


def cli_run(spec, workers: int, scratch: Path) -> dict:
    """The whole ``trussid study SPEC --out DIR --workers N --quiet`` command (cluster start,
    imports, everything): wall time and the CPU of it and all its processes (issue 35
    measured this form: serial 70.7 s, 2 workers 70.9 s on 8000 designs)."""
    import tomli_w

    spec_file = scratch / f"cli-{workers}.toml"
    spec_file.write_text(tomli_w.dumps(spec.to_dict()))
    out = scratch / f"cli-{workers}"
    cmd = [str(Path(sys.executable).with_name("trussid")), "study", str(spec_file), "--out", str(out),
           "--workers", str(workers), "--quiet"]
    r0, l0, t0 = resource.getrusage(resource.RUSAGE_CHILDREN), os.getloadavg(), time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=3600)
    wall, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(proc.stderr[-2000:])
    cpu = r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime
    from trussid.study.engine import plan

    n = len(plan(spec)[1])
    return {"workers": workers, "points": n, "wall_s": wall, "cpu_s": cpu, "cpu_s_per_point": cpu / n,
            "summary": proc.stdout.strip().splitlines()[:4], "load_before": l0, "load_after": os.getloadavg()}


def measure(name, spec, scratch, skip=()) -> dict:
    print(f"[{name}] serial loop (workers' environment, own process)", flush=True)
    out = {"serial": serial_loop(spec, worker_env=True)}
    if "serial_plain" not in skip:
        print(f"[{name}] serial loop (plain process)", flush=True)
        out["serial_plain"] = serial_loop(spec, worker_env=False)
    for key, (w, external, config, warm_all) in RUNS.items():
        if key in skip:
            continue
        print(f"[{name}] {key}", flush=True)
        out[key] = engine_run(spec, w, scratch / name, external=external, config=config, tag=key, warm_all=warm_all,
                              own=name == "wall")
    if "cli" not in skip:
        for w in (0, 2):
            print(f"[{name}] trussid study --workers {w}", flush=True)
            out[f"cli{w}"] = cli_run(spec, w, scratch / name)
        out["cli2"]["speedup_wall"] = out["cli0"]["wall_s"] / out["cli2"]["wall_s"]
    derive(out)
    print(json.dumps(out, indent=1, default=float), flush=True)
    return out


#: The configurations timed in each repetition of :func:`fits_repeated`, rotated per repetition.
REPEATED = ("serial", "workers2", "external2", "pair")


def serial_pair(spec) -> dict:
    """Two :func:`serial_loop` processes at once: what the machine itself gives two processes
    running the same evaluations (no Dask), the comparator of two workers' speed-up."""
    res = [None, None]

    def one(i):
        res[i] = serial_loop(spec, worker_env=True)

    threads = [threading.Thread(target=one, args=(i,)) for i in range(2)]
    t0 = time.perf_counter()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.perf_counter() - t0
    if None in res:
        raise RuntimeError("a serial loop of the pair failed")
    # wall: the longer of the two loops as each timed itself (their starts, imports included,
    # overlap within ~0.1 s; the outer wall time would add the interpreters' start)
    return {"points": sum(r["points"] for r in res), "wall_s": max(r["wall_s"] for r in res), "outer_wall_s": wall,
            "cpu_s_per_point": sum(r["cpu_s"] for r in res) / sum(r["points"] for r in res),
            "load_before": res[0]["load_before"], "load_after": res[0]["load_after"]}


def fits_repeated(spec, scratch: Path, reps: int) -> dict:
    """The fits on the serial loop, 2 local workers, 2 ``dask worker`` processes and two
    independent serial processes, ``reps`` times, the order rotated each time.

    One pass of 30 fits lasts ~6-12 s, and on this shared machine the CPU a fit costs moves
    by 10-30 % from one such pass to the next whatever runs it (the serial loop alone read
    0.34-0.52 s a fit in consecutive passes, 2026-11-28): a single pass per configuration
    compares those swings, not the configurations. Each repetition's speed-ups are taken
    against the serial loop of the same repetition; the medians are the result.
    """
    rows = []
    for k in range(reps):
        order = REPEATED[k % len(REPEATED):] + REPEATED[:k % len(REPEATED)]
        row = {"order": list(order)}
        for key in order:
            print(f"[fits x{reps}] repetition {k + 1}: {key}", flush=True)
            if key == "serial":
                r = serial_loop(spec, worker_env=True)
            elif key == "pair":
                r = serial_pair(spec)
            else:
                r = engine_run(spec, 2, scratch / f"rep{k}", external=key == "external2", tag=f"{key}-{k}",
                               own=False)
                r["eval_cpu_s_per_point"] = r["worker_threads"]["eval_s"] / r["points"]
            row[key] = {x: r[x] for x in ("points", "wall_s", "cpu_s_per_point", "eval_cpu_s_per_point",
                                          "load_before") if x in r}
        s = row["serial"]
        n = s["points"]
        for key in ("workers2", "external2", "pair"):
            x = row[key]
            # the pair does the serial loop's work twice over
            x["speedup_wall"] = s["wall_s"] / x["wall_s"] * x["points"] / n
            x["cpu_ratio"] = x.get("eval_cpu_s_per_point", x["cpu_s_per_point"]) / s["cpu_s_per_point"]
        row["external2"]["rate_vs_local"] = row["workers2"]["wall_s"] / row["external2"]["wall_s"]
        rows.append(row)
    med = {}
    for key in ("workers2", "external2", "pair"):
        for q in ("speedup_wall", "cpu_ratio") + (("rate_vs_local",) if key == "external2" else ()):
            v = sorted(r[key][q] for r in rows)
            med[f"{key}_{q}"] = {"median": float(np.median(v)), "min": v[0], "max": v[-1]}
    v = sorted(r["serial"]["cpu_s_per_point"] for r in rows)
    med["serial_cpu_s_per_point"] = {"median": float(np.median(v)), "min": v[0], "max": v[-1]}
    return {"reps": reps, "rows": rows, "summary": med}


def derive(out: dict) -> None:
    """Speed-ups and overheads from the raw figures of :func:`measure` (in place)."""
    s = out["serial"]
    c = s["cpu_s_per_point"]
    for key in RUNS:
        if key not in out:
            continue
        r = out[key]
        w, n = r["workers"], r["points"]
        r["speedup_wall"] = r["points_per_s"] / s["points_per_s"]
        r["overhead_cpu_s_per_point"] = r["cpu_s_per_point"] - c
        r["overhead_fraction"] = r["overhead_cpu_s_per_point"] / c
        # Split: the cluster's background (idle rate x wall time of the run) and the rest,
        # the engine's per-point work (tasks, transfers, Parquet parts). On a loaded machine
        # the background rate in the run is not the idle one, so the rest is noisy; a
        # negative rest means "below what this run can resolve" and counts as 0 below.
        rate = r["idle_cpu_per_s_driver"] + r["idle_cpu_per_s_workers"]
        r["background_cpu_s"] = rate * r["wall_s"]
        r["work_overhead_s_per_point"] = ((r["cpu_driver_s"] + r["cpu_workers_s"] - r["background_cpu_s"]) / n - c)
        r["work_overhead_fraction"] = r["work_overhead_s_per_point"] / c
        # Unloaded (each worker on a core of its own): a point lasts CPU / w of wall per
        # worker, during which the background costs rate x that.
        r["unloaded_overhead_fraction"] = max(r["work_overhead_fraction"], 0.0) + rate / w
        r["speedup_cpu_bound"] = w / (1.0 + r["unloaded_overhead_fraction"])
        # The workers alone (issue 35's acceptance: CPU per design on the workers vs serial):
        # as measured; less their idle background over the run's wall time; and with that
        # background at an unloaded machine's rate (a design lasts its CPU on its own core).
        r["worker_cpu_ratio"] = r["cpu_workers_s"] / n / c
        less = (r["cpu_workers_s"] - r["idle_cpu_per_s_workers"] * r["wall_s"]) / n / c
        r["worker_cpu_ratio_less_background"] = less
        r["worker_cpu_ratio_unloaded"] = less + r["idle_cpu_per_s_workers"] / w
        if r.get("own_serial_cpu_s"):
            # the same, against each worker's own bare loop (:func:`own_baseline`) in place
            # of the serial loop's process: the host's speed difference between processes
            # drops out (it swung the quick guard between 0.81 and 1.35 on one commit)
            own = r["own_serial_cpu_s"]
            r["worker_cpu_ratio_own"] = ((r["cpu_workers_s"] - r["idle_cpu_per_s_workers"] * r["wall_s"]) / own
                                         + r["idle_cpu_per_s_workers"] / w)
        if "eval_cpu_in_workers_s" in r:
            r["eval_cpu_per_point_in_workers"] = r["eval_cpu_in_workers_s"] / n
        if "engine_worker_cpu_s" in r:
            # the engine's own work (batch tables on the workers, receiving and writing on
            # the driver), as the engine measures it: what batching is meant to make small
            r["engine_own_fraction"] = ((r["engine_worker_cpu_s"] + r["driver_write_cpu_s"]) / n / c)
    if "external2" in out and "workers2" in out:
        out["external2"]["rate_vs_local"] = out["external2"]["points_per_s"] / out["workers2"]["points_per_s"]


def guards(results: dict, quick: bool) -> list[dict]:
    """The checks ``benchmarks/run.py`` fails on: CPU per design on the workers / serial."""
    bound = 1 + (ALLOWED_QUICK if quick else ALLOWED)
    out = []
    for key in ("workers2", "external2"):
        r = results.get("wall_study", {}).get(key)
        if r is None:
            continue
        own = "worker_cpu_ratio_own" in r
        v = r["worker_cpu_ratio_own" if own else "worker_cpu_ratio_unloaded"]
        base = ("each worker's own bare loop of the evaluator" if own else "the serial loop's")
        out.append({"name": f"wall study, {LABELS[key]}: CPU per design on the workers / {base} "
                            "(idle background at an unloaded machine's rate)", "value": v, "bound": bound,
                    "ok": bool(v <= bound), "against_serial_process": r["worker_cpu_ratio_unloaded"]})
    return out


def estimate(res: dict, workers: int = 64, n: int = 1_000_000) -> dict:
    """Wall time of a 1e6-design wall grid from the measured per-point and per-task costs.

    Per design: the serial loop's CPU. Per task (batches of ``TASK_SECONDS`` of work): on
    the worker, its CPU beyond the evaluations and its idle background; on the driver
    (scheduler, result transfer, one Parquet part), its CPU less its idle background. The
    workers each on a core of their own, with their idle background rate on top; the driver
    is one process and bounds the study whatever the number of workers.
    """
    from trussid.study.engine import TASK_SECONDS

    s, w2 = res["serial"], res["workers2"]
    c_eval = s["cpu_s_per_point"]
    worker_bg = w2["idle_cpu_per_s_workers"] * w2["wall_s"]
    c_task_worker = max(w2["cpu_workers_s"] - worker_bg - w2["eval_cpu_in_workers_s"], 0.0) / w2["tasks"]
    c_task_driver = max(w2["cpu_driver_s"] - w2["idle_cpu_per_s_driver"] * w2["wall_s"], 0.0) / w2["tasks"]
    rate = w2["idle_cpu_per_s_workers"] / w2["workers"]
    batch = max(1, round(TASK_SECONDS / c_eval))
    tasks = -(-n // batch)
    worker_cpu = n * c_eval + tasks * c_task_worker
    out = {"points": n, "workers": workers, "cpu_s_per_point_eval": c_eval, "batch": batch, "tasks": tasks,
           "worker_ms_per_task": c_task_worker * 1e3, "driver_ms_per_task": c_task_driver * 1e3,
           "idle_cpu_per_s_per_worker": rate, "idle_cpu_per_s_driver": w2["idle_cpu_per_s_driver"],
           "one_core_serial_h": n * c_eval / 3600,
           "two_cores_h": worker_cpu * (1 + rate) / 2 / 3600}
    workers_s = worker_cpu * (1 + rate) / workers
    driver_s = tasks * c_task_driver / max(1 - w2["idle_cpu_per_s_driver"], 0.5)
    out.update({"workers_bound_h": workers_s / 3600, "driver_bound_h": driver_s / 3600,
                "sixty_four_workers_h": max(workers_s, driver_s) / 3600,
                "sixty_four_workers_bound": "driver" if driver_s > workers_s else "workers"})
    return out


LABELS = {"serial": "serial loop (workers' environment)", "serial_plain": "serial loop (plain process)",
          "workers1": "1 local worker", "workers2": "2 local workers",
          "workers2_before": "2 local workers, before (Dask's default timers; one worker warmed)",
          "external2": "2 workers, `dask` command line"}


def markdown(results: dict, kept: str = "") -> str:
    """The results as the tables of study.md, then ``kept`` (the hand-written diagnosis)."""
    m = results["meta"]
    lines = ["# Study engine: serial loop vs Dask workers (issues 15, 26, 35)", "",
             f"`python benchmarks/bench_study.py {m.get('argv', '--quick' if m.get('quick') else '')}`".replace(" `", "`")
             + f" at commit {m['commit']}, "
             f"{m['started']} to {m['finished']}; {m['machine']}; Python {m['python']}. Load averages (1 min) "
             "before/after each run are in the table: on a shared machine wall-clock rates depend on what else "
             "ran; CPU seconds much less.", ""]
    for key, title in (("wall_study", f"Wall study (examples/wall_study.toml on a {m.get('grid', 7)}^3 grid: "
                                      "20 modes + labels per design)"),
                       ("fit_campaign", "Identification campaign (PLID subspace, case (a), 24 states, 1500 samples, "
                                        "60 dB; one fit per seed)")):
        if key not in results:
            continue
        r = results[key]
        lines += [f"## {title}", "",
                  "| run | points | wall s | points/s | speed-up (wall) | CPU / point, all processes | "
                  "CPU / point on the workers / serial: measured, less idle background, unloaded; "
                  "unloaded against each worker's own loop | "
                  "engine overhead (CPU, all processes) | engine's own work | tasks (points) | "
                  "cluster start + warm s | load 1-min before/after |",
                  "|---|---:|---:|---:|---:|---:|---|---:|---:|---|---:|---|"]
        for run in ("serial", "serial_plain"):
            if run not in r:
                continue
            s = r[run]
            lines.append(f"| {LABELS[run]} | {s['points']} | {s['wall_s']:.1f} | {s['points_per_s']:.3g} | "
                         f"{s['points_per_s'] / r['serial']['points_per_s']:.2f} | {s['cpu_s_per_point'] * 1e3:.2f} ms "
                         f"({s['page_faults_per_point']:.0f} page faults) | - | - | - | - | - | "
                         f"{s['load_before'][0]:.1f} / {s['load_after'][0]:.1f} |")
        for run in RUNS:
            if run not in r:
                continue
            x = r[run]
            lines.append(
                f"| {LABELS[run]} | {x['points']} | {x['wall_s']:.1f} | {x['points_per_s']:.3g} | "
                f"**{x['speedup_wall']:.2f}** | {x['cpu_s_per_point'] * 1e3:.2f} ms | "
                f"{x['worker_cpu_ratio']:.3f}, {x['worker_cpu_ratio_less_background']:.3f}, "
                f"{x['worker_cpu_ratio_unloaded']:.3f}; **{x.get('worker_cpu_ratio_own', float('nan')):.3f}** | "
                f"{x['overhead_fraction'] * 100:+.1f} % | "
                f"{x.get('engine_own_fraction', float('nan')) * 100:.2f} % | {x.get('tasks', '-')} "
                f"({x.get('batch_min', '-')}..{x.get('batch_max', '-')}) | "
                f"{x['start_and_warm_s']:.1f} | {x['load_before'][0]:.1f} / {x['load_after'][0]:.1f} |")
        lines += ["", "Where the CPU went in the timed runs [s] (per thread, `/proc/*/task/*/schedstat`; "
                  "waiting = runnable but not running: the load):", "",
                  "| run | workers: evaluating thread | workers: event loop | workers: other threads | "
                  "workers: waiting for a CPU | evaluations (`cpu_seconds`) | driver: all threads | "
                  "one-off warm-up per worker s CPU |", "|---|---:|---:|---:|---:|---:|---:|---|"]
        for run in RUNS:
            if run not in r or "worker_threads" not in r[run]:
                continue
            x, t = r[run], r[run]["worker_threads"]
            lines.append(f"| {LABELS[run]} | {t['eval_s']:.2f} | {t['event_loop_s']:.2f} | {t['other_s']:.2f} | "
                         f"{t['wait_s']:.1f} | {x['eval_cpu_in_workers_s']:.2f} | {x['cpu_driver_s']:.2f} | "
                         + ", ".join(f"{v:.2f}" for v in x["warm_cpu_s_per_worker"]) + " |")
        lines += ["", "Background CPU of an idle cluster (event loops, heartbeats), per wall second: "
                  + "; ".join(f"{LABELS[k]}: driver {r[k]['idle_cpu_per_s_driver'] * 100:.2f} %, "
                              f"workers {r[k]['idle_cpu_per_s_workers'] * 100:.2f} % of a core"
                              for k in RUNS if k in r) + ".",
                  "Unloaded figures from the CPU costs (each worker on a core of its own): engine overhead "
                  + ", ".join(f"{LABELS[k]} {r[k]['unloaded_overhead_fraction'] * 100:.1f} %" for k in RUNS if k in r)
                  + f"; 2-worker speed-up {r['workers2']['speedup_cpu_bound']:.2f}x.",
                  (f"External cluster against local workers: {r['external2']['rate_vs_local']:.2f}x the rate."
                   if "rate_vs_local" in r.get("external2", {}) else ""), ""]
        if "cli2" in r:
            lines += [f"The whole command, `trussid study SPEC --workers N` (cluster start and imports included): "
                      f"`--workers 0` {r['cli0']['wall_s']:.1f} s, {r['cli0']['cpu_s']:.1f} s CPU; `--workers 2` "
                      f"{r['cli2']['wall_s']:.1f} s, {r['cli2']['cpu_s']:.1f} s CPU (all its processes): "
                      f"**{r['cli2']['speedup_wall']:.2f}x** (load {r['cli0']['load_before'][0]:.1f} / "
                      f"{r['cli2']['load_after'][0]:.1f}).", ""]
    if "fit_repeats" in results:
        fr = results["fit_repeats"]
        lines += [f"## The identification campaign, {fr['reps']} repetitions, order rotated", "",
                  f"Each repetition times the same {fr['rows'][0]['serial']['points']} fits on the serial loop, 2 local workers, 2 `dask worker` "
                  "processes and two independent serial processes at once (no Dask: what the machine gives two "
                  "processes), in a rotated order; speed-ups and CPU ratios against that repetition's serial loop "
                  "(CPU: the workers' evaluating threads per fit; the pair's whole processes).", "",
                  "| repetition (order) | serial: wall s, CPU s/fit | 2 local: wall s, speed-up, CPU ratio | "
                  "2 `dask worker`: wall s, speed-up, CPU ratio | two serial processes: speed-up, CPU ratio | "
                  "load before |", "|---|---|---|---|---|---:|"]
        for k, row in enumerate(fr["rows"]):
            s_, w_, e_, p_ = row["serial"], row["workers2"], row["external2"], row["pair"]
            lines.append(f"| {k + 1} ({', '.join(row['order'])}) | {s_['wall_s']:.1f}, {s_['cpu_s_per_point']:.3f} | "
                         f"{w_['wall_s']:.1f}, {w_['speedup_wall']:.2f}x, {w_['cpu_ratio']:.3f} | "
                         f"{e_['wall_s']:.1f}, {e_['speedup_wall']:.2f}x, {e_['cpu_ratio']:.3f} | "
                         f"{p_['speedup_wall']:.2f}x, {p_['cpu_ratio']:.3f} | {s_['load_before'][0]:.1f} |")
        m_ = fr["summary"]

        def q(key):
            return f"**{m_[key]['median']:.2f}** ({m_[key]['min']:.2f}-{m_[key]['max']:.2f})"
        lines += ["", f"Medians (range): 2 local workers {q('workers2_speedup_wall')}x the serial loop, CPU per fit "
                  f"{q('workers2_cpu_ratio')} of its; 2 `dask worker` processes {q('external2_speedup_wall')}x, "
                  f"CPU {q('external2_cpu_ratio')}, rate {q('external2_rate_vs_local')} of the local workers'; "
                  f"two independent serial processes {q('pair_speedup_wall')}x, CPU {q('pair_cpu_ratio')}; the "
                  f"serial loop's CPU per fit {q('serial_cpu_s_per_point')} s.", ""]
    if results.get("guards"):
        lines += ["## Guard", ""] + [f"- {g['name']}: {g['value']:.3f} (bound {g['bound']:.2f}): "
                                     f"**{'pass' if g['ok'] else 'FAIL'}**" for g in results["guards"]] + [""]
    if "estimate_1e6" in results:
        e = results["estimate_1e6"]
        lines += ["## 10^6-design wall grid, estimated from the measured per-point and per-task costs", "",
                  f"- evaluation {e['cpu_s_per_point_eval'] * 1e3:.2f} ms CPU per design (20 modes + labels); "
                  f"tasks of {e['batch']} designs (1 s of work): {e['tasks']} tasks; per task "
                  f"{e['worker_ms_per_task']:.2f} ms CPU on the worker and {e['driver_ms_per_task']:.2f} ms on the "
                  f"driver (scheduler, transfer, Parquet part; less the idle background); idle background "
                  f"{e['idle_cpu_per_s_per_worker'] * 100:.2f} % of a core per worker, "
                  f"{e['idle_cpu_per_s_driver'] * 100:.2f} % on the driver;",
                  f"- 1 core, serial loop: 1e6 x {e['cpu_s_per_point_eval'] * 1e3:.2f} ms = "
                  f"**{e['one_core_serial_h']:.2f} h**;",
                  f"- 2 cores, 2 workers: **{e['two_cores_h']:.2f} h**;",
                  f"- {e['workers']} workers: workers {e['workers_bound_h'] * 60:.1f} min, driver "
                  f"{e['driver_bound_h'] * 60:.1f} min: **{e['sixty_four_workers_h'] * 60:.1f} min** (bound by the "
                  f"{e['sixty_four_workers_bound']}; the scheduler's heartbeat work grows with the workers, not "
                  "measured here). The 10^5-design run and its resume: study_scale.md.", ""]
    text = "\n".join(lines)
    return text + ("\n" + KEEP_MARK + "\n" + kept.lstrip("\n") if kept else "")


def kept_section(md_path: Path) -> str:
    """The hand-written part of an existing study.md (below :data:`KEEP_MARK`)."""
    if not md_path.exists():
        return ""
    text = md_path.read_text()
    return text.split(KEEP_MARK, 1)[1] if KEEP_MARK in text else ""


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fits", type=int, default=30)
    ap.add_argument("--grid", type=int, default=None, help="points per axis of the wall study (default 20: 8000 "
                                                           "designs; --quick: 6)")
    ap.add_argument("--out", default=str(ROOT / "benchmarks" / "results"))
    ap.add_argument("--json", default=None, help="result file (default: OUT/study.json; the markdown beside it)")
    ap.add_argument("--fit-reps", type=int, default=5,
                    help="repetitions of the fits on serial, local, external and a pair of serial processes, "
                         "order rotated, medians reported (default 5; 0: none)")
    ap.add_argument("--only", choices=("wall", "fits"), default=None)
    ap.add_argument("--quick", action="store_true",
                    help="CI form: the wall study on a 6 x 6 x 6 grid, 2 s of idle cluster, no fits, no 1-worker "
                         "or before run (give --out a scratch folder)")
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
        results["guards"] = guards(results, results["meta"].get("quick", False))
        json_path.write_text(json.dumps(results, indent=1, default=float))
        md_path.write_text(markdown(results, kept_section(md_path)) + "\n")
        return 0
    grid = args.grid or (6 if args.quick else 20)
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    meta = {"machine": f"{platform.machine()} {os.cpu_count()} cpus, shared with other agents",
            "python": platform.python_version(), "commit": commit, "quick": args.quick, "grid": grid,
            "argv": " ".join(argv if argv is not None else sys.argv[1:]),
            "started": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}
    scratch = Path(tempfile.mkdtemp(prefix="bench_study_"))
    results = {"meta": meta}
    try:
        if args.quick:
            global IDLE_S
            IDLE_S = 2.0
        if args.only in (None, "wall"):
            skip = ("serial_plain", "workers1") + (("workers2_before", "cli") if args.quick else ())
            results["wall_study"] = measure("wall", wall_spec(grid), scratch, skip)
            results["estimate_1e6"] = estimate(results["wall_study"])
        if args.only in (None, "fits") and not args.quick:
            results["fit_campaign"] = measure("fits", fit_spec(args.fits), scratch, ("cli",))
            if args.fit_reps > 0:
                results["fit_repeats"] = fits_repeated(fit_spec(args.fits), scratch / "reps", args.fit_reps)
        results["guards"] = guards(results, args.quick)
        if args.quick and not all(g["ok"] for g in results["guards"]):
            # 216 designs in tasks of ~50 on a shared CI machine: another job's burst lands on
            # a few tasks and moved the ratio between 0.81 and 1.39 in three runs of one
            # commit. Interference only adds CPU, so the wall study is measured a second
            # time and each guard keeps the lower of its two ratios (both are recorded).
            print("[wall] a guard failed: the wall study once more", flush=True)
            retry = {"wall_study": measure("wall", wall_spec(grid), scratch / "retry", skip)}
            results["wall_study_retry"] = retry["wall_study"]
            results["guards"] = [dict(min(pair, key=lambda g: g["value"]), first=pair[0]["value"],
                                      second=pair[1]["value"])
                                 for pair in zip(results["guards"], guards(retry, True))]
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    meta["finished"] = time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())
    json_path.parent.mkdir(parents=True, exist_ok=True)
    tmp = json_path.with_name("." + json_path.name + ".tmp")
    tmp.write_text(json.dumps(results, indent=1, default=float))
    os.replace(tmp, json_path)
    if args.only is None and not args.quick:
        tmp = md_path.with_name("." + md_path.name + ".tmp")
        tmp.write_text(markdown(results, kept_section(md_path)) + "\n")
        os.replace(tmp, md_path)
    for g in results["guards"]:
        print(f"guard: {g['name']}: {g['value']:.3f} (bound {g['bound']:.2f}): {'ok' if g['ok'] else 'FAIL'}",
              file=sys.stdout if g["ok"] else sys.stderr)
    print(f"wrote {json_path}")
    return 0 if all(g["ok"] for g in results["guards"]) else 1


if __name__ == "__main__":
    sys.exit(main())
