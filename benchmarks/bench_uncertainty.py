#!/usr/bin/env python3
"""Coverage of the 95 % modal intervals of ``trussid identify`` (issue 23, acceptance 5).

A known plant: four lightly damped modes (42, 97, 181, 263 Hz; damping 1.0, 2.0, 0.8, 1.5 %),
one force input, two displacement outputs, zero-order hold at 1 kHz (seeded mode shapes).
Records: 2000 samples of white input, white output noise at 40, 30 and 20 dB below each
output's RMS, ``--records`` seeded records per level (default 70: 210 in all). Each record
is identified by ``plid.recipe.identify`` with its defaults (what ``trussid identify``
runs) at the true order 8; :func:`trussid.plid.uncertainty.mode_intervals` gives the
intervals; identified modes are paired with the true ones by frequency. A case is one
(record, mode); coverage is the share of cases whose true value lies inside the interval
(target 90-99 %).

Usage::

    python benchmarks/bench_uncertainty.py [--records 70] [--out benchmarks/results/uncertainty]
"""
from __future__ import annotations

import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import control  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_io import finish, stamp, write_json  # noqa: E402

from trussid.plid.experiment import simulate  # noqa: E402
from trussid.plid.metrics import modal_parameters  # noqa: E402
from trussid.plid.multipass import identify  # noqa: E402
from trussid.plid.uncertainty import mode_intervals  # noqa: E402

FS = 1000.0
FREQS = (42.0, 97.0, 181.0, 263.0)
ZETAS = (0.010, 0.020, 0.008, 0.015)
LEVELS_DB = (40.0, 30.0, 20.0)
N_SAMPLES = 2000


def plant(seed: int = 0) -> control.StateSpace:
    """The known plant: modal, force in, displacement out, ZOH at FS."""
    rng = np.random.default_rng(seed)
    n = 2 * len(FREQS)
    A, B, C = np.zeros((n, n)), np.zeros((n, 1)), np.zeros((2, n))
    phi = rng.standard_normal((2, len(FREQS)))
    b = rng.standard_normal(len(FREQS))
    for i, (f, z) in enumerate(zip(FREQS, ZETAS)):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w * w, -2 * z * w]]
        B[2 * i + 1, 0] = b[i] * w * w          # unit static deflection per mode
        C[:, 2 * i] = phi[:, i]
    return control.c2d(control.ss(A, B, C, np.zeros((2, 1))), 1 / FS)


def record(P, snr_db: float, seed: int):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((N_SAMPLES, 1))
    y0 = simulate(P, u)
    return u, y0 + 10 ** (-snr_db / 20) * np.std(y0, 0) * rng.standard_normal(y0.shape)


def _robust_sd(z) -> float:
    z = np.asarray(z, float)
    z = z[np.isfinite(z)]
    return float(1.4826 * np.median(np.abs(z))) if z.size else float("nan")


def coverage(n_records: int, levels=LEVELS_DB, log=print) -> dict:
    """Per level: cases, frequency and damping coverage, interval widths, failures."""
    P = plant()
    f_true, z_true, _ = modal_parameters(P)
    out = {}
    for li, snr in enumerate(levels):
        hit_f = hit_z = cases = missing = 0
        width_f, width_z, zf, zz = [], [], [], []
        c0 = time.process_time()
        for r in range(n_records):
            u, y = record(P, snr, seed=10_000 * (li + 1) + r)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                idn = identify(u, y, 2 * len(FREQS), 1 / FS)
            modes = mode_intervals(idn.model, idn.result.model, idn.result.theta_cov)
            for ft, zt in zip(f_true, z_true):
                cases += 1
                if not modes:
                    missing += 1
                    continue
                m = min(modes, key=lambda q: abs(q.frequency_hz - ft))
                if not (np.isfinite(m.frequency_std_hz) and abs(m.frequency_hz - ft) < 0.05 * ft):
                    missing += 1
                    continue
                lo, hi = m.frequency_ci95_hz
                zl, zh = m.damping_ratio_ci95
                hit_f += lo <= ft <= hi
                hit_z += zl <= zt <= zh
                width_f.append((hi - lo) / ft)
                width_z.append((zh - zl) / zt)
                zf.append((m.frequency_hz - ft) / m.frequency_std_hz)
                zz.append((m.damping_ratio - zt) / m.damping_ratio_std)
        out[f"{snr:g} dB"] = {
            "records": n_records, "cases": cases, "missing": missing,
            "frequency_coverage": hit_f / cases, "damping_coverage": hit_z / cases,
            "median_relative_width_frequency": float(np.nanmedian(width_f)),
            "median_relative_width_damping": float(np.nanmedian(width_z)),
            # robust spread of (estimate - truth) / standard deviation: 1 when the
            # standard deviations are right (1.4826 x median |z| for a normal z)
            "robust_sd_of_standardised_error_frequency": _robust_sd(zf),
            "robust_sd_of_standardised_error_damping": _robust_sd(zz),
            "cpu_seconds": time.process_time() - c0}
        log(f"{snr:g} dB: {cases} cases, frequency {hit_f / cases:.3f}, damping "
            f"{hit_z / cases:.3f}, {missing} missing, "
            f"{out[f'{snr:g} dB']['cpu_seconds']:.0f} CPU s")
    return out


def report(res: dict, st: dict) -> str:
    tot = sum(v["cases"] for v in res.values())
    cf = sum(v["frequency_coverage"] * v["cases"] for v in res.values()) / tot
    cz = sum(v["damping_coverage"] * v["cases"] for v in res.values()) / tot
    L = ["# Coverage of the 95 % modal intervals (`plid.uncertainty`, `trussid identify`)\n",
         "Generated by `benchmarks/bench_uncertainty.py` (protocol in its docstring). "
         f"Commit {st['commit']}; {st['machine']}; {st['date_utc']}; load average at start "
         f"{st['loadavg_start']}, at end {st.get('loadavg_end')}.\n",
         "| noise | records | cases | frequency inside 95 % interval | damping inside | "
         "median width f (relative) | median width zeta (relative) | robust sd of (est - true) / sd, f / zeta | CPU s |",
         "|---|---|---|---|---|---|---|---|---|"]
    for k, v in res.items():
        L.append(f"| {k} below output RMS | {v['records']} | {v['cases']} | "
                 f"{100 * v['frequency_coverage']:.1f} % | {100 * v['damping_coverage']:.1f} % | "
                 f"{v['median_relative_width_frequency']:.2e} | "
                 f"{v['median_relative_width_damping']:.2f} | "
                 f"{v['robust_sd_of_standardised_error_frequency']:.2f} / "
                 f"{v['robust_sd_of_standardised_error_damping']:.2f} | {v['cpu_seconds']:.0f} |")
    L.append(f"\nAll levels: {tot} cases, frequency inside in **{100 * cf:.1f} %**, damping "
             f"in **{100 * cz:.1f} %** (target 90-99 %). A missing case (no identified mode "
             "within 5 % of the true frequency, or no interval) counts as outside.\n")
    return "\n".join(L)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=70, help="records per noise level")
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" /
                                         "uncertainty"), help="results stem (.md, .json)")
    a = ap.parse_args(argv)
    st = stamp()
    res = coverage(a.records)
    st = finish(st)
    md = report(res, st)
    write_json(Path(a.out + ".json"), {"stamp": st, "results": res})
    Path(a.out + ".md").write_text(md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
