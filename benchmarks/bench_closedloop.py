"""Closed-loop records (issue 34, acceptance 3): ``identify(..., closed_loop=True)`` (PBSID
prior, prediction-error refinement) against open-loop N4SID (``subspace_prior``) and the
default open-loop ``identify`` on the same simulated LQG loops of the testbed and of the
campaign's steel grid (``tests/plid/closedloop_cases.py``: excitation an unmeasured force on
the structure, dither 10 % of the control signal's RMS, sensor noise 1 % of each output).

Per method and record: the worst relative frequency and damping error over the truth's
modes (each matched to the nearest identified lightly damped mode) and CPU seconds, all in
one run. Writes ``closedloop.md`` and ``closedloop.json``.

    python benchmarks/bench_closedloop.py [--quick] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from results_io import RESULTS, finish, stamp, write_json  # noqa: E402
from tests.plid import closedloop_cases as cc  # noqa: E402


def _errors(model, truth):
    from trussid.plid import modal_table

    t = modal_table(model)
    keep = (t.damping > 0) & (t.damping < 0.5)
    f, z = t.frequencies_hz[keep], t.damping[keep]
    if f.size < truth.frequencies_hz.size:
        return float("inf"), float("inf")
    idx = [int(np.argmin(np.abs(f - f0))) for f0 in truth.frequencies_hz]
    return (float(np.max(np.abs(f[idx] - truth.frequencies_hz) / truth.frequencies_hz)),
            float(np.max(np.abs(z[idx] - truth.damping) / truth.damping)))


def run(quick: bool, out: Path) -> dict:
    from trussid.plid import identify
    from trussid.plid.subspace import subspace_prior

    seeds = (0,) if quick else (0, 1)
    rows = []
    for make in (cc.testbed_truth, cc.grid_truth):
        truth = make()
        n, dt = truth.plant.nstates, truth.plant.dt
        ctl = cc.lqg(truth)
        for seed in seeds:
            u, y, r = cc.record(truth, ctl, cc.SAMPLES, seed=seed)
            share = float(np.std(r) / np.std(u))
            methods = {
                "N4SID (open loop)": lambda: subspace_prior(u, y, n, dt)[0],
                "identify (open-loop recipe)": lambda: identify(u, y, n, dt, progress=False).model,
                "identify closed_loop=True": lambda: identify(u, y, n, dt, closed_loop=True,
                                                              progress=False).model,
            }
            if quick:
                methods.pop("identify (open-loop recipe)")
            for name, fit in methods.items():
                c0 = time.process_time()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    try:
                        df, dz = _errors(fit(), truth)
                        err = ""
                    except Exception as exc:  # noqa: BLE001 - a failed method is a row too
                        df = dz = float("inf")
                        err = str(exc)[:80]
                rows.append([truth.name, seed, cc.SAMPLES, round(share, 3), name,
                             round(100 * df, 2), round(100 * dz, 1),
                             round(time.process_time() - c0, 2), err])
                print(rows[-1], flush=True)
    cols = ["structure", "seed", "samples", "dither/u RMS", "method", "worst freq error %",
            "worst damping error %", "CPU s", "error"]
    # "results", not "tables": a results file's "tables" are README tables (benchmarks/readme_tables.py)
    return {"results": {"closedloop": {"columns": cols, "rows": rows,
                                      "notes": "target: frequency within 1 %, damping within "
                                               "20 % of the truth (all of the truth's modes)"}}}


def _markdown(payload: dict) -> str:
    st = payload["stamp"]
    t = payload["results"]["closedloop"]
    lines = ["# Closed-loop identification (issue 34, acceptance 3)", "",
             f"Commit {st['commit']}, {st['date_utc']}, {st['machine']['cpu']} "
             f"({st['machine']['nproc']} cores), load {st['loadavg_start']} -> "
             f"{st['loadavg_end']}.", "", t["notes"], "",
             "| " + " | ".join(t["columns"]) + " |",
             "|" + "---|" * len(t["columns"])]
    lines += ["| " + " | ".join(str(v) for v in r) + " |" for r in t["rows"]]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="one record per structure, no "
                   "open-loop identify")
    p.add_argument("--out", default=None, help="folder for closedloop.md/.json (default "
                   "benchmarks/results)")
    args = p.parse_args(argv)
    out = Path(args.out) if args.out else RESULTS
    st = stamp()
    payload = run(args.quick, out)
    payload = {"stamp": finish(st), **payload}
    write_json(out / "closedloop.json", payload)
    (out / "closedloop.md").write_text(_markdown(payload))
    print(f"wrote {out / 'closedloop.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
