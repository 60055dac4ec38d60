"""The main job, end to end: the simulated identification campaign on the default testbed.

Plain functions over plain data, in the order ``trussid demo`` runs them::

    settings = demo_settings(quick)
    tp       = build_plant(settings)                     default testbed -> modes -> plant
    exps     = run_experiments(tp.discrete, settings)    identification + validation records
    fit      = identify_model(u, y, order, dt)           PLID (the one switchable call)
    metrics  = evaluate(fit, truth, validation, h1)      prediction, FRF, poles
    write_report(out, ...)                               report.md, PNGs, summary.json, files

The experiment reproduces the thesis's campaign (``shared/docs/testbed.md``): one SIMO
model per actuator channel, from a record in which only that channel is driven (1 input,
3 accelerometers, 30 states), and one MIMO model from a record with all three channels
driven by independent signals (3 x 3, ``mimo_order`` states).

Signal chain of every record (:func:`trussid.plid.experiment.run_experiment`):

- excitation: Gaussian white noise band-limited to 0-400 Hz (the band holding the modes
  the thesis measured; "nothing significant 350-450 Hz"), 2.5 V RMS per driven channel at
  the 12-bit +-10 V D/A, i.e. a crest factor of 4: a Gaussian sample exceeds 4 sigma with
  probability 6e-5, so the D/A clips rarely (the counts are reported);
- the plant: D/A volts -> smoothing filter -> amplifier -> PZT -> structure ->
  accelerometer -> signal conditioner (``tb.accelerometers.conditioning_gain``) -> A/D
  volts, discretised by ZOH at 1600 Hz (:func:`trussid.testbed.plant.testbed_plant`);
- sensor noise: white, ``sensor_noise_g`` RMS referred to the accelerometer [g] over the
  0-800 Hz band (default 10 ug, about 0.35 ug/sqrt(Hz): a low-noise piezoelectric
  accelerometer with its charge amplifier). It is amplified with the signal by the
  conditioner, so it is independent of the gain setting. In the MIMO record it lies
  59-64 dB under the signals, near the 12-bit quantisation noise (62-67 dB), as the
  thesis reports ("the 12-bit converters give about 60 dB"); in a SIMO record the two
  accelerometers away from the driven vertex get only 38-50 dB;
- conditioner range: the nominal conditioning gain suits the MIMO record (all channels
  driven). Before each experiment the lab sets each sensor's gain in 1-2-5 steps from x0.5
  up so that its RMS is at most ``range_target`` of the A/D range, from a trial run of the
  same length (:func:`conditioner_steps`); identification and validation records of one
  experiment use the same setting. (With the nominal gain kept wherever the signal was
  strong, the driven outputs of the channel-2 and -3 SIMO records reached 0.27-0.33 of full
  scale and clipped 9-11 samples of 8000, each clipped sample a large prediction error.) In a SIMO record the two accelerometers away from the
  driven vertex see signals some 20 dB weaker; without this step they would be recorded
  with a few dozen LSB. Recorded outputs stay in the plant's units (volts at the nominal
  conditioning gain): only the A/D range seen by each channel changes.
- 12-bit A/D quantisation with clipping counted.

Identification data and validation data are separate records with different seeds.
"""

from __future__ import annotations

import json
import math
import time
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from trussid._util.files import atomic_path

#: Standard gravity [m/s^2], to give sensor noise in g.
G0 = 9.80665


# --------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class DemoSettings:
    """Every number of the demo campaign (SI units unless stated).

    Attributes
    ----------
    quick : bool
        The reduced run (``trussid demo --quick``).
    n_identification, n_validation : int
        Samples of each identification and validation record (1600 Hz).
    excitation : str
        Excitation kind (:func:`trussid.plid.experiment.excitation`).
    excitation_rms : float
        RMS of each driven D/A channel [V].
    excitation_band : (float, float)
        Excitation band [Hz].
    sensor_noise_g : float
        Sensor (accelerometer + conditioner) noise RMS referred to the accelerometer [g].
    range_target : float
        Each sensor's conditioner step is the largest 1-2-5 step (x0.5 or more) that keeps
        its RMS at most this fraction of the A/D full scale (a fifth: the lightly damped
        structure's outputs reach 4-5 times their RMS).
    gain_steps : tuple of float
        Conditioner gain steps within one decade (1-2-5).
    simo_channels : tuple of int
        Actuator channels (0-based) that get a SIMO model.
    simo_order, mimo_order : int
        States of the SIMO and MIMO models; multiples of the 3 outputs (the observer form
        gives each output n / 3 states). ``mimo_order`` 0 skips the MIMO model.
    block_rows : tuple of int
        Block rows tried by the N4SID prior of the identification recipe (it keeps the one
        with the smallest output error on the identification data). The recipe's default
        tries 20, 30, 40, 60, 80, which takes most of the run time on the shared machine;
        40 and 80 cover the winners measured on the testbed (80 for SIMO, 60-80 for MIMO).
    frf_band : (float, float)
        Band of the FRF error metrics [Hz] (the thesis's band of interest).
    plot_band : (float, float)
        Frequency range of the Bode overlays [Hz].
    h1_nperseg : int
        Welch segment length of the H1 estimate (resolution fs / nperseg).
    seed : int
        Seed of everything random (each record derives its own).
    """

    quick: bool = False
    n_identification: int = 16000
    n_validation: int = 8000
    excitation: str = "white"
    excitation_rms: float = 2.5
    excitation_band: tuple = (0.0, 400.0)
    sensor_noise_g: float = 10e-6
    range_target: float = 0.2
    gain_steps: tuple = (1.0, 2.0, 5.0)
    simo_channels: tuple = (0, 1, 2)
    simo_order: int = 30
    mimo_order: int = 36
    block_rows: tuple = (40, 80)
    frf_band: tuple = (50.0, 350.0)
    plot_band: tuple = (10.0, 450.0)
    h1_nperseg: int = 1024
    seed: int = 1997


