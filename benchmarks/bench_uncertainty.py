#!/usr/bin/env python3
"""Coverage of the 95 % modal intervals of ``trussid identify`` (issue 23, acceptance 5).

A known plant: four lightly damped modes (42, 97, 181, 263 Hz; damping 1.0, 2.0, 0.8, 1.5 %),
one force input, two displacement outputs, zero-order hold at 1 kHz (seeded mode shapes).
The same four modes seen by a MIMO plant with feed-through (issue 34, acceptance 5): two
force inputs, two accelerometers (``D = Phi b^T`` is not zero), seeded shapes.
Records: 2000 samples of white input, white output noise at 40, 30 and 20 dB below each
output's RMS, ``--records`` seeded records per level and plant (default 70: 210 per plant).
Each record is identified by ``plid.recipe.identify`` with its defaults (what ``trussid
identify`` runs: the direct term decided on the data) at the true order 8; :func:`trussid.plid.uncertainty.mode_intervals` gives the
intervals; identified modes are paired with the true ones by frequency. A case is one
(record, mode); coverage is the share of cases whose true value lies inside the interval
(target 90-99 %).

Usage::

    python benchmarks/bench_uncertainty.py [--records 70] [--plants simo,mimo_d]
        [--out benchmarks/results/uncertainty]
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


def plant_mimo_d(seed: int = 1) -> control.StateSpace:
    """The same modes, two forces in, two accelerations out (feed-through), ZOH at FS.

    Modal coordinates q_i'' + 2 zeta_i w_i q_i' + w_i^2 q_i = b_i . u; an accelerometer
    reads Phi q'', so C = Phi [-w^2, -2 zeta w] per mode and D = Phi b^T."""
    rng = np.random.default_rng(seed)
    nm = len(FREQS)
    n = 2 * nm
    A, B, C = np.zeros((n, n)), np.zeros((n, 2)), np.zeros((2, n))
    phi = rng.standard_normal((2, nm))
    b = rng.standard_normal((nm, 2))
    for i, (f, z) in enumerate(zip(FREQS, ZETAS)):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0, 1], [-w * w, -2 * z * w]]
        B[2 * i + 1] = b[i]
        C[:, 2 * i] = -w * w * phi[:, i]
        C[:, 2 * i + 1] = -2 * z * w * phi[:, i]
    return control.c2d(control.ss(A, B, C, phi @ b), 1 / FS)


#: name -> (plant, what the report calls it)
PLANTS = {"simo": (plant, "SIMO: one force, two displacements, strictly proper"),
          "mimo_d": (plant_mimo_d, "MIMO with feed-through: two forces, two accelerations")}


def record(P, snr_db: float, seed: int):
    rng = np.random.default_rng(seed)
    u = rng.standard_normal((N_SAMPLES, P.ninputs))
    y0 = simulate(P, u)
    return u, y0 + 10 ** (-snr_db / 20) * np.std(y0, 0) * rng.standard_normal(y0.shape)


def _robust_sd(z) -> float:
    z = np.asarray(z, float)
    z = z[np.isfinite(z)]
    return float(1.4826 * np.median(np.abs(z))) if z.size else float("nan")


def coverage(n_records: int, levels=LEVELS_DB, log=print, P=None) -> dict:
    """Per level: cases, frequency and damping coverage, interval widths, failures
    (``P`` the plant, default :func:`plant`)."""
    P = plant() if P is None else P
    f_true, z_true, _ = modal_parameters(P)
    out = {}
    for li, snr in enumerate(levels):
        hit_f = hit_z = cases = missing = with_d = 0
        width_f, width_z, zf, zz = [], [], [], []
        c0 = time.process_time()
        for r in range(n_records):
            u, y = record(P, snr, seed=10_000 * (li + 1) + r)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                idn = identify(u, y, 2 * len(FREQS), 1 / FS)
            direct = idn.provenance.direct
            with_d += bool(direct is not None and direct.estimated)
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
            "records": n_records, "cases": cases, "missing": missing, "records_with_d": with_d,
            "frequency_coverage": hit_f / cases, "damping_coverage": hit_z / cases,
            "median_relative_width_frequency": float(np.nanmedian(width_f)),
            "median_relative_width_damping": float(np.nanmedian(width_z)),
            # robust spread of (estimate - truth) / standard deviation: 1 when the
            # standard deviations are right (1.4826 x median |z| for a normal z)
            "robust_sd_of_standardised_error_frequency": _robust_sd(zf),
            "robust_sd_of_standardised_error_damping": _robust_sd(zz),
            "cpu_seconds": time.process_time() - c0}
        log(f"{snr:g} dB: {cases} cases, frequency {hit_f / cases:.3f}, damping "
            f"{hit_z / cases:.3f}, {missing} missing, D estimated on {with_d} records, "
            f"{out[f'{snr:g} dB']['cpu_seconds']:.0f} CPU s")
    return out


def _table(res: dict) -> list[str]:
    tot = sum(v["cases"] for v in res.values())
    cf = sum(v["frequency_coverage"] * v["cases"] for v in res.values()) / tot
    cz = sum(v["damping_coverage"] * v["cases"] for v in res.values()) / tot
    L = ["| noise | records (D estimated) | cases | frequency inside 95 % interval | damping inside | "
         "median width f (relative) | median width zeta (relative) | robust sd of (est - true) / sd, f / zeta | CPU s |",
         "|---|---|---|---|---|---|---|---|---|"]
    for k, v in res.items():
        L.append(f"| {k} below output RMS | {v['records']} ({v.get('records_with_d', '-')}) | {v['cases']} | "
                 f"{100 * v['frequency_coverage']:.1f} % | {100 * v['damping_coverage']:.1f} % | "
                 f"{v['median_relative_width_frequency']:.2e} | "
                 f"{v['median_relative_width_damping']:.2f} | "
                 f"{v['robust_sd_of_standardised_error_frequency']:.2f} / "
                 f"{v['robust_sd_of_standardised_error_damping']:.2f} | {v['cpu_seconds']:.0f} |")
    L.append(f"\nAll levels: {sum(v['records'] for v in res.values())} records, {tot} cases, frequency "
             f"inside in **{100 * cf:.1f} %**, damping in **{100 * cz:.1f} %** (target 85-99 %). A missing "
             "case (no identified mode within 5 % of the true frequency, or no interval) counts as outside.\n")
    return L


def report(res: dict, st: dict) -> str:
    """The markdown: one table per plant (``res``: plant name -> level -> figures)."""
    L = ["# Coverage of the 95 % modal intervals (`plid.uncertainty`, `trussid identify`)\n",
         "Generated by `benchmarks/bench_uncertainty.py` (protocol in its docstring). "
         f"Commit {st['commit']}; {st['machine']}; {st['date_utc']}; load average at start "
         f"{st['loadavg_start']}, at end {st.get('loadavg_end')}.\n"]
    for name, levels in res.items():
        L += [f"## {PLANTS[name][1]}\n"] + _table(levels)
    return "\n".join(L)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=70, help="records per noise level and plant")
    ap.add_argument("--plants", default=",".join(PLANTS), help="comma-separated, of: " + ", ".join(PLANTS))
    ap.add_argument("--out", default=str(Path(__file__).resolve().parent / "results" /
                                         "uncertainty"), help="results stem (.md, .json)")
    a = ap.parse_args(argv)
    names = [x.strip() for x in a.plants.split(",") if x.strip()]
    bad = [x for x in names if x not in PLANTS]
    if bad:
        ap.error(f"unknown plant {bad[0]!r} (known: {', '.join(PLANTS)})")
    st = stamp()
    res = {}
    for name in names:
        print(f"[{name}]", flush=True)
        res[name] = coverage(a.records, P=PLANTS[name][0]())
    st = finish(st)
    md = report(res, st)
    write_json(Path(a.out + ".json"), {"stamp": st, "results": res})
    Path(a.out + ".md").write_text(md)
    print(md)
    return 0


if __name__ == "__main__":
    sys.exit(main())
