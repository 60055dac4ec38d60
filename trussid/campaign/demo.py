"""The main job, end to end: the simulated identification campaign on the default testbed.

Plain functions over plain data, in the order ``trussid demo`` runs them::

    settings = demo_settings(quick)
    tp       = build_plant(tb)                           testbed -> modes -> plant (its lab)
    exps     = run_experiments(tp, settings)             identification + validation records
    fit      = identify_model(u, y, order, dt)           PLID (the one switchable call)
    metrics  = evaluate(fit, truth, validation, h1)      prediction, FRF, poles
    write_report(out, ...)                               report.md, PNGs, summary.json, files

The experiment reproduces the thesis's campaign (``docs/testbed.md``): one SIMO
model per actuator channel, from a record in which only that channel is driven (1 input,
3 accelerometers, 30 states), and one MIMO model from a record with all three channels
driven by independent signals (3 x 3, ``mimo_order`` states).

Signal chain of every record (:func:`trussid.plid.experiment.run_experiment`):

- excitation: Gaussian white noise band-limited to 0-400 Hz (the band holding the modes
  the thesis measured; "nothing significant 350-450 Hz"), 2.5 V RMS per driven channel at
  the D/A (the thesis lab: 12-bit +-10 V), i.e. a crest factor of 4: a Gaussian sample exceeds 4 sigma with
  probability 6e-5, so the D/A clips rarely (the counts are reported);
- the plant: D/A volts -> smoothing filter -> amplifier -> PZT -> structure ->
  accelerometer -> signal conditioner (``tb.accelerometers.conditioning_gain``) -> A/D
  volts, discretised by ZOH at the lab's sample rate
  (:func:`trussid.testbed.plant.testbed_plant`); every number of that chain and of the
  converters is the testbed's lab (``tb.lab``, :class:`trussid.geometry.lab.LabSpec`);
- sensor noise: white, ``tb.accelerometers.noise`` RMS referred to the accelerometer over
  0 to half the sample rate (the thesis lab: 10 ug, about 0.35 ug/sqrt(Hz): a low-noise
  piezoelectric accelerometer with its charge amplifier). It is amplified with the signal by the
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
- A/D quantisation at the lab's resolution, with clipping counted.

Identification data and validation data are separate records with different seeds.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from trussid import plots
from trussid._util.errors import UserError
from trussid._util.files import atomic_directory, atomic_path
from trussid.campaign.adapt import demo_section as adapt_demo_section
from trussid.campaign.adapt import write_files as write_adapt_files
from trussid.campaign.control import demo_section
from trussid.campaign.html_report import write_report_html
from trussid.campaign.orders import scan_orders
from trussid.campaign.report import report_markdown
from trussid.campaign.structure import DEFAULT_SNR_DB, STRUCTURAL_DAMPING_MAX
from trussid.campaign.summary import (AdaptSection, AuditedIdentifiedMode, AuditedTrueMode,
                                      DemoSummary, ExperimentRow, ModeAudit, ModeCheck,
                                      ModelIdentification, ModelSummary,
                                      PlantSummary, ReportProvenance, ReportFiles)
from trussid.geometry.lab import G0, lab_record
from trussid.lqg.grading import LoopSettings
from trussid.plid.chosen import choose_model
from trussid.plid.datafile import with_channels, write_data
from trussid.plid.evaluate import compare
from trussid.plid.experiment import excitation, run_experiment, simulate
from trussid.plid.frf import frequency_response, h1
from trussid.plid.modal import mac, modal_table
from trussid.plid.modelfile import save_model
from trussid.plots import save_figure
from trussid.testbed.plant import testbed_plant



# --------------------------------------------------------------------------- settings


@dataclass(frozen=True)
class DemoSettings:
    """Every number of the demo campaign (SI units unless stated).

    Attributes
    ----------
    quick : bool
        The reduced run (``trussid demo --quick``).
    n_identification, n_validation : int
        Samples of each identification and validation record (at the lab's sample rate).
    excitation : str
        Excitation kind (:func:`trussid.plid.experiment.excitation`).
    excitation_rms : float
        RMS of each driven D/A channel [V].
    excitation_band : (float, float)
        Excitation band [Hz].
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
    direct : {False, True, "auto"}
        Direct term D of the identified models (:func:`trussid.plid.reduced.
        identify_reduced`): the testbed's sensors see the structure through the lab's
        low-pass filters (no feed-through, False); accelerometers on a bare structure
        respond at once to a force ("auto": the data decide).
    order_scan : tuple of int
        Orders scanned for each model (:func:`trussid.campaign.orders.scan_orders`: one-step
        prediction on the held-back quarter of its identification record); the model is
        identified at the order the data choose. Empty (the testbed): ``simo_order`` and
        ``mimo_order``, the documented orders.
    order_scan_budget_s : float
        CPU budget of each model's scan [s].
    """

    quick: bool = False
    n_identification: int = 16000
    n_validation: int = 8000
    excitation: str = "white"
    excitation_rms: float = 2.5
    excitation_band: tuple = (0.0, 400.0)
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
    direct: object = False
    order_scan: tuple = ()
    order_scan_budget_s: float = 60.0


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


def derived_settings(cp, quick: bool = False, **overrides):
    """The experiment for a deck's plant (:class:`trussid.campaign.structure.CampaignPlant`),
    from its modes and sample rate (overridable):

    - excitation white 0 to 0.4 of the sample rate, a quarter of the D/A range RMS per
      driven channel (a crest factor of 4, as on the testbed);
    - FRF band from half the first mode to the top of the excitation; Bode plots to 0.95
      of Nyquist;
    - records of 6000 + 4000 samples (quick) or 16000 + 8000, at least 100 periods of
      the first mode;
    - model orders chosen from the data (issue 32): multiples of the outputs (PLID's
      observer form) from one to 48 states (quick: 36) are scanned for each model by
      one-step prediction on the held-back quarter of its identification record
      (:mod:`trussid.campaign.orders`), within 60 s of CPU each; the fallback, if no order
      gives a stable model, is twice the number of the plant's modes below Nyquist, capped
      likewise. SIMO models of every channel (quick: the first); the direct term estimated
      when the data show one (accelerometers).
    """
    fs = 1.0 / cp.discrete.dt
    f = np.asarray(cp.modes.frequencies_hz, dtype=float)
    f = f[f > 1e-6]
    top = 0.4 * fs
    p = cp.discrete.noutputs
    order = int(min(p * math.ceil(max(2 * f.size, 2) / p), p * ((36 if quick else 48) // p)))
    base = demo_settings(quick)
    n_min = int(math.ceil(100 * fs / f[0])) if f.size else 0
    lo = 0.5 * f[0] if f.size else 0.0
    kw = dict(direct="auto", excitation_band=(0.0, top),
              excitation_rms=0.25 * cp.lab.daq.full_scale, frf_band=(lo, top),
              plot_band=(lo, 0.95 * 0.5 * fs), n_identification=max(base.n_identification, n_min),
              n_validation=max(base.n_validation, n_min // 2), mimo_order=order,
              simo_order=order,
              order_scan=tuple(range(p, p * ((36 if quick else 48) // p) + 1, p)),
              simo_channels=(0,) if quick else tuple(range(cp.discrete.ninputs)))
    kw.update(overrides)
    return demo_settings(quick, **kw)


# --------------------------------------------------------------------------- plant


def build_plant(tb=None):
    """The plant of testbed ``tb`` (default: the default testbed) at its lab's sample rate,
    with its lab chain (:class:`trussid.testbed.plant.TestbedPlant`)."""
    return testbed_plant(tb)


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


def drive(settings: DemoSettings, plant, n: int, channels, seed: int) -> np.ndarray:
    """The excitation of the driven ``channels`` (others zero), at the plant's own rate."""
    u = np.zeros((n, plant.ninputs))
    u[:, list(channels)] = excitation(settings.excitation, n, len(channels), 1.0 / plant.dt,
                                      settings.excitation_rms, settings.excitation_band, seed)
    return u


def range_conditioners(plant, settings: DemoSettings, channels, seed: int, n_samples: int,
                       noise_v: float, full_scale: float) -> list:
    """Conditioner steps from a noise-free trial run of the experiment (its own seed), for an
    A/D range of +-``full_scale`` [V]."""
    trial = drive(settings, plant, n_samples, channels, seed)
    rms = np.sqrt(np.mean(simulate(plant, trial) ** 2, axis=0) + noise_v**2)
    return conditioner_steps(rms, full_scale, settings.range_target, settings.gain_steps)


def take_record(plant, settings: DemoSettings, name: str, purpose: str, channels, seed: int,
                n_samples: int, noise_v: float, steps, lab) -> Record:
    """One record with the conditioners at ``steps`` (see the module docstring), through the
    converters of ``lab`` (:class:`trussid.geometry.lab.LabSpec`)."""
    full_scale, bits = lab.daq.full_scale, lab.daq.bits
    adc_fs = [full_scale / g for g in steps]
    u = drive(settings, plant, n_samples, channels, seed)
    exp = run_experiment(plant, n_samples, u=u, seed=seed + 1, sensor_noise_rms=noise_v,
                         dac_bits=bits, adc_bits=bits, dac_full_scale=full_scale,
                         adc_full_scale=np.asarray(adc_fs),
                         input_names=list(plant.input_labels),
                         output_names=list(plant.output_labels))
    return Record(name, purpose, tuple(channels), exp, steps, adc_fs, seed)


def sensor_noise(tp, settings: DemoSettings):
    """Sensor noise RMS in plant output units: the testbed lab's accelerometer noise at the
    nominal conditioning gain, or for a deck :data:`trussid.campaign.structure.
    DEFAULT_SNR_DB` under each output in a noise-free trial of the all-channel record."""
    if hasattr(tp, "tbm"):
        return tp.lab.accelerometers.noise_volts
    trial = drive(settings, tp.discrete, settings.n_identification,
                  range(tp.discrete.ninputs), settings.seed + 99)
    rms = np.sqrt(np.mean(simulate(tp.discrete, trial) ** 2, axis=0))
    return rms * 10 ** (-DEFAULT_SNR_DB / 20)


def run_experiments(tp, settings: DemoSettings, progress=None) -> dict:
    """All records of the campaign: ``{model name: (identification, validation)}``.

    Model names are ``simo_ch<k>`` (k = 1..3) and ``mimo``.
    """
    plant, lab = tp.discrete, tp.lab
    noise_v = sensor_noise(tp, settings)
    plan = [(f"simo_ch{c + 1}", (c,)) for c in settings.simo_channels]
    if settings.mimo_order:
        plan.append(("mimo", tuple(range(plant.ninputs))))
    out = {}
    for k, (name, channels) in enumerate(plan):
        base = settings.seed + 1000 * k
        steps = range_conditioners(plant, settings, channels, base + 250,
                                   settings.n_identification, noise_v, lab.daq.full_scale)
        rid = take_record(plant, settings, name, "identification", channels, base,
                          settings.n_identification, noise_v, steps, lab)
        rval = take_record(plant, settings, name, "validation", channels, base + 500,
                           settings.n_validation, noise_v, steps, lab)
        out[name] = (rid, rval)
        if progress:
            progress(f"recorded {name}: {rid.data.n_samples} + {rval.data.n_samples} samples")
    return out


# --------------------------------------------------------------------------- identification


@dataclass
class Identified:
    """An identified model with what the report needs from the identification."""

    model: object                      # discrete control.StateSpace
    K: np.ndarray                      # one-step predictor gain used for prediction
    K_source: str
    seconds: float
    method: str
    innovations: np.ndarray            # (N, p) of the (last) PLID pass
    theta_history: np.ndarray          # (k, q)
    history_index: np.ndarray          # (k,)
    info: ModelIdentification
    modes: list = field(default_factory=list)  # plid.uncertainty.ModeInterval per mode


def identify_model(u, y, order: int, dt: float, *, block_rows=None, via=None,
                   progress: bool = False, log=None, direct=False) -> Identified:
    """Identify an order-``order`` model from one record: the one switchable call.

    Runs the project's identification recipe for under-modelled structures,
    :func:`trussid.plid.reduced.identify_reduced`: the PLID recipe :func:`trussid.plid.recipe.identify`
    (an N4SID prior with D = 0 in a rotation observer basis, refined by PLID) at ``order``
    and at the higher orders ``via``, the latter reduced to ``order`` by input-weighted
    balanced truncation and refined by PLID; the candidate with the best one-step
    prediction on the identification record wins, with its predictor gain
    (:func:`trussid.plid.metrics.choose_predictor`). Measured in
    ``benchmarks/results/plid_thesis.md``. :func:`trussid.plid.chosen.choose_model` makes the
    winner simulable, sets the subspace fit with D against it when ``direct`` is asked for,
    and keeps the parameter history of the winning PLID pass for the convergence plot.
    """
    t0 = time.perf_counter()
    ch = choose_model(u, y, order, dt, block_rows=block_rows, via=via, progress=progress,
                      log=log, direct=direct)
    idn = ch.identification
    info = ModelIdentification(
        recipe="trussid.plid.multipass.identify_reduced", start=idn.start,
        basis=getattr(idn.basis, "name", ""), R=np.asarray(idn.R).tolist(),
        provenance=idn.provenance, stabilised=ch.stabilised, predictor=ch.predictor,
        chosen=ch.chosen, candidate_with_d=ch.with_direct_term)
    return Identified(ch.model, ch.K, ch.K_source, time.perf_counter() - t0, ch.method,
                      idn.result.innovations, ch.theta_history, ch.history_index, info,
                      ch.modes)


# --------------------------------------------------------------------------- evaluation


def evaluate(fit: Identified, truth, rid: Record, rval: Record, h1_est, settings: DemoSettings,
             name: str, kind: str) -> ModelSummary:
    """All metrics of one model, by :func:`trussid.plid.evaluate.compare` (as ``trussid
    compare``): validation prediction and simulation, FRF errors against the true plant and
    the H1 estimate, matched poles."""
    model = fit.model
    val = rval.data
    cols = list(rid.channels)
    tcols = truth[:, cols]
    c = compare(model, tcols, u=val.u[:, cols], y=val.y, y_clean=rval.experiment.y_clean,
                K=fit.K, gain=fit.K_source, estimate=h1_est, band=settings.frf_band)
    # H1 itself against the truth: how far the nonparametric estimate is to be trusted.
    keep = (h1_est.f >= settings.frf_band[0]) & (h1_est.f <= settings.frf_band[1])
    h1_true = _h1_error(h1_est, tcols, keep)
    in_band = [r for r in c.poles if r.true_frequency_hz is not None
               and settings.frf_band[0] <= r.true_frequency_hz <= settings.frf_band[1]]
    y_rms = np.sqrt(np.mean(val.y**2, axis=0))
    p, s, e, eh = c.prediction, c.simulation, c.frf, c.frf_vs_estimate
    lo_x, hi_x = settings.excitation_band
    inside = (h1_est.f >= max(lo_x, h1_est.f[1])) & (h1_est.f <= hi_x)
    above = h1_est.f > hi_x
    coherence = {
        "excited_band_hz": [lo_x, hi_x],
        "mean_in_excited_band": h1_est.coherence[inside].mean(axis=0).tolist(),
        "mean_above_excited_band": (h1_est.coherence[above].mean(axis=0).tolist()
                                    if above.any() else None),
    }
    return ModelSummary(
        name=name, kind=kind, states=c.states, inputs=c.inputs, outputs=c.outputs,
        input_names=[val.input_names[c_] for c_ in cols], output_names=list(val.output_names),
        signal_to_prediction_error_db=p.overall,
        signal_to_prediction_error_db_per_output=p.per_output,
        signal_to_prediction_error_db_mean_normalised=p.mean_normalised,
        prediction_skip_samples=p.skip,
        predictor_gain=p.gain,
        frf_max_error_db=e.max_db, frf_rms_error_db=e.rms_db,
        frf_max_error_deg=e.max_deg, frf_rms_error_deg=e.rms_deg,
        frf_error_per_channel=e.per_channel,
        frf_band_hz=list(settings.frf_band),
        frf_error_vs_h1={"max_db": eh.max_db, "rms_db": eh.rms_db, "max_deg": eh.max_deg,
                         "rms_deg": eh.rms_deg},
        h1_error_vs_true=h1_true,
        simulation_fit_db=s.overall,
        simulation_fit_db_per_output=s.per_output,
        seconds=fit.seconds, method=fit.method, unstable_poles=c.unstable_poles,
        stabilised=fit.info.stabilised,
        poles=c.poles,
        poles_in_band_matched=sum(r.frequency_hz is not None for r in in_band),
        poles_in_band_true=len(in_band),
        validation_output_rms_v=y_rms.tolist(),
        h1_coherence=coherence,
        modes_check=mode_audit(c.poles, settings.frf_band, settings.excitation_band),
        mode_checks=_mode_checks(c.poles, fit.modes, model, tcols),
        identification=fit.info,
    )


def _mode_checks(poles, modes, model, truth) -> list[ModeCheck]:
    """Per matched pole pair: the identified mode's 95 % intervals
    (:mod:`trussid.plid.uncertainty`) and the MAC of the true (FE) mode shape against the
    identified one at the sensors (:func:`trussid.plid.modal.mac`)."""
    ident, true = modal_table(model), modal_table(truth)
    rows = []
    for r in poles:
        if not r.matched:
            continue
        i = int(np.argmin(np.abs(ident.frequencies_hz - r.frequency_hz)))
        j = int(np.argmin(np.abs(true.frequencies_hz - r.true_frequency_hz)))
        m = min(modes, key=lambda q: abs(q.frequency_hz - r.frequency_hz)) if modes else None
        ci = (m.as_dict() if m is not None
              and abs(m.frequency_hz - r.frequency_hz) < 1e-6 * r.frequency_hz else {})
        rows.append(ModeCheck(
            r.true_frequency_hz, r.frequency_hz,
            float(mac(ident.shapes[:, [i]], true.shapes[:, [j]], zero_shape="zero")[0, 0]),
            ci.get("frequency_ci95_hz"), ci.get("damping_ratio_ci95")))
    return rows


#: Relative frequency error within which an identified mode counts as the true one found.
FOUND_TOLERANCE = 0.05
#: Identified modes below this damping ratio are listed wherever they are (a controller
#: designed on the model would respect them).
LIGHT_DAMPING = 0.01


def mode_audit(poles: list, band, excited) -> ModeAudit:
    """What a model lacks and what it adds, from matched poles (:func:`plid.metrics.compare_poles`).

    Parameters
    ----------
    poles : list of trussid.plid.metrics.PoleMatch
        A true pole with its match, or an unmatched identified pole (true fields None).
    band : (float, float)
        The band [Hz] in which every true mode should be found (the FRF band).
    excited : (float, float)
        The excitation band [Hz] (identified poles outside it are flagged).

    Returns
    -------
    ModeAudit
        ``true_modes_in_band``: every true structural mode (damping <= STRUCTURAL_DAMPING_MAX) in
        ``band`` with ``found`` (matched within FOUND_TOLERANCE in frequency) and the
        identified frequency and damping; ``missing``: the frequencies not found;
        ``filter_poles_in_band``: true poles that are not modes (excluded from the count);
        ``spurious``: identified modes with no true structural mode within
        FOUND_TOLERANCE, anywhere; ``lightly_damped``: identified modes with damping below
        LIGHT_DAMPING anywhere, each with ``spurious`` and ``in_excited_band``.
    """
    lo, hi = band
    true_modes = sorted({(r.true_frequency_hz, r.true_damping) for r in poles
                         if r.true_frequency_hz is not None
                         and r.true_damping <= STRUCTURAL_DAMPING_MAX})
    f_true = np.array([f for f, _ in true_modes]) if true_modes else np.zeros(0)
    rows, filters = [], 0
    for r in poles:
        ft = r.true_frequency_hz
        if ft is None or not lo <= ft <= hi:
            continue
        if r.true_damping > STRUCTURAL_DAMPING_MAX:
            filters += 1
            continue
        fi = r.frequency_hz
        found = (fi is not None and r.damping <= STRUCTURAL_DAMPING_MAX
                 and abs(fi - ft) <= FOUND_TOLERANCE * ft)
        rows.append(AuditedTrueMode(true_frequency_hz=ft, true_damping=r.true_damping,
                                    found=bool(found), frequency_hz=fi if found else None,
                                    damping=r.damping if found else None))

    def nearest(f):
        if not f_true.size:
            return None, None
        k = int(np.argmin(np.abs(f_true - f)))
        return float(f_true[k]), float(abs(f_true[k] - f) / max(f_true[k], 1e-12))

    identified, spurious, light = [], [], []
    for r in poles:
        fi = r.frequency_hz
        if fi is None or r.damping > STRUCTURAL_DAMPING_MAX:
            continue
        near, rel = nearest(fi)
        entry = AuditedIdentifiedMode(frequency_hz=fi, damping=r.damping, nearest_true_hz=near,
                                      spurious=bool(near is None or rel > FOUND_TOLERANCE),
                                      in_excited_band=bool(excited[0] <= fi <= excited[1]))
        identified.append(entry)
        if entry.spurious:
            spurious.append(entry)
        if r.damping < LIGHT_DAMPING:
            light.append(entry)
    key = lambda e: e.frequency_hz  # noqa: E731
    return ModeAudit(band_hz=[lo, hi], excited_band_hz=list(excited),
                     true_modes_in_band=rows,
                     found=sum(r.found for r in rows), total=len(rows),
                     missing=[r.true_frequency_hz for r in rows if not r.found],
                     filter_poles_in_band=filters,
                     spurious=sorted(spurious, key=key), lightly_damped=sorted(light, key=key),
                     rules={"structural_damping_max": STRUCTURAL_DAMPING_MAX,
                            "found_within": FOUND_TOLERANCE, "light_damping_below": LIGHT_DAMPING})


def provenance(settings: "DemoSettings", command: str | None = None) -> ReportProvenance:
    """Who made the report, how and where: trussid version, source commit (when the package
    runs from a git checkout), seed, command line, machine, load and date (UTC)."""
    import os
    import platform
    import subprocess

    from importlib.metadata import PackageNotFoundError, version

    try:
        trussid_version = version("trussid")
    except PackageNotFoundError:  # running from a source tree that is not installed
        trussid_version = None
    commit = None
    src = Path(__file__).resolve().parents[1]
    try:  # a checkout knows its commit; an installed wheel does not (then None)
        res = subprocess.run(["git", "-C", str(src), "rev-parse", "HEAD"], capture_output=True,
                             text=True, timeout=5)
        if res.returncode == 0:
            commit = res.stdout.strip()
            dirty = subprocess.run(["git", "-C", str(src), "status", "--porcelain",
                                    "--untracked-files=no"], capture_output=True, text=True,
                                   timeout=5).stdout.strip()
            commit += " (with uncommitted changes)" if dirty else ""
    except (OSError, subprocess.SubprocessError):
        pass
    try:
        load = list(os.getloadavg())
    except OSError:
        load = None
    return ReportProvenance(trussid_version=trussid_version, commit=commit, seed=settings.seed,
                      command=command, machine=platform.node(), platform=platform.platform(),
                      cpus=os.cpu_count(), python=platform.python_version(),
                      load_average_start=load,
                      date_utc=time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()))