def demo_settings(quick: bool = False, **overrides) -> DemoSettings:
    """The full campaign, or the quick one.

    ``quick`` keeps the SIMO model of channel 1 at the full 30 states and the MIMO model
    at 18 states instead of 36, drops the SIMO models of channels 2 and 3, and uses
    records of 6000 samples (identification) and 4000 (validation) instead of 16000 and
    8000.
    """
    s = DemoSettings()
    if quick:
        s = replace(s, quick=True, n_identification=6000, n_validation=4000,
                    simo_channels=(0,), mimo_order=18, h1_nperseg=512)
    return replace(s, **overrides)


# --------------------------------------------------------------------------- plant


def build_plant(settings: DemoSettings, tb=None):
    """The default testbed's plant at 1600 Hz (:class:`trussid.testbed.plant.TestbedPlant`)."""
    from trussid.testbed.plant import testbed_plant

    return testbed_plant(tb)


def sensor_noise_volts(tb, settings: DemoSettings) -> float:
    """Sensor noise RMS in plant output units (volts at the nominal conditioning gain)."""
    acc = tb.accelerometers
    return settings.sensor_noise_g * G0 * acc.sensitivity * acc.conditioning_gain


# --------------------------------------------------------------------------- experiments


@dataclass
class Record:
    """One simulated record and how it was taken."""

    name: str
    purpose: str                      # "identification" or "validation"
    channels: tuple                   # driven actuator channels (0-based)
    experiment: object                # plid.experiment.Experiment
    gain_steps: list                  # conditioner step per output
    adc_full_scale: list              # A/D range per output, in plant output units [V]
    seed: int

    @property
    def data(self):
        return self.experiment.data


def conditioner_steps(y_rms, full_scale: float, target: float, steps=(1.0, 2.0, 5.0)):
    """Conditioner gain step per channel relative to the nominal gain: the largest 1-2-5
    step from 0.5 up that keeps ``rms * step <= target * full_scale`` (0.5 when even that
    is passed).

    Steps run from 0.5 to 5e4; a channel that is silent gets the largest.
    """
    ladder = np.sort(np.concatenate([np.asarray(steps) * 10.0**k for k in range(-1, 5)]))
    ladder = ladder[ladder >= 0.5]
    out = []
    for r in np.atleast_1d(y_rms):
        ok = ladder[ladder * r <= target * full_scale] if r > 0 else ladder
        out.append(float(ok.max() if ok.size else ladder.min()))
    return out


def _drive(settings: DemoSettings, n: int, channels, m: int, seed: int) -> np.ndarray:
    from trussid.plid.experiment import excitation

    u = np.zeros((n, m))
    u[:, list(channels)] = excitation(settings.excitation, n, len(channels), 1600.0,
                                      settings.excitation_rms, settings.excitation_band, seed)
    return u


def range_conditioners(plant, settings: DemoSettings, channels, seed: int, n_samples: int,
                       noise_v: float, full_scale: float = 10.0) -> list:
    """Conditioner steps from a noise-free trial run of the experiment (its own seed)."""
    from trussid.plid.experiment import simulate

    trial = _drive(settings, n_samples, channels, plant.ninputs, seed)
    rms = np.sqrt(np.mean(simulate(plant, trial) ** 2, axis=0) + noise_v**2)
    return conditioner_steps(rms, full_scale, settings.range_target, settings.gain_steps)


def take_record(plant, settings: DemoSettings, name: str, purpose: str, channels, seed: int,
                n_samples: int, noise_v: float, steps, full_scale: float = 10.0,
                bits: int = 12) -> Record:
    """One record with the conditioners at ``steps`` (see the module docstring)."""
    from trussid.plid.experiment import run_experiment

    m = plant.ninputs
    adc_fs = [full_scale / g for g in steps]
    u = _drive(settings, n_samples, channels, m, seed)
    exp = run_experiment(plant, n_samples, u=u, seed=seed + 1, sensor_noise_rms=noise_v,
                         dac_bits=bits, adc_bits=bits, dac_full_scale=full_scale,
                         adc_full_scale=np.asarray(adc_fs),
                         input_names=list(plant.input_labels),
                         output_names=list(plant.output_labels))
    return Record(name, purpose, tuple(channels), exp, steps, adc_fs, seed)


def run_experiments(tp, settings: DemoSettings, progress=None) -> dict:
    """All records of the campaign: ``{model name: (identification, validation)}``.

    Model names are ``simo_ch<k>`` (k = 1..3) and ``mimo``.
    """
    plant = tp.discrete
    tb = tp.tbm.testbed
    noise_v = sensor_noise_volts(tb, settings)
    plan = [(f"simo_ch{c + 1}", (c,)) for c in settings.simo_channels]
    if settings.mimo_order:
        plan.append(("mimo", tuple(range(plant.ninputs))))
    out = {}
    for k, (name, channels) in enumerate(plan):
        base = settings.seed + 1000 * k
        steps = range_conditioners(plant, settings, channels, base + 250,
                                   settings.n_identification, noise_v, tb.daq.full_scale)
        rid = take_record(plant, settings, name, "identification", channels, base,
                          settings.n_identification, noise_v, steps, tb.daq.full_scale,
                          tb.daq.bits)
        rval = take_record(plant, settings, name, "validation", channels, base + 500,
                           settings.n_validation, noise_v, steps, tb.daq.full_scale,
                           tb.daq.bits)
        out[name] = (rid, rval)
        if progress:
            progress(f"recorded {name}: {rid.data.n_samples} + {rval.data.n_samples} samples")
    return out


# --------------------------------------------------------------------------- identification


