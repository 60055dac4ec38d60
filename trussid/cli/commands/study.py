"""``trussid study SPEC.toml --out DIR [--scheduler ADDRESS] [--workers N]``; ``trussid study DIR --report``.

Runs a design study or identification campaign (:mod:`trussid.study`) on a local Dask
cluster (default: one worker process per core), on an existing cluster (``--scheduler``)
or in this process (``--workers 0``), with a progress bar, and saves one Parquet row per
point in DIR. Run the same command again to compute only the missing points (after an
interruption or a lost worker); a different spec on the same DIR is refused. ``trussid
study DIR`` resumes the study stored in DIR; ``--report`` writes DIR/_report/.
"""

from __future__ import annotations

import re


def _plain(text: str) -> str:
    """The module docstring's reST as --help shows it: ``code`` and :role:`target` bare."""
    return re.sub(r":\w+:`([^`]*)`", r"\1", text).replace("``", "")

import json
import sys
from pathlib import Path


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
    if args.workers is not None and args.scheduler:
        raise UserError("--workers and --scheduler exclude each other (the scheduler's cluster has its workers)")
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


def _run(spec, out: Path, args) -> int:
    from tqdm import tqdm

    from trussid.study.engine import plan, run_study
    from trussid.study.store import StudyStore

    names, points, schema = plan(spec)
    # Open the store first: a refused output directory ends here, before any cluster starts.
    already = len(StudyStore(out, spec, schema, len(points)).done_points())
    bar = tqdm(total=len(points), initial=already, unit="pt", desc=spec.name, disable=args.quiet,
               dynamic_ncols=True, smoothing=0.1)
    failed = 0

    def progress(rows):
        nonlocal failed
        failed += sum(r["status"] != "ok" for r in rows)
        bar.set_postfix_str(f"failed {failed}", refresh=False)
        bar.update(len(rows))

    try:
        res = run_study(spec, out, scheduler=args.scheduler, workers=args.workers, progress=progress)
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
    for reason, n in sorted(res.reasons.items(), key=lambda kv: -kv[1])[:5]:
        print(f"  failed x{n}: {reason}")
    return 0 if not res.lost else 1
