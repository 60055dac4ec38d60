"""Known plants for identification studies and benchmarks (PLID at thesis scale, issue 6).

Built directly in numpy/control; :data:`PLANTS` names them for study specs
(``[evaluate] plant = "case_a"``). ``benchmarks/plid_cases.py`` re-exports this module.

Every plant is a set of lightly damped modes ``q'' + 2 zeta w q' + w^2 q = b^T u`` with
acceleration outputs ``y_r = sum_i phi_ri q_i''``, discretised by zero-order hold at
``fs`` (default :data:`FS`, the thesis lab's rate, :class:`trussid.geometry.lab.LabSpec`). Mode shapes and participations are seeded
random numbers; each output row is scaled so that a unit-RMS white input gives a unit-RMS
output (so one converter range suits all channels).

Acceleration has a direct term ``sum_i phi_ri b_i`` (the instantaneous response to a force).
PLID models are strictly proper, and so is every real sampled record (the A/D converter
reads before the D/A output changes), so:

- :func:`case_a` (no input filter) makes the sensors non-collocated in the strict sense: the
  participations are projected so that ``sum_i phi_ri b_i = 0`` for every output (no
  instantaneous acceleration at the sensors); the plant is then exactly 24 states, D = 0.
- :func:`case_b` puts a 2-pole Butterworth filter on each input (the actuator amplifier's
  anti-imaging filter), which makes the plant strictly proper with 2 extra states per input.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
import scipy.signal

from trussid.geometry.lab import LabSpec
from trussid.plid.experiment import run_experiment

#: The thesis lab (the cases are PLID at thesis scale): its rate, smoothing filter and
#: converter resolution, from the one source of the lab's numbers.
_LAB = LabSpec()
#: Sample rate of the cases [Hz].
FS = _LAB.daq.sample_rate


@dataclass
class Case:
    """A benchmark plant and how it is identified."""

    name: str
    plant: control.StateSpace          # discrete truth, D = 0
    orders: tuple                       # orders to identify at
    freqs_hz: np.ndarray                # modal frequencies of the structure [Hz]
    zeta: float


def _modes(freqs_hz, zeta):
    n = 2 * len(freqs_hz)
    A = np.zeros((n, n))
    for i, f in enumerate(freqs_hz):
        w = 2 * np.pi * f
        A[2 * i:2 * i + 2, 2 * i:2 * i + 2] = [[0.0, 1.0], [-w * w, -2 * zeta * w]]
    return A


def _freqs(n_modes, lo, hi, rng):
    """Modal frequencies spread over [lo, hi] Hz: geometric spacing with 15 % jitter."""
    f = np.geomspace(lo, hi, n_modes)
    ratio = (hi / lo) ** (1 / (n_modes - 1))
    jit = 1 + 0.15 * (ratio - 1) * rng.uniform(-1, 1, n_modes)
    jit[0] = jit[-1] = 1.0
    return np.sort(f * jit)


def modal_acceleration_plant(freqs_hz, zeta, m, p, rng, zero_feedthrough=True):
    """Continuous modal plant with acceleration outputs (state ``[q_i, q_i']`` per mode).

    Returns ``(A, B, C, D)`` continuous; with ``zero_feedthrough`` the participations are
    projected so that ``D = Phi b = 0``.
    """
    nm = len(freqs_hz)
    A = _modes(freqs_hz, zeta)
    b = rng.standard_normal((nm, m))          # modal participation of each input
    phi = rng.standard_normal((p, nm))        # mode shape at each sensor
    if zero_feedthrough:
        # Project b's columns onto the null space of phi: phi b = 0 exactly.
        Q, _ = np.linalg.qr(phi.T)             # (nm, p) basis of phi's row space
        b = b - Q @ (Q.T @ b)
    w = 2 * np.pi * np.asarray(freqs_hz)
    B = np.zeros((2 * nm, m))
    B[1::2] = b
    C = np.zeros((p, 2 * nm))
    C[:, 0::2] = -phi * w ** 2
    C[:, 1::2] = -phi * 2 * zeta * w
    D = phi @ b
    return A, B, C, D


def _unit_rms_outputs(sysd, rng_seed=0, n=20000):
    """Scale output rows so that unit-RMS white input gives unit-RMS outputs."""
    u = np.random.default_rng(rng_seed).standard_normal((n, sysd.ninputs))
    y = control.forced_response(sysd, U=u.T).outputs
    y = np.atleast_2d(y)
    s = np.sqrt(np.mean(y[:, n // 4:] ** 2, axis=1))
    return control.ss(sysd.A, sysd.B, np.asarray(sysd.C) / s[:, None], sysd.D, sysd.dt)


def case_a(seed: int = 1, fs: float = FS) -> Case:
    """(a) 1 input, 3 outputs, 12 modes 45-360 Hz at 0.25 %, accelerations, 24 states."""
    rng = np.random.default_rng(seed)
    f = _freqs(12, 45.0, 360.0, rng)
    A, B, C, D = modal_acceleration_plant(f, 0.0025, 1, 3, rng, zero_feedthrough=True)
    assert np.allclose(D, 0.0, atol=1e-12)
    sysd = control.c2d(control.ss(A, B, C, np.zeros((3, 1))), 1 / fs, "zoh")
    return Case("a: 1x3, 12 modes, 24 states", _unit_rms_outputs(sysd), (24,), f, 0.0025)


def butterworth_inputs(m: int, f_hz: float = _LAB.filters.smoothing_cutoff,
                       order: int = _LAB.filters.smoothing_order):
    """m independent Butterworth low-pass filters (unit DC gain), continuous; default the
    thesis lab's smoothing filter (2 poles at 1300 Hz)."""
    bf, af = scipy.signal.butter(order, 2 * np.pi * f_hz, analog=True)
    one = control.tf2ss(control.tf(bf, af))
    return control.append(*([one] * m)) if m > 1 else one


def case_b(seed: int = 2, fs: float = FS) -> Case:
    """(b) 3 inputs, 3 outputs, 18 modes 40-380 Hz at 0.25 %, accelerations behind a 2-pole
    1300 Hz Butterworth on each input: 42 states."""
    rng = np.random.default_rng(seed)
    f = _freqs(18, 40.0, 380.0, rng)
    A, B, C, D = modal_acceleration_plant(f, 0.0025, 3, 3, rng, zero_feedthrough=False)
    structure = control.ss(A, B, C, D)
    filt = butterworth_inputs(3)
    plant_c = control.series(filt, structure)          # structure(filter(u))
    assert plant_c.nstates == 42 and np.allclose(plant_c.D, 0.0)
    sysd = control.c2d(plant_c, 1 / fs, "zoh")
    sysd = control.ss(sysd.A, sysd.B, sysd.C, np.zeros((3, 3)), sysd.dt)
    return Case("b: 3x3, 18 modes + filters, 42 states", _unit_rms_outputs(sysd), (42, 36),
                f, 0.0025)


def case_testbed_like(seed: int = 3, fs: float = FS) -> Case:
    """Testbed stand-in: 1 input, 3 outputs, 12 modes 50-350 Hz at 0.25 % behind a 2-pole
    1300 Hz Butterworth (accelerations): 26 states, identified at 30 (SIMO, as the thesis)."""
    rng = np.random.default_rng(seed)
    f = _freqs(12, 50.0, 350.0, rng)
    A, B, C, D = modal_acceleration_plant(f, 0.0025, 1, 3, rng, zero_feedthrough=False)
    plant_c = control.series(butterworth_inputs(1), control.ss(A, B, C, D))
    sysd = control.c2d(plant_c, 1 / fs, "zoh")
    sysd = control.ss(sysd.A, sysd.B, sysd.C, np.zeros((3, 1)), sysd.dt)
    return Case("testbed-like: 1x3, 12 modes + filter, 26 states", _unit_rms_outputs(sysd),
                (30,), f, 0.0025)


def record(case: Case, n_samples: int, noise: str, seed: int):
    """Identification record on ``case``: white unit-RMS input, and ``noise`` one of
    ``"60dB"``, ``"30dB"`` (white sensor noise that far below each output's RMS) or
    ``"12bit"`` (the thesis lab's 12-bit D/A and A/D over +-5 units: about 5 x output RMS,
    no other noise)."""
    kw = {}
    if noise.endswith("dB"):
        kw["snr_db"] = float(noise[:-2])
    elif noise == "12bit":
        bits = _LAB.daq.bits
        kw.update(dac_bits=bits, adc_bits=bits, dac_full_scale=5.0, adc_full_scale=5.0)
    elif noise != "none":
        raise ValueError(f"unknown noise {noise!r}")
    return run_experiment(case.plant, n_samples, "white", rms=1.0, seed=seed, **kw)


PLANTS = {"case_a": case_a, "case_b": case_b, "testbed_like": case_testbed_like}

__all__ = ["PLANTS", "Case", "case_a", "case_b", "case_testbed_like", "record",
           "modal_acceleration_plant", "butterworth_inputs", "FS"]
