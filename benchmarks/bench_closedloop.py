"""Closed-loop records (issue 34, acceptance 3): ``identify(..., closed_loop=True)`` (PBSID
prior, prediction-error refinement) against open-loop N4SID (``subspace_prior``) on the same
simulated LQG loops of the testbed and of the campaign's steel grid
(``tests/plid/closedloop_cases.py``), dither 10 % of the control signal's RMS, in two
settings:

- **output disturbance** (the acceptance's setting): a white unmeasured disturbance added
  at the outputs and fed back by the controller; truths reduced to the modes the actuator
  excites best. Record lengths 2e4 to 1e6 samples; besides the two methods, the
  prediction-error fit started from the truth itself ("PEM from the truth"): the spread
  the record's information leaves, against which the recipe's misses are read.
- **structural force** (harder, the acceptance not reached): a white unmeasured force on
  the structure, 2e4 samples.

Per method and record: the worst relative frequency and damping error over the truth's
modes (each matched to the nearest identified lightly damped mode) and CPU seconds, all in
one run. Writes ``closedloop_i35.md`` and ``closedloop_i35.json``.

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

#: Output-disturbance record lengths per structure (full run; --quick: the first only).
OUTPUT_SAMPLES = {"testbed": (20000, 200000, 1000000), "grid": (20000, 100000)}
#: The truth-started fit runs up to this many samples (it costs as much as the recipe).
TRUTH_START_MAX = 200000


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


def _from_truth(truth, u, y):
    """The prediction-error fit started from the truth's actuator path with ``K = 0`` (the
    true innovations model of a white output disturbance)."""
    import control

    from trussid.plid.closedloop import prediction_error_fit

    G = truth.plant
    Gu = control.ss(G.A, np.asarray(G.B)[:, :1], G.C, 0, G.dt)
    return prediction_error_fit(Gu, np.zeros((G.nstates, y.shape[1])), u, y,
                                max_evaluations=200).model


def _rows(truth, setting, samples, seed, methods):
    rows = []
    ctl = cc.lqg(truth, design_noise="actuator" if setting == "output" else "force")
    u, y, r = cc.record(truth, ctl, samples, seed=seed, disturbance=setting)
    share = float(np.std(r) / np.std(u))
    for name, fit in methods(truth, u, y).items():
        c0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                df, dz = _errors(fit(), truth)
                err = ""
            except Exception as exc:  # noqa: BLE001 - a failed method is a row too
                df = dz = float("inf")
                err = str(exc)[:80]
        rows.append([truth.name, setting, seed, samples, round(share, 3), name,
                     round(100 * df, 3), round(100 * dz, 1),
                     round(time.process_time() - c0, 2), err])
        print(rows[-1], flush=True)
    return rows


def run(quick: bool) -> dict:
    from trussid.plid import identify
    from trussid.plid.subspace import subspace_prior

    def methods(truth, u, y, with_truth=False):
        n, dt = truth.plant.nstates, truth.plant.dt
        out = {"N4SID (open loop)": lambda: subspace_prior(u, y, n, dt)[0],
               "identify closed_loop=True": lambda: identify(u, y, n, dt, closed_loop=True,
                                                             progress=False).model}
        if with_truth:
            out["PEM from the truth"] = lambda: _from_truth(truth, u, y)
        return out

    seeds = (0,) if quick else (0, 1, 2)
    rows = []
    for make in (cc.testbed_truth, cc.grid_truth):
        truth = make("actuator")
        for samples in OUTPUT_SAMPLES[truth.name][:1 if quick else None]:
            for seed in seeds:
                rows += _rows(truth, "output", samples, seed,
                              lambda t, u, y: methods(t, u, y, samples <= TRUTH_START_MAX
                                                      and not quick))
    for make in (cc.testbed_truth, cc.grid_truth):
        truth = make()
        for seed in seeds[:2]:
            rows += _rows(truth, "force", cc.SAMPLES, seed, methods)
    cols = ["structure", "disturbance", "seed", "samples", "dither/u RMS", "method",
            "worst freq error %", "worst damping error %", "CPU s", "error"]
    # "results", not "tables": a results file's "tables" are README tables (benchmarks/readme_tables.py)
    return {"results": {"closedloop": {"columns": cols, "rows": rows,
                                      "notes": "target: frequency within 1 %, damping within "
                                               "20 % of the truth (all of the truth's modes); "
                                               "inf: fewer lightly damped modes found than "
                                               "the truth has"}}}


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
    p.add_argument("--quick", action="store_true", help="one 2e4-sample record per structure "
                   "and setting, no truth-started fit")
    p.add_argument("--out", default=None, help="folder for closedloop_i35.md/.json (default "
                   "benchmarks/results)")
    args = p.parse_args(argv)
    out = Path(args.out) if args.out else RESULTS
    st = stamp()
    payload = run(args.quick)
    payload = {"stamp": finish(st), **payload}
    write_json(out / "closedloop_i35.json", payload)
    (out / "closedloop_i35.md").write_text(_markdown(payload))
    print(f"wrote {out / 'closedloop_i35.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