def _h1_error(h1_est, truth, keep) -> dict:
    """Magnitude/phase error of the H1 estimate against the true plant at its own frequencies."""
    H, H_ref = h1_est.H[keep], frequency_response(truth, h1_est.f[keep])
    with np.errstate(divide="ignore", invalid="ignore"):
        mag = 20 * np.log10(np.abs(H)) - 20 * np.log10(np.abs(H_ref))
        ph = np.degrees(np.angle(H / H_ref))
    return {"max_db": float(np.max(np.abs(mag))), "rms_db": float(np.sqrt(np.mean(mag**2))),
            "max_deg": float(np.max(np.abs(ph))), "rms_deg": float(np.sqrt(np.mean(ph**2)))}


def h1_estimate(record: Record, nperseg: int):
    """H1 estimate from an identification record (driven channels only)."""
    d = record.data
    return h1(d.u[:, list(record.channels)], d.y, d.fs, nperseg=nperseg)


# --------------------------------------------------------------------------- the run


def identify_records(records: dict, settings: DemoSettings, say) -> tuple[dict, dict]:
    """Each model identified from its identification record, and that record's H1 estimate."""
    fits, h1s = {}, {}
    for name, (rid, rval) in records.items():
        cols = list(rid.channels)
        order = settings.mimo_order if name == "mimo" else settings.simo_order
        d = rid.data
        choice = None
        if settings.order_scan:
            choice = scan_orders(d.u[:, cols], d.y, d.dt, settings.order_scan,
                                 direct=settings.direct is not False,
                                 block_rows=max(settings.block_rows),
                                 cpu_budget_s=settings.order_scan_budget_s,
                                 u_val=rval.data.u[:, cols], y_val=rval.data.y)
            if choice is not None:
                order = choice.chosen
                for line in choice.lines():
                    say(f"      {name}: {line}")
                say(f"      {name}: order {order} chosen from the data (runners-up "
                    f"{', '.join(map(str, choice.runners_up)) or 'none'})")
        say(f"      {name}: {order} states, {len(cols)} in x {d.n_outputs} out; candidates:")
        fits[name] = identify_model(d.u[:, cols], d.y, order, d.dt,
                                    block_rows=settings.block_rows,
                                    log=lambda msg: say(f"        {msg}"),
                                    direct=settings.direct)
        if choice is not None:
            fits[name].info = replace(fits[name].info, order_scan=choice)
        h1s[name] = h1_estimate(rid, settings.h1_nperseg)
        say(f"      {name}: kept {fits[name].info.chosen} "
            f"({fits[name].seconds:.1f} s)")
    return fits, h1s


