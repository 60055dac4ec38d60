"""Modal analysis of measured data: stabilisation diagram and MAC for the LMS steel subframe.

(A benchmark-style script, not a gallery example: it reads the shared measured data and runs
eleven PLID fits of 8523 samples, minutes of work.)

The DaISy "flexible structure" record (LMS International: a steel subframe hung on rubber
bands, 2 white-noise shakers, 28 accelerometers, 1024 Hz, 8523 samples; see
``../shared/realdata/README.md``) is read as MATLAB writes it, one 8523 x 30 matrix, with the
channels the PLID comparison uses: inputs columns 1-2, accelerometers 1, 10, 19 (columns 3,
12, 21). Then:

1. PLID models over a range of orders, each pole marked stable in frequency (1 %), damping
   (5 %) and mode shape (MAC 0.98) against the order below, drawn over the summed H1
   (:func:`trussid.plid.stabilisation_diagram.stabilisation`, :func:`trussid.plots.stabilisation_figure`);
2. the same order identified separately on the first and the second half of the record, and
   the MAC between the two sets of mode shapes at the three accelerometers
   (:func:`trussid.plid.modal.mac`): a physical mode gives the same shape in both halves.

Usage::

    python benchmarks/subframe_modal.py --out docs/images
    python benchmarks/subframe_modal.py --data ../shared/realdata/flexibleStructure.mat --orders 6:36:3
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DEFAULT_DATA = HERE.parent.parent / "shared" / "realdata" / "flexibleStructure.mat"


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--data", default=str(DEFAULT_DATA), help="flexibleStructure.mat")
    p.add_argument("--out", default=".", help="existing directory for the two PNGs")
    p.add_argument("--orders", default="6:36:3", help="LO:HI:STEP (default %(default)s)")
    p.add_argument("--order", type=int, default=30,
                   help="order of the two half-record models compared by MAC (default 30)")
    return p.parse_args(argv)


def main(argv=None) -> int:
    from trussid.plid.datafile import read_data
    from trussid.plid.frf import h1
    from trussid.plid.modal import mac, modal_table
    from trussid.plid.stabilisation_diagram import stabilisation
    from trussid.plid.multipass import identify
    from trussid.plots import mac_figure, save_figure, stabilisation_figure

    args = parse_args(argv)
    out = Path(args.out)
    if not out.is_dir():
        print(f"subframe_modal: error: --out {out} is not an existing directory", file=sys.stderr)
        return 2
    d = read_data(args.data, inputs=["flexibleStructure:1,2"],
                  outputs=["flexibleStructure:3,12,21"], fs=1024)
    u = d.u - d.u.mean(axis=0)
    y = d.y - d.y.mean(axis=0)
    lo, hi, step = (int(v) for v in args.orders.split(":"))
    names = ["acc1", "acc10", "acc19"]

    def fit(u_, y_, n, dt):
        return identify(u_, y_, n, dt, progress=False).model

    t0 = time.perf_counter()
    stab = stabilisation(u, y, d.dt, range(lo, hi + 1, step), identify=fit, progress=True,
                         input_names=["shaker1", "shaker2"], output_names=names)
    t_stab = time.perf_counter() - t0
    est = h1(u, y, d.fs, nperseg=1024)
    fig = stabilisation_figure(stab, frf=(est.f, est.H),
                               title="LMS steel subframe (DaISy), PLID, 2 shakers -> "
                               "accelerometers 1, 10, 19")
    save_figure(fig, out / "subframe_stabilisation.png")
    stable = stab.stable_poles(min_run=2)
    print(f"stabilisation: orders {stab.orders} in {t_stab:.0f} s "
          f"({platform.node()}, {platform.processor() or platform.machine()})")
    for n, why in stab.failed:
        print(f"  order {n}: no model ({why})")
    print(f"stable over the last 2 order steps at order {stab.orders[-1]}:")
    for f, z in zip(stable.frequencies_hz, stable.damping):
        print(f"  {f:8.2f} Hz  {100 * z:6.3f} %")

    half = d.n_samples // 2
    sets = []
    for part in (slice(0, half), slice(half, None)):
        model = fit(u[part], y[part], args.order, d.dt)
        modes = modal_table(model, physical_only=True)
        sets.append(modes.select((modes.damping < 0.05) & (modes.frequencies_hz < 0.45 * d.fs)))
    M = mac(sets[0], sets[1])
    fig = mac_figure(M, sets[0].frequencies_hz, sets[1].frequencies_hz,
                     f"first half, order {args.order}", f"second half, order {args.order}",
                     title="MAC at accelerometers 1, 10, 19: PLID on the two halves of the record\n"
                     "(3 sensors: different modes cannot all be orthogonal)")
    save_figure(fig, out / "subframe_mac.png")
    best = M.max(axis=1)
    print(f"MAC, first half ({sets[0].n_modes} modes below 5 % damping) against the second "
          f"half ({sets[1].n_modes}): best match per mode")
    for f, b, j in zip(sets[0].frequencies_hz, best, M.argmax(axis=1)):
        print(f"  {f:8.2f} Hz -> {sets[1].frequencies_hz[j]:8.2f} Hz  MAC {b:.3f}")
    print(f"wrote {out / 'subframe_stabilisation.png'} and {out / 'subframe_mac.png'}")
    print(f"seconds: stabilisation {t_stab:.0f}, whole run {time.perf_counter() - t0:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
