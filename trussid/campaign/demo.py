"""The main job, end to end: the simulated identification campaign on the default testbed.

Plain functions over plain data, in the order ``trussid demo`` runs them::

    settings = demo_settings(quick)
    tp       = build_plant(settings)                     default testbed -> modes -> plant
    exps     = run_experiments(tp.discrete, settings)    identification + validation records
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
import time
import warnings
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from trussid._util.files import atomic_path
from trussid._util.jsonio import json_safe

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


def drive(settings: DemoSettings, plant, n: int, channels, seed: int) -> np.ndarray:
    """The excitation of the driven ``channels`` (others zero), at the plant's own rate."""
    from trussid.plid.experiment import excitation

    u = np.zeros((n, plant.ninputs))
    u[:, list(channels)] = excitation(settings.excitation, n, len(channels), 1.0 / plant.dt,
                                      settings.excitation_rms, settings.excitation_band, seed)
    return u


def range_conditioners(plant, settings: DemoSettings, channels, seed: int, n_samples: int,
                       noise_v: float, full_scale: float = 10.0) -> list:
    """Conditioner steps from a noise-free trial run of the experiment (its own seed)."""
    from trussid.plid.experiment import simulate

    trial = drive(settings, plant, n_samples, channels, seed)
    rms = np.sqrt(np.mean(simulate(plant, trial) ** 2, axis=0) + noise_v**2)
    return conditioner_steps(rms, full_scale, settings.range_target, settings.gain_steps)


def take_record(plant, settings: DemoSettings, name: str, purpose: str, channels, seed: int,
                n_samples: int, noise_v: float, steps, full_scale: float = 10.0,
                bits: int = 12) -> Record:
    """One record with the conditioners at ``steps`` (see the module docstring)."""
    from trussid.plid.experiment import run_experiment

    adc_fs = [full_scale / g for g in steps]
    u = drive(settings, plant, n_samples, channels, seed)
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
    from trussid.plid.estimator import PLIDWarning
    from trussid.plid.metrics import choose_predictor
    from trussid.plid.multipass import Stabilised, default_via, fit_model

    t0 = time.perf_counter()
    with warnings.catch_warnings():
        # The candidates' PLID passes warn when a pass loses positive definiteness; the
        # recipe handles that (a failed candidate is dropped) and the report lists them.
        warnings.simplefilter("ignore", PLIDWarning)
        p = np.asarray(y).reshape(len(y), -1).shape[1]
        idn = fit_model(u, y, order, dt, start="subspace",
                        via=default_via(order, p) if via is None else via, progress=progress,
                        log=log, block_rows=None if block_rows is None else list(block_rows))
    res = idn.result
    model = idn.model
    prov = idn.provenance
    chosen = prov.chosen or ""
    stab = prov.stabilised or Stabilised()
    if np.max(np.abs(np.linalg.eigvals(np.asarray(model.A)))) >= 1:
        # No stable candidate (none was measured on the testbed): reflect the poles outside
        # the unit circle in (plid.stability keeps the magnitude response) so that the model
        # can be simulated, and choose its predictor afresh.
        from trussid.plid.stability import stabilise

        st = stabilise(model)
        model = st.model
        stab = Stabilised(bool(st.applied), int(np.size(st.reflected)))
        K, K_source, kinfo = choose_predictor(model, u, y)
    else:
        K, kinfo = idn.K, prov.predictor or {}
        K_source = kinfo.get("chosen", "")
    hist, hidx = res.theta_history, res.history_index
    if hist.shape[0] < 2 and idn.prior is not None:
        # The recipe ran without a parameter history: repeat the winner's last PLID pass
        # with one (same basis, prior and settings, so the same estimate) for the plot.
        hist, hidx = _history_of_last_pass(idn, u, y, res.model.nstates, dt)
    info = {"recipe": "trussid.plid.multipass.identify_reduced", "start": idn.start,
            "stabilised": stab, "basis": getattr(idn.basis, "name", ""),
            "R": np.asarray(idn.R).tolist(), "predictor": kinfo,
            **{k: v for k, v in prov.as_dict().items() if k not in ("passes", "predictor")},
            "passes": prov.passes}
    method = f"PLID ({res.form} form, {idn.start} start; {chosen})"
    return Identified(model, K, K_source, time.perf_counter() - t0, method,
                      res.innovations, hist, hidx, info)


