"""The modal-analysis outputs of ``trussid identify``: ``--stabilisation`` and ``--modal-table``.

Kept apart from :mod:`trussid.cli.commands.identify` so that the identification command
stays readable; nothing here is a command of its own.
"""

from __future__ import annotations

import sys

import numpy as np


def orders_arg(text, order: int, p: int) -> list[int]:
    """``LO:HI[:STEP]`` -> the list of orders; default p, 2p, ..., up to ``order``."""
    from trussid.plid.errors import IdentificationError

    if text is None:
        return list(range(p, order + 1, p))
    parts = text.split(":")
    try:
        nums = [int(v) for v in parts]
    except ValueError:
        nums = []
    if len(nums) not in (2, 3) or nums[0] < 1 or nums[1] < nums[0] or \
            (len(nums) == 3 and nums[2] < 1):
        raise IdentificationError(f"--stabilisation-orders {text!r}: give LO:HI or LO:HI:STEP "
                                  "with 1 <= LO <= HI and STEP >= 1, e.g. 6:60:6")
    step = nums[2] if len(nums) == 3 else p
    return list(range(nums[0], nums[1] + 1, step))


def check_modal_args(args, out) -> None:
    """Refuse a missing directory of ``--out`` and a bad ``--stabilisation`` path before any
    work."""
    from trussid._util.files import check_parent
    from trussid.plid.errors import DataError

    check_parent(out, "--out")
    if getattr(args, "stabilisation", None) is not None:
        if not str(args.stabilisation).lower().endswith(".png"):
            raise DataError(f"--stabilisation {args.stabilisation}: the diagram is a .png")
        check_parent(args.stabilisation, "--stabilisation")


def modal_outputs(args, data, model, start: str, form: str, summary: dict) -> list[str]:
    """Run what ``--stabilisation`` / ``--modal-table`` ask for; add it to ``summary`` and
    return the lines to print. The reader's notes (e.g. a time column read as milliseconds)
    go to stderr first."""
    import control

    for note in data.notes:
        print(f"trussid identify: note: {note}", file=sys.stderr)
    # the model as identified has generic signal names; the table names the data's channels
    model = control.ss(model.A, model.B, model.C, model.D, model.dt,
                       inputs=list(data.input_names), outputs=list(data.output_names))
    lines = []
    if getattr(args, "modal_table", False):
        from trussid.plid.modal import format_modal_table, modal_table

        modes = modal_table(model, physical_only=True)
        summary["modes"] = [
            {"frequency_hz": float(modes.frequencies_hz[k]), "damping": float(modes.damping[k]),
             "shape": {name: [float(abs(v)), float(np.degrees(np.angle(v)))]
                       for name, v in zip(modes.labels, modes.shapes[:, k])},
             "participation": {name: [float(abs(v)), float(np.degrees(np.angle(v)))]
                               for name, v in zip(modes.input_names, modes.participation[k])}}
            for k in range(modes.n_modes)]
        lines += ["modal parameters (oscillatory poles; shape magnitude at each output, "
                  "largest = 1; |L| input participation):", format_modal_table(modes)]
    if getattr(args, "stabilisation", None) is not None:
        lines += _stabilisation(args, data, start, form, summary)
    return lines


def _stabilisation(args, data, start, form, summary) -> list[str]:
    from trussid.plid.frf import h1
    from trussid.plid.stabilisation_diagram import stabilisation
    from trussid.plid.recipe import identify
    from trussid.plots import save_figure, stabilisation_figure

    orders = orders_arg(args.stabilisation_orders, args.order, data.n_outputs)
    start_ = "subspace" if start == "plain" else start

    def fit(u, y, n, dt):
        return identify(u, y, n, dt, start=start_, form=form, progress=False).model

    progress = None if sys.stderr.isatty() else False
    stab = stabilisation(data.u, data.y, data.dt, orders, identify=fit, progress=progress,
                         input_names=data.input_names, output_names=data.output_names)
    nperseg = int(min(1024, max(16, 2 ** int(np.log2(max(data.n_samples // 8, 16))))))
    est = h1(data.u, data.y, data.fs, nperseg=nperseg)
    fig = stabilisation_figure(stab, frf=(est.f, est.H),
                               title=f"stabilisation diagram: {args.data}")
    save_figure(fig, args.stabilisation)
    # a noise pole can match its neighbour once; a physical one stays: ask for two steps
    min_run = min(2, max(len(stab.orders) - 1, 1))
    stable = stab.stable_poles(min_run=min_run)
    summary["stabilisation"] = {
        "plot": str(args.stabilisation), "orders": stab.orders,
        "failed": [{"order": n, "reason": why} for n, why in stab.failed],
        "stable_steps_required": min_run,
        "stable_at_highest_order": [
            {"frequency_hz": float(f), "damping": float(z)}
            for f, z in zip(stable.frequencies_hz, stable.damping)],
        "tolerances": stab.tolerances,
    }
    lines = [f"stabilisation diagram: orders {stab.orders[0]}-{stab.orders[-1]} "
             f"({len(stab.orders)} models), written to {args.stabilisation}"]
    for n, why in stab.failed:
        lines.append(f"  order {n}: no model ({why})")
    lines.append(f"  stable at order {stab.orders[-1]} in frequency, damping and shape over "
                 f"the last {min_run} order step(s): "
                 + (", ".join(f"{f:.2f} Hz ({100 * z:.2f} %)" for f, z in
                              zip(stable.frequencies_hz, stable.damping)) or "none"))
    return lines
