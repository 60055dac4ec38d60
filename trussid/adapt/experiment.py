"""Closed-loop experiments: a controller running on a discrete plant, a dither added at the
plant input, converters and sensor noise, everything recorded.

``y_meas[k] = ADC(C x[k] + n[k])``, ``u[k] = controller(y_meas)[k]`` (``u = controller(y)``,
no hidden sign), the D/A sends ``v[k] = DAC(u[k] + d[k])`` and the plant gets ``v``. The
identification input of the direct method is ``v``: what the D/A sent, quantised, known to
the lab exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from trussid.lqg.loop import Loop
from trussid.plid.experiment import excitation


@dataclass
class ClosedLoopRecord:
    """One closed-loop record (SI units: volts at the converters).

    Attributes
    ----------
    command : (N, m) float
        The controller's output ``u`` [V].
    plant_input : (N, m) float
        What the D/A sent, ``DAC(u + d)`` [V]: the identification input.
    measured : (N, p) float
        The A/D readings [V, plant output units].
    dither : (N, m) float
        The dither ``d`` added at the D/A [V].
    dt : float
        Sample interval [s].
    input_names, output_names : list of str
        The plant's D/A and sensor names (the controller's outputs and inputs).
    adc_full_scale : (p,) float
        A/D range per sensor in plant output units [V].
    dac_clipped, adc_clipped : list of int
        Clipped samples per channel.
    x_plant, x_controller : (n,) float
        States at the end of the record (a following record continues from them).
    """

    command: np.ndarray
    plant_input: np.ndarray
    measured: np.ndarray
    dither: np.ndarray
    dt: float
    input_names: list
    output_names: list
    adc_full_scale: np.ndarray
    dac_clipped: list
    adc_clipped: list
    x_plant: np.ndarray
    x_controller: np.ndarray

    @property
    def n_samples(self) -> int:
        return self.measured.shape[0]


def dither(n: int, m: int, dt: float, rms: float, band=(0.0, 400.0), seed: int = 0):
    """White dither, band-limited to ``band`` [Hz], ``rms`` [V] per channel: ``(n, m)``."""
    return excitation("white", n, m, 1.0 / dt, rms, band, seed)


def run_loop(plant, controller, d, noise_rms, *, adc_full_scale, dac_full_scale,
             bits: int, seed: int = 0, x_plant=None, x_controller=None):
    """The loop sample by sample from given states (:mod:`module docstring <.experiment>`).

    :func:`trussid.lqg.evaluate.simulate_loop` does the same from rest and drops the states;
    the adaptive loop needs records that continue one another across controller switches,
    hence this variant.

    Parameters
    ----------
    plant, controller : control.StateSpace
        Discrete, named signals (:class:`trussid.lqg.loop.Loop`); the plant strictly
        proper from its D/A inputs to the sensors.
    d : (N, m) float
        Dither at the D/A [V], columns in the controller's output order.
    noise_rms : float or (p,) float
        White sensor noise RMS [V].
    adc_full_scale, dac_full_scale : float or array
        Converter ranges [V].
    bits : int
        The converters' resolution.
    seed : int
        Seed of the sensor noise.
    x_plant, x_controller : array, optional
        Initial states (default rest).

    Returns
    -------
    ClosedLoopRecord
    """
    loop = Loop.of(plant, controller)
    iu, iy = list(loop.iu), list(loop.iy)
    Ap = np.asarray(plant.A, dtype=float)
    Bu, Cy = (np.asarray(M, dtype=float) for M in (loop.open_loop.B, loop.open_loop.C))
    if np.any(np.asarray(loop.open_loop.D) != 0):
        raise ValueError("the plant must be strictly proper from its D/A to its sensors")
    Ac, Bc, Cc, Dc = (np.asarray(M, dtype=float) for M in
                      (controller.A, controller.B, controller.C, controller.D))
    d = np.asarray(d, dtype=float)
    N, m, p = d.shape[0], len(iu), len(iy)
    rng = np.random.default_rng(seed)
    noise = rng.standard_normal((N, p)) * np.broadcast_to(np.asarray(noise_rms, float), (p,))
    fs_a = np.broadcast_to(np.asarray(adc_full_scale, float), (p,)).copy()
    lsb_a = 2.0 * fs_a / 2**bits
    lsb_d = 2.0 * np.broadcast_to(np.asarray(dac_full_scale, float), (m,)) / 2**bits
    lo, hi = -(2 ** (bits - 1)), 2 ** (bits - 1) - 1
    xp = np.zeros(Ap.shape[0]) if x_plant is None else np.asarray(x_plant, float).copy()
    xc = np.zeros(Ac.shape[0]) if x_controller is None else np.asarray(x_controller, float).copy()
    Y, U, V = np.empty((N, p)), np.empty((N, m)), np.empty((N, m))
    clip_a, clip_d = np.zeros(p, int), np.zeros(m, int)
    # Sample by sample: the converters are not linear, so lsim cannot do it.
    for k in range(N):
        ca = np.round((Cy @ xp + noise[k]) / lsb_a)
        clip_a += (ca < lo) | (ca > hi)
        ym = np.clip(ca, lo, hi) * lsb_a
        uk = Cc @ xc + Dc @ ym
        cd = np.round((uk + d[k]) / lsb_d)
        clip_d += (cd < lo) | (cd > hi)
        v = np.clip(cd, lo, hi) * lsb_d
        xp = Ap @ xp + Bu @ v
        xc = Ac @ xc + Bc @ ym
        Y[k], U[k], V[k] = ym, uk, v
    return ClosedLoopRecord(U, V, Y, d, float(plant.dt), list(controller.output_labels),
                            list(controller.input_labels), fs_a, clip_d.tolist(),
                            clip_a.tolist(), xp, xc)


def trial_rms(plant, controller, n: int, dither_rms: float, band=(0.0, 400.0),
              seed: int = 0) -> np.ndarray:
    """Sensor RMS of a noise-free, unquantised trial run of the loop [V], one per sensor: what
    the lab ranges its conditioners from (48-bit converters with a 1e4 V range stand in for
    ideal ones)."""
    d = dither(n, controller.noutputs, plant.dt, dither_rms, band, seed)
    rec = run_loop(plant, controller, d, 0.0, adc_full_scale=1e4, dac_full_scale=1e4,
                   bits=48, seed=seed)
    return np.sqrt(np.mean(rec.measured**2, axis=0))


def closed_loop_record(plant, controller, n: int, *, dither_rms: float = 2.0,
                       band=(0.0, 400.0), noise_rms=0.0, adc_full_scale,
                       dac_full_scale, bits: int, seed: int = 0, x_plant=None,
                       x_controller=None) -> ClosedLoopRecord:
    """A closed-loop identification record: white dither of ``dither_rms`` [V] per channel
    in ``band`` [Hz] (seed ``seed``) at the D/A, sensor noise of ``noise_rms`` [V] (seed
    ``seed + 1``). 2 V RMS keeps the demo's controller plus dither inside the +-10 V D/A on
    the testbed (adapt feasibility study: peaks 8.3-9.8 V)."""
    d = dither(n, controller.noutputs, plant.dt, dither_rms, band, seed)
    return run_loop(plant, controller, d, noise_rms, adc_full_scale=adc_full_scale,
                    dac_full_scale=dac_full_scale, bits=bits, seed=seed + 1, x_plant=x_plant,
                    x_controller=x_controller)


__all__ = ["ClosedLoopRecord", "dither", "run_loop", "trial_rms", "closed_loop_record"]