def _history_of_last_pass(idn, u, y, order, dt):
    from trussid.plid.estimator import PLID, PLIDWarning

    last = (idn.provenance.passes or [{}])[-1]
    est = PLID(order, form=idn.result.form, dt=dt, Q=last.get("Q", 0.0), R=idn.R,
               Q_theta=last.get("Q_theta", 0.0), prior=idn.prior,
               prior_theta_var=last.get("prior_theta_var", 1e-4), basis=idn.basis,
               history_every=10, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PLIDWarning)  # as in identify_model
        r = est.fit(u, y)
    return r.theta_history, r.history_index


# --------------------------------------------------------------------------- evaluation


def evaluate(fit: Identified, truth, rid: Record, rval: Record, h1_est, settings: DemoSettings,
             name: str, kind: str) -> dict:
    """All metrics of one model, by :func:`trussid.plid.evaluate.compare` (as ``trussid
    compare``): validation prediction and simulation, FRF errors against the true plant and
    the H1 estimate, matched poles."""
    from trussid.plid.evaluate import compare

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
    return {
        "name": name, "kind": kind, "states": c.states, "inputs": c.inputs, "outputs": c.outputs,
        "input_names": [val.input_names[c_] for c_ in cols], "output_names": list(val.output_names),
        "signal_to_prediction_error_db": p.overall,
        "signal_to_prediction_error_db_per_output": p.per_output,
        "signal_to_prediction_error_db_mean_normalised": p.mean_normalised,
        "prediction_skip_samples": p.skip,
        "predictor_gain": p.gain,
        "frf_max_error_db": e.max_db, "frf_rms_error_db": e.rms_db,
        "frf_max_error_deg": e.max_deg, "frf_rms_error_deg": e.rms_deg,
        "frf_error_per_channel": e.per_channel,
        "frf_band_hz": list(settings.frf_band),
        "frf_error_vs_h1": {"max_db": eh.max_db, "rms_db": eh.rms_db, "max_deg": eh.max_deg,
                            "rms_deg": eh.rms_deg},
        "h1_error_vs_true": h1_true,
        "simulation_fit_db": s.overall,
        "simulation_fit_db_per_output": s.per_output,
        "seconds": fit.seconds, "method": fit.method, "unstable_poles": c.unstable_poles,
        "stabilised": fit.info.get("stabilised", {}),
        "poles": c.poles,
        "poles_in_band_matched": sum(r.frequency_hz is not None for r in in_band),
        "poles_in_band_true": len(in_band),
        "validation_output_rms_v": y_rms.tolist(),
        "h1_coherence": coherence,
        "modes_check": mode_audit(c.poles, settings.frf_band, settings.excitation_band),
        "identification": json_safe(fit.info),
    }


#: A true or identified pole with a damping ratio above this is not a structural mode (the
#: plant's filter and amplifier poles are real: damping 1).
MODE_DAMPING_MAX = 0.5
#: Relative frequency error within which an identified mode counts as the true one found.
FOUND_TOLERANCE = 0.05
#: Identified modes below this damping ratio are listed wherever they are (a controller
#: designed on the model would respect them).
LIGHT_DAMPING = 0.01


def mode_audit(poles: list, band, excited) -> dict:
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
    dict
        ``true_modes_in_band``: every true structural mode (damping <= MODE_DAMPING_MAX) in
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
                         and r.true_damping <= MODE_DAMPING_MAX})
    f_true = np.array([f for f, _ in true_modes]) if true_modes else np.zeros(0)
    rows, filters = [], 0
    for r in poles:
        ft = r.true_frequency_hz
        if ft is None or not lo <= ft <= hi:
            continue
        if r.true_damping > MODE_DAMPING_MAX:
            filters += 1
            continue
        fi = r.frequency_hz
        found = (fi is not None and r.damping <= MODE_DAMPING_MAX
                 and abs(fi - ft) <= FOUND_TOLERANCE * ft)
        rows.append({"true_frequency_hz": ft, "true_damping": r.true_damping,
                     "found": bool(found), "frequency_hz": fi if found else None,
                     "damping": r.damping if found else None})

    def nearest(f):
        if not f_true.size:
            return None, None
        k = int(np.argmin(np.abs(f_true - f)))
        return float(f_true[k]), float(abs(f_true[k] - f) / max(f_true[k], 1e-12))

    identified, spurious, light = [], [], []
    for r in poles:
        fi = r.frequency_hz
        if fi is None or r.damping > MODE_DAMPING_MAX:
            continue
        near, rel = nearest(fi)
        entry = {"frequency_hz": fi, "damping": r.damping, "nearest_true_hz": near,
                 "spurious": bool(near is None or rel > FOUND_TOLERANCE),
                 "in_excited_band": bool(excited[0] <= fi <= excited[1])}
        identified.append(entry)
        if entry["spurious"]:
            spurious.append(entry)
        if r.damping < LIGHT_DAMPING:
            light.append(entry)
    key = lambda e: e["frequency_hz"]  # noqa: E731
    return {"band_hz": [lo, hi], "excited_band_hz": list(excited),
            "true_modes_in_band": rows,
            "found": sum(r["found"] for r in rows), "total": len(rows),
            "missing": [r["true_frequency_hz"] for r in rows if not r["found"]],
            "filter_poles_in_band": filters,
            "spurious": sorted(spurious, key=key), "lightly_damped": sorted(light, key=key),
            "rules": {"structural_damping_max": MODE_DAMPING_MAX,
                      "found_within": FOUND_TOLERANCE, "light_damping_below": LIGHT_DAMPING}}


