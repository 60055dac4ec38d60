"""The PLID prior with a direct term against N4SID with D on feed-through plants (issue 34,
acceptance 4), in one run.

Three plants whose discrete models have ``D != 0`` (accelerometers, no anti-aliasing filter):
the testbed's structure (PZT volts to UDF accelerometers, every mode below Nyquist, ZOH at
the lab's 1600 Hz) with channel 1 alone (SIMO, 30 states) and with all three channels
(MIMO, 36 states), and a steel cantilever of this script's own (a shaker near the tip, two
accelerometers, 1 kHz, 12 states). White-noise records, 60 dB sensor noise; every figure is
the one-step prediction ratio [dB] on the identification record itself (what the demo
compares), the predictor gain chosen by :func:`trussid.plid.metrics.choose_predictor`, the
first quarter of the record skipped (the predictors' transients):

- ``N4SID with D``: :func:`trussid.plid.subspace.n4sid`'s model with ``D``, best of block rows
  40 and 80 (the demo's "N4SID with D" fallback candidate);
- ``prior (before)``: the former prior, the strictly proper N4SID model's ``A, C`` with
  ``B, D`` refitted by output error;
- ``prior``: :func:`trussid.plid.feedthrough.direct_prior`;
- ``identify``: :func:`trussid.plid.recipe.identify` (``direct="auto"``, block rows 40 and 80),
  with its own predictor.

Usage::

    python benchmarks/bench_feedthrough.py [--quick] [--json PATH] [--out results.md]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import control  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_io  # noqa: E402

from trussid import fem  # noqa: E402
from trussid.plid import choose_predictor, excitation, identify, n4sid, prediction_ratio_db, simulate  # noqa: E402
from trussid.plid.feedthrough import direct_prior  # noqa: E402
from trussid.plid.stability import stabilise  # noqa: E402
from trussid.plid.subspace import output_error_fit  # noqa: E402

IO = """
[plant]
fs = 1000.0
damping = 0.01
[[actuator]]
name = "shaker"
type = "force"
node = 10
direction = [0, 1, 0]
[[sensor]]
name = "acc_tip"
node = 11
direction = [0, 1, 0]
quantity = "acceleration"
[[sensor]]
name = "acc_mid"
node = 6
direction = [0, 1, 0]
quantity = "acceleration"
"""


def cantilever() -> control.StateSpace:
    """A 1 m steel cantilever (20 x 10 mm, ten beam elements), a shaker at 0.9 m, two
    accelerometers, 1 kHz: its discrete plant (every mode below Nyquist)."""
    m = fem.Model()
    m.add_nodes(np.arange(1, 12), np.c_[np.linspace(0, 1, 11), np.zeros((11, 2))])
    m.add_beams(np.arange(1, 11), np.c_[np.arange(1, 11), np.arange(2, 12)],
                fem.Section.rectangle(0.02, 0.01), fem.STEEL, orient=[0, 0, 1])
    m.fix(1)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "io.toml"
        path.write_text(IO)
        _, sd, _, _ = fem.io_plant(m, fem.read_io(path))
    return sd


def testbed_structure() -> control.StateSpace:
    """The testbed's structure alone (PZT volts to accelerometer volts), ZOH at 1600 Hz."""
    from trussid.testbed.plant import testbed_plant
    tp = testbed_plant()
    return control.c2d(tp.structure, tp.discrete.dt, "zoh")


def record(G, n_samples: int, seed: int, snr_db: float = 60.0):
    u = excitation("white", n_samples, G.ninputs, fs=1.0 / G.dt, seed=seed)
    y0 = simulate(G, u)
    rng = np.random.default_rng(seed + 100)
    return u, y0 + rng.standard_normal(y0.shape) * y0.std(0) * 10 ** (-snr_db / 20)


def one_step(model, u, y, skip: int) -> float:
    """One-step ratio [dB] with the predictor that choose_predictor picks on the record."""
    K, _, _ = choose_predictor(model, u, y)
    return float(prediction_ratio_db(model, u, y, K=K, skip=skip).overall)


