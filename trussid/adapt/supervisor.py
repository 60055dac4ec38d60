"""Redesign from a closed-loop model, the supervisor's checks, and the adaptive loop.

The adaptive loop (:func:`adapt`) runs the lab as windows of closed-loop records: after
each window the plant is re-identified from that window (PLID direct method, a batch fit
on a sliding window: the feasibility study measured a recursive PLID update at 0.8 of a
core at 1600 Hz in Python, and a window fit gives the same model family at a known cost),
a change is *detected* when a dominant mode of the new model moved from the reference
model's or the running controller's damping predicted on the new model fell, a redesign
is made from the new model and its window, and the **supervisor** lets the new controller
replace the running one only if it passes every check on the model
(:func:`check_candidate`) and, on the *next* window (fresh closed-loop data taken with the
running controller), the model still predicts the measurements (:func:`check_fresh`).
Otherwise the running controller stays. The loop is thus never switched to a controller
the data have not vouched for; the simulator additionally records the truth's closed-loop
spectral radius at every switch (a check the supervisor cannot make in a lab).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from trussid.lqg.design import excited_band
from trussid.lqg.errors import ControlError
from trussid.lqg.evaluate import (MODE_DAMPING_MAX, DampingTable, closed_loop, damping_table,
                                  disk_margins)
from trussid.lqg.grading import DEFAULT_BAND, THRESHOLDS, Thresholds
from trussid.lqg.procedure import design_procedure
from trussid.plid.metrics import prediction_ratio_db

from .experiment import ClosedLoopRecord, closed_loop_record
from .identify import ClosedLoopModel, identify_plid

# --------------------------------------------------------------------------- damping per mode


def mode_damping(plant, controller, band=(40.0, 450.0), n_dominant: int = 3,
                 window: float = 0.03) -> DampingTable:
    """The plant's modes in ``band`` under ``controller``, as the supervisor grades them:
    :func:`trussid.lqg.evaluate.damping_table` with its ``pairing="window"`` (issue 27's
    definition: an identified model's eigenvectors are not trusted)."""
    return damping_table(plant, controller, band=band, pairing="window", window=window,
                         n_dominant=n_dominant)


# --------------------------------------------------------------------------- supervisor

#: The adaptive loop's default dither band [Hz] (:class:`AdaptSettings`).
DITHER_BAND = (0.0, 400.0)


@dataclass(frozen=True)
class SupervisorSettings:
    """What a new controller must show before it replaces the running one.

    Attributes
    ----------
    target_damping : float
        The redesign's state-feedback damping of its target modes [-].
    thresholds : trussid.lqg.grading.Thresholds
        What the model must show under the new controller (the nominal thresholds of every
        graded loop): every dominant mode at least ``dominant_nominal`` damping, the other
        modes in ``band`` at least ``other_ratio_nominal`` of theirs, a MIMO disk gain
        margin of at least ``mimo_gm_nominal_db`` (balanced, at the plant input).
    max_prediction_loss_db : float
        Fresh data: the model's one-step prediction ratio on the fresh record may fall at
        most this much below its ratio on its own identification record [dB].
    detect_shift : float
        Detection: a dominant mode of the new model moved by more than this (relative).
    detect_damping : float
        Detection: the running controller's least dominant damping predicted on the new
        model fell below this fraction of ``target_damping``.
    band : (float, float)
        Modes of the model considered [Hz]: the graded band
        (:data:`trussid.lqg.grading.DEFAULT_BAND`) up to the top of the dither's band
        (:data:`DITHER_BAND`), where the model is identified (a 36-state model can hold a
        spurious lightly damped mode above it).
    """

    target_damping: float = 0.07
    thresholds: Thresholds = THRESHOLDS
    max_prediction_loss_db: float = 3.0
    detect_shift: float = 0.01
    detect_damping: float = 0.95
    band: tuple = (DEFAULT_BAND[0], min(DEFAULT_BAND[1], DITHER_BAND[1]))


@dataclass
class Verdict:
    """A supervisor check: ``accepted`` and the figures behind it (``reasons`` lists every
    failed criterion, empty when accepted).

    Attributes
    ----------
    accepted : bool
    reasons : list of str
    figures : CandidateFigures or FreshFigures
    """

    accepted: bool
    reasons: list
    figures: object


def _detail(record) -> dict:
    """A typed figure record as an event's plain detail (fields that are None left out)."""
    return {k: v for k, v in asdict(record).items() if v is not None}


@dataclass(frozen=True)
class CandidateFigures:
    """The model checks' figures of a candidate controller (:func:`check_candidate`).

    Attributes
    ----------
    stable : bool
    spectral_radius : float
    dominant_hz, dominant_damping, running_dominant_damping : list of float
        The dominant modes [Hz], their damping with the candidate and with the running
        controller (ratios).
    others_ratio : float
        Least fraction of its damping another mode keeps.
    disk_margin_db : float or None
        MIMO disk gain margin [dB] (None when the loop is unstable: not computed).
    """

    stable: bool
    spectral_radius: float
    dominant_hz: list
    dominant_damping: list
    running_dominant_damping: list
    others_ratio: float
    disk_margin_db: float | None = None


@dataclass(frozen=True)
class FreshFigures:
    """One-step prediction ratios [dB] of a model on its own and on a fresh record
    (:func:`check_fresh`)."""

    prediction_db_identification: float
    prediction_db_fresh: float


@dataclass(frozen=True)
class Detection:
    """What :func:`detect` found.

    Attributes
    ----------
    changed : bool
    dominant_hz : list of float
        Dominant modes of the new model [Hz].
    shift : list of float
        Each one's relative distance to the nearest reference frequency.
    predicted_damping : list of float
        The running controller's damping of each on the new model.
    stable_on_model : bool
    """

    changed: bool
    dominant_hz: list
    shift: list
    predicted_damping: list
    stable_on_model: bool


def redesign(fit: ClosedLoopModel, rec: ClosedLoopRecord,
             settings: SupervisorSettings = SupervisorSettings()) -> list:
    """The candidate LQG design from a closed-loop model and its record: the one design
    path of ``trussid control`` (:func:`trussid.lqg.procedure.design_procedure`), with the
    targets chosen in the band the record excited within ``settings.band``, and the
    supervisor's margin and spillover requirements graded on the model as it designs.
    The procedure backs off the damping and drops targets (a mode merged into a cluster
    is the first to go) rather than fail; the supervisor's checks follow.

    Returns ``[(label, LQGDesign or ControlError)]`` (one entry).
    """
    u, y = rec.plant_input, rec.measured
    # targets inside the band the record excited: a model's mode outside it is poorly
    # identified (a spurious 420 Hz one showed up on the testbed)
    lo, hi = excited_band(u, 1.0 / rec.dt)
    band = (max(settings.band[0], lo), min(settings.band[1], hi))
    try:
        proc = design_procedure(fit.model, u, y, K=fit.K, band=band,
                                target_damping=settings.target_damping,
                                min_gain_db=settings.thresholds.mimo_gm_nominal_db,
                                others_ratio=settings.thresholds.other_ratio_nominal)
    except ControlError as exc:  # e.g. no lightly damped mode in the band
        return [("procedure", exc)]
    des = proc.design
    des.procedure = proc
    return [("procedure", des)]


def check_candidate(model, candidate, running,
                    settings: SupervisorSettings = SupervisorSettings()) -> Verdict:
    """The model checks of a new controller ``candidate`` against the ``running`` one.

    Accepted when, on ``model``: the loop is stable; every dominant mode reaches the
    thresholds' ``dominant_nominal`` and the least dominant damping is above the running
    controller's (on the same model); the other modes keep ``other_ratio_nominal`` of their
    damping; the MIMO disk gain margin is at least ``mimo_gm_nominal_db``.
    """
    T = settings.thresholds
    new = mode_damping(model, candidate, settings.band)
    old = mode_damping(model, running, settings.band)
    fig = CandidateFigures(stable=new.stable, spectral_radius=new.spectral_radius,
                           dominant_hz=new.dominant_frequency_hz.tolist(),
                           dominant_damping=new.dominant_damping.tolist(),
                           running_dominant_damping=old.dominant_damping.tolist(),
                           others_ratio=new.others_ratio)
    reasons = []
    if not new.stable:
        reasons.append(f"unstable on the model (|z| = {new.spectral_radius:.4f})")
        return Verdict(False, reasons, fig)
    if new.dominant_damping.min() < T.dominant_nominal:
        reasons.append(f"a dominant mode at {100 * new.dominant_damping.min():.2f} % "
                       f"(< {100 * T.dominant_nominal:.1f} %)")
    if new.dominant_damping.min() <= old.dominant_damping.min():
        reasons.append("no better than the running controller on the model")
    if new.others_ratio < T.other_ratio_nominal:
        reasons.append(f"another mode keeps {new.others_ratio:.2f} of its damping")
    dm = disk_margins(model, candidate).mimo
    fig = replace(fig, disk_margin_db=dm.gain_db)
    if dm.gain_db < T.mimo_gm_nominal_db:
        reasons.append(f"MIMO disk margin {dm.gain_db:.1f} dB (< {T.mimo_gm_nominal_db:g})")
    return Verdict(not reasons, reasons, fig)


def check_fresh(fit: ClosedLoopModel, identification: ClosedLoopRecord,
                fresh: ClosedLoopRecord,
                settings: SupervisorSettings = SupervisorSettings()) -> Verdict:
    """Fresh closed-loop data: the model must still predict the loop one step ahead on a
    record taken after its own, within ``max_prediction_loss_db`` of its ratio on its
    identification record (a model of a structure still changing, or fitted to a record's
    noise, fails)."""
    skip = min(400, identification.n_samples // 10)
    own = prediction_ratio_db(fit.model, identification.plant_input, identification.measured,
                              K=fit.K, skip=skip).overall
    new = prediction_ratio_db(fit.model, fresh.plant_input, fresh.measured, K=fit.K,
                              skip=skip).overall
    fig = FreshFigures(prediction_db_identification=own, prediction_db_fresh=new)
    ok = new >= own - settings.max_prediction_loss_db
    reasons = [] if ok else [f"one-step prediction on fresh data {new:.1f} dB, "
                             f"{own - new:.1f} dB below the identification record's"]
    return Verdict(ok, reasons, fig)


# --------------------------------------------------------------------------- adaptive loop


@dataclass(frozen=True)
class AdaptSettings:
    """The adaptive loop's lab (SI units).

    Attributes
    ----------
    window : int
        Samples per record window (each re-identification uses one window).
    order : int
        States of each closed-loop model.
    block_rows : tuple of int
        N4SID block rows of PLID's prior.
    dither_rms : float
        White dither at each D/A channel [V] (2 V keeps the testbed's loop unclipped).
    dither_band : (float, float)
        [Hz].
    noise_rms : float or tuple
        Sensor noise RMS [V].
    adc_full_scale : float or tuple
        A/D range per sensor in plant units [V].
    dac_full_scale : float
    bits : int
    max_windows : int
        Windows run at most.
    seed : int
    supervisor : SupervisorSettings
    """

    window: int = 6000
    order: int = 36
    block_rows: tuple = (40, 80)
    dither_rms: float = 2.0
    dither_band: tuple = DITHER_BAND
    noise_rms: object = 0.0
    adc_full_scale: object = None   # the lab's converters: required (adapt() checks)
    dac_full_scale: float | None = None
    bits: int | None = None
    max_windows: int = 4
    seed: int = 27
    supervisor: SupervisorSettings = SupervisorSettings()


@dataclass
class Event:
    """Something the adaptive loop did, at simulated time ``t`` [s] (the end of the window
    whose data it used), with the CPU seconds it cost."""

    t: float
    kind: str          # identified | detected | candidate | rejected | switched | kept
    cpu_seconds: float
    detail: dict = field(default_factory=dict)


@dataclass
class AdaptRun:
    """What :func:`adapt` did.

    Attributes
    ----------
    events : list of Event
    controllers : list of control.StateSpace
        Every controller that ran, in order (the first the one given).
    switch_times : list of float
        Simulated times [s] of the switches (``controllers[k + 1]`` from ``switch_times[k]``).
    truth_spectral_radius : list of float
        The truth's closed-loop spectral radius under each controller that ran (the
        simulator's check at every switch).
    models : list of ClosedLoopModel
        Each window's model.
    records : list of ClosedLoopRecord
    detected_at, switched_at : float or None
        Simulated times [s] (the change at t = 0).
    detect_cpu_seconds, redesign_cpu_seconds : float or None
        CPU seconds from the change to the detection, and of the redesign and its checks.
    """

    events: list
    controllers: list
    switch_times: list
    truth_spectral_radius: list
    models: list
    records: list
    detected_at: float | None = None
    switched_at: float | None = None
    detect_cpu_seconds: float | None = None
    redesign_cpu_seconds: float | None = None

    @property
    def controller(self):
        """The controller in the loop at the end."""
        return self.controllers[-1]


def detect(fit: ClosedLoopModel, running, reference_hz,
           settings: SupervisorSettings = SupervisorSettings()) -> Detection:
    """Has the plant changed? ``changed`` when a dominant mode of ``fit``'s model is more
    than ``detect_shift`` from the nearest of ``reference_hz`` (the dominant modes of the
    model the running controller was accepted on), or the running controller's least
    dominant damping predicted on the new model is below ``detect_damping`` x target."""
    md = mode_damping(fit.model, running, settings.band)
    ref = np.asarray(reference_hz, float)
    shift = [float(np.min(np.abs(ref / f - 1))) for f in md.dominant_frequency_hz]
    low = float(md.dominant_damping.min()) if md.stable else 0.0
    changed = (max(shift) > settings.detect_shift
               or low < settings.detect_damping * settings.target_damping)
    return Detection(changed=bool(changed), dominant_hz=md.dominant_frequency_hz.tolist(), shift=shift,
                     predicted_damping=md.dominant_damping.tolist(), stable_on_model=md.stable)


def adapt(truth, controller, reference_hz, settings: AdaptSettings = AdaptSettings(),
          progress=None) -> AdaptRun:
    """Run the loop on ``truth`` from rest, the change at t = 0, with ``controller`` in it;
    re-identify, detect, redesign and switch under the supervisor (module docstring).

    ``truth`` drives the simulation only; the supervisor sees the records alone. After a
    switch one more window is recorded with the new controller, then the run ends (or after
    ``max_windows``).
    """
    missing = [k for k in ("adc_full_scale", "dac_full_scale", "bits")
               if getattr(settings, k) is None]
    if missing:
        raise ValueError(f"AdaptSettings: the lab's converters are needed: {', '.join(missing)}")
    say = progress or (lambda msg: None)
    sv = settings.supervisor
    dt = float(truth.dt)
    running = controller
    run = AdaptRun([], [controller], [], [_rho(truth, controller)], [], [])
    xp = xc = None
    pending = None   # (label, design, fit, record) waiting for fresh data
    cpu_since_change = 0.0
    for w in range(settings.max_windows):
        rec = closed_loop_record(truth, running, settings.window, dither_rms=settings.dither_rms,
                                 band=settings.dither_band, noise_rms=settings.noise_rms,
                                 adc_full_scale=settings.adc_full_scale,
                                 dac_full_scale=settings.dac_full_scale, bits=settings.bits,
                                 seed=settings.seed + 10 * w, x_plant=xp, x_controller=xc)
        xp, xc = rec.x_plant, rec.x_controller
        run.records.append(rec)
        t = (w + 1) * settings.window * dt
        if run.switched_at is not None:
            break   # the window after the switch is recorded: done
        if pending is not None:
            new = _fresh_check(run, pending, rec, truth, t, sv, say)
            pending = None
            if new is not None:
                running, xc = new, np.zeros(new.nstates)   # the new controller from rest
                continue
        fit = identify_plid(rec, settings.order, block_rows=settings.block_rows)
        run.models.append(fit)
        c0 = time.process_time()
        det = detect(fit, running, reference_hz, sv)
        cpu = fit.cpu_seconds + time.process_time() - c0
        cpu_since_change += cpu
        run.events.append(Event(t, "identified", cpu, _detail(det)))
        say(f"t = {t:.2f} s: identified {fit.model.nstates} states ({fit.cpu_seconds:.1f} s CPU); "
            f"dominant modes {', '.join(f'{f:.1f}' for f in det.dominant_hz)} Hz, "
            f"change {'detected' if det.changed else 'not detected'}")
        if not det.changed:
            continue
        if run.detected_at is None:
            run.detected_at, run.detect_cpu_seconds = t, cpu_since_change
            run.events.append(Event(t, "detected", 0.0, _detail(det)))
        pending = _candidate(run, fit, rec, running, t, sv, say)
    return run


def _fresh_check(run: AdaptRun, pending, rec, truth, t, sv, say):
    """The pending candidate against the fresh window ``rec``: switch (returns the new
    controller) or reject (returns None)."""
    label, des, pfit, prec = pending
    c0 = time.process_time()
    v = check_fresh(pfit, prec, rec, sv)
    cpu = time.process_time() - c0
    run.redesign_cpu_seconds = (run.redesign_cpu_seconds or 0.0) + cpu
    if not v.accepted:
        run.events.append(Event(t, "rejected", cpu, {"design": label, "stage": "fresh data",
                                                     "reasons": v.reasons, **_detail(v.figures)}))
        say(f"t = {t:.2f} s: {label} redesign rejected on fresh data: {'; '.join(v.reasons)}")
        return None
    run.controllers.append(des.controller)
    run.switch_times.append(t)
    run.truth_spectral_radius.append(_rho(truth, des.controller))
    run.switched_at = t
    run.events.append(Event(t, "switched", cpu, {"design": label, **_detail(v.figures)}))
    say(f"t = {t:.2f} s: switched to the {label} redesign "
        f"(truth's closed-loop |z|max {run.truth_spectral_radius[-1]:.6f})")
    return des.controller


def _candidate(run: AdaptRun, fit, rec, running, t, sv, say):
    """Redesign from ``fit`` and keep the best candidate that passes the model checks:
    ``(label, design, fit, rec)`` or None (the running controller stays)."""
    c0 = time.process_time()
    best = None
    for label, des in redesign(fit, rec, sv):
        if isinstance(des, ControlError):
            run.events.append(Event(t, "rejected", 0.0, {"design": label, "stage": "design",
                                                         "reasons": [str(des)]}))
            continue
        v = check_candidate(fit.model, des.controller, running, sv)
        if not v.accepted:
            run.events.append(Event(t, "rejected", 0.0, {"design": label, "stage": "model",
                                                         "reasons": v.reasons, **_detail(v.figures)}))
            say(f"t = {t:.2f} s: {label} redesign rejected on the model: "
                f"{'; '.join(v.reasons)}")
            continue
        score = min(v.figures.dominant_damping)
        if best is None or score > best[0]:
            best = (score, label, des, v)
    cpu = time.process_time() - c0
    run.redesign_cpu_seconds = (run.redesign_cpu_seconds or 0.0) + cpu
    if best is None:
        run.events.append(Event(t, "kept", cpu, {"reason": "no redesign passed the model "
                                                 "checks"}))
        say(f"t = {t:.2f} s: no redesign passed; the running controller stays")
        return None
    _, label, des, v = best
    run.events.append(Event(t, "candidate", cpu, {"design": label, **_detail(v.figures)}))
    say(f"t = {t:.2f} s: {label} redesign passed the model checks "
        f"({', '.join(f'{100 * z:.1f}' for z in v.figures.dominant_damping)} %, "
        f"margin {v.figures.disk_margin_db:.1f} dB); waiting for fresh data")
    return label, des, fit, rec


def _rho(truth, controller) -> float:
    return float(np.max(np.abs(np.linalg.eigvals(np.asarray(closed_loop(truth, controller).A)))))


__all__ = ["MODE_DAMPING_MAX", "DITHER_BAND", "mode_damping",
           "SupervisorSettings", "Verdict", "CandidateFigures", "FreshFigures", "Detection", "redesign", "check_candidate", "check_fresh",
           "AdaptSettings", "Event", "AdaptRun", "detect", "adapt"]