def write_files(out: Path, records: dict, fits: dict, truth, lab) -> ReportFiles:
    """The records (driven channels only) and the models as data and model files; the true
    plant's file records its ``lab`` (:func:`trussid.geometry.lab.lab_record`)."""
    files = ReportFiles()
    for name, (rid, rval) in records.items():
        for rec in (rid, rval):
            fname = f"data_{name}_{rec.purpose[:3]}.npz"
            # Only the driven channels: the others are zero and a data file refuses them.
            write_data(with_channels(rec.data, inputs=[rec.data.input_names[c] for c in
                                                       rec.channels]), out / fname)
            files.data.append(fname)
        fname = f"model_{name}.npz"
        cols = list(rid.channels)
        save_model(out / fname, fits[name].model, K=fits[name].K,
                   input_names=[rid.data.input_names[c] for c in cols],
                   output_names=rid.data.output_names)
        files.models.append(fname)
    save_model(out / "plant_true.npz", truth, input_names=list(truth.input_labels),
               output_names=list(truth.output_labels), extra=lab_record(lab))
    files.models.append("plant_true.npz")
    return files


def write_figures(out: Path, records: dict, fits: dict, h1s: dict, truth,
                  settings: DemoSettings, keep: dict | None = None, unit: str = "V/V") -> list:
    """Bode overlays, pole maps, traces and the convergence plot; their file names. ``keep``:
    a dict that receives each figure by file name (for ``report.html``)."""
    written = []

    def save(fig, fname):
        plots.save_figure(fig, out / fname, dpi=100)
        written.append(fname)
        if keep is not None:
            keep[fname] = fig

    for name, (rid, rval) in records.items():
        cols = list(rid.channels)
        in_names = [rid.data.input_names[c] for c in cols]
        figs = plots.bode_overlay(truth[:, cols], h1s[name], fits[name].model, in_names,
                                  rid.data.output_names, settings.plot_band, f"{name}",
                                  excited=settings.excitation_band, unit=unit)
        for fig, nm in zip(figs, in_names):
            save(fig, f"bode_{name}_{nm}.png" if name == "mimo" else f"bode_{name}.png")
        save(plots.pole_zero_figure(fits[name].model, truth[:, cols], settings.plot_band,
                                    f"{name}: poles and zeros, identified vs true",
                                    collocated=cols[0], excited=settings.excitation_band),
             f"poles_{name}.png")
        save(plots.trace_figure(fits[name].model, fits[name].K, rval.data, cols,
                                f"{name}: validation record, measured vs one-step predicted"),
             f"trace_{name}.png")
    y_rms = {name: np.sqrt(np.mean(rid.data.y**2, axis=0)) for name, (rid, _) in
             records.items()}
    save(plots.convergence_figure(fits, 1.0 / truth.dt, y_rms), "convergence.png")
    return written


