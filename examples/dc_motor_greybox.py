"""DC-motor grey-box identification, as a user would run it (after Adewusi 2016).

Makes square-wave speed data with the parameters the paper identified (J = 9.85e-3 kg m^2,
R = 6.29 ohm, b = 2.52e-3 N m s/rad, k = 1.57e-2 N m/A) and 1 % output noise, then:

1. fits the first-order model G/(T s + 1);
2. fits b, R, k with J given -- and shows that the data cannot single them out: the
   multi-start lands on very different (R, k) that all fit equally well;
3. fits b, k with J and R given -- now all four are determined.

Run:  python examples/dc_motor_greybox.py [--plot response.png]
"""

from __future__ import annotations

import argparse

import numpy as np

from trussid.plid.dcmotor import first_order_from_physical, identify_dc_motor, physical_model
from trussid.plid.greybox import simulate_continuous

J, R, B, K = 9.85e-3, 6.29, 2.52e-3, 1.57e-2


def square_wave_data(seed: int = 0, fs: float = 20.0, half_period: float = 20.0):
    T, G = first_order_from_physical(J, B, R, K)
    t = np.arange(int(6 * half_period * fs)) / fs
    u = np.where((t // half_period) % 2 == 0, 3.25, -3.25)
    y = simulate_continuous(physical_model({"J": J, "b": B, "R": R, "k": K}), t, u)[:, 0]
    rng = np.random.default_rng(seed)
    return t, u, y + 0.01 * np.sqrt(np.mean(y**2)) * rng.standard_normal(t.size)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plot", help="save measured vs fitted response to this PNG")
    args = ap.parse_args()

    t, u, y = square_wave_data()
    T, G = first_order_from_physical(J, B, R, K)
    print(f"true first-order model: T = {T:.4f} s, G = {G:.4f} rad/s/V\n")

    print("== J given ==")
    only_j = identify_dc_motor(t, u, y, J=J, n_starts=8)
    print(only_j.summary())
    print("\nequally good fits from the multi-start (each reproduces T and G):")
    for s in only_j.physical.starts:
        if s.equivalent:
            e = s.estimate
            Ts, Gs = first_order_from_physical(e["J"], e["b"], e["R"], e["k"])
            print(f"  b = {e['b']:.3e}  R = {e['R']:9.4g}  k = {e['k']:.3e}"
                  f"   -> T = {Ts:.4f}, G = {Gs:.4f}")

    print("\n== J and R given ==")
    both = identify_dc_motor(t, u, y, J=J, R=R, n_starts=2)
    print(both.summary())

    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from trussid._util.files import atomic_path

        fit = simulate_continuous(physical_model(both.representative), t, u)[:, 0]
        fig, ax = plt.subplots(figsize=(8, 4))
        ax.plot(t, y, ".", ms=2, label="measured (synthetic, 1 % noise)")
        ax.plot(t, fit, label="fitted physical model")
        ax.set(xlabel="time [s]", ylabel="speed [rad/s]")
        ax.legend()
        with atomic_path(args.plot) as tmp:
            fig.savefig(tmp, dpi=120)
        print(f"\nwrote {args.plot}")


if __name__ == "__main__":
    main()
