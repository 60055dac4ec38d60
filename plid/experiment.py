"""Simulated identification experiments: excitation signals and a data-acquisition model.

Signal flow of :func:`run_experiment` (one line per sample, all vectorised over samples)::

    command  = excitation(kind, rms, band, seed)                 (N x m)
    u        = DAC(command)          quantised to dac_bits over +-full_scale, clipped
    u_plant  = u + input noise       (actuator/amplifier noise the record does not see)
    y_phys   = plant(u_plant)        any discrete control.StateSpace, from x0 = 0
    y        = ADC(y_phys + sensor noise)
    y_clean  = plant(u)              what a perfect model predicts from the record

The recorded input is the D/A output itself: the computer knows the codes it sent, and a
discrete plant already includes the zero-order hold. ``y`` and ``u`` are what a lab would
record; ``y_clean`` is the reference for simulation-error metrics.

Quantiser: bipolar, mid-tread, ``2**bits`` codes from ``-2**(bits-1)`` to ``2**(bits-1)-1``,
LSB = 2 full_scale / 2**bits. Inside the range the error is within +-LSB/2; a sample beyond
it is clipped to the end code and counted.
"""

from __future__ import annotations

from dataclasses import dataclass, field
import os

import control
import numpy as np
import scipy.signal

from trussid.plid.data import IOData
from trussid.plid.errors import DataError
from trussid.plid.kernel_common import state_sequence
from trussid.plid.stability import require_stable

EXCITATIONS = ("white", "prbs", "chirp", "multisine")


# --------------------------------------------------------------------------- excitation


def _band(band, fs: float) -> tuple[float, float]:
    nyq = fs / 2
    if band is None:
        return 0.0, nyq
    lo, hi = (float(b) for b in band)
    if not (0 <= lo < hi <= nyq * (1 + 1e-12)):
        raise DataError(f"excitation band ({lo:g}, {hi:g}) Hz must satisfy "
                        f"0 <= low < high <= fs/2 = {nyq:g} Hz")
    return lo, min(hi, nyq)


