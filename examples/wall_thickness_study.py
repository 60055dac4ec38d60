"""
Wall-thickness study of the testbed
===================================

How each strut's wall thickness moves the testbed's natural frequencies. Sweeps one
strut's wall at a time (the others at their nominal values) from ``--low`` to ``--high``
times nominal, plots the lowest modes' frequencies against the thickness (one panel per
strut) and prints the analytic sensitivities ``df/dt`` at the nominal design with each
mode's label. The model is built once (:func:`trussid.testbed.build_testbed`); every
design of the sweep only re-forms the strut terms of K and M
(:func:`trussid.testbed.wall_basis`, :func:`trussid.testbed.wall_modes`), and the
sensitivities are analytic (:func:`trussid.testbed.wall_sensitivities`).

Usage::

    python examples/wall_thickness_study.py --out study.png
    python examples/wall_thickness_study.py --params examples/testbed.toml --points 21

Imported, the module runs the default study and its globals hold the results
(``f0``, ``dfdt``, ``labels``, ``walls``, ``sweep``).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

import numpy as np
from tqdm import tqdm

from trussid import geometry, testbed
from trussid.geometry.params_toml import testbed_to_dict
from trussid.study import read_study, run_study, spec_from_dict


def parse_args(argv=None):
    """Options of the study; a bad value or parameter file exits with status 2 and one line."""
    p = argparse.ArgumentParser(prog="wall_thickness_study",
                                description="Wall-thickness study of the testbed")
    p.add_argument("--out", default="wall_thickness_study.png", help="output PNG (default %(default)s)")
    p.add_argument("--params", default=None, help="testbed parameter file (.toml); default: the default testbed")
    p.add_argument("--points", type=int, default=15, help="designs per strut (default %(default)s)")
    p.add_argument("--low", type=float, default=0.6, help="lowest wall / nominal (default %(default)s)")
    p.add_argument("--high", type=float, default=1.4, help="highest wall / nominal (default %(default)s)")
    p.add_argument("--modes", type=int, default=30, help="modes computed (default %(default)s)")
    p.add_argument("--fmax", type=float, default=400.0, help="plot frequencies up to this [Hz] (default %(default)s)")
    p.add_argument("--study", default=None, help="study output directory (Parquet; default: a temporary one)")
    p.add_argument("--workers", type=int, default=0,
                   help="0: in this process (default); N: a local Dask cluster of N worker processes")
    args = p.parse_args(argv)
    if args.points < 2:
        p.exit(2, f"wall_thickness_study: error: --points {args.points} must be at least 2\n")
    if not 0 < args.low < args.high:
        p.exit(2, f"wall_thickness_study: error: need 0 < --low < --high, got {args.low}, {args.high}\n")
    try:
        args.testbed = geometry.load_testbed(args.params) if args.params else geometry.Testbed()
    except geometry.ParameterError as exc:
        p.exit(2, f"wall_thickness_study: error: {exc}\n")
    return args


args = parse_args(sys.argv[1:] if __name__ == "__main__" else [])
tb = args.testbed
tbm = testbed.build_testbed(tb)
basis = testbed.wall_basis(tbm)
nominal = np.array(tb.struts.walls)  # m

# %%
# Nominal modes, their labels and the analytic sensitivities df/dt [Hz/m], (modes, struts).
modes = testbed.solve_testbed_modes(tbm, args.modes, system=basis.system)
labels = testbed.label_testbed_modes(tbm, modes).labels
f0, dfdt = testbed.wall_sensitivities(basis, nominal, args.modes)

# %%
# The sweep, run as a study (:mod:`trussid.study`, docs/studies.md): one point per design,
# listed strut by strut, each design's frequencies from the wall basis; its table is a
# Parquet dataset (``--study DIR``, resumable) and ``--workers N`` spreads it over N local
# Dask worker processes. ``sweep[i, j]``: the k-th lowest frequencies of design j of strut i.
factors = np.linspace(args.low, args.high, args.points)
designs = np.repeat(nominal[None, :], 6 * args.points, axis=0)
for i in range(6):  # a wall stays inside the tube
    designs[i * args.points:(i + 1) * args.points, i] = np.minimum(factors * nominal[i],
                                                                    0.95 * tb.struts.outer_radius)
walls = designs.reshape(6, args.points, 6)[np.arange(6), :, np.arange(6)]  # m, (strut, design)
spec = spec_from_dict({
    "study": {"name": "wall-thickness-sweeps", "evaluate": "modes"},
    "evaluate": {"n_modes": args.modes, "labels": False,
                 **({"testbed": testbed_to_dict(tb)} if args.params else {})},
    "sample": {"method": "list"},
    "parameters": {f"wall{i}": [float(v) for v in designs[:, i]] for i in range(6)}})
study_dir = args.study or tempfile.mkdtemp(prefix="wall_sweeps_")
with tqdm(total=6 * args.points, desc="designs", unit="design", disable=__name__ != "__main__") as bar:
    run_study(spec, study_dir, workers=args.workers, progress=lambda batch: bar.update(batch.points))
table = read_study(study_dir)[1]  # one row per design, in point order
sweep = table[[f"f{k + 1}" for k in range(len(f0))]].to_numpy().reshape(6, args.points, len(f0))  # Hz

if __name__ == "__main__":
    import matplotlib.pyplot as plt

    INCH = geometry.INCH
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
    tmp = f"{args.out}.tmp"  # a temporary name, then a rename: no partial file on failure
    fig.savefig(tmp, dpi=110, format="png")
    os.replace(tmp, args.out)

    print(f"wrote {args.out}: {6 * args.points} designs, {len(f0)} modes each (table: {study_dir})")
    print()
    print("sensitivities df/dt at the nominal walls [Hz per 0.001 in of wall]")
    header = "".join(f"{f'strut {i}':>11}" for i in range(6))
    print(f"{'mode':>4} {'f [Hz]':>9}  {'label':<34}{header}")
    for k in range(len(f0)):
        row = "".join(f"{v:>11.3g}" for v in dfdt[k] * 0.001 * INCH)
        print(f"{k + 1:>4} {f0[k]:>9.3f}  {labels[k]:<34}{row}")
    plt.show()
