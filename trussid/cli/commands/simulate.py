"""``trussid simulate PLANT.npz --out DATA``: a simulated identification experiment.

Drives the discrete plant of a model file with a seeded excitation through D/A and A/D
converters and sensor noise (:func:`trussid.plid.experiment.run_experiment`) and writes the record
as CSV, NPZ or MAT (:mod:`trussid.plid.datafile`). NPZ and MAT files also get ``y_clean``, the
noise-free outputs, which ``trussid compare`` uses for the simulation-error metric.
"""

from __future__ import annotations

import json
import sys

import numpy as np

# Kept in step with plid.experiment.EXCITATIONS / plid.datafile.SUFFIXES (a test checks);
# plid is imported inside run() because it pulls in python-control and scipy.signal, which
# take seconds, and `trussid --help` imports every command module.
EXCITATIONS = ("white", "prbs", "chirp", "multisine")
SUFFIXES = (".csv", ".npz", ".mat", ".uff", ".unv")


def count_arg(text: str) -> int:
    """A sample count: an integer, also written as ``1e6`` or ``1_000_000``."""
    import argparse

    try:
        value = float(text.replace("_", ""))
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not np.isfinite(value) or value != int(value):
        raise argparse.ArgumentTypeError(f"not a whole number of samples: {text!r}")
    return int(value)


def add_parser(subparsers):
    p = subparsers.add_parser(
        "simulate", help="simulate an identification experiment on a plant file",
        description="Simulate an identification experiment on the discrete plant of PLANT.npz "
        "(as written by 'trussid plant'): seeded excitation, D/A and A/D quantisation with "
        "clipping counted, sensor and input noise. Writes inputs as recorded (D/A output) and "
        "outputs as measured (A/D output).")
    p.add_argument("plant", metavar="PLANT.npz", help="model file with a discrete plant")
    p.add_argument("--out", required=True, metavar="DATA",
                   help="output data file: .csv, .npz, .mat or .uff (UFF 58 time histories)")
    p.add_argument("--samples", type=count_arg, default=4000, metavar="N",
                   help="number of samples (default 4000)")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="random seed (default 0)")
    p.add_argument("--excitation", choices=EXCITATIONS, default="white",
                   help="excitation signal (default white)")
    p.add_argument("--rms", type=float, default=1.0, metavar="V",
                   help="excitation RMS per input, input units (default 1.0)")
    p.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"),
                   help="excitation band [Hz] (default 0 to Nyquist)")
    noise = p.add_mutually_exclusive_group()
    noise.add_argument("--snr-db", type=float, metavar="DB",
                       help="sensor noise: output signal-to-noise ratio per channel [dB] "
                       "(default: no sensor noise)")
    noise.add_argument("--noise-rms", type=float, metavar="V",
                       help="sensor noise RMS, output units")
    p.add_argument("--input-noise-rms", type=float, default=0.0, metavar="V",
                   help="noise between the recorded input and the plant, input units "
                   "(default 0)")
    p.add_argument("--bits", type=int, metavar="B",
                   help="D/A and A/D resolution (default: no quantisation)")
    p.add_argument("--full-scale", type=float, default=None, metavar="V",
                   help="converter range +-V, D/A and A/D (default: that of the lab PLANT "
                   "records, as trussid plant writes it; else the default testbed lab's)")
    p.add_argument("--adc-full-scale", metavar="V|auto",
                   help="A/D range +-V instead of --full-scale; 'auto' ranges each output to "
                   "+-4 times its RMS, as a lab sets its amplifier gains")
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=run)
    return p