def run_demo(out, settings: DemoSettings | None = None, progress=print, *,
             force: bool = False, command: str | None = None, testbed=None,
             plant=None, adapt: bool = False) -> dict:
    """Run the whole campaign and write the report directory ``out``.

    Parameters
    ----------
    out : path-like
        Report directory. It is written as a whole (into a temporary sibling, renamed at
        the end: :func:`trussid._util.files.atomic_directory`), so an interruption leaves
        the previous ``out`` untouched, or none. Its parent must exist.
    settings : DemoSettings, optional
        Default :func:`demo_settings` ``()``.
    progress : callable or None
        Called with one line per stage.
    force : bool
        Replace an existing ``out``; without it an existing ``out`` is refused at once
        (before any computation).
    command : str, optional
        The command line that asked for the report (recorded in its provenance).
    testbed : trussid.geometry.spec.Testbed, optional
        The testbed and its lab (``testbed.lab``: sample rate, converters, chain, sensor
        noise); default the default testbed in the thesis lab.
    plant : trussid.campaign.structure.CampaignPlant, optional
        Any other structure (a deck with its IO file and lab) instead of a testbed; its
        experiment comes from :func:`derived_settings`.
    adapt : bool
        Add the closed-loop identification and adaptive redesign section and its files
        under ``adapt/`` (:mod:`trussid.campaign.adapt`, issue 27).

    Returns
    -------
    DemoSummary
        The summary (written as ``summary.json`` and ``report.md``).
    """
    settings = settings or demo_settings()
    say = progress or (lambda msg: None)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out} exists and is not a directory")
    if out.exists() and not force:
        raise UserError(f"--out {out} exists; give --force to replace it (it is replaced "
                        "only once the new report is complete)")
    if not out.resolve().parent.is_dir():
        raise UserError(f"--out {out}: the directory {out.resolve().parent} does not exist "
                        "(it is not created for you)")
    if adapt:
        _check_adapt(plant, settings)
    prov = provenance(settings, command)
    t_start = time.perf_counter()
    timings = {}

    t0 = time.perf_counter()
    if plant is None:
        say("[1/5] testbed -> modes -> plant ...")
        tp = build_plant(testbed)
    else:
        say(f"[1/5] {plant.description}: modes -> plant ...")
        tp = plant
    truth = tp.discrete
    fs = 1.0 / truth.dt
    timings["plant"] = time.perf_counter() - t0
    f_modes = tp.modes.frequencies_hz
    say(f"      {len(f_modes)} modes below Nyquist ({f_modes[f_modes > 5][0]:.1f} to "
        f"{f_modes[-1]:.1f} Hz), plant {truth.nstates} states, {truth.ninputs} x "
        f"{truth.noutputs}, {fs:g} Hz ({timings['plant']:.1f} s)")

    t0 = time.perf_counter()
    say(f"[2/5] simulated experiments ({tp.lab.daq.bits}-bit D/A and A/D, sensor noise) ...")
    records = run_experiments(tp, settings, progress=lambda m: say("      " + m))
    timings["experiments"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    say("[3/5] identification (PLID) ...")
    fits, h1s = identify_records(records, settings, say)
    timings["identification"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    say("[4/5] evaluation against the true plant, H1 and validation data ...")
    models = []
    for name, (rid, rval) in records.items():
        kind = "MIMO" if name == "mimo" else "SIMO"
        models.append(evaluate(fits[name], truth, rid, rval, h1s[name], settings, name, kind))
    timings["evaluation"] = time.perf_counter() - t0

    control = None
    if "mimo" in records:  # close the loop on the MIMO model (issue 14)

        t0 = time.perf_counter()
        say("      closing the loop: LQG from the MIMO model, on the FE truths ...")
        # the plant's own lab and the demo's excitation at the D/A
        loop = LoopSettings.for_lab(tp.lab, excitation_rms=settings.excitation_rms,
                                    excitation_band_hz=settings.excitation_band[1])
        control = demo_section(fits["mimo"].model, fits["mimo"].K, records["mimo"][0].data,
                               truth, settings.quick, loop,
                               tp.tbm.testbed if hasattr(tp, "tbm") else None,
                               progress=lambda m: say("      " + m), lab=tp.lab,
                               excitation_rms=settings.excitation_rms)
        timings["control"] = time.perf_counter() - t0

    adapted = _adapt_section(tp, fits, records, settings, timings, say) if adapt else None

    t0 = time.perf_counter()
    say(f"[5/5] writing the report in {out}/ ...")
    with atomic_directory(out, force=force) as tmp:
        summary, html_s = _write_report(tmp, tp, records, fits, h1s, truth, settings, models,
                                        timings, prov, t0, t_start, control, adapted)
    say(f"      done in {timings['total']:.1f} s, then report.html in {html_s:.1f} s")
    return summary


def _check_adapt(plant, settings) -> None:
    """Refuse ``--adapt`` where it cannot run, before any work."""
    if plant is not None:
        raise UserError("--adapt changes the testbed (UDF mass, strut stiffness) under a "
                        "running controller: it needs a testbed MODEL (.toml or none), not a "
                        "deck")
    if not settings.mimo_order:
        raise UserError("--adapt closes the loop with the MIMO model's controller; this "
                        "campaign has no MIMO model (mimo_order 0)")


def _adapt_section(tp, fits, records, settings, timings, say):
    """Closed-loop identification and adaptive redesign (issue 27) in the plant's own lab,
    with this campaign's conditioner ranging; timed into ``timings``."""
    t0 = time.perf_counter()
    say("      closed-loop identification and adaptive redesign on changed truths ...")

    def ranging(rms):
        return conditioner_steps(rms, tp.lab.daq.full_scale, settings.range_target,
                                 settings.gain_steps)

    out = adapt_demo_section(tp.discrete, tp.tbm.testbed, tp.lab, fits["mimo"].model,
                             fits["mimo"].K, records["mimo"][0].data, settings, ranging,
                             progress=lambda m: say("      " + m))
    timings["adapt"] = time.perf_counter() - t0
    return out


def _write_report(out, tp, records, fits, h1s, truth, settings, models, timings, prov, t0,
                  t_start, control=None, adapted=None) -> tuple[DemoSummary, float]:
    """Every file of the report into ``out`` (the temporary directory); the summary and
    the seconds report.html took.
    ``control``: the closed-loop section and its figures (:func:`trussid.campaign.control.
    demo_section`) or None;
    ``adapted``: :func:`trussid.campaign.adapt.demo_section`'s result or None."""
    files = write_files(out, records, fits, truth, tp.lab)
    figures = {}  # file name -> Figure, drawn again interactively in report.html
    files.figures = write_figures(out, records, fits, h1s, truth, settings, keep=figures,
                                  unit="V/V" if hasattr(tp, "tbm") else "IO-file units")
    if control is not None:
        for fname, fig in control[1].items():
            save_figure(fig, out / fname)
        files.figures += list(control[1])
        figures.update(control[1])
    if adapted is not None:
        for fname, fig in adapted[1].items():
            save_figure(fig, out / fname)
        files.figures += list(adapted[1])
        figures.update(adapted[1])
        files.adapt = write_adapt_files(out, adapted[3])
    summary = DemoSummary(
        format_version=1, provenance=prov, settings=settings, plant=plant_section(tp),
        experiments=experiment_summary(records, settings), models=models, files=files,
        timings_s=timings,
        control=None if control is None else control[0],
        adapt=None if adapted is None else AdaptSection(adapted[0], adapted[2]))
    timings["report"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    with atomic_path(out / "summary.json") as tmp:
        tmp.write_text(json.dumps(summary.to_dict(), indent=2) + "\n")
    markdown = report_markdown(summary)
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text(markdown)
    # timed apart (the page's cost on the demo, issue 36), and not into the summary, which is
    # written already and must equal summary.json
    t_html = time.perf_counter()
    write_report_html(out, summary, markdown, figures, tp)
    return summary, time.perf_counter() - t_html


def plant_section(tp) -> PlantSummary:
    """The summary's plant: size, rate, modes, transducers, converters and noise."""
    lab = tp.lab
    f = tp.modes.frequencies_hz
    acc = lab.accelerometers
    if not hasattr(tp, "tbm"):  # a deck's plant: outputs in its own units, no conditioner
        nan = float("nan")
        return PlantSummary(
            states=int(tp.discrete.nstates), inputs=list(tp.discrete.input_labels),
            outputs=list(tp.discrete.output_labels), sample_rate_hz=1.0 / tp.discrete.dt,
            modes=int(f.size), mode_frequencies_hz=f.tolist(), modal_damping=tp.damping,
            accelerometer_sensitivity_v_per_g=nan, conditioning_gain=1.0,
            converter_bits=lab.daq.bits, converter_full_scale_v=lab.daq.full_scale,
            sensor_noise_g_rms=nan, sensor_noise_v_rms=nan, lab=lab,
            structure=tp.description, lab_source=tp.lab_source)
    tb = tp.tbm.testbed
    return PlantSummary(
        states=int(tp.discrete.nstates), inputs=list(tp.discrete.input_labels),
        outputs=list(tp.discrete.output_labels), sample_rate_hz=1.0 / tp.discrete.dt,
        modes=int(f.size), mode_frequencies_hz=f.tolist(),
        modal_damping=tb.damping.modal_ratio,
        accelerometer_sensitivity_v_per_g=acc.sensitivity * G0,
        conditioning_gain=acc.conditioning_gain,
        converter_bits=lab.daq.bits, converter_full_scale_v=lab.daq.full_scale,
        sensor_noise_g_rms=acc.noise / G0,
        sensor_noise_v_rms=acc.noise_volts,
        lab=lab,
    )


def experiment_summary(records: dict, settings: DemoSettings) -> list[ExperimentRow]:
    """One row per record: its size, rate, drive, converters, ranges and signal-to-noise."""
    rows = []
    for name, pair in records.items():
        for rec in pair:
            e = rec.experiment
            d = e.data
            y_rms = np.sqrt(np.mean(e.y_clean**2, axis=0))
            noise = np.asarray(e.sensor_noise_rms)
            lsb = np.asarray(e.lsb["adc"], dtype=float)
            rows.append(ExperimentRow(
                model=name, purpose=rec.purpose, samples=d.n_samples,
                sample_rate_hz=d.fs,
                driven_channels=[d.input_names[c] for c in rec.channels], seed=rec.seed,
                excitation=settings.excitation, excitation_rms_v=settings.excitation_rms,
                excitation_band_hz=list(settings.excitation_band),
                dac_clipped=e.clipping["dac"], adc_clipped=e.clipping["adc"],
                conditioner_steps=rec.gain_steps,
                adc_full_scale_v=rec.adc_full_scale,
                # the converters' LSB as the experiment applied them [V]
                dac_lsb_v=np.atleast_1d(np.asarray(e.lsb["dac"], dtype=float)).tolist(),
                adc_lsb_v=np.atleast_1d(lsb).tolist(),
                # converter resolution from the LSB the experiment used: 2 FS / 2^bits
                adc_bits=[int(round(np.log2(2 * fs / q)))
                          for fs, q in zip(rec.adc_full_scale, np.atleast_1d(lsb))],
                output_rms_v=y_rms.tolist(),
                output_rms_fraction_of_range=(y_rms / np.asarray(rec.adc_full_scale)).tolist(),
                sensor_snr_db=(20 * np.log10(y_rms / noise)).tolist(),
                quantisation_snr_db=(20 * np.log10(y_rms / (lsb / np.sqrt(12)))).tolist(),
            ))
    return rows


__all__ = ["DemoSettings", "demo_settings", "build_plant", "run_experiments", "take_record",
           "conditioner_steps", "identify_model", "evaluate",
           "run_demo", "report_markdown", "Identified", "Record", "mode_audit", "provenance"]