@dataclass
class Identified:
    """An identified model with what the report needs from the identification."""

    model: object                      # discrete control.StateSpace, D = 0
    K: np.ndarray                      # one-step predictor gain used for prediction
    K_source: str
    seconds: float
    method: str
    innovations: np.ndarray            # (N, p) of the (last) PLID pass
    theta_history: np.ndarray          # (k, q)
    history_index: np.ndarray          # (k,)
    info: dict = field(default_factory=dict)


def identify_model(u, y, order: int, dt: float, *, block_rows=None, via=None,
                   progress: bool = False, log=None) -> Identified:
    """Identify an order-``order`` model from one record: the one switchable call.

    Runs the project's identification recipe for under-modelled structures,
    :func:`trussid.plid.multipass.identify_reduced`: the PLID recipe :func:`trussid.plid.multipass.identify`
    (an N4SID prior with D = 0 in a rotation observer basis, refined by PLID) at ``order``
    and at the higher orders ``via``, the latter reduced to ``order`` by input-weighted
    balanced truncation and refined by PLID; the candidate with the best one-step
    prediction on the identification record wins, with its predictor gain
    (:func:`trussid.plid.metrics.choose_predictor`). Measured in
    ``benchmarks/results/plid_thesis.md``. The parameter history of the winning PLID pass is
    kept for the convergence plot.
    """
    from trussid.plid.multipass import identify_reduced

    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        idn = identify_reduced(u, y, order, dt, via=via, progress=progress, log=log,
                               block_rows=None if block_rows is None else list(block_rows))
    res = idn.result
    model = idn.model
    chosen = idn.info.get("chosen", "")
    stab = {"applied": chosen.endswith("stabilised"), "reflected_poles": 0}
    if stab["applied"]:
        # identify_reduced reflected the candidate's unstable poles in (plid.stabilise).
        stab["reflected_poles"] = int(np.sum(np.abs(np.linalg.eigvals(
            np.asarray(res.model.A))) > 1))
    if np.max(np.abs(np.linalg.eigvals(np.asarray(model.A)))) >= 1:
        # No stable candidate (none was measured on the testbed): reflect the poles outside
        # the unit circle in (plid.stabilise keeps the magnitude response) so that the model
        # can be simulated, and choose its predictor afresh.
        from trussid.plid.stability import stabilise

        st = stabilise(model)
        model = st.model
        stab = {"applied": bool(st.applied), "reflected_poles": int(np.size(st.reflected))}
        K, K_source, kinfo = choose_predictor(model, u, y, None)
    else:
        K, kinfo = idn.K, idn.info.get("predictor") or {}
        K_source = kinfo.get("chosen", "")
    hist, hidx = res.theta_history, res.history_index
    if hist.shape[0] < 2 and idn.prior is not None:
        # The recipe ran without a parameter history: repeat the winner's last PLID pass
        # with one (same basis, prior and settings, so the same estimate) for the plot.
        hist, hidx = _history_of_last_pass(idn, u, y, res.model.nstates, dt)
    info = {"recipe": "trussid.plid.multipass.identify_reduced", "start": idn.start,
            "stabilised": stab, "basis": getattr(idn.basis, "name", ""),
            "R": np.asarray(idn.R).tolist(), "predictor": kinfo,
            **{k: v for k, v in idn.info.items() if k not in ("passes", "predictor")},
            "passes": idn.info.get("passes", [])}
    method = f"PLID ({res.form} form, {idn.start} start; {chosen})"
    return Identified(model, K, K_source, time.perf_counter() - t0, method,
                      res.innovations, hist, hidx, info)


def _history_of_last_pass(idn, u, y, order, dt):
    from trussid.plid.estimator import PLID

    last = (idn.info.get("passes") or [{}])[-1]
    est = PLID(order, form=idn.result.form, dt=dt, Q=last.get("Q", 0.0), R=idn.R,
               Q_theta=last.get("Q_theta", 0.0), prior=idn.prior,
               prior_theta_var=last.get("prior_theta_var", 1e-4), basis=idn.basis,
               history_every=10, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = est.fit(u, y)
    return r.theta_history, r.history_index


def choose_predictor(model, u, y, res=None):
    """One-step predictor gain for ``model`` chosen on the identification record
    (:func:`trussid.plid.metrics.choose_predictor`), with the estimator's own gain among the
    candidates when ``res`` (its :class:`trussid.plid.estimator.PLIDResult`) belongs to ``model``."""
    from trussid.plid.metrics import choose_predictor as choose

    cands = {}
    if res is not None and getattr(res, "K", None) is not None:
        cands["estimator"] = res.K
    return choose(model, u, y, cands)


# --------------------------------------------------------------------------- evaluation


def fast_frequency_response(sys, f) -> np.ndarray:
    """Frequency response (n_freq, p, m) of a discrete model through its eigendecomposition.

    ``C (zI - A)^-1 B = (C V) diag(1 / (z - lambda)) (V^-1 B)``: O(n) per frequency after one
    eigendecomposition, where python-control solves an n x n system per frequency (10 ms
    each for the 141-state plant on the shared machine). Falls back to
    :func:`trussid.plid.frf.frequency_response` when the eigenvectors are ill-conditioned.
    """
    from trussid.plid.frf import frequency_response

    A, B, C, D = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D))
    f = np.atleast_1d(np.asarray(f, dtype=float))
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) > 1e8:
        return frequency_response(sys, f)
    CV = C @ V
    ViB = np.linalg.solve(V, B)
    z = np.exp(2j * np.pi * f * sys.dt)
    H = np.einsum("ps,fs,sm->fpm", CV, 1.0 / (z[:, None] - lam[None, :]), ViB)
    return H + D[None, :, :]


