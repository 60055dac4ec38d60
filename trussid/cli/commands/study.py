"""``trussid study SPEC.toml --out DIR [--workers N | --scheduler ADDRESS | --cluster FILE]``; ``trussid study DIR --report``.

Runs a design study or identification campaign (:mod:`trussid.study`) on a local Dask
cluster (default: one worker process per core), on an existing cluster (``--scheduler``),
on batch jobs (``--cluster``: a dask-jobqueue cluster file) or in this process
(``--workers 0``), with a progress bar (rate, time left), and saves one Parquet row per
point in DIR; at the end, what a point and a task cost. Run the same command again to
compute only the missing points (after an interruption or a lost worker); a different
spec on the same DIR is refused. ``trussid study DIR`` resumes the study stored in DIR;
``--report`` writes DIR/_report/.
"""

from __future__ import annotations

import contextlib
import json
import re
import signal
import sys
from pathlib import Path


def _plain(text: str) -> str:
    """The module docstring's reST as --help shows it: ``code`` and :role:`target` bare."""
    return re.sub(r":\w+:`([^`]*)`", r"\1", text).replace("``", "")


def add_parser(sub) -> None:
    p = sub.add_parser("study", help="run a design study / identification campaign (Dask); report on one",
                       description=_plain(__doc__.split("\n\n")[0] + "\n\n"
                                          + __doc__.split("\n\n")[1]),
                       formatter_class=__import__("argparse").RawDescriptionHelpFormatter)
    p.add_argument("spec", metavar="SPEC.toml|DIR", help="study spec (TOML), or a study output directory")
    p.add_argument("--out", metavar="DIR", help="output directory (a Parquet dataset); required with a spec")
    p.add_argument("--scheduler", metavar="ADDRESS", help="run on this Dask scheduler (tcp://host:8786)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: one per core; 0: no Dask, this process)")
    p.add_argument("--cluster", metavar="FILE",
                   help="run on batch jobs (SLURM, PBS, ...) described by this TOML file (dask-jobqueue; "
                        "docs/studies.md)")
    p.add_argument("--chunk", type=int, metavar="N",
                   help="points per task (default: the spec's chunk, else about 1 s of work from the "
                        "measured cost of a point); does not change results")
    p.add_argument("--report", action="store_true", help="write plots and report.md of the study in DIR")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args) -> int:
    from trussid._util.errors import UserError
    from trussid.study.spec import load_spec, spec_from_dict
    from trussid.study.store import META

    src = Path(args.spec)
    if args.workers is not None and args.workers < 0:
        raise UserError(f"--workers {args.workers}: must be 0 (this process) or a positive count")
    where = [o for o, v in (("--workers", args.workers is not None), ("--scheduler", args.scheduler),
                              ("--cluster", args.cluster)) if v]
    if len(where) > 1:
        raise UserError(f"{where[0]} and {where[1]} exclude each other (one place to run the study)")
    if args.chunk is not None and args.chunk < 1:
        raise UserError(f"--chunk {args.chunk}: must be a positive number of points per task")
    if src.is_dir():
        if not (src / META).exists():
            raise UserError(f"{src}: not a study output directory (no {META}) and not a spec file")
        if args.report:
            from trussid.study.report import write_report

            path = write_report(src)
            print(f"wrote {path} and its figures")
            return 0
        spec = spec_from_dict(json.loads((src / META).read_text())["spec"], where=str(src / META))
        out = Path(args.out) if args.out else src
    else:
        if args.report:
            raise UserError(f"{src}: --report takes a study output directory")
        if not src.exists():
            raise UserError(f"{src}: no such spec file")
        if not args.out:
            raise UserError("--out DIR is required with a spec file (where the results go)")
        spec = load_spec(src)
        out = Path(args.out)
    return _run(spec, out, args)


@contextlib.contextmanager
def _stop_on_signals():
    """``stop()``: true once SIGINT or SIGTERM arrived; a second one raises KeyboardInterrupt.

    The handler only sets a flag that the engine reads after each saved batch: a
    KeyboardInterrupt raised from the handler while Python runs a finaliser (a Dask future
    released) is lost ("Exception ignored in ..."), and a study went on after Ctrl-C.
    SIGTERM (a batch system ending the job) stops the same way. The previous handlers are
    restored on exit.
    """
    got = []

    def handler(signum, frame):
        if got:
            raise KeyboardInterrupt
        got.append(signum)

    old = {s: signal.signal(s, handler) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield lambda: bool(got)
    finally:
        for s, h in old.items():
            signal.signal(s, h)


def _run(spec, out: Path, args) -> int:
    from tqdm import tqdm

    from trussid.study.engine import plan, run_study
    from trussid.study.store import StudyStore

    cluster = None
    if args.cluster:
        from trussid.study.cluster import load_cluster_config

        cluster = load_cluster_config(args.cluster)  # a bad file ends here, before anything runs
    names, points, schema = plan(spec)
    # Open the store first: a refused output directory ends here, before any cluster starts.
    already = len(StudyStore(out, spec, schema, len(points)).done_points())
    # tqdm: rate (points/s) and time left, from the points of this run
    bar = tqdm(total=len(points), initial=already, unit="pt", desc=spec.name, disable=args.quiet,
               dynamic_ncols=True, smoothing=0.1)
    failed = 0

    def progress(batch):
        nonlocal failed
        failed += batch.failed
        bar.set_postfix_str(f"failed {failed}", refresh=False)
        bar.update(batch.points)

    try:
        with contextlib.ExitStack() as stack:
            client = None
            if cluster is not None:
                from trussid.study.cluster import jobqueue_client

                client = stack.enter_context(jobqueue_client(cluster))
            stop = stack.enter_context(_stop_on_signals())
            res = run_study(spec, out, client=client, scheduler=args.scheduler, workers=args.workers,
                            chunk=args.chunk, progress=progress, stop=stop)
    except KeyboardInterrupt:
        bar.close()
        done = len(StudyStore(out, spec, schema, len(points)).done_points())
        print(f"trussid study: interrupted: {done} of {len(points)} points saved in {out}; "
              "run the same command again to compute the rest", file=sys.stderr)
        return 130
    bar.close()
    rate = res.computed / res.seconds if res.seconds > 0 else float("nan")
    print(f"{out}: {res.total} points: computed {res.computed} in this run ({res.failed} failed), "
          f"{res.already} already done" + (f", {res.lost} lost (run again)" if res.lost else "")
          + f"; {res.seconds:.1f} s, {rate:.3g} points/s on "
          + (f"{res.workers} worker(s)" if res.workers else "this process"))
    if res.computed:
        print("\n".join("  " + line for line in res.costs().splitlines()))
    for reason, n in sorted(res.reasons.items(), key=lambda kv: -kv[1])[:5]:
        print(f"  failed x{n}: {reason}")
    return 0 if not res.lost else 1
