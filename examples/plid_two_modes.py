r"""
Identification from data: PLID recovers a two-mode plant
========================================================

A lightly damped structure with two modes (12 Hz at 2 % damping, 31 Hz at 1 %), one
force input and one velocity sensor (a laser vibrometer, say), sampled at 200 Hz, is excited with band-limited white
noise; the record carries 12-bit converters and sensor noise 40 dB below the signal
(:func:`trussid.plid.run_experiment`). :func:`trussid.plid.identify` fits a 4-state
discrete model to the input/output record alone (what ``trussid identify DATA --order 4``
does), and :func:`trussid.plid.modal_parameters` reads the modes off it.

With your own measurements, ``u`` (N x m) and ``y`` (N x p) come from a file instead:
:func:`trussid.plid.read_data` reads CSV (``u*`` and ``y*`` columns), NPZ or MAT.

The true modes are known here, so the identified frequencies and damping ratios can be
checked; the Bode plot overlays the true plant, the H1 estimate from the same record
(:func:`trussid.plid.h1`) and the identified model.

Run: ``python examples/plid_two_modes.py``. Imported, the module's globals hold the
results (``identified_hz``, ``true_hz``, ``identified_damping`` ...).
"""

import control
import numpy as np

from trussid import plid

FS = 200.0  # sampling frequency [Hz]
true_hz = np.array([12.0, 31.0])
true_damping = np.array([0.02, 0.01])
modal_mass_inv = np.array([1.0, 0.6])  # participation of each mode [1/kg]

# %%
# The plant: force [N] in, velocity [m/s] out, as a sum of modes; discretised with a
# zero-order hold, as a D/A converter drives it. A velocity output keeps the plant strictly
# proper, as PLID's models are (an accelerometer's feed-through would need a D term).
w = 2 * np.pi * true_hz
s = control.tf("s")
continuous = sum(b * s / (s**2 + 2 * z * wn * s + wn**2)
                 for b, z, wn in zip(modal_mass_inv, true_damping, w))
plant = control.c2d(control.ss(continuous), 1 / FS, method="zoh")

# %%
# The experiment: 20 s of white noise in 1-90 Hz, 12-bit converters (a +-10 V D/A, the
# A/D range set from the signals), sensor noise 40 dB below the response.
experiment = plid.run_experiment(plant, 4000, "white", rms=1.0, band=(1.0, 90.0), seed=7,
                                 snr_db=40.0, dac_bits=12, adc_bits=12, dac_full_scale=10.0,
                                 adc_full_scale="auto")
u, y = experiment.data.u, experiment.data.y

# %%
# Identification from u and y alone, then the modes of the identified model.
fit = plid.identify(u, y, order=4, dt=1 / FS)
identified_hz, identified_damping, _ = plid.modal_parameters(fit.model)
order = np.argsort(identified_hz)
identified_hz, identified_damping = identified_hz[order], identified_damping[order]
frequency_error = identified_hz / true_hz - 1

if __name__ == "__main__":
    import matplotlib.pyplot as plt

    print(f"{'mode':>4} {'true [Hz]':>10} {'PLID [Hz]':>10} {'rel. error':>11} "
          f"{'true damping':>13} {'PLID damping':>13}")
    for k in range(2):
        print(f"{k + 1:>4} {true_hz[k]:>10.3f} {identified_hz[k]:>10.4f} {frequency_error[k]:>11.2e} "
              f"{100 * true_damping[k]:>12.2f}% {100 * identified_damping[k]:>12.3f}%")

    est = plid.h1(u, y, FS, nperseg=512)
    f = np.linspace(1.0, 90.0, 900)
    H_true = plid.frequency_response(plant, f)[:, 0, 0]
    H_fit = plid.frequency_response(fit.model, f)[:, 0, 0]
    fig, (ax_m, ax_p) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True)
    band = (est.f >= 1.0) & (est.f <= 90.0)
    ax_m.semilogy(f, np.abs(H_true), color="0.55", lw=2.6, label="true plant")
    ax_m.semilogy(est.f[band], np.abs(est.H[band, 0, 0]), ".", color="C1", ms=3,
                  label="H1 estimate")
    ax_m.semilogy(f, np.abs(H_fit), color="C0", lw=1.0, label="PLID, 4 states")
    ax_p.plot(f, np.degrees(np.angle(H_true)), color="0.55", lw=2.6)
    ax_p.plot(est.f[band], np.degrees(np.angle(est.H[band, 0, 0])), ".", color="C1", ms=3)
    ax_p.plot(f, np.degrees(np.angle(H_fit)), color="C0", lw=1.0)
    ax_m.set_ylabel("|velocity / force| [m/(N s)]")
    ax_p.set(xlabel="frequency [Hz]", ylabel="phase [deg]", ylim=(-190, 190))
    for ax in (ax_m, ax_p):
        ax.grid(True, which="both", alpha=0.3)
    ax_m.legend(fontsize=8)
    ax_m.set_title("Two-mode plant: true, H1 estimate and PLID model")
    fig.tight_layout()
    plt.show()
