"""``trussid identify DATA --order N --out MODEL.npz``: PLID on a data file.

Reads CSV/NPZ/MAT data (:mod:`trussid.plid.datafile`), runs :class:`trussid.plid.estimator.PLID` in batch,
writes the identified discrete model with its one-step predictor gain K
(:mod:`trussid.plid.modelfile`) and reports the identified poles and the one-step
signal-to-prediction-error ratio of the final model on the same data (in-sample, after the
burn-in of :func:`trussid.plid.metrics.prediction_burn_in`; definitions in
:mod:`trussid.plid.metrics`). The recipe is :func:`trussid.plid.frontend.fit_model`.
"""

from __future__ import annotations

import sys
import time
import warnings

import numpy as np

from trussid._util.errors import UserError
from trussid._util.jsonio import dumps

# plid (and through it python-control and scipy.signal) is imported inside the functions:
# it takes seconds, and `trussid --help` imports every command module.


def names_arg(values):
    """``--inputs a b`` and ``--inputs a,b`` both give ['a', 'b']."""
    if values is None:
        return None
    out = [s.strip() for v in values for s in v.split(",") if s.strip()]
    return out or None


def via_arg(text, order: int, p: int, start: str):
    """``--via``: None, ``auto`` (:func:`trussid.plid.reduced.default_via`) or a comma list."""
    from trussid.plid.errors import DataError
    from trussid.plid.reduced import default_via

    if text is None:
        return None
    if start == "plain":
        raise DataError("--via works with --start subspace or scratch, not plain")
    if text.strip().lower() == "auto":
        return default_via(order, p)
    try:
        orders = tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise DataError(f"--via {text!r}: give 'auto' or comma-separated orders, "
                        "e.g. 60,72") from None
    bad = [h for h in orders if h <= order or h % p]
    if not orders or bad:
        raise DataError(f"--via {text!r}: orders must exceed --order {order} and be "
                        f"multiples of the {p} outputs")
    return orders


