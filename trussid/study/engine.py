"""Running a study: points in batches on Dask workers, each finished batch saved at once.

Engines
-------
- default: a :class:`distributed.LocalCluster` of ``workers`` processes (default: the
  machine's cores), one thread each, started and shut down here (:func:`local_cluster`);
- ``scheduler="tcp://host:8786"``: an existing cluster (``dask scheduler`` /
  ``dask worker``, or dask-jobqueue on SLURM/PBS: :mod:`trussid.study.cluster`);
- ``client=``: a :class:`distributed.Client` the caller owns (left open);
- ``workers=0``: no Dask, every point in this process (tests, debugging).

Batches
-------
A task evaluates a *batch* of points and returns them as one Arrow table built on the
worker, so that the driver's work per point is a Parquet write of ready columns. The batch
size comes from the measured cost of a point (:class:`BatchSizer`): about
:data:`TASK_SECONDS` of work per task, shrinking towards the end of the study (guided
self-scheduling) so that the workers finish together; ``chunk`` (spec or argument) fixes it.
The driver keeps only :data:`IN_FLIGHT` tasks per worker thread submitted and submits the
next batch as one finishes, so neither its memory nor the scheduler's grows with the study.

Every point runs with BLAS at one thread (:func:`trussid._util.threads.blas_threads`): the
per-point linear algebra is small, and one process per core is the parallelism. A point
that raises becomes a row with ``status = "failed"`` and its one-line reason. The driver
(this process) writes each returned batch as one Parquet part (:mod:`trussid.study.store`),
so a batch whose worker died and that Dask ran again elsewhere is still written once.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import resource
import socket
import sys
import time
import uuid
from dataclasses import asdict, dataclass, field
from pathlib import Path

import dask
import pyarrow as pa
from distributed import Client, LocalCluster, as_completed

from trussid._util.threads import blas_threads
from trussid.study.evaluators import get_evaluator
from trussid.study.spec import StudySpec, sample_points, spec_hash
from trussid.study.store import STATUS_COLUMNS, StudyStore

#: Work per task the batch size aims at [s]: the per-task costs (scheduler, transfer, one
#: Parquet part; ~5 ms) stay under 1 % of it, a lost worker loses at most this much, and
#: the progress bar moves several times a second on a handful of workers.
TASK_SECONDS = 1.0
#: Smallest task near the end of a study [s of work]: below it the per-task costs grow
#: past a few per cent; the idle tail of the last tasks is at most about this long.
MIN_TASK_SECONDS = 0.15
#: Tasks submitted per worker thread at any time: one running, one queued behind it (so a
#: worker never waits for the driver), and no more (memory does not grow with the study).
IN_FLIGHT = 2

#: Environment of the worker processes this module starts (and of the ``dask worker``
#: commands of the recipes in docs/studies.md). BLAS at one thread (one process per core is
#: the parallelism). glibc's malloc: distributed sets ``MALLOC_TRIM_THRESHOLD_=65536``,
#: which also freezes the mmap threshold at 128 kB, so every array of the eigen-solutions
#: and fits is a fresh mmap and its pages fault in again (measured: ~900 page faults and
#: ~25 % more CPU per wall-study design than in a plain process); thresholds of 32 MiB
#: (mmap) and 128 MiB (trim) let freed blocks be reused (<1 fault per design).
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1",
              "MALLOC_TRIM_THRESHOLD_": str(128 * 2**20), "MALLOC_MMAP_THRESHOLD_": str(32 * 2**20)}
#: Dask settings of a study's processes (workers and nannies, and the scheduler that a local
#: or batch-system cluster runs in the driver). Dask's timers run per wall second whatever
#: the work, and on this cluster they were the per-design cost of the workers beyond the
#: evaluation (benchmarks/results/study.md: 6.3 % of a core idle, 1.3 % with these):
#: no statistical profiler (it samples every thread's stack every 10 ms, for a dashboard a
#: study does not use); the event-loop watchdog ("tick", 20 ms: 50 wake-ups a second, each
#: taking the GIL from the evaluation) once a second; the memory monitor (pause, spill,
#: restart; 100 ms) and the host statistics (500 ms) less often: a worker's memory does not
#: grow by much within a second of points; no GIL sampler (with ``gilknocker`` installed it
#: takes the GIL every millisecond).
WORKER_CONFIG = {"distributed.worker.profile.enabled": False,
                 "distributed.admin.tick.interval": "1s",
                 "distributed.worker.memory.monitor-interval": "1s",
                 "distributed.admin.system-monitor.interval": "5s",
                 "distributed.admin.system-monitor.gil.enabled": False}


@dataclass
class StudyRun:
    """What one call of :func:`run_study` did, and what it cost.

    Attributes
    ----------
    out : Path
    total : int
        Points of the study.
    already : int
        Points found finished in ``out`` before this run.
    computed : int
        Points evaluated in this run (ok or failed).
    failed : int
        Of ``computed``, the points that raised.
    lost : int
        Points whose batch never came back (Dask gave up on it); a rerun retries them.
    seconds : float
        Wall time of the run [s], cluster start included.
    workers : int
        Worker processes (0: in-process).
    reasons : dict
        Failure reason -> count, of this run.
    tasks : int
        Batches saved in this run (one Parquet part each).
    batch_min, batch_max : int
        Smallest and largest batch [points].
    eval_cpu_s : float
        CPU of the evaluations of the points, summed [s] (the ``cpu_seconds`` column).
    eval_s : float
        Wall time of the evaluations, summed [s] (the ``seconds`` column).
    task_cpu_s : float
        CPU of the tasks on the workers, summed [s]: the evaluations plus each task's own
        work (evaluator context lookup, the batch's Arrow table).
    context_cpu_s : float
        CPU of building the evaluator's context on the workers, summed [s] (once per worker
        process and study: the testbed model, the truth plant).
    driver_cpu_s : float
        CPU of this process from the first submitted batch to the last saved one [s]: the
        result handling and Parquet writes, and with a local cluster its scheduler and
        nannies (the cluster start is not included: ``start_s``).
    driver_write_cpu_s : float
        Of ``driver_cpu_s``, the CPU of receiving and writing the batches [s].
    start_s : float
        Wall time until the first batch was submitted [s] (cluster start, connection).
    peak_rss_mb : float
        Peak resident memory of this process so far [MB] (``getrusage``).
    """

    out: Path
    total: int
    already: int
    computed: int = 0
    failed: int = 0
    lost: int = 0
    seconds: float = 0.0
    workers: int = 0
    reasons: dict = field(default_factory=dict)
    tasks: int = 0
    batch_min: int = 0
    batch_max: int = 0
    eval_cpu_s: float = 0.0
    eval_s: float = 0.0
    task_cpu_s: float = 0.0
    context_cpu_s: float = 0.0
    driver_cpu_s: float = 0.0
    driver_write_cpu_s: float = 0.0
    start_s: float = 0.0
    peak_rss_mb: float = 0.0

    @property
    def engine_cpu_s(self) -> float:
        """CPU of the tasks on the workers beyond the evaluations and contexts [s]."""
        return self.task_cpu_s - self.eval_cpu_s - self.context_cpu_s

    def add(self, res: BatchResult) -> None:
        """Count a saved batch into the totals of the run."""
        self.computed += res.points
        self.failed += res.failed
        for reason, k in res.reasons.items():
            self.reasons[reason] = self.reasons.get(reason, 0) + k
        self.tasks += 1
        self.batch_min = min(self.batch_min or res.points, res.points)
        self.batch_max = max(self.batch_max, res.points)
        self.eval_s += res.eval_s
        self.eval_cpu_s += res.eval_cpu_s
        self.task_cpu_s += res.task_cpu_s
        self.context_cpu_s += res.context_cpu_s

    def costs(self) -> str:
        """Per-point and per-task costs of the run, as lines of text (the CLI's summary)."""
        if not self.computed:
            return "nothing computed"
        n, t = self.computed, max(self.tasks, 1)
        ms = 1e3
        lines = [f"per point: evaluation {self.eval_cpu_s / n * ms:.2f} ms CPU ({self.eval_s / n * ms:.2f} ms wall); "
                 f"engine on the workers {self.engine_cpu_s / n * ms:.3f} ms CPU; "
                 f"driver {self.driver_cpu_s / n * ms:.3f} ms CPU",
                 f"per task: {self.tasks} tasks of {self.batch_min}..{self.batch_max} points "
                 f"({n / t:.1f} on average); driver receive + write {self.driver_write_cpu_s / t * ms:.2f} ms CPU; "
                 f"engine on the worker {self.engine_cpu_s / t * ms:.2f} ms CPU",
                 f"start {self.start_s:.1f} s; evaluator context {self.context_cpu_s:.2f} s CPU (all workers); "
                 f"driver peak memory {self.peak_rss_mb:.0f} MB"]
        return "\n".join(lines)


@dataclass
class BatchResult:
    """What a task returns: the rows of its points as one table, and what they cost.

    Attributes
    ----------
    table : pyarrow.Table
        One row per point, in the study's schema.
    points, failed : int
    reasons : dict
        Failure reason -> count.
    eval_s, eval_cpu_s : float
        Wall and CPU of the evaluations, summed [s].
    task_s, task_cpu_s : float
        Wall and CPU of the whole task on the worker [s].
    context_cpu_s : float
        Of ``task_cpu_s``, the CPU of building the evaluator's context (first task of a
        worker process; 0 afterwards) [s].
    """

    table: pa.Table
    points: int
    failed: int
    reasons: dict
    eval_s: float
    eval_cpu_s: float
    task_s: float
    task_cpu_s: float
    context_cpu_s: float = 0.0


def _arrow_type(values) -> pa.DataType:
    if all(isinstance(v, bool) for v in values):
        return pa.bool_()
    if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return pa.int64()
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return pa.float64()
    return pa.string()


def plan(spec: StudySpec) -> tuple[list[str], list[tuple], pa.Schema]:
    """Parameter names, every point's values, and the result schema of ``spec``."""
    names, points = sample_points(spec)
    ev = get_evaluator(spec.evaluate)
    types = [_arrow_type([p[j] for p in points]) for j in range(len(names))]
    if any(t == pa.float64() for t in types):
        points = [tuple(float(v) if t == pa.float64() else v for v, t in zip(p, types)) for p in points]
    fields = [("point", pa.int64())] + list(zip(names, types)) + STATUS_COLUMNS + ev.columns(spec.options)
    return names, points, pa.schema(fields)


@dataclass(frozen=True)
class PointStatus:
    """How one point went: the status columns of its row (:data:`trussid.study.store.STATUS_COLUMNS`).

    Attributes
    ----------
    status : str
        "ok" or "failed".
    error : str
        ``"Type: message"`` (first line) of a failed point, else "".
    seconds, cpu_seconds : float
        Wall time and CPU time of this thread [s].
    """

    status: str
    error: str
    seconds: float
    cpu_seconds: float


@dataclass(frozen=True)
class Chunk:
    """Rows of a chunk of points, each point's status, and the context's CPU [s]."""

    rows: list
    statuses: list
    context_cpu_s: float


def _evaluate(evaluate: str, options: dict, names: list[str], chunk: list) -> Chunk:
    ev = get_evaluator(evaluate)
    worker = f"{socket.gethostname()}:{os.getpid()}"
    rows, statuses = [], []
    with blas_threads(1):
        ctx_error, c0 = None, time.thread_time()
        try:
            ctx = ev.context(options)
        except Exception as exc:  # any error building the testbed or plant: every point fails with it
            ctx, ctx_error = None, exc
        context_cpu_s = time.thread_time() - c0
        for point, values in chunk:
            params = dict(zip(names, values))
            row = {"point": int(point), **params, "worker": worker}
            t0, c0 = time.perf_counter(), time.thread_time()
            status, error = "ok", ""
            try:
                if ctx_error is not None:
                    raise ctx_error
                row.update(ev.point(ctx, params, options))
            except Exception as exc:  # whatever a point raises (numerics, fits): a failed row
                text = str(exc).strip().splitlines()
                status, error = "failed", f"{type(exc).__name__}: {text[0] if text else ''}"
            # CPU time of this thread (BLAS runs in it at one thread): the cost of the
            # point whatever else shares the machine.
            st = PointStatus(status=status, error=error, seconds=time.perf_counter() - t0,
                             cpu_seconds=time.thread_time() - c0)
            row.update(asdict(st))
            rows.append(row)
            statuses.append(st)
    return Chunk(rows=rows, statuses=statuses, context_cpu_s=context_cpu_s)


def evaluate_chunk(evaluate: str, options: dict, names: list[str], chunk: list,
                   timing: dict | None = None) -> list[dict]:
    """Rows of the points ``chunk`` = ``[(point, values), ...]``.

    Every point is evaluated under a one-thread BLAS limit; an exception becomes a failed
    row with ``"Type: message"`` (first line) as its ``error``.

    Parameters
    ----------
    evaluate : str
        The evaluator's name.
    options : dict
        Its options.
    names : list of str
        Parameter names, in the order of each point's values.
    chunk : list of (int, tuple)
        The points and their values.
    timing : dict, optional
        Receives ``context_cpu_s``: the CPU of getting the evaluator's context [s].

    Returns
    -------
    list of dict
        One row per point: its number, parameters, outputs and status columns.
    """
    out = _evaluate(evaluate, options, names, chunk)
    if timing is not None:
        timing["context_cpu_s"] = out.context_cpu_s
    return out.rows


def evaluate_batch(evaluate: str, options: dict, names: list[str], batch: list,
                   schema: pa.Schema) -> BatchResult:
    """One task: the points ``batch`` = ``[(point, values), ...]`` as a table (runs on a worker).

    The table is built here, on the worker, so that the driver only writes it.
    """
    t0, c0 = time.perf_counter(), time.thread_time()
    out = _evaluate(evaluate, options, names, batch)
    reasons: dict = {}
    for st in out.statuses:
        if st.status != "ok":
            reasons[st.error] = reasons.get(st.error, 0) + 1
    table = pa.Table.from_pylist(out.rows, schema=schema)
    return BatchResult(table=table, points=len(out.rows), failed=sum(reasons.values()), reasons=reasons,
                       eval_s=sum(st.seconds for st in out.statuses),
                       eval_cpu_s=sum(st.cpu_seconds for st in out.statuses),
                       task_s=time.perf_counter() - t0, task_cpu_s=time.thread_time() - c0,
                       context_cpu_s=out.context_cpu_s)


class BatchSizer:
    """Points per task from the measured cost of a point (guided self-scheduling).

    Before any batch came back, ``first`` points (the evaluator's hint). Then, with ``c``
    the mean CPU time of a point so far [s], ``R`` the points not yet submitted and ``T``
    the worker threads: ``min(TASK_SECONDS / c, max(R / (2 T), MIN_TASK_SECONDS / c))``,
    at least 1. Large tasks while much remains; smaller ones at the end, so that no worker
    is left with a long task while the others idle. ``fixed`` overrides all of it.

    CPU, not wall time: on a loaded machine a point's wall time grows with the load (ten
    times on the shared 2-core machine) while its CPU does not; sized by wall time the
    batches shrank to a few points and the per-task costs (scheduler, transfer, table,
    Parquet part: ~10 ms of CPU a task there) became a tenth of the work (issue 35).

    Parameters
    ----------
    first : int
        Batch size before a cost is measured.
    fixed : int, optional
        Constant batch size (the spec's or the caller's ``chunk``).
    task_seconds, min_task_seconds : float
        Target and smallest work per task [s].
    """

    def __init__(self, first: int, fixed: int | None = None, task_seconds: float = TASK_SECONDS,
                 min_task_seconds: float = MIN_TASK_SECONDS):
        self.first, self.fixed = max(1, int(first)), fixed
        self.task_seconds, self.min_task_seconds = task_seconds, min_task_seconds
        self.points, self.seconds = 0, 0.0

    def observe(self, points: int, seconds: float) -> None:
        """Record a finished batch: ``points`` evaluated in ``seconds`` of CPU, summed."""
        self.points += points
        self.seconds += seconds

    @property
    def point_seconds(self) -> float | None:
        """Mean CPU time of a point so far [s] (None before the first batch)."""
        return self.seconds / self.points if self.points else None

    def size(self, remaining: int, threads: int) -> int:
        """Points of the next batch, ``remaining`` points being still unsubmitted."""
        if self.fixed:
            return max(1, min(self.fixed, remaining))
        c = self.point_seconds
        if c is None:
            return max(1, min(self.first, remaining))
        c = max(c, 1e-6)
        guided = max(math.ceil(remaining / (2 * max(threads, 1))), math.ceil(self.min_task_seconds / c))
        return max(1, min(remaining, math.floor(self.task_seconds / c), guided))


def _peak_rss_mb() -> float:
    # ru_maxrss is in kB on Linux, in bytes on macOS
    r = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return r / (2**20 if sys.platform == "darwin" else 2**10)


@contextlib.contextmanager
def local_cluster(workers: int, config: dict | None = None):
    """A LocalCluster of ``workers`` processes, one thread each, set up for studies.

    The workers get :data:`WORKER_ENV`, and the scheduler, nannies and workers the Dask
    settings ``config`` (default :data:`WORKER_CONFIG`), set only while the cluster is
    created (``dask.config.set`` as a context; each server reads them when it starts).
    Yields the cluster; closes it on exit.
    """
    config = WORKER_CONFIG if config is None else config
    pre_spawn = {**dask.config.get("distributed.nanny.pre-spawn-environ", {}), **WORKER_ENV}
    with dask.config.set({**config, "distributed.nanny.pre-spawn-environ": pre_spawn}):
        # silence_logs: Dask's own log lines about its processes (a slow worker shutdown on
        # a loaded machine; after Ctrl-C, workers losing the scheduler they were
        # heartbeating to) are not the user's business: what matters reaches the user as
        # failed rows, lost batches or an exception.
        # The scheduler's HTTP server on a free loopback port (with None it takes 8787 and
        # warns when another cluster holds it).
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
                               dashboard_address="127.0.0.1:0", silence_logs=logging.CRITICAL)
    try:
        yield cluster
    finally:
        cluster.close()