def provenance(settings: "DemoSettings", command: str | None = None) -> dict:
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
    return {"trussid_version": trussid_version, "commit": commit, "seed": settings.seed,
            "command": command, "machine": platform.node(), "platform": platform.platform(),
            "cpus": os.cpu_count(), "python": platform.python_version(),
            "load_average_start": load,
            "date_utc": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime())}


def _h1_error(h1_est, truth, keep) -> dict:
    """Magnitude/phase error of the H1 estimate against the true plant at its own frequencies."""
    from trussid.plid.frf import frequency_response

    H, H_ref = h1_est.H[keep], frequency_response(truth, h1_est.f[keep])
    with np.errstate(divide="ignore", invalid="ignore"):
        mag = 20 * np.log10(np.abs(H)) - 20 * np.log10(np.abs(H_ref))
        ph = np.degrees(np.angle(H / H_ref))
    return {"max_db": float(np.max(np.abs(mag))), "rms_db": float(np.sqrt(np.mean(mag**2))),
            "max_deg": float(np.max(np.abs(ph))), "rms_deg": float(np.sqrt(np.mean(ph**2)))}


def h1_estimate(record: Record, nperseg: int):
    """H1 estimate from an identification record (driven channels only)."""
    from trussid.plid.frf import h1

    d = record.data
    return h1(d.u[:, list(record.channels)], d.y, d.fs, nperseg=nperseg)


# --------------------------------------------------------------------------- the run


def identify_records(records: dict, settings: DemoSettings, say) -> tuple[dict, dict]:
    """Each model identified from its identification record, and that record's H1 estimate."""
    fits, h1s = {}, {}
    for name, (rid, _) in records.items():
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
    return fits, h1s


def write_files(out: Path, records: dict, fits: dict, truth) -> dict:
    """The records (driven channels only) and the models as data and model files."""
    from trussid.plid.datafile import with_channels, write_data
    from trussid.plid.modelfile import save_model

    files = {"data": [], "models": []}
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
    return files


