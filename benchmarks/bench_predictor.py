#!/usr/bin/env python3
"""CPU time and profile of ``identify``'s predictor step on the four shared measured sets.

The predictor step is the end of :func:`trussid.plid.recipe.identify`: the candidate gains
(``recipe._best_gain``: K = 0, the recursion's gain, the former default and the Kalman
gains of :func:`trussid.plid.metrics.best_predictor`) and their prediction-error refinement
(``recipe.pem_gain``). For each set of ``bench_realdata.py`` (same split, at PLID's chosen
order there) ``identify`` runs with defaults; the two parts are timed by wrapping them (CPU
seconds, ``time.process_time``, min over repeats after one warm-up fit) and the validation
fits are scored as ``bench_realdata.py`` scores them. Then a cProfile of the predictor step
alone (both parts, 5 repeats) on flutter and on the subframe.

The script only calls names that the code before issue 34's predictor work had too, so the
same file measures a checkout of either: run it with the interpreter of each, e.g. ::

    OPENBLAS_NUM_THREADS=1 python benchmarks/bench_predictor.py --out profile.txt
    OPENBLAS_NUM_THREADS=1 /path/to/old/venv/bin/python benchmarks/bench_predictor.py \
        --commit 139e132 --out before.txt

``--quick``: robot arm only, one repeat, no profile. ``--json PATH``: the table as JSON.
"""
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import cProfile  # noqa: E402
import io  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import pstats  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import bench_realdata as br  # noqa: E402

#: PLID's chosen orders in ``benchmarks/results/realdata_lean.md`` (subframe: 30 there,
#: 36 in a later run of bench_realdata; both measured)
ORDERS = (("robotarm", 8), ("flutter", 8), ("cdplayer", 10), ("subframe", 30),
          ("subframe", 36))


def _wrapped(rc, acc):
    """Wrap ``rc._best_gain`` and ``rc.pem_gain`` so that their CPU seconds add up in acc."""
    def timed(name):
        f = getattr(rc, name)

        def g(*a, **k):
            c = time.process_time()
            try:
                return f(*a, **k)
            finally:
                acc[name] = acc.get(name, 0.0) + time.process_time() - c
        return f, g
    orig = {}
    for name in ("_best_gain", "pem_gain"):
        orig[name], g = timed(name)
        setattr(rc, name, g)
    return orig


def measure(name, order, repeats, rc):
    u, y = br.load(name)
    dt = br.DATASETS[name]["dt"]
    (ui, yi), (uv, yv) = br.split(u, y)
    rows = []
    for _ in range(repeats):
        acc = {}
        orig = _wrapped(rc, acc)
        try:
            c = time.process_time()
            idn = rc.identify(ui, yi, order=order, dt=dt, progress=False)
            total = time.process_time() - c
        finally:
            for k, f in orig.items():
                setattr(rc, k, f)
        rows.append((total, acc.get("_best_gain", 0.0), acc.get("pem_gain", 0.0)))
    total, cands, pem = np.min(np.array(rows), axis=0)
    m = br._mk(*(np.asarray(M) for M in (idn.model.A, idn.model.B, idn.model.C, idn.model.D)),
               K=np.asarray(idn.K))
    pr = idn.provenance.predictor or {}
    return dict(set=name, order=order, identify_cpu=float(total), candidates_cpu=float(cands),
                pem_cpu=float(pem), step_cpu=float(cands + pem),
                one_step=br.pred_fit(m, uv, yv), sim=br.sim_fit(m, uv, yv),
                chosen=pr.get("chosen"), logdet_end=(pr.get("pem") or {}).get("logdet_end"))


def profile(name, order, rc):
    """cProfile of the predictor step alone (candidates and refinement, 5 times)."""
    u, y = br.load(name)
    dt = br.DATASETS[name]["dt"]
    (ui, yi), _ = br.split(u, y)
    idn = rc.identify(ui, yi, order=order, dt=dt, progress=False, predictor="candidates")
    own = {"estimator": idn.result.K}
    pr = cProfile.Profile()
    pr.enable()
    for _ in range(5):
        K, kinfo = rc._best_gain(idn.model, ui, yi, idn.R, own)
        rc.pem_gain(idn.model, ui, yi, K, kinfo)
    pr.disable()
    out = io.StringIO()
    pstats.Stats(pr, stream=out).sort_stats("cumulative").print_stats(30)
    return out.getvalue()


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="text report (table and profiles)")
    ap.add_argument("--json", help="the table as JSON")
    ap.add_argument("--commit", help="label of the code measured (default: git HEAD of "
                    "this checkout)")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    import trussid.plid.recipe as rc

    commit = a.commit or br.environment().get("commit")
    load0 = os.getloadavg()
    # warm-up (compiled kernels load from numba's cache on the first call)
    u, y = br.load("robotarm")
    (ui, yi), _ = br.split(u, y)
    rc.identify(ui, yi, order=4, dt=1.0, progress=False)
    todo = ORDERS[:1] if a.quick else ORDERS
    rows = []
    for name, order in todo:
        rows.append(measure(name, order, 1 if a.quick else (2 if name == "subframe" else 5), rc))
        r = rows[-1]
        print(f"{name} n={order}: identify {r['identify_cpu']:.3f} CPU s, predictor step "
              f"{r['step_cpu']:.3f} (candidates {r['candidates_cpu']:.3f}, refinement "
              f"{r['pem_cpu']:.3f}); 1-step {r['one_step']:.2f} % sim {r['sim']:.2f} %; "
              f"{r['chosen']}", flush=True)
    profiles = [] if a.quick else [(n, o, profile(n, o, rc)) for n, o in (("flutter", 8),
                                                                        ("subframe", 30))]
    head = (f"trussid commit {commit}; {platform.node()} {platform.machine()}, "
            f"{os.cpu_count()} CPUs, BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS')}; "
            f"numpy {np.__version__}; load average at start {[round(x, 2) for x in load0]}, "
            f"at end {[round(x, 2) for x in os.getloadavg()]}; "
            f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    lines = ["# identify's predictor step: CPU seconds (min of repeats) and fits", "", head, "",
             "| set | order | identify CPU s | predictor step CPU s | candidates | refinement "
             "| 1-step % | sim % | K |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['set']} | {r['order']} | {r['identify_cpu']:.3f} | "
                     f"{r['step_cpu']:.3f} | {r['candidates_cpu']:.3f} | {r['pem_cpu']:.3f} | "
                     f"{r['one_step']:.2f} | {r['sim']:.2f} | {r['chosen']} |")
    for n, o, text in profiles:
        lines += ["", f"## cProfile of the predictor step, {n} (order {o}), 5 times", "",
                  text]
    if a.out:
        with open(a.out, "w") as fh:
            fh.write("\n".join(lines) + "\n")
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(dict(commit=commit, header=head, results=rows), fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
