"""``trussid compare MODEL.npz REFERENCE --out DIR``: how good is an identified model.

REFERENCE is either a model file (a plant: the truth) or a data file (validation data).
Against a plant: frequency-response error over a band, pole comparison (Hungarian matching),
one-step prediction and simulation fit on a seeded white-noise record of the plant. Against
data: one-step signal-to-prediction-error ratio (with the model's K), simulation fit
(against the noise-free outputs when the file has ``y_clean``, else the measured ones) and
the frequency-response error against the H1 estimate from the data. All by
:func:`trussid.plid.evaluate.compare`, as in the demo's report. Writes into DIR:
``bode_<input>.png`` (one per input), ``poles.png`` and ``metrics.json``. Everything is
computed before the first file is written, and each file is written atomically, so a
mistake leaves no output behind.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np

from trussid._util.errors import UserError
from trussid._util.files import atomic_path, check_parent
from trussid._util.jsonio import dumps, json_safe
from trussid.cli.commands.identify import names_arg

# plid, python-control and matplotlib are imported inside the functions: they take seconds
# and `trussid --help` imports every command module. The evaluation is
# trussid.plid.evaluate.compare, as in the demo report.

#: Samples of the seeded white-noise validation record used against a plant reference.
VALIDATION_SAMPLES = 4000


def add_parser(subparsers):
    p = subparsers.add_parser(
        "compare", help="compare a model with a plant or with validation data",
        description="Compare MODEL.npz with REFERENCE, a plant/model file (the truth) or a "
        "data file (validation data). Writes Bode overlays (bode_<input>.png), a pole map "
        "(poles.png) and metrics.json into DIR.")
    p.add_argument("model", metavar="MODEL.npz", help="the (identified) model file")
    p.add_argument("reference", metavar="REFERENCE",
                   help="a plant/model file (.npz with A, B, C, D, dt) or a data file "
                   "(.csv, .npz, .mat)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--band", type=float, nargs=2, metavar=("LO", "HI"),
                   help="frequency band of the FRF error and plots [Hz] (default: against a "
                   "plant its modes' band, against data the excited band, as printed; a "
                   "band over two decades or more is plotted on a log axis)")
    p.add_argument("--fs", type=float, metavar="HZ", help="sampling frequency of a data file "
                   "that has neither fs nor a time column")
    p.add_argument("--inputs", nargs="+", metavar="NAME", help="data input channels to use")
    p.add_argument("--outputs", nargs="+", metavar="NAME", help="data output channels to use")
    p.add_argument("--nperseg", type=int, metavar="N",
                   help="segment length of the H1 estimate from data (default: the largest "
                   "power of 2 up to N/8 samples, 64 to 4096, so that about 15 segments are "
                   "averaged)")
    p.add_argument("--json", action="store_true", help="print the metrics as JSON")
    p.set_defaults(func=run)
    return p


def _reference_kind(path: Path) -> str:
    from trussid.plid.modelfile import is_model_file

    if not path.exists():
        raise UserError(f"no such reference file: {path}")
    if path.suffix.lower() in (".csv", ".mat"):
        return "data"
    if path.suffix.lower() != ".npz":
        raise UserError(f"{path}: unknown reference file type '{path.suffix}' (a model .npz or "
                        "a data file .csv/.npz/.mat)")
    if is_model_file(path):
        return "plant"
    try:
        with np.load(path, allow_pickle=False) as z:
            keys = set(z.files)
    except Exception as exc:  # numpy raises several types for a foreign file
        raise UserError(f"{path}: not a readable .npz file ({exc})") from None
    if {"u", "y"} <= keys:
        return "data"
    raise UserError(f"{path}: neither a model file (no array 'A' and 'dt') nor a data file "
                    "(no arrays 'u' and 'y')")


def _check_channels(model_meta, ref_names, kind):
    m_in, m_out = model_meta.input_names, model_meta.output_names
    r_in, r_out = ref_names
    if len(m_in) != len(r_in) or len(m_out) != len(r_out):
        raise UserError(f"the model has {len(m_in)} input(s) and {len(m_out)} output(s) but "
                        f"the {kind} has {len(r_in)} and {len(r_out)}")


def _safe_name(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name) or "input"


def _load_reference(args, model, meta, kind, ref_path):
    """The reference plant (or None) and the record ``(u, y, y_clean, K, H1 estimate)``."""
    import control

    from trussid.plid.datafile import read_data
    from trussid.plid.experiment import run_experiment
    from trussid.plid.frf import h1
    from trussid.plid.modelfile import load_model

    fs = 1.0 / model.dt
    if kind == "plant":
        truth, rmeta = load_model(ref_path)
        if not control.isdtime(truth, strict=True):
            # A continuous plant is compared through its zero-order-hold equivalent.
            truth = control.c2d(truth, model.dt, "zoh")
        elif abs(truth.dt - model.dt) > 1e-9 * model.dt:
            raise UserError(f"the model samples at {fs:g} Hz but the plant at "
                            f"{1 / truth.dt:g} Hz")
        _check_channels(meta, (rmeta.input_names, rmeta.output_names), "plant")
        val = run_experiment(truth, VALIDATION_SAMPLES, seed=12345)
        return truth, (val.data.u, val.data.y, val.y_clean, meta.K, None)
    data = read_data(ref_path, inputs=names_arg(args.inputs), outputs=names_arg(args.outputs),
                     fs=args.fs)
    for note in data.notes:  # what the reader assumed, e.g. a time column in milliseconds
        print(f"trussid compare: note: {note}", file=sys.stderr)
    if abs(data.fs - fs) > 1e-6 * fs:
        raise UserError(f"the model samples at {fs:g} Hz but the data at {data.fs:g} Hz")
    _check_channels(meta, (data.input_names, data.output_names), "data")
    nperseg = args.nperseg or int(2 ** np.clip(np.floor(np.log2(data.n_samples / 8)), 6, 12))
    est = h1(data.u, data.y, data.fs, nperseg=int(min(nperseg, data.n_samples)))
    return None, (data.u, data.y, data.y_clean, meta.K, est)


def run(args) -> int:
    import control

    from trussid.plid.evaluate import Band, compare, default_band, frf_grid
    from trussid.plid.frf import frequency_response
    from trussid.plid.modelfile import load_model
    from trussid.plots import bode_figure, pole_map_figure, save_figure

    model, meta = load_model(args.model)
    if not control.isdtime(model, strict=True):
        raise UserError(f"{args.model}: the model is continuous (dt = 0); compare needs a "
                        "discrete (identified) model")
    ref_path = Path(args.reference)
    kind = _reference_kind(ref_path)
    nyq = 0.5 / model.dt
    if args.band:
        band = tuple(args.band)
        if not 0 <= band[0] < band[1] <= nyq * (1 + 1e-9):
            raise UserError(f"--band {band[0]:g} {band[1]:g}: need 0 <= LO < HI <= Nyquist "
                            f"({nyq:g} Hz)")
    truth, (u, y, y_clean, K, est) = _load_reference(args, model, meta, kind, ref_path)
    chosen = (Band(*args.band, "--band") if args.band
              else default_band(2 * nyq, plant=truth, u=u if truth is None else None))
    band = chosen.as_tuple()
    c = compare(model, truth, u=u, y=y, y_clean=y_clean, K=K, gain="model file",
                estimate=est, band=band)
    metrics = {"model": str(args.model), "reference": str(ref_path), "reference_kind": kind,
               "input_names": meta.input_names, "output_names": meta.output_names,
               "fs": 2 * nyq, "band": list(band), "band_source": chosen.source,
               "stable": c.stable,
               "stability": meta.stability.message(f"the model {args.model}"),
               "record": (f"seeded white-noise record of the plant, {VALIDATION_SAMPLES} "
                          "samples" if kind == "plant" else str(ref_path)),
               **json_safe(c)}

    # ---- figures (built in memory, then written)
    logx = band[0] > 0 and band[1] / band[0] >= 100
    if truth is not None:
        f_lo = band[0] if band[0] > 0 else nyq * 1e-3
        f_ref = (np.geomspace(f_lo, band[1] * (1 - 1e-9), 1200) if logx
                 else frf_grid(truth, (f_lo, band[1]), 800))
        curves = [("plant", f_ref, frequency_response(truth, f_ref))]
        f_plot = f_ref
    else:
        keep = (est.f >= band[0]) & (est.f <= band[1]) & (est.f > 0)
        f_plot = est.f[keep]
        curves = [(f"H1 ({est.n_averages} averages)", f_plot, est.H[keep])]
    curves.append(("model", f_plot, frequency_response(model, f_plot)))
    figs = {f"bode_{_safe_name(name)}.png": bode_figure(
        curves, j, name, meta.output_names,
        title=f"Bode overlay, input {name}: model vs {curves[0][0]}", logx=logx)
        for j, name in enumerate(meta.input_names)}
    figs["poles.png"] = pole_map_figure([("plant", truth), ("model", model)] if truth is not None
                                        else [("model", model)])
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out} exists and is not a directory")
    # --out names the directory itself, so it is made; a missing parent is refused
    check_parent(out, "--out")
    out.mkdir(exist_ok=True)
    for fname, fig in figs.items():
        save_figure(fig, out / fname)
    with atomic_path(out / "metrics.json") as tmp:
        tmp.write_text(dumps(metrics))
    if args.json:
        print(dumps(metrics), end="")
        return 0
    _print_metrics(args, metrics, c, sorted([*figs, "metrics.json"]), out)
    return 0


def _print_metrics(args, metrics, c, written, out) -> None:
    band = metrics["band"]
    print(f"compared {args.model} ({c.states} states) with {metrics['reference_kind']} "
          f"{metrics['reference']}")
    if not c.stable:
        # stderr, as every warning; the numbers below are printed but flagged
        print(f"trussid compare: warning: {metrics['stability']}; its simulation diverges, "
              "so the simulation fit below is meaningless", file=sys.stderr)
    if c.frf is not None:
        e = c.frf
        print(f"FRF error over {band[0]:.4g}-{band[1]:.4g} Hz ({metrics['band_source']}): "
              f"max {e.max_db:.3f} dB, RMS {e.rms_db:.3f} dB; phase max {e.max_deg:.2f} deg, "
              f"RMS {e.rms_deg:.2f} deg")
        print("poles: true [Hz, damping] -> model [Hz, damping]")
        for row in c.poles:
            t = ("-" if row.true_frequency_hz is None
                 else f"{row.true_frequency_hz:10.3f} {row.true_damping:9.5f}")
            mdl = ("-" if row.frequency_hz is None
                   else f"{row.frequency_hz:10.3f} {row.damping:9.5f}")
            print(f"  {t:>21} -> {mdl}")
    if c.frf_vs_estimate is not None:
        e = c.frf_vs_estimate
        print(f"FRF error vs {e.reference} over {band[0]:.4g}-{band[1]:.4g} Hz "
              f"({metrics['band_source']}): max {e.max_db:.3f} dB, RMS {e.rms_db:.3f} dB")
    r, s = c.prediction, c.simulation
    print(f"one-step signal-to-prediction-error ratio ({metrics['record']}; first {r.skip} "
          f"samples left out): {r.overall:.2f} dB")
    print(f"simulation fit (against {s.against}): "
          + (f"{s.overall:.2f} dB" if c.stable else "none: the model is unstable"))
    print(f"wrote {', '.join(written)} in {out}")