def _thread_count(client):
    """``threads()``: the cluster's worker threads, looked up again at most once a second
    (workers may join or leave: dask-jobqueue jobs start late, a machine is lost)."""
    n, t = max(1, sum(client.nthreads().values())), time.perf_counter()

    def threads() -> int:
        nonlocal n, t
        if time.perf_counter() - t > 1.0:
            n, t = max(1, sum(client.nthreads().values())), time.perf_counter()
        return n

    return threads


def _check(stop) -> None:
    if stop is not None and stop():
        raise KeyboardInterrupt


def _stream(client, submit, source, threads, saved, run: StudyRun, stop=None) -> None:
    """Keep :data:`IN_FLIGHT` batches per worker thread submitted; save each as it returns.

    ``submit(batch)`` makes a future, ``source`` yields the batches, ``saved(result)``
    writes one. A batch Dask gave up on (its workers kept dying: KilledWorker) counts as
    lost and is left for a rerun. ``stop()`` true after a saved batch ends the loop as
    Ctrl-C does. On any exception (Ctrl-C included) the submitted batches are cancelled
    before it is passed on.
    """
    pending, sizes = as_completed(), {}

    def top_up(n_tasks):
        for _ in range(n_tasks):
            batch = next(source, None)
            if batch is None:
                return
            fut = submit(batch)
            sizes[fut.key] = len(batch)
            pending.add(fut)

    try:
        top_up(IN_FLIGHT * threads())
        for fut in pending:
            size = sizes.pop(fut.key)
            try:
                res = fut.result()
            except Exception as exc:  # KilledWorker, CancelledError, ...: Dask's many types
                run.lost += size
                reason = f"not computed: {type(exc).__name__}: {exc}"
                run.reasons[reason] = run.reasons.get(reason, 0) + size
                res = None
            fut.release()
            if res is not None:
                saved(res)
            _check(stop)
            top_up(max(1, IN_FLIGHT * threads() - pending.count()))  # more if workers joined
    except BaseException:  # Ctrl-C included: cancel the submitted batches, then re-raise
        client.cancel(list(pending.futures))
        raise