def add_parser(subparsers):
    # Long: one add_argument per option, each with its help text.
    p = subparsers.add_parser(
        "identify", help="identify a state-space model from input/output data with PLID",
        description="Identify a discrete state-space model of order N from a data file "
        "(CSV with u*/y* columns and optional time column t, or NPZ/MAT with u, y, fs) by "
        "PLID, and write it as a model file with its one-step predictor gain. Noise "
        "covariances are in units of the data scaled to unit RMS per channel.")
    p.add_argument("data", metavar="DATA",
                   help="data file: .csv (',', ';' or tab; units in the header such as "
                   "'t [ms]'; # comments), .npz, .mat or .uff/.unv (UFF 58 time histories)")
    what = p.add_mutually_exclusive_group(required=True)
    what.add_argument("--order", type=int, metavar="N",
                      help="model order (number of states): any order; one that is not a multiple of the "
                      "outputs is identified at the next multiple and reduced to it")
    what.add_argument("--orders", metavar="LO:HI:STEP",
                      help="order selection instead of one model: identify at each order "
                      "LO, LO+STEP, ... HI (multiples of the number of outputs) on the first "
                      "70 %% of the record, score the one-step prediction on the last 30 %% "
                      "(validation) and the FRF change from the previous order "
                      "(plid.order_table); --out TABLE.csv gets the table and TABLE.png the "
                      "plot. The order the data support is where the prediction stops "
                      "rising and the change drops to the noise level")
    p.add_argument("--out", required=True, metavar="MODEL.npz",
                   help="output model file (with --orders: the table, .csv)")
    p.add_argument("--fs", type=float, metavar="HZ",
                   help="sampling frequency, if the file has neither fs nor a time column")
    p.add_argument("--inputs", nargs="+", metavar="NAME",
                   help="input columns/channels to use (names; space or comma separated); "
                   "in .mat/.npz files also variable names or VAR:COLUMNS counted from 1, "
                   "e.g. data:1,2 or data:3-5")
    p.add_argument("--outputs", nargs="+", metavar="NAME",
                   help="output columns/channels to use (as --inputs)")
    p.add_argument("--start", choices=("subspace", "scratch", "plain"), default="subspace",
                   help="subspace (default): a quick N4SID estimate (D = 0) refined by one "
                   "PLID pass in a rotation observer basis (won the thesis-scale benchmarks, "
                   "benchmarks/results/plid_thesis.md); scratch: no prior, rotation basis "
                   "at the output-spectrum peaks, four passes with shrinking state noise; "
                   "plain: one PLID run in the shift basis with --Q and --passes")
    p.add_argument("--form", choices=("sqrt", "direct"), default=None,
                   help="PLID recursion: square-root or direct covariance form (default: "
                   "direct for --start subspace/scratch, as benchmarked; sqrt for plain)")
    p.add_argument("--R", type=float, default=None, metavar="VAR",
                   help="output-noise variance, scaled units (default: estimated from the "
                   "subspace estimate's residual; 1e-4, i.e. 40 dB SNR, otherwise)")
    p.add_argument("--Q", type=float, default=1e-6, metavar="VAR",
                   help="state-noise variance, scaled units, --start plain only (default 1e-6)")
    p.add_argument("--passes", type=int, default=1, metavar="P",
                   help="batch passes over the data, --start plain only (default 1)")
    p.add_argument("--via", default=None, metavar="ORDERS",
                   help="also identify at these higher orders (comma separated, or 'auto' "
                   "for 2 and 2.4 times N), reduce each to N by input-weighted balanced "
                   "truncation, refine by PLID, and keep the candidate with the best "
                   "one-step prediction on the data (plid.reduced.identify_reduced; "
                   "what trussid demo uses: for a structure with more significant modes "
                   "than N/2). --start subspace or scratch only")
    p.add_argument("--stabilisation", metavar="PLOT.png", default=None,
                   help="also identify over a range of orders (--stabilisation-orders) and "
                   "draw the stabilisation diagram: each pole marked stable in frequency "
                   "(1 %%), damping (5 %%) and mode shape (MAC 0.98) against the order below, "
                   "over the summed H1 of the data")
    p.add_argument("--stabilisation-orders", metavar="LO:HI[:STEP]", default=None,
                   help="orders of the stabilisation diagram (default: the number of "
                   "outputs up to --order in steps of the number of outputs)")
    p.add_argument("--modal-table", action="store_true",
                   help="print the modal parameter table of the model: frequency, damping, "
                   "mode shape at each output (magnitude, largest = 1) and the participation "
                   "of each input")
    p.add_argument("--direct", choices=("auto", "yes", "no"), default=None,
                   help="direct term D (feed-through): auto (default for --start subspace or "
                   "scratch) decides on the data by a held-out output-error test, and the "
                   "report says what it chose; yes / no force it (with --via: for every "
                   "candidate); --start plain has none")
    p.add_argument("--closed-loop", action="store_true",
                   help="the record was taken under feedback (the input depends on past "
                   "outputs): identify with a predictor-based subspace prior (PBSID) refined "
                   "by the innovations model's prediction error (the direct method), both "
                   "consistent under feedback, instead of N4SID and PLID's output-error pass "
                   "(which are biased there); D = 0; --start subspace, no --via")
    p.add_argument("--reference", metavar="NAME", default=None,
                   help="a reference (dither) channel of the data file: the record is "
                   "treated as closed loop when the reference explains less than 90 %% of "
                   "the inputs' power (plid.closedloop.feedback_share)")
    p.add_argument("--json", action="store_true",
                   help="print poles and the prediction ratio as JSON")
    p.set_defaults(func=run)
    return p


