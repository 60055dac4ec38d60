"""
FE model updating of the strut walls from a simulated identification test
=========================================================================

End to end, as a user would run it:

1. perturb the six wall thicknesses of the nominal testbed (seeded, up to ``--perturb``);
2. simulate an identification test on the perturbed ("true") testbed: all six struts'
   wafer pairs driven in anti-phase (bending) from one D/A channel with band-limited
   white noise, six lateral accelerometers at the struts' mid-spans, 12-bit converters,
   sensor noise (:func:`trussid.testbed.testbed_plant` with ``arrangement="bending"``,
   ``sensors="struts"``). The lab's own plant
   (extension drive, UDF accelerometers) barely sees the strut bending modes that carry
   the wall information, which is why this experiment is used;
3. identify a SIMO model with PLID and take its strongest modes in the bending band, with
   standard deviations from PLID's parameter covariance
   (:func:`trussid.updating.modes_from_data`);
4. update the nominal model's walls (MAC + frequency pairing, bounds, analytic
   sensitivities, :func:`trussid.updating.update_walls`);
5. print the table and save a PNG of nominal / true / updated walls with intervals.

``--exact`` skips 2-3 and updates from the exact frequencies of the true model's 12 strut
bending and 6 UDF modes (no shapes, no noise); the documentation's gallery runs it so.
``--quick`` uses a shorter record.

Usage::

    python examples/model_updating.py --out updating.png
    python examples/model_updating.py --quick --out updating.png
    python examples/model_updating.py --exact --seed 3

Imported, the module runs the ``--exact`` case (seconds, not a minute) and its globals hold
the results (``truth``: the true walls [m], ``report``: the
:class:`~trussid.updating.UpdateReport`, ``wall_error``: relative, per strut).
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import numpy as np

from trussid import geometry, plid, testbed, updating
from trussid.testbed.plant import strut_sensors  # where the test's sensors sit (not in __all__)


def parse_args(argv=None):
    """Options of the run; a bad value exits with status 2 and one line."""
    p = argparse.ArgumentParser(
        prog="model_updating",
        description="FE model updating of the strut walls from a simulated identification test")
    p.add_argument("--out", default="model_updating.png", help="output PNG (default %(default)s)")
    p.add_argument("--seed", type=int, default=1, help="seed of the perturbation and the test (default %(default)s)")
    p.add_argument("--perturb", type=float, default=0.15,
                   help="largest relative wall change (default %(default)s)")
    p.add_argument("--samples", type=int, default=16000, help="samples in the record (default %(default)s)")
    p.add_argument("--order", type=int, default=18, help="PLID model order (default %(default)s)")
    p.add_argument("--snr", type=float, default=40.0, help="sensor signal-to-noise ratio [dB] (default %(default)s)")
    p.add_argument("--exact", action="store_true", help="update from exact model frequencies instead")
    p.add_argument("--quick", action="store_true", help="a short record (4000 samples)")
    args = p.parse_args(argv)
    if not 0 <= args.perturb < 0.5:
        p.exit(2, f"model_updating: error: --perturb {args.perturb} must be in [0, 0.5)\n")
    if args.samples < 1000:
        p.exit(2, f"model_updating: error: --samples {args.samples} must be at least 1000\n")
    if args.order < 2:
        p.exit(2, f"model_updating: error: --order {args.order} must be at least 2\n")
    args.n_samples = 4000 if args.quick else args.samples
    return args


args = parse_args(sys.argv[1:] if __name__ == "__main__" else ["--exact"])
t0 = time.perf_counter()

# %%
# The nominal and the perturbed ("true") testbed, and the true model's modes.
nominal_tb = geometry.Testbed()
nominal = np.array(nominal_tb.struts.walls)  # m
rng = np.random.default_rng(args.seed)
truth = nominal * (1 + rng.uniform(-args.perturb, args.perturb, 6))
true_tb = nominal_tb.with_walls(tuple(float(w) for w in truth))
true_tbm = testbed.build_testbed(true_tb)
nominal_tbm = testbed.build_testbed(nominal_tb)
print(f"true walls / nominal: {np.round(truth / nominal, 4).tolist()}")

true_modes = testbed.solve_testbed_modes(true_tbm, 40)
lab = testbed.label_testbed_modes(true_tbm, true_modes)
first_bending = [j for j, (k, o) in enumerate(zip(lab.kind, lab.order)) if k == "bending" and o == 1]
udf = [j for j, k in enumerate(lab.kind) if k == "udf"]

# %%
# The measured modes (exact, or identified by PLID from a simulated test) and the update.
if args.exact:
    measured = true_modes.frequencies_hz[sorted(first_bending + udf)]
    print(f"exact frequencies of the true model: {len(first_bending)} first strut bending and "
          f"{len(udf)} UDF rigid-body modes")
    report = updating.update_walls(measured, nominal_tb, tbm=nominal_tbm, seed=args.seed)
    title = "exact frequencies (12 bending + 6 UDF modes)"
else:
    tp = testbed.testbed_plant(true_tbm, arrangement="bending", sensors="struts")
    plant, daq = tp.discrete, tp.lab.daq  # the testbed lab's converters
    fb = true_modes.frequencies_hz[first_bending]
    band = (0.8 * fb.min(), 1.25 * fb.max())  # around the first strut bending modes
    exp = plid.run_experiment(plant, args.n_samples, "white", rms=1.0, band=(30.0, 90.0),
                              seed=args.seed, snr_db=args.snr, dac_bits=daq.bits, adc_bits=daq.bits,
                              dac_full_scale=daq.full_scale, adc_full_scale="auto")
    print(f"simulated {args.n_samples} samples at {1 / plant.dt:g} Hz "
          f"({args.n_samples * plant.dt:.1f} s), {args.snr:g} dB sensor SNR, {daq.bits}-bit converters; "
          f"clipped {exp.clipped_total}")
    ident, info = updating.modes_from_data(exp.data.u, exp.data.y, plant.dt, args.order,
                                           band=band, n_modes=6)
    print(f"PLID order {args.order}: {len(ident.frequencies_hz)} modes in "
          f"{band[0]:.1f}-{band[1]:.1f} Hz")
    for f, z, sf in zip(ident.frequencies_hz, ident.damping, ident.frequency_std_hz):
        print(f"  {f:9.4f} Hz +- {sf:.4f}   damping {100 * z:.3f} %")
    if info["std_fallback"]:
        print(f"  (modes {info['std_fallback']}: PLID's covariance gave no positive variance; "
              "they take the largest of the others)")
    report = updating.update_walls(
        ident.frequencies_hz, nominal_tb, tbm=nominal_tbm, damping=ident.damping,
        frequency_std_hz=ident.frequency_std_hz, damping_std=ident.damping_std,
        shapes=ident.shapes, sensors=strut_sensors(nominal_tbm), seed=args.seed)
    title = f"PLID (order {args.order}, {args.n_samples} samples) of a bending SIMO test"

wall_error = np.abs(report.walls / truth - 1)  # relative, per strut

if __name__ == "__main__":
    import matplotlib.pyplot as plt

    print()
    print(report.table(truth))
    finite = np.isfinite(report.intervals).all(axis=1)
    print(f"\nlargest relative wall error {wall_error.max():.3e}; finite intervals cover the "
          f"truth for {int((report.covers(truth) & finite).sum())} of {int(finite.sum())} struts"
          + ("" if finite.all() else f"; {int((~finite).sum())} wall(s) undetermined by these "
             "modes (infinite interval)")
          + (" (exact data: the intervals hold only round-off)" if args.exact else ""))
    if report.damping is not None:
        print(f"true modal damping {100 * true_tb.damping.modal_ratio:.4f} %")

    INCH = geometry.INCH
    fig, ax = plt.subplots(figsize=(8, 4.5))
    x = np.arange(6)
    ax.bar(x - 0.25, nominal / INCH, 0.25, label="nominal", color="0.75")
    ax.bar(x, truth / INCH, 0.25, label="true", color="tab:green")
    yerr = None
    if np.isfinite(report.intervals).all():
        yerr = np.abs(report.intervals.T - report.walls) / INCH
    ax.bar(x + 0.25, report.walls / INCH, 0.25, yerr=yerr, capsize=4, label="updated (95 % interval)",
           color="tab:blue")
    ax.set_xticks(x, [f"strut {i}" for i in range(6)])
    ax.set_ylabel("wall thickness [in]")
    ax.set_title(f"Model updating from {title}", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    tmp = f"{args.out}.tmp"  # a temporary name, then a rename: no partial file on failure
    fig.savefig(tmp, format="png", dpi=120)
    os.replace(tmp, args.out)
    print(f"wrote {args.out} ({time.perf_counter() - t0:.0f} s)")
    plt.show()
