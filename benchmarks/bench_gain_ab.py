#!/usr/bin/env python3
"""``identify``'s CPU time against nfoursid N4SID's on the four shared measured sets, paired:
this checkout and another one (``--before``), in alternating processes.

Why a paired run: on the shared 2-core machine the CPU seconds of one small fit vary by 2x
with the other users' load (hyper-threads and caches are shared), so figures from two
separate runs of ``bench_realdata.py`` cannot show a change of a few tens of per cent. Here
each worker process times N4SID and ``identify`` interleaved (N4SID, PLID, N4SID, PLID, ...;
CPU seconds, ``time.process_time``, after a warm-up fit) and reports the ratio of their
minima; the two checkouts' workers alternate, ``--rounds`` times, so both see the same load.
The ratio per set is the median over rounds (and the spread). The validation fits are
scored as ``bench_realdata.py`` scores them (same split, same order).

``--before DIR``: a tree of another commit, e.g. ``git archive f041aae | tar -x -C DIR``;
its ``plid``, ``fem``, ``geometry`` and ``trussid`` folders are imported instead of this
checkout's (the editable install's mapping is redirected in the worker).

Usage::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_gain_ab.py --before /tmp/before \\
        --rounds 5 --out benchmarks/results/plid_gain_ab_i35.md --json ab.json
    python benchmarks/bench_gain_ab.py --quick --json ab.json     # robot arm, this checkout
"""
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)

#: set -> (order, nfoursid block rows): PLID's and N4SID's chosen ones (``PROFILE_AT`` of
#: ``bench_realdata.py``; the subframe at the order issue 34 names)
SETS = {"robotarm": (8, 20), "flutter": (8, 10), "cdplayer": (10, 10), "subframe": (30, 40)}


def _redirect(root):
    """Import ``trussid`` (and its mapped packages) from ``root`` instead of this checkout."""
    for mod in list(sys.modules.values()):
        mapping = getattr(mod, "MAPPING", None)
        if (isinstance(mapping, dict) and "trussid" in mapping
                and getattr(mod, "__name__", "").startswith("__editable__")):
            for k, v in mapping.items():
                mapping[k] = os.path.join(root, os.path.relpath(v, REPO))
            return
    raise SystemExit("bench_gain_ab: --root needs the editable install of trussid")


def worker(root, sets, reps):
    """Time the sets in this process; print a JSON line ``{set: {...}}``."""
    if os.path.abspath(root) != REPO:
        _redirect(os.path.abspath(root))
    sys.path.insert(0, HERE)
    import bench_realdata as br
    import trussid.plid as plid_pkg
    from trussid.plid import identify

    warnings.simplefilter("ignore")
    out = {"plid_file": plid_pkg.__file__}
    for name in sets:
        order, rows = SETS[name]
        dt = br.DATASETS[name]["dt"]
        u, y = br.load(name)
        (ui, yi), (uv, yv) = br.split(u, y)
        identify(ui, yi, order, dt, progress=False)      # warm-up (numba caches, imports)
        br.fit_n4sid(ui, yi, order, dt, rows)
        pl, n4 = [], []
        for _ in range(reps):
            c0 = time.process_time()
            br.fit_n4sid(ui, yi, order, dt, rows)
            n4.append(time.process_time() - c0)
            c0 = time.process_time()
            idn = identify(ui, yi, order, dt, progress=False)
            pl.append(time.process_time() - c0)
        m = idn.model
        mk = br._mk(m.A, m.B, m.C, m.D, idn.K)
        out[name] = {"plid_cpu": pl, "n4sid_cpu": n4, "ratio": min(pl) / min(n4),
                     "pred": br.pred_fit(mk, uv, yv), "sim": br.sim_fit(mk, uv, yv),
                     "predictor": str(idn.provenance.predictor.get("chosen"))}
    print(json.dumps(out))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", help="tree of the other commit (see the module docstring)")
    ap.add_argument("--before-label", default="before")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--sets", default=",".join(SETS))
    ap.add_argument("--quick", action="store_true", help="robot arm, one round, this checkout")
    ap.add_argument("--out", help="markdown report")
    ap.add_argument("--json", help="the measurements as JSON")
    ap.add_argument("--worker", metavar="ROOT", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    sets = a.sets.split(",")
    unknown = [s for s in sets if s not in SETS]
    if unknown:
        ap.error(f"unknown set {unknown[0]!r} (known: {', '.join(SETS)})")
    if a.worker:
        worker(a.worker, sets, 3 if sets == ["subframe"] else 5)
        return 0
    sys.path.insert(0, HERE)
    import results_io

    if a.quick:
        sets, a.rounds, a.before = ["robotarm"], 1, None
    codes = [("after", REPO)] + ([(a.before_label, a.before)] if a.before else [])
    st = results_io.stamp()
    runs = {label: [] for label, _ in codes}
    for r in range(a.rounds):
        for label, root in (codes if r % 2 == 0 else codes[::-1]):
            res = subprocess.run([sys.executable, os.path.abspath(__file__), "--worker", root,
                                  "--sets", ",".join(sets)], capture_output=True, text=True)
            if res.returncode:
                print(res.stderr[-2000:], file=sys.stderr)
                return 1
            runs[label].append(json.loads(res.stdout.strip().splitlines()[-1]))
            print(f"round {r + 1} {label}: " + ", ".join(
                f"{s} {runs[label][-1][s]['ratio']:.2f}x" for s in sets), flush=True)
    st = results_io.finish(st)
    summary = {}
    for label, rs in runs.items():
        summary[label] = {s: {"ratio_median": float(np.median([x[s]["ratio"] for x in rs])),
                              "ratio_min": float(min(x[s]["ratio"] for x in rs)),
                              "ratio_max": float(max(x[s]["ratio"] for x in rs)),
                              "plid_cpu_min": float(min(min(x[s]["plid_cpu"]) for x in rs)),
                              "n4sid_cpu_min": float(min(min(x[s]["n4sid_cpu"]) for x in rs)),
                              "pred": rs[-1][s]["pred"], "sim": rs[-1][s]["sim"],
                              "predictor": rs[-1][s]["predictor"]} for s in sets}
    payload = {**st, "rounds": a.rounds, "sets": sets, "summary": summary, "runs": runs}
    if a.json:
        results_io.write_json(a.json, payload)
    lines = [f"# `identify` against nfoursid N4SID, CPU, paired ({' vs '.join(runs)})", "",
             "Generated by `benchmarks/bench_gain_ab.py` (protocol in its docstring). "
             f"Commit {st['commit']}; {a.rounds} rounds; load average at start "
             f"{st['loadavg_start']}, at end {st['loadavg_end']}; machine {st['machine']}.", "",
             "Cell: PLID / N4SID CPU ratio, median over rounds (min-max); PLID and N4SID "
             "CPU s (min over all repeats); validation one-step / sim fit [%]; predictor.", "",
             "| set (order) | " + " | ".join(runs) + " |",
             "|---|" + "---|" * len(runs)]
    for s in sets:
        cells = []
        for label in runs:
            x = summary[label][s]
            cells.append(f"**{x['ratio_median']:.2f}x** ({x['ratio_min']:.2f}-{x['ratio_max']:.2f}); "
                         f"{x['plid_cpu_min']:.3f} / {x['n4sid_cpu_min']:.3f} s; "
                         f"{x['pred']:.2f} / {x['sim']:.2f}; {x['predictor']}")
        lines.append(f"| {s} ({SETS[s][0]}) | " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    print(text)
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
