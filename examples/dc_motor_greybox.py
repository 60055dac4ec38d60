"""
DC-motor grey-box identification (after Adewusi 2016)
=====================================================

Makes square-wave speed data with the parameters the paper identified (J = 9.85e-3 kg m^2,
R = 6.29 ohm, b = 2.52e-3 N m s/rad, k = 1.57e-2 N m/A) and 1 % output noise, then, with
:func:`trussid.plid.identify_dc_motor`:

1. fits the first-order model G/(T s + 1);
2. fits b, R, k with J given -- and shows that the data cannot single them out: the
   multi-start lands on very different (R, k) that all fit equally well;
3. fits b, k with J and R given -- now all four are determined.

Run: ``python examples/dc_motor_greybox.py [--plot response.png]``. Imported, the
module's globals hold the results (``only_j``, ``both``: the two fits).
"""

from __future__ import annotations

import argparse
import os

import control
import numpy as np

from trussid import plid

J, R, B, K = 9.85e-3, 6.29, 2.52e-3, 1.57e-2


def first_order(J: float, b: float, R: float, k: float) -> tuple[float, float]:
    """Time constant T [s] and gain G [rad/s per V] of the motor (inductance neglected).

    From ``J dw/dt = k i - b w`` and ``R i = V - k w``: ``T = J R / (b R + k^2)``,
    ``G = k / (b R + k^2)``.
    """
    den = b * R + k * k
    return J * R / den, k / den


def square_wave_data(seed: int = 0, fs: float = 20.0, half_period: float = 20.0):
    """Time [s], voltage [V] and noisy speed [rad/s] of the motor under a +-3.25 V square wave.

    The speed is the exact response to the sampled voltage held between samples (a
    zero-order hold, as a D/A converter drives the motor), plus 1 % white noise.
    """
    T, G = first_order(J, B, R, K)
    t = np.arange(int(6 * half_period * fs)) / fs
    u = np.where((t // half_period) % 2 == 0, 3.25, -3.25)
    motor = control.c2d(control.tf([G], [T, 1.0]), 1 / fs, method="zoh")
    y = control.forced_response(motor, U=u).outputs
    rng = np.random.default_rng(seed)
    return t, u, y + 0.01 * np.sqrt(np.mean(y**2)) * rng.standard_normal(t.size)


t, u, y = square_wave_data()
true_T, true_G = first_order(J, B, R, K)

# %%
# J given: three unknowns, two numbers (T, G) in the data. One combination stays free.
only_j = plid.identify_dc_motor(t, u, y, J=J, n_starts=8)

# %%
# J and R given: b and k follow uniquely.
both = plid.identify_dc_motor(t, u, y, J=J, R=R, n_starts=2)
fitted = both.representative

if __name__ == "__main__":
    import matplotlib.pyplot as plt

    ap = argparse.ArgumentParser(prog="dc_motor_greybox", description="DC-motor grey-box identification")
    ap.add_argument("--plot", help="save measured vs fitted response to this PNG")
    args = ap.parse_args()

    print(f"true first-order model: T = {true_T:.4f} s, G = {true_G:.4f} rad/s/V\n")
    print("== J given ==")
    print(only_j.summary())
    print("\nequally good fits from the multi-start (each reproduces T and G):")
    for start in only_j.physical.starts:
        if start.equivalent:
            e = start.estimate
            Ts, Gs = first_order(e["J"], e["b"], e["R"], e["k"])
            print(f"  b = {e['b']:.3e}  R = {e['R']:9.4g}  k = {e['k']:.3e}"
                  f"   -> T = {Ts:.4f}, G = {Gs:.4f}")
    print("\n== J and R given ==")
    print(both.summary())

    T_fit, G_fit = first_order(fitted["J"], fitted["b"], fitted["R"], fitted["k"])
    motor = control.c2d(control.ss([[-1 / T_fit]], [[G_fit / T_fit]], [[1.0]], [[0.0]]),
                        t[1] - t[0], method="zoh")  # the state is the speed
    speed = control.forced_response(motor, U=u, X0=both.initial_speed or 0.0).outputs
    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, y, ".", ms=2, color="0.5", label="measured (synthetic, 1 % noise)")
    ax.plot(t, speed, color="C0", label="fitted physical model (J, R given)")
    ax.set(xlabel="time [s]", ylabel="speed [rad/s]", title="DC motor under a square-wave voltage")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    if args.plot:  # a temporary name, then a rename: no partial file on failure
        tmp = f"{args.plot}.tmp"
        fig.savefig(tmp, dpi=120, format="png")
        os.replace(tmp, args.plot)
        print(f"\nwrote {args.plot}")
    plt.show()