def orders_arg(text: str, p: int) -> list[int]:
    """``--orders LO:HI:STEP`` (or a comma list) as a list of orders, each checked."""
    from trussid.plid.errors import DataError

    try:
        if ":" in text:
            parts = [int(v) for v in text.split(":")]
            if len(parts) == 2:
                parts.append(p)
            lo, hi, step = parts
            if step < 1 or lo < 1 or hi < lo:
                raise ValueError
            orders = list(range(lo, hi + 1, step))
        else:
            orders = sorted({int(v) for v in text.split(",") if v.strip()})
    except ValueError:
        raise DataError(f"--orders {text!r}: give LO:HI:STEP (e.g. 12:60:6) or a comma "
                        "list of positive orders") from None
    bad = [n for n in orders if n < 1 or n % p]
    if not orders or bad:
        raise DataError(f"--orders {text!r}: every order must be a positive multiple of the "
                        f"{p} outputs (not {bad[0] if bad else 'none'})")
    if len(orders) > 100:
        raise DataError(f"--orders {text!r}: {len(orders)} orders; give at most 100")
    return orders


def run_orders(args, data) -> int:
    """``--orders``: the order table (CSV) and its plot (PNG)."""
    from pathlib import Path

    from trussid.plid.datafile import check_enough_samples
    from trussid.plid.order import format_table, order_table, order_warnings
    from trussid.plots import order_figure, save_figure
    from trussid._util.files import atomic_path

    out = Path(args.out)
    if out.suffix.lower() != ".csv":
        raise UserError(f"--out {out}: with --orders the table is written as .csv (and the "
                        "plot beside it as .png)")
    m, p = data.n_inputs, data.n_outputs
    orders = orders_arg(args.orders, p)
    n = max(orders)
    check_enough_samples(data, int(np.ceil(n * (m + p) / 0.7)),
                         f"an order-{n} model with {m} inputs and {p} outputs on 70 % of "
                         "the record")
    rows = order_table(data.u, data.y, orders, data.dt,
                       progress=None if sys.stderr.isatty() else False)
    lines = ["order,prediction_db_validation,frf_change_db,unstable_poles,seconds,error"]
    for r in rows:
        ch = "" if r.frf_change_db is None else f"{r.frf_change_db:.6g}"
        err = '"' + r.error.replace('"', "'") + '"' if r.error else ""
        lines.append(f"{r.order},{r.prediction_db:.6g},{ch},{r.unstable_poles},{r.seconds:.3f},"
                     f"{err}")
    ok = [r for r in rows if not r.error]
    for note in order_warnings(rows):
        print(f"trussid identify: warning: {note}", file=sys.stderr)
    if not ok:
        raise UserError("no order could be identified: " + "; ".join(
            f"order {r.order}: {r.error}" for r in rows))
    fig = order_figure(ok)
    fig.axes[0].set_title(f"order selection: {Path(args.data).name}; prediction on the "
                          "last 30 % (validation)", fontsize=10)
    fig.tight_layout()
    png = out.with_suffix(".png")
    with atomic_path(out) as tmp:
        tmp.write_text("\n".join(lines) + "\n")
    save_figure(fig, png)
    print(f"order selection on {data.n_samples} samples at {data.fs:g} Hz: identified on the "
          "first 70 %, one-step prediction scored on the last 30 % (validation)")
    print(format_table(rows))
    print(f"wrote {out} and {png}")
    return 0


