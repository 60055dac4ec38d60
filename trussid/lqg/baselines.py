"""Decentralised model-free baselines: each actuator channel fed back from its own sensor.

``u_i = g y_i`` (static acceleration feedback) or ``u_i = g BP(z) y_i`` (a second-order
band-pass around the target band), each with or without one sample of computation delay.
The gain is tuned on the identified model (the truth is never used): the gain on a
logarithmic ladder, both signs, that maximises the least damping of the model's dominant
modes with the loop stable, then halved (6 dB of gain margin on the model).
"""

from __future__ import annotations

import math

import control
import numpy as np

from .errors import ControlError
from .evaluate import damping_table

__all__ = ["KINDS", "decentralised", "tune_baseline"]

KINDS = ("static", "static+delay", "bandpass", "bandpass+delay")


def decentralised(kind: str, gain: float, dt: float, inputs, outputs, band=(150.0, 250.0),
                  ) -> control.StateSpace:
    """A diagonal controller ``u_i = gain H(z) y_i``; ``inputs`` (sensors) pair with
    ``outputs`` (actuators) in order."""
    m = len(outputs)
    if len(inputs) != m:
        raise ControlError(f"decentralised control pairs sensors with actuators: {len(inputs)} "
                           f"sensors, {m} actuators (a baseline needs as many of each)")
    if kind.startswith("static"):
        h = control.ss([], [], [], [[1.0]], dt)
    elif kind.startswith("bandpass"):
        lo, hi = band
        f0 = math.sqrt(lo * hi)
        w0, bw = 2 * math.pi * f0, 2 * math.pi * (hi - lo)
        hc = control.tf([bw, 0], [1, bw, w0**2])
        h = control.ss(control.sample_system(hc, dt, method="bilinear", prewarp_frequency=w0))
    else:
        raise ValueError(f"baseline kind must be one of {', '.join(KINDS)}, got {kind!r}")
    if kind.endswith("+delay"):
        h = control.series(control.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]], dt), h)
    bank = control.append(*([h] * m)) if m > 1 else h
    return control.ss(bank.A, bank.B, gain * np.asarray(bank.C), gain * np.asarray(bank.D), dt,
                      inputs=list(inputs), outputs=list(outputs), name=kind)


def tune_baseline(model, kind: str, band=(150.0, 250.0), gains=None) -> tuple[float, dict]:
    """Gain of a baseline from the identified ``model`` (module docstring).

    Returns
    -------
    gain : float
    info : dict
        The damping reached on the model at the best gain, before halving.
    """
    if gains is None:
        mag = np.logspace(-3, 1, 33)
        gains = np.concatenate([mag, -mag])
    ins, outs = list(model.output_labels), list(model.input_labels)
    best, best_z = None, -np.inf
    for g in gains:
        c = decentralised(kind, g, model.dt, ins, outs, band)
        t = damping_table(model, c, band=(0.0, 0.5 / model.dt))
        if not t.stable:
            continue
        dom = [r.damping_worst_visible for r in t.dominant]
        z = min(dom) if dom else -np.inf
        if z > best_z:
            best, best_z = float(g), z
    if best is None:
        return 0.0, {"model_dominant_damping": None}
    return 0.5 * best, {"model_dominant_damping": float(best_z), "best_gain": best}