def _stable(model):
    if np.max(np.abs(np.linalg.eigvals(np.asarray(model.A)))) >= 1:
        return stabilise(model).model
    return model


def case(name: str, G, order: int, n_samples: int, seed: int = 3, block_rows=(40, 80)) -> dict:
    u, y = record(G, n_samples, seed)
    dt = G.dt
    skip = n_samples // 4
    c0 = time.process_time()
    ref = {int(br): one_step(_stable(n4sid(u, y, order, int(br), dt).with_d), u, y, skip)
           for br in block_rows}
    c_n4 = time.process_time() - c0
    before = {int(br): one_step(output_error_fit(_stable(n4sid(u, y, order, int(br), dt).zero_d),
                                                 u, y, direct=True)[0], u, y, skip)
              for br in block_rows}
    c0 = time.process_time()
    prior, choice = direct_prior(u, y, order, dt, block_rows=list(block_rows))
    c_prior = time.process_time() - c0
    c0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = identify(u, y, order, dt, block_rows=list(block_rows), progress=False)
    c_id = time.process_time() - c0
    row = {"plant": name, "true_states": int(G.nstates), "inputs": int(G.ninputs),
           "outputs": int(G.noutputs), "order": order, "samples": n_samples,
           "max_abs_D": float(np.max(np.abs(G.D))),
           "n4sid_with_d_db": max(ref.values()), "n4sid_with_d_by_block_rows": ref,
           "prior_before_db": before[choice.block_rows], "prior_db": one_step(prior, u, y, skip),
           "prior_block_rows": choice.block_rows,
           "identify_db": float(prediction_ratio_db(fit.model, u, y, K=fit.K,
                                                    skip=skip).overall),
           "identify_direct": bool(fit.provenance.direct.estimated),
           "cpu_s": {"n4sid_with_d_both_block_rows": c_n4, "prior": c_prior, "identify": c_id}}
    row["prior_minus_n4sid_db"] = row["prior_db"] - row["n4sid_with_d_db"]
    row["identify_minus_n4sid_db"] = row["identify_db"] - row["n4sid_with_d_db"]
    return row


def table(rows) -> str:
    out = ["| plant | states (true / model) | N4SID with D | prior (before) | prior | prior - N4SID "
           "| identify | identify - N4SID | CPU s N4SID x2 / prior / identify |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        c = r["cpu_s"]
        out.append(f"| {r['plant']} | {r['true_states']} / {r['order']} | "
                   f"{r['n4sid_with_d_db']:.2f} | {r['prior_before_db']:.2f} | {r['prior_db']:.2f} | "
                   f"{r['prior_minus_n4sid_db']:+.2f} | {r['identify_db']:.2f} | "
                   f"{r['identify_minus_n4sid_db']:+.2f} | {c['n4sid_with_d_both_block_rows']:.1f} / "
                   f"{c['prior']:.1f} / {c['identify']:.1f} |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the cantilever alone, 3000 samples")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--out", type=Path, default=None, help="markdown table")
    args = ap.parse_args(argv)
    st = results_io.stamp()
    rows = [case("cantilever (own)", cantilever(), 12, 3000 if args.quick else 6000)]
    if not args.quick:
        G = testbed_structure()
        rows.append(case("testbed SIMO ch1", G[:, 0], 30, 6000))
        rows.append(case("testbed MIMO", G, 36, 6000))
    st = results_io.finish(st)
    md = table(rows)
    print(md)
    if args.json:
        results_io.write_json(args.json, {**st, "rows": rows})
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(f"# PLID prior with D against N4SID with D (issue 34, acceptance 4)\n\n"
                            f"`python benchmarks/bench_feedthrough.py{' --quick' if args.quick else ''}` "
                            f"at commit {st['commit']}, {st['date_utc']}, load "
                            f"{st['loadavg_start']} -> {st['loadavg_end']} (1/5/15 min), "
                            f"one BLAS thread. One-step ratio [dB] on the identification "
                            f"record (first quarter skipped).\n\n{md}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