def run(args) -> int:
    # Long: the command's steps in order (check the paths, read, fit, score, write, report),
    # each a few lines; split up they would only pass the same dozen names around.
    from trussid.cli.commands._modal import check_modal_args, modal_outputs
    from trussid.plid.canonical import check_order
    from trussid.plid.datafile import check_enough_samples, read_data
    from trussid.plid.errors import DataError, IdentificationError
    from trussid.plid.metrics import modal_parameters, prediction_burn_in, prediction_ratio_db
    from trussid.plid.modelfile import save_model
    from trussid.plid.frontend import fit_model
    from trussid.plid.stability import UnstableModelWarning, check_stability
    from trussid.plid.uncertainty import mode_intervals

    out = str(args.out)
    if getattr(args, "orders", None) is not None:
        if not out.lower().endswith(".csv"):
            raise DataError(f"--out {out}: with --orders the table is written as .csv (and "
                            "the plot beside it as .png)")
        return run_orders(args, read_data(args.data, inputs=names_arg(args.inputs),
                                          outputs=names_arg(args.outputs), fs=args.fs))
    if not out.lower().endswith(".npz"):
        raise DataError(f"--out {out}: model files are .npz")
    check_modal_args(args, out)
    if args.order < 1:
        raise IdentificationError(f"--order must be a positive integer, got {args.order}")
    data = read_data(args.data, inputs=names_arg(args.inputs), outputs=names_arg(args.outputs),
                     fs=args.fs)
    n, m, p = args.order, data.n_inputs, data.n_outputs
    start = getattr(args, "start", "plain")
    if start == "plain":   # the shift basis; the recipes handle any order (by reduction)
        check_order(n, p)
    direct_opt = getattr(args, "direct", None)
    if direct_opt is not None and start == "plain":
        raise DataError("--direct works with --start subspace or scratch, not plain")
    direct = {"auto": "auto", "yes": True, "no": False, None: None}[direct_opt]
    check_enough_samples(data, n * (m + p), f"an order-{n} model with {m} inputs and "
                         f"{p} outputs")
    via = via_arg(getattr(args, "via", None), n, p, start)
    closed_loop = bool(getattr(args, "closed_loop", False))
    reference = None
    if getattr(args, "reference", None) is not None:
        reference = read_data(args.data, inputs=names_arg([args.reference]),
                              outputs=names_arg(args.outputs), fs=args.fs).u
    if (closed_loop or reference is not None) and (start != "subspace" or via is not None):
        raise DataError("--closed-loop and --reference work with --start subspace and no "
                        "--via")
    t0 = time.perf_counter()
    ident = fit_model(data.u, data.y, n, data.dt, start=start, via=via, form=args.form,
                      R=args.R, Q=args.Q, passes=args.passes, direct=direct,
                      progress=None if sys.stderr.isatty() else False,
                      log=lambda msg: print(f"  {msg}", file=sys.stderr),
                      closed_loop=closed_loop, reference=reference)
    form = ident.result.form if ident.result is not None else None
    if ident.result is not None:
        start_label = start
    else:
        start_label = "closed-loop (PBSID prior, prediction-error refinement)"
    seconds = time.perf_counter() - t0
    model, K = ident.model, ident.K
    skip = prediction_burn_in(model, K, data.n_samples)
    ratio = prediction_ratio_db(model, data.u, data.y, K=K, skip=skip)
    stability = check_stability(model)
    unstable = int(stability.unstable.size)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnstableModelWarning)  # said below, in one line
        save_model(out, model, K=K, input_names=data.input_names,
                   output_names=data.output_names)
    stability_note = stability.message(f"the identified model {out}")
    freq, damp, _ = modal_parameters(model)
    prov = ident.provenance
    # complex pairs with 95 % intervals (plid.uncertainty: first-order propagation of the
    # PLID pass's posterior parameter covariance)
    modes = mode_intervals(model, *((ident.result.model, ident.result.theta_cov)
                                    if ident.result is not None else (None, None)))
    warned = prov.warnings + ([stability_note] if stability_note else [])
    summary = {
        "model": out, "data": str(args.data), "order": n, "inputs": data.input_names,
        "outputs": data.output_names, "samples": data.n_samples, "fs": data.fs,
        "start": start_label, "form": form,
        "passes": len(prov.passes), "Q": [ps.Q for ps in prov.passes],
        "R": [float(r) for r in np.atleast_1d(ident.R)],
        "seconds": seconds, "K_source": prov.K_source,
        # in-sample: scored on the identification data itself
        "signal_to_prediction_error_db": ratio.overall,
        "signal_to_prediction_error_db_per_output": ratio.per_output,
        "signal_to_prediction_error_db_mean_normalised": ratio.mean_normalised,
        "prediction_skip_samples": skip, "unstable_poles": unstable,
        "poles": [{"frequency_hz": float(a), "damping": float(b)} for a, b in zip(freq, damp)],
        "modes": [mi.as_dict() for mi in modes],
        "warnings": warned,
        "stable": stability.stable, "stability": stability_note,
    }
    if prov.direct is not None:
        summary["direct_term"] = prov.direct
    if prov.closed_loop is not None:
        summary["closed_loop"] = prov.closed_loop
    if prov.structure is not None:
        summary["structure"] = prov.structure
    if via is not None:
        summary.update(via=list(prov.via), chosen=prov.chosen, candidates=prov.candidates)
    modal_lines = modal_outputs(args, data, model, start, form, summary)
    for note in warned:
        print(f"trussid identify: warning: {note}", file=sys.stderr)
    if args.json:
        print(dumps(summary), end="")
        return 0
    print(f"identified an order-{n} model ({m} input(s), {p} output(s)) from "
          f"{data.n_samples} samples at {data.fs:g} Hz in {seconds:.2f} s "
          f"({form + ' form, ' if form else ''}{start_label} start"
          f"{'; kept ' + prov.chosen if via is not None else ''})")
    print(f"wrote {out}")
    _print_fit(prov, data.output_names, ratio, modes, zip(freq, damp))
    for line in modal_lines:
        print(line)
    return 0