def excitation(kind: str, n_samples: int, n_channels: int = 1, fs: float = 1.0,
               rms: float | np.ndarray = 1.0, band=None, seed=None) -> np.ndarray:
    """Excitation signals, one independent column per channel.

    Parameters
    ----------
    kind : {"white", "prbs", "chirp", "multisine"}
        ``white``: Gaussian white noise; with a band, its FFT is zeroed outside the band
        (an ideal band-pass, exact on the record). ``prbs``: a maximum-length binary sequence
        of +-rms, each bit held ``max(1, floor(0.4 fs / f_high))`` samples so that the
        spectrum stays within 2.4 dB of flat up to the band's upper edge (the lower edge is
        ignored: a PRBS is flat down to 1/period). ``chirp``: a linear sweep from the band's
        lower to upper edge over the record with a seeded random start phase (channel j
        starts j N/m samples later, circularly, so channels are not identical).
        ``multisine``: all FFT lines of the record inside the band, equal amplitude,
        independent uniformly random phases per channel.
    n_samples, n_channels : int
        Record length N and number of channels m.
    fs : float
        Sampling frequency [Hz].
    rms : float or array of m floats
        RMS of each channel [input units].
    band : (float, float), optional
        Frequency band [Hz]; default (0, fs/2).
    seed : int or numpy Generator, optional
        Reproducibility: the same seed gives the same signal.

    Returns
    -------
    ndarray, shape (N, m)

    Examples
    --------
    >>> from trussid.plid import excitation
    >>> u = excitation("white", 8000, n_channels=3, fs=1600.0, rms=2.5, band=(0.0, 400.0), seed=3)
    >>> u.shape
    (8000, 3)
    >>> print(u.std(axis=0).round(3))             # [V], exactly the RMS asked for
    [2.5 2.5 2.5]
    """
    if kind not in EXCITATIONS:
        raise DataError(f"unknown excitation '{kind}' (use {', '.join(EXCITATIONS)})")
    n, m = int(n_samples), int(n_channels)
    if n < 2:
        raise DataError(f"need at least 2 samples, got {n}")
    if m < 1:
        raise DataError(f"need at least 1 channel, got {m}")
    if not (np.isfinite(fs) and fs > 0):
        raise DataError(f"fs must be a positive number of Hz, got {fs}")
    rms = np.broadcast_to(np.asarray(rms, dtype=float), (m,))
    if np.any(~np.isfinite(rms)) or np.any(rms <= 0):
        raise DataError(f"excitation rms must be positive, got {rms.tolist()}")
    lo, hi = _band(band, fs)
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, 1 / fs)
    inband = (f >= lo) & (f <= hi)
    if kind in ("white", "multisine") and band is not None and not inband[1:].any():
        raise DataError(f"band ({lo:g}, {hi:g}) Hz holds no frequency line of a {n}-sample "
                        f"record (resolution {fs / n:g} Hz)")
    if kind == "white":
        x = rng.standard_normal((n, m))
        if band is not None:
            X = np.fft.rfft(x, axis=0)
            X[~inband] = 0
            x = np.fft.irfft(X, n, axis=0)
    elif kind == "multisine":
        lines = np.flatnonzero(inband & (f > 0))
        X = np.zeros((f.size, m), complex)
        X[lines] = np.exp(2j * np.pi * rng.random((lines.size, m)))
        x = np.fft.irfft(X, n, axis=0)
    elif kind == "prbs":
        hold = max(1, int(np.floor(0.4 * fs / hi))) if hi < fs / 2 else 1
        bits_needed = int(np.ceil(n / hold))
        nbits = int(np.clip(np.ceil(np.log2(bits_needed + 1)), 4, 24))
        x = np.empty((n, m))
        for j in range(m):  # loop over channels only; each gets its own register state
            state = rng.integers(0, 2, nbits)
            state[rng.integers(nbits)] = 1  # the all-zero state is the one forbidden state
            seq = scipy.signal.max_len_seq(nbits, state=state, length=bits_needed)[0]
            x[:, j] = np.repeat(2.0 * seq - 1.0, hold)[:n]
    else:  # chirp
        t = np.arange(n) / fs
        phase = rng.uniform(0, 360, m)
        x = np.column_stack([
            np.roll(scipy.signal.chirp(t, f0=lo, t1=t[-1], f1=hi, method="linear",
                                       phi=phase[j]), j * n // m) for j in range(m)])
    x = x - x.mean(axis=0) if kind in ("white",) else x
    scale = np.sqrt(np.mean(x**2, axis=0))
    if np.any(scale == 0):
        raise DataError("excitation came out identically zero; widen the band or lengthen "
                        "the record")
    return x * (rms / scale)


# --------------------------------------------------------------------------- converters


def quantize(x: np.ndarray, bits: int, full_scale: float):
    """Bipolar mid-tread quantisation with clipping, as an ideal converter does it.

    Parameters
    ----------
    x : ndarray, shape (N, k) or (N,)
        Signal [V].
    bits : int
        Converter resolution (1 .. 32).
    full_scale : float or array of k floats
        The range is +-full_scale [V] (per channel if an array); LSB = 2 full_scale / 2**bits.

    Returns
    -------
    xq : ndarray
        Quantised signal (same shape).
    clipped : ndarray of int, shape (k,) (or scalar for 1-D x)
        Samples per channel that fell beyond the last code by more than LSB/2 and were
        clipped.

    Examples
    --------
    A 12-bit +-10 V converter: LSB 4.88 mV, codes rounded to the nearest, beyond full scale clipped:

    >>> import numpy as np
    >>> from trussid.plid.experiment import lsb, quantize
    >>> print(f"{1e3 * lsb(12, 10.0):.4f} mV")
    4.8828 mV
    >>> xq, clipped = quantize(np.array([0.0012, 0.0049, -0.0074, 12.0]), bits=12, full_scale=10.0)
    >>> print(np.round(xq / lsb(12, 10.0), 3), clipped)
    [   0.    1.   -2. 2047.] 1
    """
    bits = int(bits)
    if not 1 <= bits <= 32:
        raise DataError(f"converter bits must be 1..32, got {bits}")
    fsv = np.asarray(full_scale, dtype=float)
    if fsv.ndim > 1 or np.any(~np.isfinite(fsv)) or np.any(fsv <= 0):
        raise DataError(f"converter full scale must be positive volts, got {full_scale}")
    lsb = 2.0 * fsv / 2**bits
    codes = np.round(np.asarray(x, dtype=float) / lsb)
    lo, hi = -(2 ** (bits - 1)), 2 ** (bits - 1) - 1
    over = (codes < lo) | (codes > hi)
    return np.clip(codes, lo, hi) * lsb, over.sum(axis=0)


def lsb(bits: int, full_scale):
    """Size of one least significant bit [V] of a +-full_scale converter (per channel if
    ``full_scale`` is an array)."""
    return 2.0 * np.asarray(full_scale, dtype=float) / 2**int(bits)


def _lsb_report(bits, full_scale):
    value = lsb(bits, full_scale)
    return float(value) if value.ndim == 0 else value.tolist()


# --------------------------------------------------------------------------- simulation


def simulate(plant: control.StateSpace, u: np.ndarray, x0=None) -> np.ndarray:
    """Response of a discrete ``plant`` to inputs ``u`` (N x m) from x0 (default 0); (N x p).

    A plain state recursion with ``B u`` and the output map applied to whole arrays:
    ``control.forced_response`` (scipy's ``dlsim``) does the same recursion with two
    products and more Python work per sample, about 10x slower, and identification
    scores many candidate models with it.

    Examples
    --------
    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import simulate
    >>> G = control.ss([[0.5]], [[1.0]], [[2.0]], [[0.0]], 1.0)   # x' = 0.5 x + u, y = 2 x
    >>> simulate(G, np.ones((4, 1))).ravel().tolist()
    [0.0, 2.0, 3.0, 3.5]
    """
    if not control.isdtime(plant, strict=True):
        raise DataError("the plant must be discrete-time (dt > 0); discretise it first")
    u = np.asarray(u, dtype=float)
    u = u[:, None] if u.ndim == 1 else u
    if u.shape[1] != plant.ninputs:
        raise DataError(f"plant has {plant.ninputs} inputs but the input data has "
                        f"{u.shape[1]} columns")
    A, B, C, D = (np.asarray(M, dtype=float) for M in (plant.A, plant.B, plant.C, plant.D))
    n = A.shape[0]
    x = np.zeros(n) if x0 is None else np.broadcast_to(np.asarray(x0, float), (n,)).copy()
    X = state_sequence(A, u @ B.T, x)
    return X @ C.T + u @ D.T


@dataclass
class Experiment:
    """Result of :func:`run_experiment`.

    Attributes
    ----------
    data : IOData
        Recorded inputs (D/A output) and measured outputs (A/D output), ``y_clean`` set.
    y_clean : ndarray, shape (N, p)
        Plant response to the recorded inputs, without any noise or A/D effect.
    clipping : dict
        ``{"dac": [count per input], "adc": [count per output]}`` samples clipped.
    sensor_noise_rms, input_noise_rms : ndarray
        Noise RMS used per output / input channel [channel units].
    lsb : dict
        ``{"dac": V or None, "adc": V or None}`` converter resolution.
    """

    data: IOData
    y_clean: np.ndarray
    clipping: dict = field(default_factory=dict)
    sensor_noise_rms: np.ndarray | None = None
    input_noise_rms: np.ndarray | None = None
    lsb: dict = field(default_factory=dict)

    @property
    def clipped_total(self) -> int:
        return int(sum(sum(v) for v in self.clipping.values()))


def experiment_memory_bytes(plant: control.StateSpace, n_samples: int) -> int:
    """Peak memory [bytes] :func:`run_experiment` needs, roughly, for ``n_samples``.

    ``control.forced_response`` keeps the whole state trajectory (n_states x N doubles) and
    its time and output arrays; the experiment holds about ten N x (m + p) arrays besides
    (excitation, quantised and noisy copies, ``y_clean``).
    """
    n, m, p = plant.nstates, plant.ninputs, plant.noutputs
    return int(8 * n_samples * (2 * n + 2 + 10 * (m + p)))


def available_memory_bytes() -> int | None:
    """Memory the system can still give this process [bytes] (Linux ``MemAvailable``), or
    None when it cannot be told."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def check_memory(plant: control.StateSpace, n_samples: int, available: int | None = None):
    """Refuse (DataError) a record whose simulation would not fit in memory.

    Parameters
    ----------
    plant : control.StateSpace
    n_samples : int
    available : int, optional
        Bytes available (default :func:`available_memory_bytes`).
    """
    need = experiment_memory_bytes(plant, n_samples)
    have = available_memory_bytes() if available is None else available
    if have is not None and need > have:
        raise DataError(
            f"{n_samples} samples of a {plant.nstates}-state plant need about "
            f"{need / 2**30:.3g} GiB of memory, but {have / 2**30:.3g} GiB are available; "
            f"use at most {int(have / need * n_samples):d} samples")


def _per_channel(value, count: int, what: str) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (count,)).copy()
    if np.any(~np.isfinite(arr)) or np.any(arr < 0):
        raise DataError(f"{what} must be finite and non-negative, got {arr.tolist()}")
    return arr


def run_experiment(plant: control.StateSpace, n_samples: int, excitation_kind: str = "white",
                   rms=1.0, band=None, seed=None, u=None, snr_db=None, sensor_noise_rms=None,
                   input_noise_rms=0.0, dac_bits=None, adc_bits=None, dac_full_scale=None,
                   adc_full_scale=None, auto_range=4.0, input_names=None,
                   output_names=None) -> Experiment:
    """Simulate an identification experiment on a discrete plant (see the module docstring).

    Parameters
    ----------
    plant : control.StateSpace
        Discrete (dt > 0), any size.
    n_samples : int
        Record length N (ignored when ``u`` is given).
    excitation_kind, rms, band : see :func:`excitation`.
    seed : int, optional
        One seed drives excitation and all noises (independent streams), so runs repeat.
    u : ndarray (N, m), optional
        Commanded input instead of a generated excitation.
    snr_db : float or array of p floats, optional
        Sensor noise so that RMS(y_phys_j) / RMS(noise_j) = 10**(snr_db/20) per output.
    sensor_noise_rms : float or array of p floats, optional
        Sensor noise RMS directly [output units] (exclusive with ``snr_db``).
    input_noise_rms : float or array of m floats
        Noise added between the recorded input and the plant [input units].
    dac_bits, adc_bits : int, optional
        Converter resolutions; None means no quantisation (and no clipping).
    dac_full_scale, adc_full_scale : float or array (per channel)
        Converter ranges +-V, required with ``dac_bits``/``adc_bits`` (a lab's numbers have
        no default here: they come from the caller's lab). ``adc_full_scale="auto"`` ranges each output channel so that
        +-full scale is +-``auto_range`` times its measured RMS (as a lab sets amplifier
        gains; with 4, a Gaussian signal clips in 6e-5 of the samples and a 12-bit
        converter's quantisation noise is 65 dB below the signal).
    auto_range : float
        See ``adc_full_scale``.
    input_names, output_names : sequence of str, optional
        Channel names for the data.

    Returns
    -------
    Experiment
    """
    if not isinstance(plant, control.StateSpace):
        raise DataError("the plant must be a control.StateSpace")
    if not control.isdtime(plant, strict=True):
        raise DataError("the plant must be discrete-time (dt > 0); discretise it first")
    if snr_db is not None and sensor_noise_rms is not None:
        raise DataError("give either snr_db or sensor_noise_rms, not both")
    for which, bits, full in (("dac", dac_bits, dac_full_scale), ("adc", adc_bits, adc_full_scale)):
        if bits is not None and full is None:
            raise DataError(f"{which}_bits={bits} needs {which}_full_scale, the converter's "
                            "range +-V")

    require_stable(plant, "the plant", "a simulation of it diverges")
    fs = 1.0 / plant.dt
    m, p = plant.ninputs, plant.noutputs
    streams = np.random.default_rng(seed).spawn(3)
    if u is None:
        n = int(n_samples)
        check_memory(plant, n)
        command = excitation(excitation_kind, n, m, fs, rms, band, streams[0])
    else:
        command = np.asarray(u, dtype=float)
        command = command[:, None] if command.ndim == 1 else command
        if command.shape[1] != m:
            raise DataError(f"plant has {m} inputs but u has {command.shape[1]} columns")
        n = command.shape[0]
    clipping = {}
    lsbs = {"dac": None, "adc": None}
    if dac_bits is not None:
        u_rec, clipping["dac"] = quantize(command, dac_bits, dac_full_scale)
        lsbs["dac"] = _lsb_report(dac_bits, dac_full_scale)
    else:
        u_rec, clipping["dac"] = command, np.zeros(m, int)
    in_rms = _per_channel(input_noise_rms, m, "input noise rms")
    u_plant = u_rec + streams[1].standard_normal((n, m)) * in_rms if in_rms.any() else u_rec
    y_clean = simulate(plant, u_rec)
    y_phys = simulate(plant, u_plant) if in_rms.any() else y_clean
    if snr_db is not None:
        snr = np.broadcast_to(np.asarray(snr_db, dtype=float), (p,))
        if np.any(~np.isfinite(snr)):
            raise DataError(f"snr_db must be finite, got {snr.tolist()}")
        noise_rms = np.sqrt(np.mean(y_phys**2, axis=0)) / 10 ** (snr / 20)
    elif sensor_noise_rms is not None:
        noise_rms = _per_channel(sensor_noise_rms, p, "sensor noise rms")
    else:
        noise_rms = np.zeros(p)
    y = y_phys + streams[2].standard_normal((n, p)) * noise_rms
    if adc_bits is not None:
        if isinstance(adc_full_scale, str):
            if adc_full_scale != "auto":
                raise DataError(f"adc_full_scale must be volts or 'auto', got "
                                f"'{adc_full_scale}'")
            # A lab sets each sensor's amplifier so that the signal fills the range; here
            # +-full scale spans +-auto_range RMS of the measured signal.
            adc_full_scale = auto_range * np.sqrt(np.mean(y**2, axis=0))
            if np.any(adc_full_scale <= 0):
                raise DataError("an output is identically zero; it cannot be auto-ranged")
        y, clipping["adc"] = quantize(y, adc_bits, adc_full_scale)
        lsbs["adc"] = _lsb_report(adc_bits, adc_full_scale)
    else:
        clipping["adc"] = np.zeros(p, int)
    clipping = {k: [int(c) for c in np.atleast_1d(v)] for k, v in clipping.items()}
    data = IOData(u=u_rec, y=y, fs=fs, input_names=list(input_names or []),
                  output_names=list(output_names or []), y_clean=y_clean)
    return Experiment(data=data, y_clean=y_clean, clipping=clipping,
                      sensor_noise_rms=noise_rms, input_noise_rms=in_rms, lsb=lsbs)


__all__ = ["excitation", "quantize", "lsb", "simulate", "run_experiment", "Experiment",
           "EXCITATIONS", "experiment_memory_bytes", "available_memory_bytes", "check_memory"]