def write_figures(out: Path, records: dict, fits: dict, h1s: dict, truth,
                  settings: DemoSettings) -> list:
    """Bode overlays, pole maps, traces and the convergence plot; their file names."""
    from trussid import plots

    written = []

    def save(fig, fname):
        plots.save_figure(fig, out / fname, dpi=100)
        written.append(fname)

    for name, (rid, rval) in records.items():
        cols = list(rid.channels)
        in_names = [rid.data.input_names[c] for c in cols]
        figs = plots.bode_overlay(truth[:, cols], h1s[name], fits[name].model, in_names,
                                  rid.data.output_names, settings.plot_band, f"{name}",
                                  excited=settings.excitation_band)
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
             force: bool = False, command: str | None = None) -> dict:
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

    Returns
    -------
    dict
        The summary (also written as ``summary.json``).
    """
    from trussid._util.errors import UserError
    from trussid._util.files import atomic_directory

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
    prov = provenance(settings, command)
    t_start = time.perf_counter()
    timings = {}

    t0 = time.perf_counter()
    say("[1/5] testbed -> modes -> plant ...")
    tp = build_plant(settings)
    truth = tp.discrete
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
        from trussid.campaign.control import demo_section

        t0 = time.perf_counter()
        say("      closing the loop: LQG from the MIMO model, on the FE truths ...")
        control = demo_section(fits["mimo"].model, fits["mimo"].K, records["mimo"][0].data,
                               truth, settings.quick, progress=lambda m: say("      " + m))
        timings["control"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    say(f"[5/5] writing the report in {out}/ ...")
    with atomic_directory(out, force=force) as tmp:
        summary = _write_report(tmp, tp, records, fits, h1s, truth, settings, models, timings,
                                prov, t0, t_start, control)
    say(f"      done in {timings['total']:.1f} s")
    return summary


def _write_report(out, tp, records, fits, h1s, truth, settings, models, timings, prov, t0,
                  t_start, control=None) -> dict:
    """Every file of the report into ``out`` (the temporary directory); the summary.
    ``control``: the closed-loop section ``(markdown, figures, summary)`` or None."""
    files = write_files(out, records, fits, truth)
    files["figures"] = write_figures(out, records, fits, h1s, truth, settings)
    if control is not None:
        from trussid.plots import save_figure

        for fname, fig in control[1].items():
            save_figure(fig, out / fname)
        files["figures"] += list(control[1])
    summary = {
        "format_version": 1,
        "provenance": prov,
        "settings": asdict(settings),
        "plant": plant_section(tp, settings),
        "experiments": experiment_summary(records, settings),
        "models": models,
        "files": files,
        "timings_s": timings,
    }
    if control is not None:
        summary["control"] = control[2]
    timings["report"] = time.perf_counter() - t0
    timings["total"] = time.perf_counter() - t_start
    summary = json_safe(summary)
    with atomic_path(out / "summary.json") as tmp:
        tmp.write_text(json.dumps(summary, indent=2) + "\n")
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text(report_markdown(summary) + ("\n" + control[0] if control else ""))
    return summary


def plant_section(tp, settings: DemoSettings) -> dict:
    """The summary's plant: size, rate, modes, transducers, converters and noise."""
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
    # Long: a report template, read best top to bottom in the order of the report.
    st, pl = s["settings"], s["plant"]
    L = ["# trussid demo: PLID on the simulated testbed", ""]
    L += provenance_lines(s.get("provenance") or {})
    L += [f"Run: {'quick' if st['quick'] else 'full'}; total {s['timings_s']['total']:.1f} s "
          f"(plant {s['timings_s']['plant']:.1f} s, experiments "
          f"{s['timings_s']['experiments']:.1f} s, identification "
          f"{s['timings_s']['identification']:.1f} s, evaluation "
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
          "Every score in this table is on the **validation** record (a separate record "
          "with its own seed), never on the record the model was fitted to; the simulation "
          "fit runs the model from the inputs alone (no measured outputs fed back), "
          "against the noise-free outputs. Phase errors are against the true plant, "
          "magnitude and phase separately. \"Modes found\" counts the true structural "
          "modes in the FRF band (the filter poles excluded) matched within "
          "5 % in frequency; the next section lists the rest.", "",
          "| model | kind | states | in x out | SPE, validation [dB] | SPE per output [dB] | "
          "SPE mean-normalised [dB] | simulation fit, validation [dB] | FRF max / RMS [dB] | "
          "phase max / RMS [deg] | H1 vs true RMS [dB] | modes found (in band) | seconds |",
          "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for m in s["models"]:
        mc = m.get("modes_check") or {}
        L.append(f"| {m['name']} | {m['kind']} | {m['states']} | {m['inputs']} x "
                 f"{m['outputs']} | {_f(m['signal_to_prediction_error_db'])} | "
                 f"{', '.join(_f(v, '.1f') for v in m['signal_to_prediction_error_db_per_output'])}"
                 f" | {_f(m['signal_to_prediction_error_db_mean_normalised'])} | "
                 f"{_f(m.get('simulation_fit_db'))} | "
                 f"{_f(m['frf_max_error_db'])} / {_f(m['frf_rms_error_db'])} | "
                 f"{_f(m.get('frf_max_error_deg'), '.1f')} / {_f(m.get('frf_rms_error_deg'), '.1f')} | "
                 f"{_f(m['h1_error_vs_true']['rms_db'])} | "
                 f"{mc.get('found', '-')} / {mc.get('total', '-')} | "
                 f"{m['seconds']:.1f} |")
    L += lacks_lines(s)
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
              "| candidate | one-step, identification record (in-sample) [dB] | seconds |",
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
    L += ["### Convergence", "", "![convergence](convergence.png)", "",
          "The top panel is the *mean-normalised* one-step ratio of each model's last PLID "
          "pass on its identification record (in-sample), not the headline SPE of the table "
          "above.", ""]
    L += ["## Files", "", "Data: " + ", ".join(s["files"]["data"]), "",
          "Models: " + ", ".join(s["files"]["models"]), "",
          "All metrics: `summary.json`.", ""]
    return "\n".join(L)


def provenance_lines(pv: dict) -> list:
    """The report's provenance paragraph."""
    if not pv:
        return []
    load = pv.get("load_average_start")
    return ["## Provenance", "",
            f"trussid {pv.get('trussid_version')}, commit {pv.get('commit') or 'unknown'}; "
            f"seed {pv.get('seed')}; command `{pv.get('command') or '(from Python)'}`; "
            f"machine {pv.get('machine')} ({pv.get('platform')}, {pv.get('cpus')} CPUs, Python "
            f"{pv.get('python')}), load average "
            f"{'-' if not load else ', '.join(f'{v:.2f}' for v in load)} at the start; "
            f"{pv.get('date_utc')}. The seconds below depend on that load.", ""]


def lacks_lines(s: dict) -> list:
    """What each model lacks (true modes missing) and adds (spurious or lightly damped
    poles anywhere, reflected poles), and the H1 coherence."""
    # Long: one report section, read top to bottom.
    L = ["", "## What the models lack, and what they add", ""]
    for m in s["models"]:
        mc = m.get("modes_check")
        if not mc:
            continue
        lo, hi = mc["band_hz"]
        xlo, xhi = mc["excited_band_hz"]
        L += [f"**{m['name']}**: found {mc['found']} of the {mc['total']} true structural "
              f"modes in {lo:g}-{hi:g} Hz ({mc['filter_poles_in_band']} filter/amplifier "
              "poles in the band are not counted)."]
        if mc["missing"]:
            L += [f"Missing ({len(mc['missing'])}): "
                  + ", ".join(f"{f:.2f} Hz" for f in mc["missing"]) + "."]
        else:
            L += ["Missing: none."]
        st = m.get("stabilised") or {}
        if st.get("applied"):
            L += [f"Stabilised: {st.get('reflected_poles', 0)} unstable pole(s) reflected into "
                  "the unit circle (magnitude kept, phase changed)."]
        if m.get("unstable_poles"):
            L += [f"**Unstable**: {m['unstable_poles']} pole(s) on or outside the unit circle."]
        rows = {(e["frequency_hz"], e["damping"]): e for e in mc["spurious"] + mc["lightly_damped"]}
        L += [""]
        if rows:
            L += ["Spurious modes (no true mode within 5 %) and lightly damped modes "
                  f"(damping under {100 * mc['rules']['light_damping_below']:g} %), anywhere "
                  f"up to Nyquist (excited band {xlo:g}-{xhi:g} Hz):", "",
                  "| identified f [Hz] | damping [%] | nearest true mode [Hz] | spurious | "
                  "in excited band |", "| --- | --- | --- | --- | --- |"]
            for (f, z), e in sorted(rows.items()):
                near = "-" if e["nearest_true_hz"] is None else f"{e['nearest_true_hz']:.2f}"
                L.append(f"| {f:.2f} | {100 * z:.3f} | {near} | "
                         f"{'yes' if e['spurious'] else 'no'} | "
                         f"{'yes' if e['in_excited_band'] else '**no**'} |")
        else:
            L += ["No spurious or lightly damped identified modes."]
        coh = m.get("h1_coherence")
        if coh:
            above = coh.get("mean_above_excited_band")
            L += ["", f"H1 multiple coherence, mean per output: "
                  + ", ".join(f"{v:.3f}" for v in coh["mean_in_excited_band"])
                  + f" in the excited band {xlo:g}-{xhi:g} Hz"
                  + ("; " + ", ".join(f"{v:.3f}" for v in above)
                     + " above it, where the H1 estimate is noise (shaded band in the Bode "
                       "plots)" if above else "") + "."]
        L += [""]
    return L


__all__ = ["DemoSettings", "demo_settings", "build_plant", "run_experiments", "take_record",
           "conditioner_steps", "identify_model", "evaluate",
           "run_demo", "report_markdown", "Identified", "Record", "mode_audit", "provenance"]