def _print_fit(prov, outputs, ratio, modes, poles) -> None:
    """The text summary after its first two lines: structure, direct term, predictor,
    in-sample one-step ratio, modes with intervals, poles."""
    if prov.structure is not None:
        print(f"structure: {prov.structure}")
    if prov.direct is not None:
        d = prov.direct
        t = d.test
        why = (f" (held-out output error {t.held_out_nmse_with:.3g} with D against "
               f"{t.held_out_nmse_without:.3g} without)" if t else "")
        print(f"direct term D: {'estimated' if d.estimated else 'none (D = 0)'}"
              f"{' (' + str(d.mode) + ')' if d.mode != 'auto' else ''}{why}")
        if d.estimated and d.start:
            # which prior PLID started from matters when it is not N4SID's model with D
            print(f"  PLID started from: {d.start}")
    if prov.closed_loop is not None:
        c = prov.closed_loop
        print(f"closed loop ({c.decided_by}): PBSID prior ({c.prior.past} lags), refined by "
              f"{c.refinement}; PLID pass: {c.plid_passes}")
    print(f"predictor gain K: {prov.K_source}")
    per = ", ".join(f"{name} {v:.2f}" for name, v in zip(outputs, ratio.per_output))
    print(f"one-step signal-to-prediction-error ratio on the identification data (in-sample): "
          f"{ratio.overall:.2f} dB ({per}; first {ratio.skip} samples left out)")
    if modes:
        print("modes with 95 % intervals (first-order propagation of the parameter "
              "covariance; '-' where none):")
        print(f"  {'frequency [Hz]':>14s}  {'95 % interval [Hz]':>27s}  {'damping':>9s}  "
              f"{'95 % interval':>21s}")
        for mo in modes:
            fi, zi = mo.frequency_ci95_hz, mo.damping_ratio_ci95
            fci = f"[{fi[0]:.4f}, {fi[1]:.4f}]" if np.all(np.isfinite(fi)) else "-"
            zci = f"[{zi[0]:.5f}, {zi[1]:.5f}]" if np.all(np.isfinite(zi)) else "-"
            print(f"  {mo.frequency_hz:14.4f}  {fci:>27s}  {mo.damping_ratio:9.5f}  "
                  f"{zci:>21s}")
    print("poles (frequency [Hz], damping):")
    for f, z in poles:
        print(f"  {f:12.4f}  {z:10.6f}")
