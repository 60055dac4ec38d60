"""The lab's electrical and data-acquisition chain around a structural plant.

Command (D/A, volts) -> smoothing filter (Butterworth) -> power amplifier (gain with a
low-pass pole) -> PZT actuators -> structure -> sensors (volts) -> A/D, discretised by
zero-order hold at the sample rate. Each block is optional. Filters are built with
scipy.signal (analog Butterworth) and connected by their signal names with
:func:`control.interconnect` (command ``ch1`` -> electronics -> ``ch1 pzt`` -> structure).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import control
import numpy as np
from scipy import signal

from trussid.fem.errors import ModelError
from trussid.geometry.lab import LabSpec


@dataclass(frozen=True)
class LabChain:
    """Electronics and sample rate of one actuator channel (identical on every channel).

    No field has a default: a chain comes from a lab (:meth:`from_lab`, the one source of
    the lab's numbers) or is given in full.

    Parameters
    ----------
    smoothing_order : int
        Butterworth smoothing filter order; 0 to omit.
    smoothing_cutoff : float
        Its cut-off [Hz].
    amplifier_gain : float
        Power amplifier gain [V/V].
    lowpass_order : int
        Order of the amplifier's low-pass (repeated real pole); 0 to omit.
    lowpass_cutoff : float
        Its cut-off [Hz].
    sample_rate : float
        A/D and D/A rate [Hz]; the plant is discretised by zero-order hold.
    """

    smoothing_order: int
    smoothing_cutoff: float
    amplifier_gain: float
    lowpass_order: int
    lowpass_cutoff: float
    sample_rate: float

    def __post_init__(self):
        for key in ("smoothing_cutoff", "lowpass_cutoff", "sample_rate"):
            value = getattr(self, key)
            if not (math.isfinite(value) and value > 0):
                raise ModelError(f"lab chain: {key} must be positive [Hz], got {value!r}")
        for key in ("smoothing_order", "lowpass_order"):
            if int(getattr(self, key)) < 0:
                raise ModelError(f"lab chain: {key} must be >= 0, got {getattr(self, key)!r}")
        if not math.isfinite(self.amplifier_gain) or self.amplifier_gain == 0:
            raise ModelError(f"lab chain: amplifier_gain must be finite and non-zero, got {self.amplifier_gain!r}")

    @classmethod
    def from_lab(cls, lab: LabSpec, sample_rate: float | None = None) -> "LabChain":
        """The chain of ``lab`` (at ``sample_rate`` [Hz] instead of the lab's, if given)."""
        f = lab.filters
        return cls(smoothing_order=f.smoothing_order, smoothing_cutoff=f.smoothing_cutoff,
                   amplifier_gain=lab.electrics.amplifier_gain, lowpass_order=f.lowpass_order,
                   lowpass_cutoff=f.lowpass_cutoff,
                   sample_rate=lab.daq.sample_rate if sample_rate is None else sample_rate)


def butterworth(order: int, cutoff_hz: float) -> control.StateSpace:
    """Unit-DC-gain analog Butterworth low-pass, SISO."""
    z, p, k = signal.butter(order, 2 * np.pi * cutoff_hz, btype="low", analog=True, output="zpk")
    A, B, C, D = signal.zpk2ss(z, p, k)
    return control.ss(A, B, C, D)


def lowpass(order: int, cutoff_hz: float, gain: float = 1.0) -> control.StateSpace:
    """``gain / (1 + s/w_c)^order``, SISO."""
    wc = 2 * np.pi * cutoff_hz
    num, den = [gain * wc**order], np.poly(np.full(order, -wc))
    return control.ss(control.tf(num, den))


def channel_electronics(chain: LabChain) -> control.StateSpace:
    """Command volts to PZT volts for one channel: smoothing filter then amplifier."""
    sys = control.ss([], [], [], [[chain.amplifier_gain]]) if chain.lowpass_order == 0 else \
        lowpass(chain.lowpass_order, chain.lowpass_cutoff, chain.amplifier_gain)
    if chain.smoothing_order:
        sys = control.series(butterworth(chain.smoothing_order, chain.smoothing_cutoff), sys)
    return sys


def lab_plant(structure: control.StateSpace, chain: LabChain, *,
              check_nyquist: bool = True, max_mode_hz: float | None = None,
              n_commands: int | None = None) -> tuple[control.StateSpace, control.StateSpace]:
    """Compose the electronics with a structural plant and discretise.

    Parameters
    ----------
    structure : control.StateSpace
        PZT volts in, sensor volts out (continuous).
    chain : LabChain
        The electronics and sample rate (:meth:`LabChain.from_lab`).
    check_nyquist : bool
        Refuse a sample rate below twice ``max_mode_hz``.
    max_mode_hz : float, optional
        Highest kept structural mode [Hz] (for the Nyquist check).
    n_commands : int, optional
        The first ``n_commands`` inputs are D/A commands and go through the electronics;
        the others (disturbances acting on the structure) enter the structure directly.
        Default: all inputs.

    Returns
    -------
    continuous, discrete : control.StateSpace
        Command volts in, sensor volts out; the discrete one at ``dt = 1/sample_rate``.

    Notes
    -----
    The converters sample simultaneously and then update the output (sample-and-hold), so
    a direct term of the continuous plant (acceleration outputs with no filters) reaches the
    samples one period late: the discrete plant is always strictly proper.
    """
    fs = chain.sample_rate
    if check_nyquist and max_mode_hz is not None and fs < 2 * max_mode_hz:
        raise ModelError(f"sample rate {fs:g} Hz is below twice the highest kept mode "
                         f"({max_mode_hz:.1f} Hz): keep fewer modes or sample faster")
    inputs, outputs = list(structure.input_labels), list(structure.output_labels)
    m = len(inputs) if n_commands is None else int(n_commands)
    if not 0 <= m <= len(inputs):
        raise ModelError(f"n_commands must be in 0..{len(inputs)}, got {n_commands}")
    elec = channel_electronics(chain)
    blocks = [control.ss(elec.A, elec.B, elec.C, elec.D, inputs=[name], outputs=[f"{name} pzt"],
                         name=f"electronics {name}") for name in inputs[:m]]
    # disturbances (inputs after the first m) act on the structure directly
    pzt = control.ss(structure.A, structure.B, structure.C, structure.D,
                     inputs=[f"{name} pzt" for name in inputs[:m]] + inputs[m:], outputs=outputs,
                     name="structure")
    cont = control.interconnect([*blocks, pzt], inplist=inputs, outlist=outputs, name="plant")
    cont = control.ss(cont.A, cont.B, cont.C, cont.D, inputs=inputs, outputs=outputs, name="plant")
    disc = control.c2d(cont, 1.0 / fs, method="zoh")
    if np.any(disc.D != 0):
        disc = _delay_direct_term(disc)
    disc = control.ss(disc.A, disc.B, disc.C, disc.D, 1.0 / fs, inputs=list(structure.input_labels),
                      outputs=list(structure.output_labels), name="plant")
    return cont, disc


def _delay_direct_term(sys: control.StateSpace) -> control.StateSpace:
    """y_k = C x_k + D u_{k-1}: append the held input as states, one per input with a
    direct term (every input when none is filtered; only the disturbances otherwise)."""
    n = sys.A.shape[0]
    cols = np.flatnonzero(np.any(np.asarray(sys.D) != 0, axis=0))
    m, k = sys.B.shape[1], cols.size
    A = np.block([[sys.A, np.zeros((n, k))], [np.zeros((k, n + k))]])
    E = np.zeros((k, m))
    E[np.arange(k), cols] = 1.0
    B = np.vstack([sys.B, E])
    C = np.hstack([sys.C, np.asarray(sys.D)[:, cols]])
    return control.ss(A, B, C, np.zeros_like(sys.D), sys.dt)
