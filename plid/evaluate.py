"""The one evaluator of an identified model: ``compare(model, ...) -> Comparison``.

``trussid compare``, the demo report and the benchmarks all call :func:`compare`, so a
figure means the same thing wherever it is printed: one burn-in rule
(:func:`trussid.plid.metrics.prediction_burn_in`), one frequency-response evaluator
(:func:`trussid.plid.frf.frequency_response`), one frequency grid (:func:`frf_grid`), the
definitions of :mod:`trussid.plid.metrics`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import control
import numpy as np

from trussid.plid.errors import DataError
from trussid.plid.frf import FRF, frequency_response
from trussid.plid.metrics import (PoleMatch, compare_poles, default_noise_covariances, frf_error,
                                  modal_parameters, prediction_burn_in, prediction_ratio_db,
                                  predictor_gain, simulation_fit,
                                  FRFScore, PredictionScore, SimulationScore)


@dataclass(frozen=True)
class Comparison:
    """Everything known about how well ``model`` matches a reference plant and/or a record.

    Attributes
    ----------
    states, inputs, outputs : int
    unstable_poles : int
        Poles on or outside the unit circle (an unstable model cannot be simulated).
    prediction : PredictionScore or None
        On the record (when one was given).
    simulation : SimulationScore or None
    frf : FRFScore or None
        Against the reference plant (when one was given).
    frf_vs_estimate : FRFScore or None
        Against a nonparametric estimate (H1) of the record.
    poles : list of PoleMatch
        Identified poles matched to the reference plant's
        (:func:`.metrics.compare_poles`), or the model's own poles (true fields None) when
        there is no plant.
    """

    states: int
    inputs: int
    outputs: int
    unstable_poles: int
    prediction: PredictionScore | None = None
    simulation: SimulationScore | None = None
    frf: FRFScore | None = None
    frf_vs_estimate: FRFScore | None = None
    poles: list = field(default_factory=list)

    @property
    def stable(self) -> bool:
        return self.unstable_poles == 0


def frf_grid(reference: control.StateSpace, band, n_freq: int = 400) -> np.ndarray:
    """A linear grid over ``band`` [Hz] plus the reference's modal frequencies inside it, so
    that no resonance peak is stepped over (as :func:`.metrics.frf_error` builds it)."""
    lo, hi = (float(b) for b in band)
    fr, _, _ = modal_parameters(reference)
    grid = np.linspace(max(lo, 1e-9 * hi), hi * (1 - 1e-9), n_freq)
    return np.unique(np.concatenate([grid, fr[(fr > lo) & (fr < hi)]]))


@dataclass(frozen=True)
class Band:
    """A frequency band [Hz] and where it came from (printed with the figures over it)."""

    lo: float
    hi: float
    source: str

    def as_tuple(self) -> tuple[float, float]:
        return (self.lo, self.hi)


def default_band(fs: float, plant: control.StateSpace | None = None, u=None, *,
                 margin: float = 1.25, level_db: float = -20.0) -> Band:
    """The band a headline frequency-response error is measured over, when none is given.

    From 0 Hz to Nyquist the maximum error sits at the plant's deep anti-resonances and
    beyond its modes (a reasonable 24-state model of the testbed read "max 207.5 dB"), so:

    - with a plant: its modes' band, from the lowest to the highest modal frequency below
      Nyquist (poles with damping under 0.5) widened by ``margin`` each side;
    - else with an input record ``u``: the excited band, where the input's power spectral
      density (Welch, summed over inputs) is within ``level_db`` of its peak;
    - else 0 Hz to Nyquist.

    Parameters
    ----------
    fs : float
        Sampling frequency [Hz].
    plant : control.StateSpace, optional
    u : array (N, m), optional
    margin : float
        Factor the modes' band is widened by at each end.
    level_db : float
        Level under the input spectrum's peak that bounds the excited band [dB].

    Returns
    -------
    Band
    """
    import scipy.signal

    nyq = 0.5 * fs
    if plant is not None and plant.nstates:
        fr, zeta, _ = modal_parameters(plant)
        keep = (fr > 0) & (zeta < 0.5) & (fr < nyq)
        if keep.any():
            lo, hi = fr[keep].min() / margin, min(nyq, fr[keep].max() * margin)
            return Band(float(lo), float(hi),
                        f"the plant's modes ({fr[keep].min():.4g}-{fr[keep].max():.4g} Hz) "
                        f"widened by {margin:g}x")
    if u is not None:
        u = np.asarray(u, float).reshape(len(u), -1)
        f, P = scipy.signal.welch(u - u.mean(0), fs=fs, axis=0,
                                  nperseg=int(min(len(u), 1024)))
        psd = P.sum(axis=1)
        on = np.flatnonzero(psd >= psd.max() * 10 ** (level_db / 10))
        if on.size and psd.max() > 0:
            lo, hi = float(f[on[0]]), float(f[on[-1]])
            if hi > lo:
                return Band(lo, hi, f"the excited band (input spectrum within "
                                    f"{-level_db:g} dB of its peak)")
    return Band(0.0, nyq, "0 Hz to Nyquist")


def _frf_score(model, reference, band, label, n_freq) -> FRFScore:
    if isinstance(reference, FRF):
        e = frf_error(model, reference, band)
    else:
        f = frf_grid(reference, band, n_freq)
        e = frf_error(model, FRF(f, frequency_response(reference, f)), band)
    return replace(e, reference=label)


def compare(model: control.StateSpace, plant: control.StateSpace | None = None, *,
            u=None, y=None, y_clean=None, K=None, gain: str = "given", estimate: FRF | None = None,
            band=None, n_freq: int = 400) -> Comparison:
    """Compare an identified discrete model with a reference plant and/or a record.

    Parameters
    ----------
    model : control.StateSpace
        The identified model (discrete).
    plant : control.StateSpace, optional
        The true plant, discrete at the model's rate, with the model's inputs and outputs:
        gives the FRF error and the matched poles.
    u, y : array (N, m), (N, p), optional
        A record (validation data, never the identification record for a fair score):
        gives the one-step prediction ratio (with ``K``) and the simulation fit.
    y_clean : array (N, p), optional
        The record's noise-free outputs, when known (simulated data): the simulation fit is
        taken against them, otherwise against ``y``.
    K : array (n, p), optional
        One-step predictor gain; default: the steady-state gain of default noise
        covariances (:func:`.metrics.one_step_predict`).
    gain : str
        Where ``K`` came from, for the report.
    estimate : FRF, optional
        A nonparametric estimate (H1 of the record) to compare the model with.
    band : (float, float), optional
        FRF band [Hz]; default 0 to Nyquist.
    n_freq : int
        Size of the FRF grid against the plant.

    Returns
    -------
    Comparison

    Examples
    --------
    A model against the plant it came from: simulation fit [dB] on the record, FRF error
    against the truth, and each true pole paired with the model's:

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import excitation, identify, simulate
    >>> from trussid.plid.evaluate import compare
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.04 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> plant = control.c2d(control.ss(G), 1e-3)
    >>> u = excitation("white", 2000, fs=1000.0, seed=1)
    >>> y = simulate(plant, u)
    >>> model = identify(u, y, order=4, dt=1e-3, progress=False).model
    >>> c = compare(model, plant, u=u, y=y)
    >>> c.states, c.unstable_poles, len(c.poles)
    (4, 0, 2)
    >>> c.simulation.overall > 100, c.frf.max_db < 1e-5    # [dB]: exact to round-off
    (True, True)
    """
    if not control.isdtime(model, strict=True):
        raise DataError("compare needs a discrete (identified) model, dt > 0")
    nyq = 0.5 / model.dt
    band = (0.0, nyq) if band is None else tuple(float(b) for b in band)
    unstable = int(np.sum(np.abs(np.linalg.eigvals(np.asarray(model.A))) >= 1)) \
        if model.nstates else 0
    prediction = simulation = frf = frf_est = None
    if u is not None and y is not None:
        u = np.asarray(u, dtype=float).reshape(len(u), -1)
        y = np.asarray(y, dtype=float).reshape(len(y), -1)
        if K is None:  # the default gain, made here so that the burn-in is its own
            K = predictor_gain(model, *default_noise_covariances(model, u, y))
            gain = "steady state, default noise"
        with np.errstate(all="ignore"):  # an unstable model overflows; it is reported as such
            skip = prediction_burn_in(model, K, u.shape[0])
            prediction = replace(prediction_ratio_db(model, u, y, K=K, skip=skip), gain=gain)
            clean = y_clean is not None
            simulation = replace(simulation_fit(model, u, y_clean if clean else y, skip=skip),
                                 against="noise-free outputs" if clean
                                 else "measured (noisy) outputs")
    if plant is not None:
        if not control.isdtime(plant, strict=True):
            plant = control.c2d(plant, model.dt, "zoh")
        elif abs(plant.dt - model.dt) > 1e-9 * model.dt:
            raise DataError(f"the model samples at {1 / model.dt:g} Hz but the plant at "
                            f"{1 / plant.dt:g} Hz")
        frf = _frf_score(model, plant, band, "plant", n_freq)
        poles = compare_poles(model, plant)
    else:
        fr, z, _ = modal_parameters(model)
        poles = [PoleMatch(frequency_hz=float(a), damping=float(b)) for a, b in zip(fr, z)]
    if estimate is not None:
        frf_est = _frf_score(model, estimate, band,
                             f"H1 ({estimate.n_averages} averages)" if estimate.n_averages else "estimate",
                             n_freq)
    return Comparison(int(model.nstates), int(model.ninputs), int(model.noutputs), unstable,
                      prediction, simulation, frf, frf_est, poles)


__all__ = ["PoleMatch", "Comparison", "PredictionScore", "SimulationScore", "FRFScore", "compare", "frf_grid"]