def run_study(spec: StudySpec, out, *, client=None, scheduler: str | None = None,
              workers: int | None = None, chunk: int | None = None, progress=None, stop=None) -> StudyRun:
    """Evaluate every point of ``spec`` not yet in ``out`` and save the rows there.

    Parameters
    ----------
    spec : StudySpec
    out : path-like
        Output directory: new, empty, or holding this same study (then only the missing
        points are computed). Another study's output is refused.
    client : distributed.Client, optional
        Run on this client's cluster (not closed here).
    scheduler : str, optional
        Address of a running Dask scheduler to connect to.
    workers : int, optional
        Local worker processes (default: ``os.cpu_count()``); 0 evaluates in this process.
    chunk : int, optional
        Points per task (default: ``spec.chunk``, else from the measured cost of a point,
        :class:`BatchSizer`). Does not change results.
    progress : callable, optional
        ``progress(batch)`` after each saved batch, with its :class:`BatchResult`.
    stop : callable, optional
        ``stop()`` is asked after each saved batch; true ends the run as Ctrl-C does
        (``KeyboardInterrupt``). For a caller whose signal handler only sets a flag: an
        exception raised by a handler while Python runs a finaliser (a Dask future's
        ``__del__``) is lost, so a plain Ctrl-C can go unnoticed in a long study.

    Returns
    -------
    StudyRun

    Raises
    ------
    StudyError
        When ``out`` holds another study.
    KeyboardInterrupt
        Passed on after the cluster is shut down; every batch saved so far stays.
    """
    t_start = time.perf_counter()
    c_submit = time.process_time()
    ev = get_evaluator(spec.evaluate)
    names, points, schema = plan(spec)
    store = StudyStore(out, spec, schema, len(points))
    done = store.done_points()
    todo = [i for i in range(len(points)) if i not in done]
    del done
    run = StudyRun(out=store.out, total=len(points), already=len(points) - len(todo))
    sizer = BatchSizer(first=ev.default_chunk, fixed=chunk or spec.chunk)

    def finish():
        run.seconds = time.perf_counter() - t_start
        run.driver_cpu_s = time.process_time() - c_submit
        run.peak_rss_mb = _peak_rss_mb()
        return run

    if not todo:
        return finish()

    def saved(res: BatchResult):
        c0 = time.thread_time()
        store.write_table(res.table)
        run.driver_write_cpu_s += time.thread_time() - c0
        sizer.observe(res.points, res.eval_cpu_s)
        run.add(res)
        if progress is not None:
            progress(res)

    def batches(threads):
        """The next batch of ``todo`` (a generator over the study, sized as it goes)."""
        i = 0
        while i < len(todo):
            k = sizer.size(len(todo) - i, threads())
            yield [(p, points[p]) for p in todo[i:i + k]]
            i += k

    if client is None and scheduler is None and workers == 0:
        run.start_s, c_submit = time.perf_counter() - t_start, time.process_time()
        for batch in batches(lambda: 1):
            saved(evaluate_batch(spec.evaluate, spec.options, names, batch, schema))
            _check(stop)
        return finish()

    with contextlib.ExitStack() as stack:
        if client is None:
            if scheduler is None:
                n = (os.cpu_count() or 1) if workers is None else int(workers)
                client = stack.enter_context(Client(stack.enter_context(local_cluster(n))))
            else:
                client = stack.enter_context(Client(scheduler))
        run.workers = len(client.scheduler_info().get("workers", {})) or (workers or 0)
        threads = _thread_count(client)
        # Keys unique per run: two runs of one spec on one cluster must not share results.
        token = f"study-{spec_hash(spec)}-{uuid.uuid4().hex[:8]}"

        def submit(batch):
            return client.submit(evaluate_batch, spec.evaluate, spec.options, names, batch, schema,
                                 key=f"{token}-{batch[0][0]}", pure=False)

        run.start_s, c_submit = time.perf_counter() - t_start, time.process_time()
        _stream(client, submit, batches(threads), threads, saved, run, stop)
        finish()  # before the cluster's shutdown: the run's own cost
    run.seconds = time.perf_counter() - t_start
    return run


__all__ = ["run_study", "evaluate_batch", "evaluate_chunk", "plan", "local_cluster", "BatchSizer",
           "BatchResult", "StudyRun", "TASK_SECONDS", "MIN_TASK_SECONDS", "IN_FLIGHT", "WORKER_ENV",
           "WORKER_CONFIG"]