def _grid(truth, band, n_freq=400):
    """Linear grid over ``band`` plus the truth's modal frequencies inside it (so that no
    resonance peak is stepped over), as :func:`trussid.plid.metrics.frf_error` builds it."""
    from trussid.plid.metrics import modal_parameters

    lo, hi = band
    fr, _, _ = modal_parameters(truth)
    grid = np.linspace(max(lo, 1e-9 * hi), hi * (1 - 1e-9), n_freq)
    return np.unique(np.concatenate([grid, fr[(fr > lo) & (fr < hi)]]))


def _frf_db_deg_error(H, H_ref) -> dict:
    with np.errstate(divide="ignore", invalid="ignore"):
        mag = 20 * np.log10(np.abs(H)) - 20 * np.log10(np.abs(H_ref))
        ph = np.degrees(np.angle(H / H_ref))
    return {"max_db": float(np.max(np.abs(mag))), "rms_db": float(np.sqrt(np.mean(mag**2))),
            "max_deg": float(np.max(np.abs(ph))), "rms_deg": float(np.sqrt(np.mean(ph**2)))}


def prediction_burn_in(model, K, n_samples: int) -> int:
    """Samples left out of the prediction ratio while the predictor forgets x0 = 0.

    Until its slowest pole (of ``A - K C``) has decayed by 60 dB, at least 10 samples per
    state and at most a quarter of the record. (``trussid identify`` uses 10 per state; on
    the 0.25 %-damped testbed the predictor's slowest pole can take 1000 samples.)
    """
    A, C = np.asarray(model.A), np.asarray(model.C)
    rho = float(np.max(np.abs(np.linalg.eigvals(A - np.asarray(K) @ C))))
    k = int(np.ceil(np.log(1e-3) / np.log(rho))) if 0 < rho < 1 else n_samples
    return int(min(max(k, 10 * A.shape[0]), n_samples // 4))


def evaluate(fit: Identified, truth, rid: Record, rval: Record, h1_est, settings: DemoSettings,
             name: str, kind: str) -> dict:
    """All metrics of one model (validation prediction, FRF errors, poles, simulation fit)."""
    with np.errstate(all="ignore"):  # an unstable identified model overflows in simulation
        return _evaluate(fit, truth, rid, rval, h1_est, settings, name, kind)


def _evaluate(fit, truth, rid, rval, h1_est, settings, name, kind):
    from trussid.plid.metrics import (compare_poles, frf_error, one_step_predict, prediction_ratio_db,
                              simulation_fit)

    model = fit.model
    val = rval.data
    cols = list(rid.channels)
    uval = val.u[:, cols]
    skip = prediction_burn_in(model, fit.K, val.n_samples)
    spe = prediction_ratio_db(model, uval, val.y, K=fit.K, skip=skip)
    sim = simulation_fit(model, uval, rval.experiment.y_clean, skip=skip)
    from trussid.plid.frf import FRF

    tcols = truth[:, cols]
    f = _grid(tcols, settings.frf_band)
    fe_true = frf_error(model, FRF(f, fast_frequency_response(tcols, f)), settings.frf_band)
    # H1 was estimated from the driven channels only: already p x len(cols).
    fe_h1 = frf_error(model, h1_est, settings.frf_band)
    keep = (h1_est.f >= settings.frf_band[0]) & (h1_est.f <= settings.frf_band[1])
    h1_true = _frf_db_deg_error(h1_est.H[keep], fast_frequency_response(tcols, h1_est.f[keep]))
    poles = compare_poles(model, tcols)
    in_band = [r for r in poles if r["true_frequency_hz"] is not None
               and settings.frf_band[0] <= r["true_frequency_hz"] <= settings.frf_band[1]]
    unstable = int(np.sum(np.abs(np.linalg.eigvals(np.asarray(model.A))) >= 1))
    y_rms = np.sqrt(np.mean(val.y**2, axis=0))
    return {
        "name": name, "kind": kind, "states": int(model.nstates), "inputs": int(model.ninputs),
        "outputs": int(model.noutputs),
        "input_names": [val.input_names[c] for c in cols], "output_names": list(val.output_names),
        "signal_to_prediction_error_db": spe["overall"],
        "signal_to_prediction_error_db_per_output": spe["per_channel"],
        "signal_to_prediction_error_db_mean_normalised": spe["mean_normalised"],
        "prediction_skip_samples": skip,
        "predictor_gain": fit.K_source,
        "frf_max_error_db": fe_true["max_db"], "frf_rms_error_db": fe_true["rms_db"],
        "frf_max_error_deg": fe_true["max_deg"], "frf_rms_error_deg": fe_true["rms_deg"],
        "frf_error_per_channel": fe_true["per_channel"],
        "frf_band_hz": list(settings.frf_band),
        "frf_error_vs_h1": {k: fe_h1[k] for k in ("max_db", "rms_db", "max_deg", "rms_deg")},
        "h1_error_vs_true": {k: h1_true[k] for k in ("max_db", "rms_db", "max_deg", "rms_deg")},
        "simulation_fit_db": sim["overall_db"],
        "simulation_fit_db_per_output": sim["per_channel_db"],
        "seconds": fit.seconds, "method": fit.method, "unstable_poles": unstable,
        "stabilised": fit.info.get("stabilised", {}),
        "poles": poles,
        "poles_in_band_matched": sum(r["frequency_hz"] is not None for r in in_band),
        "poles_in_band_true": len(in_band),
        "validation_output_rms_v": y_rms.tolist(),
        "identification": _json_info(fit.info),
    }


def _json_info(info):
    try:
        json.dumps(info, default=float)
        return info
    except TypeError:
        return {k: str(v) for k, v in info.items()}


def h1_estimate(record: Record, nperseg: int):
    """H1 estimate from an identification record (driven channels only)."""
    from trussid.plid.frf import h1

    d = record.data
    return h1(d.u[:, list(record.channels)], d.y, d.fs, nperseg=nperseg)


# --------------------------------------------------------------------------- figures


def bode_overlay(truth, h1_est, model, cols, output_names, input_names, band, title):
    """One Bode overlay figure per input column: true plant, H1 estimate, identified model."""
    from trussid.plid.frf import frequency_response
    from trussid.plid.metrics import modal_parameters
    from trussid.plots import bode_figure

    tcols = truth[:, cols]
    f = np.linspace(band[0], band[1], 1500)
    fr, _, _ = modal_parameters(tcols)
    f = np.unique(np.concatenate([f, fr[(fr > band[0]) & (fr < band[1])]]))
    Ht = fast_frequency_response(tcols, f)
    Hm = frequency_response(model, f)
    keep = (h1_est.f >= band[0]) & (h1_est.f <= band[1])
    figs = []
    for j, name in enumerate(input_names):
        curves = [("true plant", f, Ht), (f"H1 estimate ({h1_est.n_averages} averages)",
                                          h1_est.f[keep], h1_est.H[keep]),
                  ("identified model", f, Hm)]
        figs.append(bode_figure(curves, j, name, output_names, title=f"{title}, input {name}"))
    return figs


def pole_zero_figure(model, truth, cols, band, title):
    """z-plane poles and zeros near the unit circle, and a frequency-damping map.

    Zeros are those of the collocated channel (input channel k to accelerometer k), the
    transfer function whose zeros interlace its poles; poles are those of the whole model.
    """
    import control
    import matplotlib.pyplot as plt

    from trussid.plid.metrics import modal_parameters

    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 5.6))
    dt = model.dt
    tcols = truth[:, cols]
    zp_t = np.linalg.eigvals(np.asarray(tcols.A))
    zp_m = np.linalg.eigvals(np.asarray(model.A))
    j = cols[0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        zz_t = np.asarray(control.zeros(control.ss(tcols.A, tcols.B[:, :1], tcols.C[j:j + 1],
                                                   tcols.D[j:j + 1, :1], dt)))
        zz_m = np.asarray(control.zeros(control.ss(model.A, model.B[:, :1], model.C[j:j + 1],
                                                   model.D[j:j + 1, :1], dt)))
    th = np.linspace(0, 2 * np.pi * band[1] * dt, 400)
    ax.plot(np.cos(th), np.sin(th), color="0.6", lw=0.8, label="unit circle (0-%g Hz)" % band[1])
    ax.plot(zp_t.real, zp_t.imag, "o", mfc="none", color="0.35", ms=8, label="true poles")
    ax.plot(zz_t.real, zz_t.imag, "s", mfc="none", color="C2", ms=7,
            label=f"true zeros (ch{j + 1} to acc{j + 1})")
    ax.plot(zp_m.real, zp_m.imag, "x", color="C3", ms=7, label="identified poles")
    ax.plot(zz_m.real, zz_m.imag, "+", color="C0", ms=9, label="identified zeros")
    # The lightly damped modes sit on the unit circle between 0 and the band's edge: zoom.
    a_hi = 2 * np.pi * band[1] * dt
    ax.set_xlim(min(np.cos(a_hi), 0.2) - 0.15, 1.08)
    ax.set_ylim(-0.1, np.sin(min(a_hi, np.pi / 2)) + 0.15)
    ax.set_aspect("equal")
    ax.set_xlabel("Re z")
    ax.set_ylabel("Im z")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower left", fontsize=8)
    ax.set_title("z-plane, upper half near the unit circle")
    ft, zt, _ = modal_parameters(tcols)
    fm, zm, _ = modal_parameters(model)
    sel_t = (ft > 1) & (ft < band[1])
    sel_m = (fm > 1) & (fm < band[1])
    ax2.semilogy(ft[sel_t], np.maximum(zt[sel_t], 1e-5), "o", mfc="none", color="0.35", ms=8,
                 label="true modes")
    ax2.semilogy(fm[sel_m], np.clip(zm[sel_m], 1e-5, None), "x", color="C3", ms=7,
                 label="identified")
    ax2.set_xlabel("frequency [Hz]")
    ax2.set_ylabel("damping ratio")
    ax2.grid(True, which="both", alpha=0.3)
    ax2.legend(loc="upper right", fontsize=8)
    ax2.set_title("modes: frequency and damping")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def convergence_figure(fits: dict, fs: float, y_rms: dict):
    """Innovations (moving RMS relative to the output RMS) and parameter change per sample."""
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
    for k, (name, fit) in enumerate(fits.items()):
        e = fit.innovations
        if e.size:
            w = 160  # 0.1 s windows
            nwin = e.shape[0] // w
            ms = np.mean((e[: nwin * w] ** 2).reshape(nwin, w, -1), axis=1)
            rel = np.mean(ms / y_rms[name][None, :] ** 2, axis=1)
            t = (np.arange(nwin) + 0.5) * w / fs
            a1.plot(t, 10 * np.log10(rel), color=f"C{k}", label=name)
        h, idx = fit.theta_history, fit.history_index
        if h.shape[0] >= 2:
            step = np.diff(idx)
            change = np.linalg.norm(np.diff(h, axis=0), axis=1) / step
            scale = max(np.linalg.norm(h[-1]), 1e-300)
            a2.semilogy(idx[1:] / fs, np.maximum(change / scale, 1e-18), color=f"C{k}",
                        lw=0.8, label=name)
    a1.set_ylabel("innovation power / output power [dB]\n(0.1 s windows)")
    a1.grid(True, alpha=0.3)
    a1.legend(loc="upper right", fontsize=8)
    a1.set_title("PLID convergence on the identification records")
    a2.set_ylabel("|theta_k - theta_(k-10)| / 10 / |theta_final|\nper sample")
    a2.set_xlabel("time in the record [s]")
    a2.grid(True, which="both", alpha=0.3)
    a2.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    return fig


def trace_figure(model, K, record: Record, title: str, seconds=(2.0, 2.25)):
    """Measured versus one-step predicted sensor signals on validation data."""
    import matplotlib.pyplot as plt

    from trussid.plid.metrics import one_step_predict

    d = record.data
    cols = list(record.channels)
    yhat = one_step_predict(model, d.u[:, cols], d.y, K=K)
    k0, k1 = int(seconds[0] * d.fs), int(seconds[1] * d.fs)
    k0, k1 = min(k0, d.n_samples - 2), min(k1, d.n_samples)
    t = np.arange(k0, k1) / d.fs
    p = d.y.shape[1]
    fig, axes = plt.subplots(p, 1, figsize=(10, 2.3 * p + 0.6), sharex=True, squeeze=False)
    for i in range(p):
        ax = axes[i, 0]
        ax.plot(t, d.y[k0:k1, i], color="0.5", lw=2.2, label="measured (A/D)")
        ax.plot(t, yhat[k0:k1, i], color="C0", lw=1.0, label="one-step predicted")
        ax.plot(t, 10 * (d.y - yhat)[k0:k1, i], color="C3", lw=0.8,
                label="prediction error x 10")
        ax.set_ylabel(f"{d.output_names[i]} [V]")
        ax.grid(True, alpha=0.3)
    axes[0, 0].legend(loc="upper right", fontsize=8, ncol=3)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


# --------------------------------------------------------------------------- the run


def json_safe(obj):
    """Non-finite floats to None, numpy to Python, recursively (JSON holds neither)."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    return obj


def run_demo(out, settings: DemoSettings | None = None, progress=print) -> dict:
    """Run the whole campaign and write the report directory ``out``.

    Parameters
    ----------
    out : path-like
        Report directory (created; files in it are replaced atomically).
    settings : DemoSettings, optional
        Default :func:`demo_settings` ``()``.
    progress : callable or None
        Called with one line per stage.

    Returns
    -------
    dict
        The summary (also written as ``summary.json``).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from trussid.plid.datafile import with_channels, write_data
    from trussid.plid.modelfile import save_model

    settings = settings or demo_settings()
    say = progress or (lambda msg: None)
    out = Path(out)
    if out.exists() and not out.is_dir():
        from trussid._util.errors import UserError

        raise UserError(f"--out {out} exists and is not a directory")
    t_start = time.perf_counter()
    timings = {}

    t0 = time.perf_counter()
    say("[1/5] testbed -> modes -> plant ...")
    tp = build_plant(settings)
    truth = tp.discrete
    tb = tp.tbm.testbed
    fs = 1.0 / truth.dt
    timings["plant"] = time.perf_counter() - t0
    f_modes = tp.modes.frequencies_hz
    say(f"      {len(f_modes)} modes below Nyquist ({f_modes[f_modes > 5][0]:.1f} to "
        f"{f_modes[-1]:.1f} Hz), plant {truth.nstates} states, {truth.ninputs} x "
        f"{truth.noutputs}, {fs:g} Hz ({timings['plant']:.1f} s)")

    t0 = time.perf_counter()
    say("[2/5] simulated experiments (12-bit D/A and A/D, sensor noise) ...")
    records = run_experiments(tp, settings, progress=lambda m: say("      " + m))
    timings["experiments"] = time.perf_counter() - t0

    say("[3/5] identification (PLID) ...")
    fits, h1s = {}, {}
    for name, (rid, rval) in records.items():
        cols = list(rid.channels)
        order = settings.mimo_order if name == "mimo" else settings.simo_order
        d = rid.data
        say(f"      {name}: {order} states, {len(cols)} in x {d.n_outputs} out; candidates:")
        fits[name] = identify_model(d.u[:, cols], d.y, order, d.dt,
                                    block_rows=settings.block_rows,
                                    log=lambda msg: say(f"        {msg}"))
        h1s[name] = h1_estimate(rid, settings.h1_nperseg)
        say(f"      {name}: kept {fits[name].info.get('chosen', '')} "
            f"({fits[name].seconds:.1f} s)")

    t0 = time.perf_counter()
    say("[4/5] evaluation against the true plant, H1 and validation data ...")
    models = []
    for name, (rid, rval) in records.items():
        kind = "MIMO" if name == "mimo" else "SIMO"
        models.append(evaluate(fits[name], truth, rid, rval, h1s[name], settings, name, kind))
    timings["evaluation"] = time.perf_counter() - t0

    control_md = None
    if "mimo" in records:  # close the loop on the MIMO model (issue 14)
        from trussid.campaign.control import demo_section
        from trussid.plots import save_figure

        t0 = time.perf_counter()
        say("      closing the loop: LQG from the MIMO model, on the FE truths ...")
        control_md, control_figs, control_summary = demo_section(
            fits["mimo"].model, fits["mimo"].K, records["mimo"][0].data, truth, settings.quick,
            progress=lambda m: say("      " + m))
        out.mkdir(parents=True, exist_ok=True)
        for fname, fig in control_figs.items():
            save_figure(fig, out / fname)
        timings["control"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    say(f"[5/5] writing the report in {out}/ ...")
    files = {"data": [], "models": [], "figures": []}
    for name, (rid, rval) in records.items():
        for rec in (rid, rval):
            fname = f"data_{name}_{rec.purpose[:3]}.npz"
            # Only the driven channels: the others are zero and a data file refuses them.
            write_data(with_channels(rec.data, inputs=[rec.data.input_names[c] for c in
                                                       rec.channels]), out / fname)
            files["data"].append(fname)
        fname = f"model_{name}.npz"
        cols = list(rid.channels)
        save_model(out / fname, fits[name].model, K=fits[name].K,
                   input_names=[rid.data.input_names[c] for c in cols],
                   output_names=rid.data.output_names)
        files["models"].append(fname)
    save_model(out / "plant_true.npz", truth, input_names=list(truth.input_labels),
               output_names=list(truth.output_labels))
    files["models"].append("plant_true.npz")

    def save(fig, fname):
        with atomic_path(out / fname) as tmp:
            fig.savefig(tmp, dpi=100, format="png")
        plt.close(fig)
        files["figures"].append(fname)

    try:
        for name, (rid, rval) in records.items():
            cols = list(rid.channels)
            in_names = [rid.data.input_names[c] for c in cols]
            figs = bode_overlay(truth, h1s[name], fits[name].model, cols, rid.data.output_names,
                                in_names, settings.plot_band, f"{name}")
            for fig, nm in zip(figs, in_names):
                save(fig, f"bode_{name}_{nm}.png" if name == "mimo" else f"bode_{name}.png")
            save(pole_zero_figure(fits[name].model, truth, cols, settings.plot_band,
                                  f"{name}: poles and zeros, identified vs true"),
                 f"poles_{name}.png")
            save(trace_figure(fits[name].model, fits[name].K, rval,
                              f"{name}: validation record, measured vs one-step predicted"),
                 f"trace_{name}.png")
        y_rms = {name: np.sqrt(np.mean(rid.data.y**2, axis=0)) for name, (rid, _) in
                 records.items()}
        save(convergence_figure(fits, fs, y_rms), "convergence.png")
    finally:
        plt.close("all")

    summary = {
        "format_version": 1,
        "settings": asdict(settings),
        "plant": plant_summary(tp, settings),
        "experiments": experiment_summary(records, settings),
        "models": models,
        "files": files,
        "timings_s": timings,
    }
    if control_md is not None:
        summary["control"] = control_summary
        files["figures"] += list(control_figs)
    timings["report"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    summary = json_safe(summary)
    with atomic_path(out / "summary.json") as tmp:
        tmp.write_text(json.dumps(summary, indent=2) + "\n")
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text(report_markdown(summary) + ("\n" + control_md if control_md else ""))
    say(f"      done in {timings['total']:.1f} s")
    return summary


def plant_summary(tp, settings: DemoSettings) -> dict:
    tb = tp.tbm.testbed
    f = tp.modes.frequencies_hz
    acc = tb.accelerometers
    return {
        "states": int(tp.discrete.nstates), "inputs": list(tp.discrete.input_labels),
        "outputs": list(tp.discrete.output_labels), "sample_rate_hz": 1.0 / tp.discrete.dt,
        "modes": int(f.size), "mode_frequencies_hz": f.tolist(),
        "modal_damping": tb.damping.modal_ratio,
        "accelerometer_sensitivity_v_per_g": acc.sensitivity * G0,
        "conditioning_gain": acc.conditioning_gain,
        "converter_bits": tb.daq.bits, "converter_full_scale_v": tb.daq.full_scale,
        "sensor_noise_g_rms": settings.sensor_noise_g,
        "sensor_noise_v_rms": sensor_noise_volts(tb, settings),
    }


def experiment_summary(records: dict, settings: DemoSettings) -> list:
    rows = []
    for name, pair in records.items():
        for rec in pair:
            e = rec.experiment
            d = e.data
            y_rms = np.sqrt(np.mean(e.y_clean**2, axis=0))
            noise = np.asarray(e.sensor_noise_rms)
            lsb = np.asarray(e.lsb["adc"], dtype=float)
            rows.append({
                "model": name, "purpose": rec.purpose, "samples": d.n_samples,
                "driven_channels": [d.input_names[c] for c in rec.channels], "seed": rec.seed,
                "excitation": settings.excitation, "excitation_rms_v": settings.excitation_rms,
                "excitation_band_hz": list(settings.excitation_band),
                "dac_clipped": e.clipping["dac"], "adc_clipped": e.clipping["adc"],
                "conditioner_steps": rec.gain_steps,
                "adc_full_scale_v": rec.adc_full_scale,
                # converter resolution from the LSB the experiment used: 2 FS / 2^bits
                "adc_bits": [int(round(np.log2(2 * fs / q)))
                             for fs, q in zip(rec.adc_full_scale, np.atleast_1d(lsb))],
                "output_rms_v": y_rms.tolist(),
                "output_rms_fraction_of_range": (y_rms / np.asarray(rec.adc_full_scale)).tolist(),
                "sensor_snr_db": (20 * np.log10(y_rms / noise)).tolist(),
                "quantisation_snr_db": (20 * np.log10(y_rms / (lsb / np.sqrt(12)))).tolist(),
            })
    return rows


def _f(x, fmt=".2f"):
    return "-" if x is None else format(x, fmt)


def report_markdown(s: dict) -> str:
    """The human-readable report (Markdown) from the summary."""
    st, pl = s["settings"], s["plant"]
    L = ["# trussid demo: PLID on the simulated testbed", ""]
    L += [f"Run: {'quick' if st['quick'] else 'full'}; total {s['timings_s']['total']:.1f} s "
          f"(plant {s['timings_s']['plant']:.1f} s, experiments "
          f"{s['timings_s']['experiments']:.1f} s, evaluation "
          f"{s['timings_s']['evaluation']:.1f} s).", ""]
    L += ["## Plant", "",
          f"Default testbed, {pl['modes']} modes below Nyquist, modal damping "
          f"{100 * pl['modal_damping']:.2f} %; discrete plant of {pl['states']} states, "
          f"{len(pl['inputs'])} D/A channels ({', '.join(pl['inputs'])}) to "
          f"{len(pl['outputs'])} accelerometers ({', '.join(pl['outputs'])}) at "
          f"{pl['sample_rate_hz']:g} Hz, with the smoothing filter, amplifier and 120 Hz "
          f"low-pass. Accelerometers {1000 * pl['accelerometer_sensitivity_v_per_g']:.0f} mV/g, "
          f"signal conditioner gain {pl['conditioning_gain']:g} V/V; "
          f"{pl['converter_bits']}-bit converters, +-{pl['converter_full_scale_v']:g} V; "
          f"sensor noise {1e6 * pl['sensor_noise_g_rms']:.0f} ug RMS "
          f"({1e3 * pl['sensor_noise_v_rms']:.2f} mV at the nominal gain).", ""]
    L += ["## Experiments", "",
          f"Excitation: {st['excitation']} noise, {st['excitation_band'][0]:g}-"
          f"{st['excitation_band'][1]:g} Hz, {st['excitation_rms']:g} V RMS per driven "
          "channel. Conditioners ranged in 1-2-5 steps to about "
          f"{st['range_target']:.2f} of full scale at most.", "",
          "| record | samples | driven | D/A clipped | A/D clipped | gain steps | "
          "RMS / range | sensor SNR [dB] | quantisation SNR [dB] |",
          "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in s["experiments"]:
        L.append(f"| {r['model']} {r['purpose']} | {r['samples']} | "
                 f"{', '.join(r['driven_channels'])} | {sum(r['dac_clipped'])} | "
                 f"{', '.join(map(str, r['adc_clipped']))} | "
                 f"{', '.join(f'{g:g}' for g in r['conditioner_steps'])} | "
                 f"{', '.join(f'{v:.2f}' for v in r['output_rms_fraction_of_range'])} | "
                 f"{', '.join(f'{v:.1f}' for v in r['sensor_snr_db'])} | "
                 f"{', '.join(f'{v:.1f}' for v in r['quantisation_snr_db'])} |")
    L += ["", "## Identified models", "",
          "One-step signal-to-prediction-error ratio (SPE) on the validation record, as the "
          "thesis defines it: the RMS of the sensor signals over the RMS of the one-step "
          "prediction error, over all sensors and samples (`10 log10(sum y^2 / sum e^2)`, "
          "volts at the A/D; `plid.metrics`). Beside it, per output, and the mean of the "
          "normalised error powers (`-10 log10(mean_j MS(e_j)/MS(y_j))`, dominated by the "
          "weakest output: in a SIMO record the two accelerometers away from the driven "
          "vertex are limited by sensor noise to 38-50 dB). FRF errors are against the "
          f"true plant over {st['frf_band'][0]:g}-{st['frf_band'][1]:g} Hz.", "",
          "| model | kind | states | in x out | SPE [dB] | SPE per output [dB] | "
          "SPE mean-normalised [dB] | FRF max [dB] | FRF RMS [dB] | H1 vs true RMS [dB] | "
          "modes matched (in band) | seconds |",
          "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for m in s["models"]:
        L.append(f"| {m['name']} | {m['kind']} | {m['states']} | {m['inputs']} x "
                 f"{m['outputs']} | {_f(m['signal_to_prediction_error_db'])} | "
                 f"{', '.join(_f(v, '.1f') for v in m['signal_to_prediction_error_db_per_output'])}"
                 f" | {_f(m['signal_to_prediction_error_db_mean_normalised'])} | "
                 f"{_f(m['frf_max_error_db'])} | {_f(m['frf_rms_error_db'])} | "
                 f"{_f(m['h1_error_vs_true']['rms_db'])} | "
                 f"{m['poles_in_band_matched']} / {m['poles_in_band_true']} | "
                 f"{m['seconds']:.1f} |")
    L += ["", "## How each model was identified", "",
          "`plid.multipass.identify_reduced`: PLID at the model's order and at higher "
          "orders reduced to it (input-weighted balanced truncation, then one PLID pass); "
          "the candidate with the best one-step ratio on the *identification* record is "
          "kept (marked). Candidates with poles outside the unit circle compete with those "
          "poles reflected in (`stabilised`).", ""]
    for m in s["models"]:
        ident = m.get("identification") or {}
        rows = ident.get("candidates") or []
        L += [f"**{m['name']}**: {m.get('method', '')}", "",
              "| candidate | one-step, identification record [dB] | seconds |",
              "| --- | --- | --- |"]
        for r in rows:
            mark = " (kept)" if r.get("label") == ident.get("chosen") else ""
            score = r.get("identification_ratio_db")
            txt = _f(score) if score is not None else (r.get("error") or "unstable")
            L.append(f"| {r.get('label', '')}{mark} | {txt} | {r.get('seconds', 0):.1f} |")
        L.append("")
    L += ["", "## Figures", ""]
    for m in s["models"]:
        n = m["name"]
        bodes = [f for f in s["files"]["figures"] if f.startswith(f"bode_{n}")]
        L += [f"### {n}", ""]
        L += [f"![Bode overlay]({b})" for b in bodes]
        L += ["", f"![poles and zeros](poles_{n}.png)", "",
              f"![measured vs predicted](trace_{n}.png)", "",
              "Poles in the FRF band (true -> identified):", "",
              "| true f [Hz] | true damping | identified f [Hz] | identified damping |",
              "| --- | --- | --- | --- |"]
        lo, hi = st["frf_band"]
        for r in m["poles"]:
            if r["true_frequency_hz"] is not None and lo <= r["true_frequency_hz"] <= hi:
                L.append(f"| {r['true_frequency_hz']:.2f} | {r['true_damping']:.5f} | "
                         f"{_f(r['frequency_hz'])} | {_f(r['damping'], '.5f')} |")
        L.append("")
    L += ["### Convergence", "", "![convergence](convergence.png)", ""]
    L += ["## Files", "", "Data: " + ", ".join(s["files"]["data"]), "",
          "Models: " + ", ".join(s["files"]["models"]), "",
          "All metrics: `summary.json`.", ""]
    return "\n".join(L)


__all__ = ["DemoSettings", "demo_settings", "build_plant", "run_experiments", "take_record",
           "conditioner_steps", "identify_model", "choose_predictor", "evaluate",
           "run_demo", "report_markdown", "Identified", "Record"]
