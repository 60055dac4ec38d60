"""FE model updating of the testbed's strut walls from a simulated identification test.

End to end, as a user would run it:

1. perturb the six wall thicknesses of the nominal testbed (seeded, up to ``--perturb``);
2. simulate an identification test on the perturbed ("true") testbed: all six struts'
   wafer pairs driven in anti-phase (bending) from one D/A channel with band-limited
   white noise, six lateral accelerometers at the struts' mid-spans, 12-bit converters,
   sensor noise (:func:`trussid.testbed.plant.testbed_plant` with ``arrangement="bending"``). The lab's own plant
   (extension drive, UDF accelerometers) barely sees the strut bending modes that carry
   the wall information, which is why this experiment is used;
3. identify a SIMO model with PLID and take its strongest modes in the bending band, with
   standard deviations from PLID's parameter covariance;
4. update the nominal model's walls (MAC + frequency pairing, bounds, analytic
   sensitivities, :func:`trussid.updating.update_walls`);
5. print the table and save a PNG of nominal / true / updated walls with intervals.

``--exact`` skips 2-3 and updates from the exact frequencies of the true model's 12 strut
bending and 6 UDF modes (no shapes, no noise). ``--quick`` uses a shorter record.

Usage::

    python examples/model_updating.py --out updating.png
    python examples/model_updating.py --quick --out updating.png
    python examples/model_updating.py --exact --seed 3
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="model_updating.png", help="output PNG (default %(default)s)")
    p.add_argument("--seed", type=int, default=1, help="seed of the perturbation and the test (default %(default)s)")
    p.add_argument("--perturb", type=float, default=0.15,
                   help="largest relative wall change (default %(default)s)")
    p.add_argument("--samples", type=int, default=16000, help="samples in the record (default %(default)s)")
    p.add_argument("--order", type=int, default=18, help="PLID model order (default %(default)s)")
    p.add_argument("--snr", type=float, default=40.0, help="sensor signal-to-noise ratio [dB] (default %(default)s)")
    p.add_argument("--exact", action="store_true", help="update from exact model frequencies instead")
    p.add_argument("--quick", action="store_true", help="a short record (4000 samples)")
    return p.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    if not 0 <= args.perturb < 0.5:
        print(f"model_updating: error: --perturb {args.perturb} must be in [0, 0.5)", file=sys.stderr)
        return 2
    if args.samples < 1000:
        print(f"model_updating: error: --samples {args.samples} must be at least 1000", file=sys.stderr)
        return 2
    n_samples = 4000 if args.quick else args.samples

    import matplotlib

    matplotlib.use("Agg")
    from trussid._util.errors import UserError

    try:
        return _run(args, n_samples)
    except UserError as exc:  # bad parameters: one line, no traceback, no file
        print(f"model_updating: error: {exc}", file=sys.stderr)
        return 2


def _run(args, n_samples) -> int:
    import matplotlib.pyplot as plt

    from trussid.testbed.labels import label_testbed_modes
    from trussid.testbed.model import build_testbed, solve_testbed_modes
    from trussid.geometry.spec import INCH, Testbed
    from trussid.plid.experiment import run_experiment
    from trussid._util.files import atomic_path
    from trussid.testbed.plant import strut_sensors, testbed_plant
    from trussid.updating import modes_from_data, update_walls

    t0 = time.perf_counter()
    nominal_tb = Testbed()
    nominal = np.array(nominal_tb.struts.walls)
    rng = np.random.default_rng(args.seed)
    truth = nominal * (1 + rng.uniform(-args.perturb, args.perturb, 6))
    true_tb = nominal_tb.with_walls(tuple(float(w) for w in truth))
    true_tbm = build_testbed(true_tb)
    nominal_tbm = build_testbed(nominal_tb)
    print(f"true walls / nominal: {np.round(truth / nominal, 4).tolist()}")

    true_modes = solve_testbed_modes(true_tbm, 40)
    lab = label_testbed_modes(true_tbm, true_modes)
    first_bending = [j for j, (k, o) in enumerate(zip(lab.kind, lab.order)) if k == "bending" and o == 1]
    udf = [j for j, k in enumerate(lab.kind) if k == "udf"]
    if args.exact:
        measured = true_modes.frequencies_hz[sorted(first_bending + udf)]
        print(f"exact frequencies of the true model: {len(first_bending)} first strut bending and "
              f"{len(udf)} UDF rigid-body modes")
        rep = update_walls(measured, nominal_tb, tbm=nominal_tbm, seed=args.seed)
        title = "exact frequencies (12 bending + 6 UDF modes)"
    else:
        tp = testbed_plant(tbm=true_tbm, arrangement="bending", sensors="struts")
        plant = tp.discrete
        fb = true_modes.frequencies_hz[first_bending]
        band = (0.8 * fb.min(), 1.25 * fb.max())  # around the first strut bending modes
        exp = run_experiment(plant, n_samples, "white", rms=1.0, band=(30.0, 90.0), seed=args.seed,
                             snr_db=args.snr, dac_bits=12, adc_bits=12, adc_full_scale="auto")
        print(f"simulated {n_samples} samples at {1 / plant.dt:g} Hz ({n_samples * plant.dt:.1f} s), "
              f"{args.snr:g} dB sensor SNR, 12-bit converters; clipped {exp.clipped_total}")
        ident, info = modes_from_data(exp.data.u, exp.data.y, plant.dt, args.order, band=band, n_modes=6)
        print(f"PLID order {args.order}: {len(ident.frequencies_hz)} modes in "
              f"{band[0]:.1f}-{band[1]:.1f} Hz")
        for f, z, sf in zip(ident.frequencies_hz, ident.damping, ident.frequency_std_hz):
            print(f"  {f:9.4f} Hz +- {sf:.4f}   damping {100 * z:.3f} %")
        if info["std_fallback"]:
            print(f"  (modes {info['std_fallback']}: PLID's covariance gave no positive variance; "
                  "they take the largest of the others)")
        rep = update_walls(ident.frequencies_hz, nominal_tb, tbm=nominal_tbm, damping=ident.damping,
                           frequency_std_hz=ident.frequency_std_hz, damping_std=ident.damping_std,
                           shapes=ident.shapes, sensors=strut_sensors(nominal_tbm), seed=args.seed)
        title = f"PLID (order {args.order}, {n_samples} samples) of a bending SIMO test"

    print()
    print(rep.table(truth))
    err = np.abs(rep.walls / truth - 1)
    print(f"\nlargest relative wall error {err.max():.3e}; intervals cover the truth for "
          f"{int(rep.covers(truth).sum())} of 6 struts"
          + (" (exact data: the intervals hold only round-off)" if args.exact else ""))
    if rep.damping is not None:
        print(f"true modal damping {100 * true_tb.damping.modal_ratio:.4f} %")

    fig, ax = plt.subplots(figsize=(8, 4.5))
    x = np.arange(6)
    ax.bar(x - 0.25, nominal / INCH, 0.25, label="nominal", color="0.75")
    ax.bar(x, truth / INCH, 0.25, label="true", color="tab:green")
    yerr = None
    if np.isfinite(rep.intervals).all():
        yerr = np.abs(rep.intervals.T - rep.walls) / INCH
    ax.bar(x + 0.25, rep.walls / INCH, 0.25, yerr=yerr, capsize=4, label="updated (95 % interval)",
           color="tab:blue")
    ax.set_xticks(x, [f"strut {i}" for i in range(6)])
    ax.set_ylabel("wall thickness [in]")
    ax.set_title(f"Model updating from {title}", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    with atomic_path(args.out) as tmp:
        fig.savefig(tmp, format="png", dpi=120)
    plt.close(fig)
    print(f"wrote {args.out} ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