def run(args) -> int:
    from trussid._util.files import check_parent
    from trussid.plid.datafile import write_data
    from trussid.plid.errors import DataError
    from trussid.plid.experiment import check_memory, run_experiment
    from trussid.plid.modelfile import load_model
    from trussid.plid.stability import require_stable

    out = args.out
    if not str(out).lower().endswith(SUFFIXES):
        raise DataError(f"--out {out}: the data file type must be one of {', '.join(SUFFIXES)}")
    check_parent(out, "--out")
    adc_fs = _adc_full_scale(args.adc_full_scale)  # None: --full-scale's, once known
    if args.samples < 2:
        raise DataError(f"--samples must be at least 2, got {args.samples}")
    plant, meta = load_model(args.plant, which="discrete")
    if args.full_scale is None:
        args.full_scale = _lab_full_scale(meta, args.plant)
    adc_fs = args.full_scale if adc_fs is None else adc_fs
    require_stable(plant, f"the plant {args.plant}", "a simulation of it diverges")
    check_memory(plant, args.samples)
    exp = run_experiment(plant, args.samples, args.excitation, rms=args.rms, band=args.band,
                         seed=args.seed, snr_db=args.snr_db, sensor_noise_rms=args.noise_rms,
                         input_noise_rms=args.input_noise_rms, dac_bits=args.bits,
                         adc_bits=args.bits, dac_full_scale=args.full_scale,
                         adc_full_scale=adc_fs, input_names=meta.input_names,
                         output_names=meta.output_names)
    write_data(exp.data, out)
    d = exp.data
    # A signal far below one LSB records as quantisation only: say so, it is not clipping
    # but just as fatal for identification.
    under = []
    if args.bits is not None:
        rms_clean = np.sqrt(np.mean(exp.y_clean**2, axis=0))
        q_adc = np.broadcast_to(np.asarray(exp.lsb["adc"], dtype=float), rms_clean.shape)
        under = [(name, r, q) for name, r, q in zip(d.output_names, rms_clean, q_adc) if r < 4 * q]
    summary = {
        "out": str(out), "samples": d.n_samples, "fs": d.fs, "inputs": d.input_names,
        "outputs": d.output_names, "excitation": args.excitation, "seed": args.seed,
        "rms": args.rms, "band": args.band, "snr_db": args.snr_db,
        "sensor_noise_rms": exp.sensor_noise_rms.tolist(),
        "input_noise_rms": exp.input_noise_rms.tolist(), "bits": args.bits,
        "full_scale": args.full_scale, "adc_full_scale": adc_fs, "lsb": exp.lsb,
        "clipping": exp.clipping, "below_4_lsb": [name for name, _, _ in under],
        "output_rms": np.sqrt(np.mean(d.y**2, axis=0)).tolist(),
    }
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"wrote {out}: {d.n_samples} samples at {d.fs:g} Hz, {d.n_inputs} input(s) "
          f"({', '.join(d.input_names)}), {d.n_outputs} output(s) ({', '.join(d.output_names)})")
    print(f"excitation: {args.excitation}, RMS {args.rms:g}, seed {args.seed}"
          + (f", band {args.band[0]:g}-{args.band[1]:g} Hz" if args.band else ""))
    if args.snr_db is not None or args.noise_rms is not None:
        print("sensor noise RMS: " + ", ".join(f"{v:.4g}" for v in exp.sensor_noise_rms))
    if args.bits is None:
        print("converters: ideal (no quantisation, no clipping)")
    else:
        ranges = {"D/A": f"+-{args.full_scale:g} V",
                  "A/D": "auto (+-4 RMS per output)" if adc_fs == "auto" else f"+-{adc_fs:g} V"}
        for name, counts, names in (("D/A", exp.clipping["dac"], d.input_names),
                                    ("A/D", exp.clipping["adc"], d.output_names)):
            detail = ", ".join(f"{n} {c}" for n, c in zip(names, counts))
            print(f"{name}: {args.bits} bits, {ranges[name]}; clipped samples: "
                  f"{sum(counts)} of {d.n_samples * len(counts)} ({detail})")
        # Warnings go to stderr, as in every other command.
        if exp.clipped_total:
            print("trussid simulate: warning: the converters clipped; lower --rms or raise "
                  "--full-scale", file=sys.stderr)
        for name, r, q in under:
            print(f"trussid simulate: warning: output {name} has RMS {r:.3g} V, under 4 A/D "
                  f"LSB ({q:.3g} V): the record is mostly quantisation; use "
                  "--adc-full-scale auto or a smaller range", file=sys.stderr)
    return 0


def _lab_full_scale(meta, path) -> float:
    """The converter range of the lab the plant file records (``trussid plant`` writes it),
    else the default testbed lab's [V]."""
    from trussid.geometry.lab import recorded_lab
    from trussid.geometry.spec import Testbed

    return (recorded_lab(meta.extra, path) or Testbed().lab).daq.full_scale


def _adc_full_scale(text):
    """``--adc-full-scale``: volts, ``"auto"``, or None when not given."""
    from trussid.plid.errors import DataError

    if text is None or text == "auto":
        return text
    try:
        return float(text)
    except ValueError:
        raise DataError(f"--adc-full-scale must be volts or 'auto', got '{text}'") from None
