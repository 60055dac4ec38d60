"""Grading a controller on any discrete plant: what a loop is exercised with
(:class:`LoopSettings`), the acceptance thresholds (:class:`Thresholds`, issue 14's by
default), one loop's figures of merit (:func:`evaluate_loop`), its pass/fail
(:func:`check`), a controller and its baselines on several plants (:func:`robustness`).
The LQG with its baselines designed from an identified model is
:func:`trussid.lqg.procedure.design_controller`.

``trussid control``, ``trussid closed-loop``, the demo's closed-loop section and the adaptive
supervisor all grade with these; the testbed's perturbed truths and the report live in
:mod:`trussid.campaign.control`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, fields, replace

import numpy as np

from trussid.plid.experiment import excitation

from .baselines import KINDS, decentralised
from .design import LQGDesign
from .errors import ControlError
from .evaluate import (DampingTable, DiskMargins, ModeRow, damping_table, disk_margins, h2_norm,
                       simulate_loop)
from .loop import Loop

__all__ = ["DEFAULT_BAND", "Thresholds", "THRESHOLDS", "LoopSettings", "plant_loop_settings",
           "DominantMode", "WatchedMode", "Converters", "LoopEvaluation", "evaluate_loop",
           "CHECKS", "Checks", "check", "BASELINE_KINDS", "Baseline", "Robustness", "robustness"]

#: Plant modes graded by default [Hz] (issue 14's band on the testbed).
DEFAULT_BAND = (40.0, 450.0)


@dataclass(frozen=True)
class Thresholds:
    """Acceptance thresholds of a loop (issue 14's by default); ``None``: not graded.

    Attributes
    ----------
    dominant_nominal, dominant_perturbed : float
        Least damping [-] of every dominant mode (worst visible) on the nominal plant and on
        a perturbed one.
    other_ratio_nominal, other_ratio_perturbed : float
        Least ratio of closed- to open-loop damping of the other modes in the band [-].
    mimo_gm_nominal_db, mimo_pm_nominal_deg, mimo_gm_perturbed_db : float
        Least balanced MIMO disk gain [dB] and phase [deg] margins.
    loop_gm_db : float
        Least loop-at-a-time disk gain margin [dB].
    h2_reduction_db : float or None
        Least H2 reduction from the D/A disturbance to the sensors, closed over open [dB].
    command_rms_v : float or None
        Largest command RMS per channel in the closed-loop simulation [V].
    """

    dominant_nominal: float = 0.05
    dominant_perturbed: float = 0.04
    other_ratio_nominal: float = 0.80
    other_ratio_perturbed: float = 0.75
    mimo_gm_nominal_db: float = 6.0
    mimo_pm_nominal_deg: float = 35.0
    mimo_gm_perturbed_db: float = 4.0
    loop_gm_db: float = 8.0
    h2_reduction_db: float | None = 10.0
    command_rms_v: float | None = 1.0


#: Issue 14's acceptance thresholds.
THRESHOLDS = Thresholds()


@dataclass(frozen=True)
class LoopSettings:
    """How a loop is exercised and graded: the lab's converters, excitation at the
    actuators, sensor noise, thresholds. The other defaults are the testbed demo's (issue
    14); :func:`plant_loop_settings` derives them for any other plant.

    The converters have no default: they are the lab's (:meth:`for_lab`, from a
    :class:`trussid.geometry.lab.LabSpec`: the testbed's ``tb.lab``, a plant's
    ``TestbedPlant.lab`` or the lab recorded in a plant file); ``bits=None``: ideal
    converters (no quantising, no clipping).

    Attributes
    ----------
    bits, full_scale : int, float
        D/A and A/D resolution [-] and range +-``full_scale`` [V].
    sample_rate : float
        The converters' rate [Hz]; a plant sampled at another rate is refused.
    band : (float, float)
        Modes tabulated [Hz] (:data:`DEFAULT_BAND`).
    excitation_rms : float or sequence of float
        RMS of the white 0-``excitation_band_hz`` noise added at each actuator channel, in
        the channel's unit (the testbed's D/A volts).
    excitation_band_hz : float
    noise_rms : float or sequence of float
        Sensor noise RMS, in each sensor's unit.
    n_samples : int
        Length of the time simulation (at the plant's rate).
    seed : int
    thresholds : Thresholds
        Acceptance thresholds; ``command_rms_v`` ``None`` grades no command level.
    watch_hz : tuple of float
        Modes tabulated on their own in the robustness table (the testbed's 118, 138 Hz).
    targets_hz : tuple of float
        The design's target modes [Hz]: the plant mode nearest each (within 10 %) is graded
        as dominant. Empty: dominant by residue (:func:`trussid.lqg.evaluate.damping_table`).
    input_unit, output_unit : str
        Unit names in the report ("V" on the testbed, "unit" for a plant's own units).
    """

    bits: int
    full_scale: float
    sample_rate: float
    band: tuple = DEFAULT_BAND
    excitation_rms: object = 2.5
    excitation_band_hz: float = 400.0
    noise_rms: object = 0.0245
    n_samples: int = 8000
    seed: int = 14
    thresholds: Thresholds = THRESHOLDS
    watch_hz: tuple = (118.0, 138.0)
    targets_hz: tuple = ()
    input_unit: str = "V"
    output_unit: str = "V"

    @classmethod
    def for_lab(cls, lab, **overrides) -> "LoopSettings":
        """The settings with ``lab``'s converters (a :class:`~trussid.geometry.lab.LabSpec`);
        ``overrides`` set the other fields."""
        return cls(bits=lab.daq.bits, full_scale=lab.daq.full_scale,
                   sample_rate=lab.daq.sample_rate, **overrides)


def plant_loop_settings(plant, *, input_rms=None, output_rms=None, target_damping=None,
                        targets_hz=(), n_samples: int = 8000, seed: int = 14,
                        lab=None) -> LoopSettings:
    """:class:`LoopSettings` for any discrete plant, graded in its own units.

    Every mode up to the Nyquist frequency is tabulated; the excitation is white up to 0.4
    of the sample rate at ``input_rms`` per actuator (the identification record's levels,
    default 1 unit), the sensor noise 1 % of ``output_rms`` (default none); the converters
    are ``lab``'s (a :class:`~trussid.geometry.lab.LabSpec`), ideal without one; the design's
    target modes (``targets_hz``) are the dominant ones and pass at half its
    ``target_damping`` (default 7 %); every other mode keeps 80 % of its damping; no command
    level and no H2 change is graded (no unit is known to compare the one with, and the
    other depends on how many modes the plant has beside the targets).

    Parameters
    ----------
    plant : control.StateSpace
        Discrete.
    input_rms, output_rms : sequence of float, optional
        The identification record's levels per actuator and sensor.
    target_damping : float, optional
        The design's target damping [-].
    targets_hz : sequence of float
        The design's target modes [Hz].
    n_samples, seed : int
        The closed-loop simulation's length and seed.
    lab : trussid.geometry.lab.LabSpec, optional
        The lab's converters (ideal without one).
    """
    fs = 1.0 / plant.dt
    zeta = 0.07 if target_damping is None else float(target_damping)
    t = replace(THRESHOLDS, dominant_nominal=0.5 * zeta, dominant_perturbed=0.4 * zeta,
                command_rms_v=None, h2_reduction_db=None)
    exc = 1.0 if input_rms is None else [float(v) for v in np.ravel(input_rms)]
    noise = 0.0 if output_rms is None else [0.01 * float(v) for v in np.ravel(output_rms)]
    bits, full = (None, 1.0) if lab is None else (lab.daq.bits, lab.daq.full_scale)
    return LoopSettings(band=(0.0, 0.5 * fs), excitation_rms=exc, excitation_band_hz=0.4 * fs,
                        noise_rms=noise, n_samples=n_samples, bits=bits, full_scale=full,
                        sample_rate=fs, seed=seed,
                        thresholds=t, watch_hz=(), targets_hz=tuple(map(float, targets_hz)),
                        input_unit="unit", output_unit="unit")


# --------------------------------------------------------------------------- one loop


@dataclass(frozen=True)
class DominantMode:
    """A dominant mode's closed-loop damping: worst visible and tracked [-]."""

    frequency_hz: float
    worst: float
    tracked: float


@dataclass(frozen=True)
class WatchedMode:
    """A mode tabulated on its own (:attr:`LoopSettings.watch_hz`): the plant mode within
    8 % of ``frequency_hz`` nearest to it, its worst visible damping (None if none is)."""

    frequency_hz: float
    damping: float | None


@dataclass(frozen=True)
class Converters:
    """The converters of a closed-loop simulation, as it ran them."""

    sample_rate_hz: float
    dac_lsb_v: list
    adc_lsb_v: list
    bits: int | None
    full_scale_v: float


@dataclass(frozen=True)
class LoopEvaluation:
    """Every figure of merit of one controller on one plant (:func:`evaluate_loop`).

    Attributes
    ----------
    stable : bool
    spectral_radius : float
    rows : tuple of ModeRow
        The plant's modes in the band (:func:`trussid.lqg.evaluate.damping_table`).
    dominant : tuple of DominantMode
    dominant_min : float or None
        Least worst-visible damping of the dominant modes.
    other_min_ratio : float or None
        Least closed- to open-loop damping ratio of the other modes (None: there are none).
    other_worst_mode_hz : float or None
        The mode with that ratio [Hz].
    watched : tuple of WatchedMode
    margins : DiskMargins or None
        None when unstable or not asked for.
    h2_open, h2_closed, h2_ratio_db : float or None
        H2 norms of the D/A disturbance to the sensors, and their ratio [dB].
    command_rms_v, command_peak_v, y_rms_closed : list of float or None
        Per channel, in the simulation past its start-up (the first 10 %).
    dac_clipped, adc_clipped : list of int or None
        Clipped samples per channel in the simulation.
    converters : Converters or None
    seconds : float
        Wall time of the evaluation.
    """

    stable: bool
    spectral_radius: float
    rows: tuple
    dominant: tuple
    dominant_min: float | None
    other_min_ratio: float | None
    other_worst_mode_hz: float | None = None
    watched: tuple = ()
    margins: DiskMargins | None = None
    h2_open: float | None = None
    h2_closed: float | None = None
    h2_ratio_db: float | None = None
    command_rms_v: list | None = None
    command_peak_v: list | None = None
    dac_clipped: list | None = None
    adc_clipped: list | None = None
    y_rms_closed: list | None = None
    converters: Converters | None = None
    seconds: float = 0.0

    def watched_damping(self, frequency_hz: float) -> float | None:
        """The worst visible damping of the watched mode at ``frequency_hz`` [-] (None if
        it is not watched or not found)."""
        return next((w.damping for w in self.watched if w.frequency_hz == frequency_hz), None)


def evaluate_loop(plant, controller, settings: LoopSettings,
                  margins: bool = True, simulate: bool = True) -> LoopEvaluation:
    """Every figure of merit of ``controller`` on ``plant`` (one row of the tables).

    Parameters
    ----------
    plant, controller : control.StateSpace
        Discrete, matched by channel name (:class:`trussid.lqg.loop.Loop`).
    settings : LoopSettings
    margins, simulate : bool
        Compute the disk margins, run the closed-loop simulation.

    Returns
    -------
    LoopEvaluation

    Raises
    ------
    ControlError
        If ``plant`` is not sampled at the converters' rate ``settings.sample_rate``.
    """
    if not np.isclose(1.0 / plant.dt, settings.sample_rate, rtol=1e-9):
        raise ControlError(f"the plant is sampled at {1.0 / plant.dt:g} Hz but the lab's "
                           f"converters run at {settings.sample_rate:g} Hz")
    t0 = time.perf_counter()
    tab = damping_table(plant, controller, band=settings.band, targets_hz=settings.targets_hz)
    ev = _from_table(tab, settings.watch_hz)
    if tab.stable:
        loop = tab.loop
        h_ol, h_cl = h2_norm(loop.open_loop), h2_norm(loop.disturbance_to_sensors)
        ev = replace(ev, margins=disk_margins(plant, controller) if margins else None,
                     h2_open=h_ol, h2_closed=h_cl, h2_ratio_db=float(20 * np.log10(h_cl / h_ol)))
        if simulate:
            ev = _with_simulation(ev, loop, settings)
    return replace(ev, seconds=time.perf_counter() - t0)


def _from_table(tab: DampingTable, watch_hz) -> LoopEvaluation:
    """The figures of :class:`LoopEvaluation` that the damping table gives."""
    dom, oth = tab.dominant, tab.others
    watched = []
    for f0 in watch_hz:
        # the mode nearest f0 within 8 % (it moves with the perturbations)
        near = sorted((r for r in tab.rows if abs(r.frequency_hz / f0 - 1) < 0.08),
                      key=lambda r: abs(r.frequency_hz - f0))
        watched.append(WatchedMode(float(f0), near[0].damping_worst_visible if near else None))
    return LoopEvaluation(
        stable=bool(tab.stable), spectral_radius=tab.spectral_radius, rows=tab.rows,
        dominant=tuple(DominantMode(r.frequency_hz, r.damping_worst_visible, r.damping_tracked)
                       for r in dom),
        dominant_min=min((r.damping_worst_visible for r in dom), default=None),
        other_min_ratio=min((_ratio(r) for r in oth), default=None),
        other_worst_mode_hz=min(oth, key=_ratio).frequency_hz if oth else None,
        watched=tuple(watched))


def _ratio(r: ModeRow) -> float:
    return r.damping_worst_visible / r.damping_open


def _with_simulation(ev: LoopEvaluation, loop: Loop, settings: LoopSettings) -> LoopEvaluation:
    """``ev`` with the figures of the closed-loop simulation."""
    plant, nu = loop.plant, len(loop.iu)
    d = excitation("white", settings.n_samples, nu, 1.0 / plant.dt, 1.0,
                   (0.0, settings.excitation_band_hz), settings.seed)
    d = d * np.broadcast_to(np.asarray(settings.excitation_rms, dtype=float), (nu,))
    sim = simulate_loop(plant, loop.controller, d, settings.noise_rms, bits=settings.bits,
                        dac_full_scale=settings.full_scale,
                        adc_full_scale=settings.full_scale, seed=settings.seed + 1)
    skip = settings.n_samples // 10  # past the start-up transient
    return replace(ev, command_rms_v=np.sqrt(np.mean(sim.u[skip:] ** 2, axis=0)).tolist(),
                   command_peak_v=np.max(np.abs(sim.u[skip:]), axis=0).tolist(),
                   dac_clipped=sim.dac_clipped, adc_clipped=sim.adc_clipped,
                   y_rms_closed=np.sqrt(np.mean(sim.y[skip:] ** 2, axis=0)).tolist(),
                   # what the simulated converters were, from the simulation itself
                   converters=Converters(1.0 / plant.dt, sim.dac_lsb, sim.adc_lsb,
                                         settings.bits, settings.full_scale))


# --------------------------------------------------------------------------- pass / fail


#: The acceptance items of issue 14 as the reports show them: code -> what it checks.
CHECKS = {
    "1_stable": "the closed loop is stable",
    "2_dominant": "every dominant mode reaches the least damping",
    "3_others": "every other mode in the band keeps the least ratio of its open-loop damping",
    "4_mimo": "the MIMO disk margins (gain and, nominal, phase) reach the least",
    "4_loops": "every loop-at-a-time disk gain margin reaches the least",
    "5_h2": "the H2 norm from the D/A disturbance to the sensors falls by the least",
    "5_command": "the command RMS of every channel stays below the most",
}


@dataclass(frozen=True)
class Checks:
    """Pass/fail of the acceptance items (:data:`CHECKS`) for one evaluated loop; ``None``:
    not graded (an unstable loop, no margins computed, no threshold set, a perturbed truth)."""

    stable: bool
    dominant: bool | None = None
    others: bool | None = None
    mimo: bool | None = None
    loops: bool | None = None
    h2: bool | None = None
    command: bool | None = None

    @property
    def graded(self) -> tuple:
        """``((code, passed), ...)`` of the items graded, codes as :data:`CHECKS`."""
        return tuple((code, getattr(self, f.name)) for code, f in zip(CHECKS, fields(self))
                     if getattr(self, f.name) is not None)

    @property
    def failed(self) -> list:
        """The codes of the failed items."""
        return [code for code, ok in self.graded if not ok]

    @property
    def passed(self) -> bool:
        return not self.failed


def check(evaluation: LoopEvaluation, nominal: bool,
          thresholds: Thresholds | None = None) -> Checks:
    """Pass/fail of the acceptance items 1-5 (:data:`CHECKS`) for one evaluated loop.

    Parameters
    ----------
    evaluation : LoopEvaluation
    nominal : bool
        The nominal plant (the stricter thresholds, margins' phase, H2 and command graded).
    thresholds : Thresholds, optional
        Default :data:`THRESHOLDS`.
    """
    T = THRESHOLDS if thresholds is None else thresholds
    r = evaluation
    if not r.stable:
        return Checks(stable=False)
    ok = {"stable": True}
    ok["dominant"] = (r.dominant_min or 0) >= (T.dominant_nominal if nominal
                                               else T.dominant_perturbed)
    # no other mode in the band: nothing to spoil
    ok["others"] = r.other_min_ratio is None or r.other_min_ratio >= (
        T.other_ratio_nominal if nominal else T.other_ratio_perturbed)
    m = r.margins
    if m:
        if nominal:
            ok["mimo"] = (m.mimo.gain_db >= T.mimo_gm_nominal_db
                          and m.mimo.phase_deg >= T.mimo_pm_nominal_deg)
        else:
            ok["mimo"] = m.mimo.gain_db >= T.mimo_gm_perturbed_db
        ok["loops"] = all(lp.gain_db >= T.loop_gm_db for lp in m.loops)
    if nominal and r.h2_ratio_db is not None and T.h2_reduction_db is not None:
        ok["h2"] = r.h2_ratio_db <= -T.h2_reduction_db
    if nominal and r.command_rms_v is not None and T.command_rms_v is not None:
        ok["command"] = max(r.command_rms_v) <= T.command_rms_v
    return Checks(**ok)


# --------------------------------------------------------------------------- design


#: The decentralised baselines graded beside an LQG (:data:`trussid.lqg.baselines.KINDS`).
BASELINE_KINDS = KINDS


@dataclass(frozen=True)
class Baseline:
    """A decentralised baseline (:func:`trussid.lqg.decentralised`): its gain, band [Hz],
    how the gain was tuned, and (after :func:`robustness`) its evaluation per plant."""

    gain: float
    band: list
    tuning: dict | None = None
    rows: dict = field(default_factory=dict)


# --------------------------------------------------------------------------- several plants


@dataclass(frozen=True)
class Robustness:
    """A controller (and its baselines) on several plants (:func:`robustness`).

    Attributes
    ----------
    rows : dict
        ``{plant label: LoopEvaluation}``, the nominal plant first.
    checks : dict
        ``{plant label: Checks}``.
    baselines : dict
        ``{kind: Baseline}`` with their evaluations.
    timings_s : dict
        Wall seconds per step.
    nominal : str
        The nominal plant's label.
    plants : list of (str, control.StateSpace)
    controller : control.StateSpace
    settings : LoopSettings
    design : LQGDesign or None
        The design, when the study made it.
    design_info : dict or None
        What a controller file records of its design (``trussid control``'s JSON).
    """

    rows: dict
    checks: dict
    baselines: dict
    timings_s: dict
    nominal: str
    plants: list
    controller: object
    settings: LoopSettings
    design: LQGDesign | None = None
    design_info: dict | None = None


def robustness(controller, plants, baselines, settings: LoopSettings,
               progress=None) -> Robustness:
    """``controller`` (and each baseline) on every plant of ``plants`` (the first nominal).

    Parameters
    ----------
    controller : control.StateSpace
    plants : list of (str, control.StateSpace)
        Labelled plants, the nominal one first.
    baselines : dict
        ``{kind: Baseline}`` (:func:`design_controller`), evaluated beside the controller.
    settings : LoopSettings
    progress : callable, optional
        Called with a one-line message after each loop.

    Returns
    -------
    Robustness
    """
    say = progress or (lambda msg: None)
    rows, checks, timings = {}, {}, {}
    t0 = time.perf_counter()
    for k, (label, plant) in enumerate(plants):
        rows[label] = r = evaluate_loop(plant, controller, settings)
        checks[label] = check(r, nominal=(k == 0), thresholds=settings.thresholds)
        say(f"controller on {label}: stable {r.stable}, dominant worst "
            f"{100 * (r.dominant_min or 0):.2f} % ({r.seconds:.1f} s)")
    timings["evaluation"] = time.perf_counter() - t0
    base = {}
    t0 = time.perf_counter()
    for kind, b in (baselines or {}).items():
        ctrl = decentralised(kind, b.gain, controller.dt, list(controller.input_labels),
                             list(controller.output_labels), tuple(b.band))
        brows = {label: evaluate_loop(plant, ctrl, settings, simulate=(j == 0))
                 for j, (label, plant) in enumerate(plants)}
        base[kind] = replace(b, rows=brows)
        say(f"baseline {kind}: gain {b.gain:.3g}, nominal dominant worst "
            f"{100 * (brows[plants[0][0]].dominant_min or 0):.2f} %")
    if baselines:
        timings["baselines"] = time.perf_counter() - t0
    return Robustness(rows, checks, base, timings, plants[0][0], plants, controller, settings)
