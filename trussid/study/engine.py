"""Running a study: points in chunks on Dask workers, each finished chunk saved at once.

Engines
-------
- default: a :class:`distributed.LocalCluster` of ``workers`` processes (default: the
  machine's cores), one thread each, started and shut down here;
- ``scheduler="tcp://host:8786"``: an existing cluster (``dask scheduler`` /
  ``dask worker``, or dask-jobqueue on SLURM/PBS; docs/studies.md);
- ``client=``: a :class:`distributed.Client` the caller owns (left open);
- ``workers=0``: no Dask, every point in this process (tests, debugging, the serial
  reference of the benchmark).

Every point runs with BLAS at one thread (:func:`trussid._util.threads.blas_threads`): the
per-point linear algebra is small, and one process per core is the parallelism. A point
that raises becomes a row with ``status = "failed"`` and its one-line reason. The driver
(this process) writes each returned chunk as one Parquet part (:mod:`trussid.study.store`),
so a chunk whose worker died and that Dask ran again elsewhere is still written once.
"""

from __future__ import annotations

import logging
import math
import os
import socket
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

import pyarrow as pa

from trussid._util.threads import blas_threads
from trussid.study.evaluators import get_evaluator
from trussid.study.spec import StudySpec, sample_points, spec_hash
from trussid.study.store import STATUS_COLUMNS, StudyStore


@dataclass
class StudyRun:
    """What one call of :func:`run_study` did.

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
        Points whose chunk never came back (Dask gave up on it); a rerun retries them.
    seconds : float
        Wall time of the run [s], cluster start included.
    workers : int
        Worker processes (0: in-process).
    reasons : dict
        Failure reason -> count, of this run.
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


def evaluate_chunk(evaluate: str, options: dict, names: list[str], chunk: list) -> list[dict]:
    """Rows of the points ``chunk`` = ``[(point, values), ...]`` (runs on a worker).

    Every point is evaluated under a one-thread BLAS limit; an exception becomes a failed
    row with ``"Type: message"`` (first line) as its ``error``.
    """
    ev = get_evaluator(evaluate)
    worker = f"{socket.gethostname()}:{os.getpid()}"
    rows = []
    with blas_threads(1):
        ctx_error = None
        try:
            ctx = ev.context(options)
        except Exception as exc:  # any error building the testbed or plant: every point fails with it
            ctx, ctx_error = None, exc
        for point, values in chunk:
            params = dict(zip(names, values))
            row = {"point": int(point), **params, "worker": worker}
            t0, c0 = time.perf_counter(), time.thread_time()
            try:
                if ctx_error is not None:
                    raise ctx_error
                row.update(ev.point(ctx, params, options))
                row["status"], row["error"] = "ok", ""
            except Exception as exc:  # whatever a point raises (numerics, fits): a failed row
                text = str(exc).strip().splitlines()
                row["status"] = "failed"
                row["error"] = f"{type(exc).__name__}: {text[0] if text else ''}"
            row["seconds"] = time.perf_counter() - t0
            # CPU time of this thread (BLAS runs in it at one thread): the cost of the
            # point whatever else shares the machine.
            row["cpu_seconds"] = time.thread_time() - c0
            rows.append(row)
    return rows


def _chunks(todo: list, size: int) -> list[list]:
    return [todo[i:i + size] for i in range(0, len(todo), size)]


def run_study(spec: StudySpec, out, *, client=None, scheduler: str | None = None,
              workers: int | None = None, progress=None) -> StudyRun:
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
    progress : callable, optional
        ``progress(rows)`` after each saved chunk, with its rows (for a progress bar).

    Returns
    -------
    StudyRun

    Raises
    ------
    StudyError
        When ``out`` holds another study.
    KeyboardInterrupt
        Passed on after the cluster is shut down; every chunk saved so far stays.
    """
    t_start = time.perf_counter()
    ev = get_evaluator(spec.evaluate)
    names, points, schema = plan(spec)
    store = StudyStore(out, spec, schema, len(points))
    done = store.done_points()
    todo = [(i, p) for i, p in enumerate(points) if i not in done]
    run = StudyRun(out=store.out, total=len(points), already=len(points) - len(todo))
    if not todo:
        run.seconds = time.perf_counter() - t_start
        return run

    def saved(rows):
        store.write_chunk(rows)
        run.computed += len(rows)
        for r in rows:
            if r["status"] != "ok":
                run.failed += 1
                run.reasons[r["error"]] = run.reasons.get(r["error"], 0) + 1
        if progress is not None:
            progress(rows)

    if client is None and scheduler is None and workers == 0:
        size = spec.chunk or ev.default_chunk
        for chunk in _chunks(todo, size):
            saved(evaluate_chunk(spec.evaluate, spec.options, names, chunk))
        run.seconds = time.perf_counter() - t_start
        return run

    from distributed import Client, LocalCluster, as_completed

    own_cluster = own_client = None
    try:
        if client is None:
            if scheduler is None:
                n = (os.cpu_count() or 1) if workers is None else int(workers)
                # silence_logs: Dask's own log lines about its processes (a slow worker
                # shutdown on a loaded machine; after Ctrl-C, workers losing the scheduler
                # they were heartbeating to) are not the user's business: what matters
                # reaches the user as failed rows, lost chunks or an exception.
                own_cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                           dashboard_address=None, silence_logs=logging.CRITICAL)
                own_client = client = Client(own_cluster)
            else:
                own_client = client = Client(scheduler)
        run.workers = len(client.scheduler_info().get("workers", {})) or (workers or 0)
        threads = max(1, sum(client.nthreads().values()))
        # Enough tasks to keep every worker busy to the end (4 per thread), never more
        # points per task than the evaluator's default (per-task overhead ~ms).
        size = spec.chunk or max(1, min(ev.default_chunk, math.ceil(len(todo) / (4 * threads))))
        # Keys unique per run: two runs of one spec on one cluster must not share results.
        token = f"study-{spec_hash(spec)}-{uuid.uuid4().hex[:8]}"
        futures = {client.submit(evaluate_chunk, spec.evaluate, spec.options, names, chunk,
                                 key=f"{token}-{chunk[0][0]}", pure=False): len(chunk)
                   for chunk in _chunks(todo, size)}
        try:
            for fut in as_completed(list(futures)):
                try:
                    rows = fut.result()
                except Exception as exc:  # KilledWorker, CancelledError, ...: Dask's many types
                    # Dask gave up on the chunk (its workers kept dying, KilledWorker):
                    # leave it unsaved so that a rerun retries it.
                    run.lost += futures[fut]
                    run.reasons[f"not computed: {type(exc).__name__}: {exc}"] = futures[fut]
                    continue
                saved(rows)
                fut.release()
        except BaseException:  # Ctrl-C included: cancel the queued chunks, then re-raise
            client.cancel(list(futures))
            raise
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()
    run.seconds = time.perf_counter() - t_start
    return run


__all__ = ["run_study", "evaluate_chunk", "plan", "StudyRun"]
