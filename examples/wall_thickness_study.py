"""Wall-thickness study of the testbed: how each strut's wall moves the natural frequencies.

Sweeps one strut's wall thickness at a time (the others at their nominal values) from
``--low`` to ``--high`` times nominal, plots the lowest modes' frequencies against the
thickness (one panel per strut) and prints the analytic sensitivities ``df/dt`` at the
nominal design with each mode's label. The model is built once; every design of the
sweep only re-forms the strut terms of K and M (:func:`trussid.testbed.model.wall_basis`).

Usage::

    python examples/wall_thickness_study.py --out study.png
    python examples/wall_thickness_study.py --params examples/testbed.toml --points 21
"""

from __future__ import annotations

import argparse
import sys

import numpy as np


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--out", default="wall_thickness_study.png", help="output PNG (default %(default)s)")
    p.add_argument("--params", default=None, help="testbed parameter file (.toml); default: the default testbed")
    p.add_argument("--points", type=int, default=15, help="designs per strut (default %(default)s)")
    p.add_argument("--low", type=float, default=0.6, help="lowest wall / nominal (default %(default)s)")
    p.add_argument("--high", type=float, default=1.4, help="highest wall / nominal (default %(default)s)")
    p.add_argument("--modes", type=int, default=30, help="modes computed (default %(default)s)")
    p.add_argument("--fmax", type=float, default=400.0, help="plot frequencies up to this [Hz] (default %(default)s)")
    return p.parse_args(argv)


def main(argv=None) -> int:
    args = parse_args(argv)
    if args.points < 2:
        print(f"wall_thickness_study: error: --points {args.points} must be at least 2", file=sys.stderr)
        return 2
    if not 0 < args.low < args.high:
        print(f"wall_thickness_study: error: need 0 < --low < --high, got {args.low}, {args.high}", file=sys.stderr)
        return 2

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from tqdm import tqdm

    from trussid.testbed.labels import label_testbed_modes
    from trussid.testbed.sensitivity import wall_sensitivities
    from trussid.testbed.model import build_testbed, solve_testbed_modes, wall_basis, wall_modes
    from trussid.geometry.params_toml import load_testbed
    from trussid.geometry.spec import INCH, Testbed
    from trussid._util.errors import UserError
    from trussid._util.files import atomic_path

    try:
        tb = load_testbed(args.params) if args.params else Testbed()
    except UserError as exc:
        print(f"wall_thickness_study: error: {exc}", file=sys.stderr)
        return 2
    tbm = build_testbed(tb)
    basis = wall_basis(tbm)
    nominal = np.array(tb.struts.walls)
    r_out = tb.struts.outer_radius

    # Nominal modes, their labels and sensitivities.
    modes = solve_testbed_modes(tbm, args.modes, system=basis.system)
    labels = label_testbed_modes(tbm, modes).labels
    f0, dfdt = wall_sensitivities(basis, nominal, args.modes)

    factors = np.linspace(args.low, args.high, args.points)
    sweep = np.empty((6, args.points, len(f0)))
    walls = np.empty((6, args.points))
    with tqdm(total=6 * args.points, desc="designs", unit="design") as bar:
        for i in range(6):
            for j, fac in enumerate(factors):
                w = nominal.copy()
                w[i] = min(fac * nominal[i], 0.95 * r_out)  # a wall must stay inside the tube
                walls[i, j] = w[i]
                sweep[i, j], _ = wall_modes(basis, w, args.modes)
                bar.update()

    fig, axes = plt.subplots(2, 3, figsize=(13, 8), sharey=True)
    # Curves follow the k-th lowest frequency of each design, coloured by mode k's nominal
    # label; the sub-hertz suspension modes would only squash the scale.
    shown = (f0 <= args.fmax) & np.array([lab != "suspension" for lab in labels])
    for i, ax in enumerate(axes.ravel()):
        t_in = walls[i] / INCH
        for k in np.flatnonzero(shown):
            own = labels[k].startswith(f"strut {i} ")
            ax.plot(t_in, sweep[i, :, k], color="C3" if own else ("C0" if "UDF" in labels[k] else "0.6"),
                    lw=1.6 if own else 0.8)
        ax.axvline(nominal[i] / INCH, color="k", ls=":", lw=0.8)
        ax.set_title(f"strut {i} (nominal {nominal[i] / INCH:.3f} in)")
        ax.set_xlabel(f"strut {i} wall thickness [in]")
        ax.grid(alpha=0.3)
    for ax in axes[:, 0]:
        ax.set_ylabel("natural frequency [Hz]")
    fig.suptitle("Testbed frequencies vs one strut's wall thickness "
                 "(red: that strut's modes, blue: UDF rigid-body, grey: others)")
    fig.tight_layout()
    with atomic_path(args.out) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)

    print(f"wrote {args.out}: {6 * args.points} designs, {len(f0)} modes each")
    print()
    print("sensitivities df/dt at the nominal walls [Hz per 0.001 in of wall]")
    header = "".join(f"{f'strut {i}':>11}" for i in range(6))
    print(f"{'mode':>4} {'f [Hz]':>9}  {'label':<34}{header}")
    for k in range(len(f0)):
        row = "".join(f"{v:>11.3g}" for v in dfdt[k] * 0.001 * INCH)
        print(f"{k + 1:>4} {f0[k]:>9.3f}  {labels[k]:<34}{row}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
