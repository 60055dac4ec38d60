"""The demo's summary as one typed object: ``summary.json`` and ``report.md`` are both made
from a :class:`DemoSummary`.

``summary.json`` is :meth:`DemoSummary.to_dict` (the dataclasses' own fields, by
:func:`trussid._util.jsonio.json_safe`), and the report renderer
(:mod:`trussid.campaign.report`) reads the same object by attribute: a renamed field either
renames the JSON key or breaks the renderer at once (``tests/campaign/test_summary.py``), it
cannot silently drop a figure from the report.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from trussid._util.jsonio import json_safe
from trussid.geometry.lab import LabSpec
from trussid.lqg.grading import LoopSettings
from trussid.plid.provenance import Provenance, Stabilised

__all__ = ["ReportProvenance", "PlantSummary", "ExperimentRow", "AuditedTrueMode",
           "AuditedIdentifiedMode", "ModeAudit", "ModelIdentification", "ModelSummary", "ReportFiles",
           "ControllerSummary", "DesignSummary", "ClosedLoopSummary", "ClosedLoopSection",
           "AdaptSection", "DemoSummary"]


@dataclass(frozen=True)
class ReportProvenance:
    """Who made the report, how and where."""

    trussid_version: str | None
    commit: str | None            # source commit, "(with uncommitted changes)" when dirty
    seed: int
    command: str | None           # the command line, None from Python
    machine: str
    platform: str
    cpus: int | None
    python: str
    load_average_start: list | None
    date_utc: str


@dataclass(frozen=True)
class PlantSummary:
    """The true plant: size, rate, modes, transducers, converters and noise (SI units)."""

    states: int
    inputs: list
    outputs: list
    sample_rate_hz: float
    modes: int
    mode_frequencies_hz: list
    modal_damping: float
    accelerometer_sensitivity_v_per_g: float
    conditioning_gain: float
    converter_bits: int
    converter_full_scale_v: float
    sensor_noise_g_rms: float
    sensor_noise_v_rms: float
    lab: LabSpec                  # the lab the plant and its records were made in
    structure: str = "the default testbed"  # or "deck X.bdf with io.toml"
    lab_source: str = ""          # where a deck's lab came from


@dataclass(frozen=True)
class ExperimentRow:
    """One record and how it was taken (per-output lists in the plant's output order)."""

    model: str
    purpose: str                  # "identification" or "validation"
    samples: int
    sample_rate_hz: float
    driven_channels: list
    seed: int
    excitation: str
    excitation_rms_v: float
    excitation_band_hz: list
    dac_clipped: list
    adc_clipped: list
    conditioner_steps: list
    adc_full_scale_v: list
    dac_lsb_v: list               # the converters' LSB as the experiment applied them [V]
    adc_lsb_v: list
    adc_bits: list                # resolution from the LSB used: log2(2 FS / LSB)
    output_rms_v: list
    output_rms_fraction_of_range: list
    sensor_snr_db: list
    quantisation_snr_db: list


@dataclass(frozen=True)
class AuditedTrueMode:
    """A true structural mode in the band and whether the model found it."""

    true_frequency_hz: float
    true_damping: float
    found: bool
    frequency_hz: float | None    # the identified mode, when found
    damping: float | None


@dataclass(frozen=True)
class AuditedIdentifiedMode:
    """An identified structural mode and its nearest true mode."""

    frequency_hz: float
    damping: float
    nearest_true_hz: float | None
    spurious: bool                # no true structural mode within the tolerance
    in_excited_band: bool


@dataclass(frozen=True)
class ModeAudit:
    """What a model lacks and what it adds (:func:`trussid.campaign.demo.mode_audit`)."""

    band_hz: list
    excited_band_hz: list
    true_modes_in_band: list      # of AuditedTrueMode
    found: int
    total: int
    missing: list                 # true frequencies not found [Hz]
    filter_poles_in_band: int
    spurious: list                # of AuditedIdentifiedMode
    lightly_damped: list          # of AuditedIdentifiedMode
    rules: dict


@dataclass(frozen=True)
class ModelIdentification:
    """How one model of the demo was identified: the recipe's typed
    :class:`trussid.plid.provenance.Provenance` with what
    :func:`trussid.plid.chosen.choose_model` decided after it.

    Attributes
    ----------
    recipe : str
        The recipe that ran.
    start : str
        Its start (``"subspace"``).
    basis : str
        The observer basis of the winning PLID pass.
    R : list of float
        The output-noise variances of that pass (scaled units).
    provenance : trussid.plid.provenance.Provenance
        What the recipe ran, tried, chose and measured.
    stabilised : trussid.plid.provenance.Stabilised
        Whether poles were reflected in (by the recipe or after it).
    predictor : dict
        How the kept model's predictor gain was chosen.
    chosen : str
        The kept candidate's label.
    order_scan : trussid.campaign.orders.OrderChoice or None
        The order chosen from the data, when the campaign scanned orders.
    """

    recipe: str
    start: str
    basis: str
    R: list
    provenance: Provenance
    stabilised: Stabilised
    predictor: dict
    chosen: str
    order_scan: object = None

    @property
    def candidates(self) -> list:
        """The recipe's candidates, one row each (empty when it compared none)."""
        return self.provenance.candidates or []

    def to_dict(self) -> dict:
        """The JSON form (``summary.json``'s ``identification``): the provenance's fields that
        are set, beside the others in one flat object; ``order_scan`` only when set."""
        out = {"recipe": self.recipe, "start": self.start, "stabilised": self.stabilised,
               "basis": self.basis, "R": self.R, "predictor": self.predictor}
        out.update((k, v) for k, v in self.provenance.as_dict().items()
                   if k not in ("passes", "predictor"))
        out["stabilised"] = self.stabilised
        out["passes"] = self.provenance.passes
        out["chosen"] = self.chosen
        if self.order_scan is not None:
            out["order_scan"] = self.order_scan
        return json_safe(out)


@dataclass(frozen=True)
class ModelSummary:
    """Every metric of one identified model (validation record, true plant, H1)."""

    name: str
    kind: str                     # "SIMO" or "MIMO"
    states: int
    inputs: int
    outputs: int
    input_names: list
    output_names: list
    signal_to_prediction_error_db: float
    signal_to_prediction_error_db_per_output: list
    signal_to_prediction_error_db_mean_normalised: float
    prediction_skip_samples: int
    predictor_gain: str
    frf_max_error_db: float
    frf_rms_error_db: float
    frf_max_error_deg: float
    frf_rms_error_deg: float
    frf_error_per_channel: object
    frf_band_hz: list
    frf_error_vs_h1: dict
    h1_error_vs_true: dict
    simulation_fit_db: float | None
    simulation_fit_db_per_output: list
    seconds: float
    method: str
    unstable_poles: int
    stabilised: Stabilised        # poles reflected into the unit circle, if any
    poles: list                   # of trussid.plid.metrics.PoleMatch (plid.evaluate.compare)
    poles_in_band_matched: int
    poles_in_band_true: int
    validation_output_rms_v: list
    h1_coherence: dict
    modes_check: ModeAudit
    identification: ModelIdentification
    mode_checks: list = field(default_factory=list)  # ModeCheck per matched pole


@dataclass(frozen=True)
class ModeCheck:
    """A matched true (FE) and identified mode: the identified mode's 95 % intervals
    (:mod:`trussid.plid.uncertainty`; None without one) and the MAC of the two mode shapes
    at the sensors (:func:`trussid.plid.modal.mac`)."""

    true_frequency_hz: float
    frequency_hz: float
    mac: float
    frequency_ci95_hz: list | None = None
    damping_ratio_ci95: list | None = None


@dataclass
class ReportFiles:
    """The files of the report directory, by kind."""

    data: list = field(default_factory=list)
    models: list = field(default_factory=list)
    figures: list = field(default_factory=list)
    adapt: list = field(default_factory=list)     # adapt/... (``trussid demo --adapt``)


@dataclass(frozen=True)
class ControllerSummary:
    """A controller's size and channels."""

    states: int
    sensors: list
    actuators: list


@dataclass(frozen=True)
class DesignSummary:
    """How the LQG was designed (:class:`trussid.lqg.LQGDesign` without its systems).

    Attributes
    ----------
    form : str
    target_modes : tuple of trussid.lqg.design.TargetMode
    design_states : int
        States of the design model.
    target_damping : float
        The state feedback's damping of the target modes [-].
    estimator : str
        How the estimator gain was chosen.
    info : dict
        Everything else :func:`trussid.lqg.design_lqg` recorded (its ``info`` without the
        model's mode table).
    procedure : ProcedureSummary or None
        How the default design procedure chose it (None: designed otherwise).
    """

    form: str
    target_modes: tuple
    design_states: int
    target_damping: float
    estimator: str
    info: dict
    procedure: "ProcedureSummary | None" = None


@dataclass(frozen=True)
class ProcedureSummary:
    """How :func:`trussid.lqg.procedure.design_procedure` reached a design (its
    :class:`~trussid.lqg.procedure.Procedure` without the systems).

    Attributes
    ----------
    attempts : int
        Designs tried.
    disk_gain_db : float
        MIMO disk gain margin of the chosen design on the identified model [dB].
    asked : float
        The damping asked of each target [-].
    outcomes : tuple of trussid.lqg.procedure.TargetOutcome
        Per original target: what it reached on the model and what limited it.
    lines : tuple of str
        The per-target report, one line per target.
    warning : str or None
        One line when some target reached less than asked.
    """

    attempts: int
    disk_gain_db: float
    asked: float
    outcomes: tuple
    lines: tuple
    warning: str | None


@dataclass(frozen=True)
class ClosedLoopSummary:
    """A controller graded on one or more plants (:func:`trussid.lqg.grading.robustness`),
    without the systems: ``summary.json``'s ``control`` and what the closed-loop report is
    rendered from (:func:`trussid.campaign.loop_report.closed_loop_markdown`).

    Attributes
    ----------
    nominal : str
        The nominal plant's label.
    settings : trussid.lqg.grading.LoopSettings
        How the loops were exercised and graded (thresholds included).
    rows : dict
        ``{plant label: trussid.lqg.grading.LoopEvaluation}``.
    checks : dict
        ``{plant label: trussid.lqg.grading.Checks}``.
    baselines : dict
        ``{kind: trussid.lqg.grading.Baseline}``.
    timings_s : dict
    controller : ControllerSummary
    design : DesignSummary or None
        When the study designed the controller.
    design_file : dict or None
        What a controller file records of its design (``trussid control``'s JSON).
    """

    nominal: str
    settings: LoopSettings
    rows: dict
    checks: dict
    baselines: dict
    timings_s: dict
    controller: ControllerSummary
    design: DesignSummary | None = None
    design_file: dict | None = None


@dataclass(frozen=True)
class ClosedLoopSection:
    """The closed-loop section of the demo (:func:`trussid.campaign.control.demo_section`):
    its summary (``summary.json``'s ``control``) and figure files, or why no controller was
    designed."""

    summary: ClosedLoopSummary | None
    figures: list = field(default_factory=list)
    error: str | None = None


@dataclass(frozen=True)
class AdaptSection:
    """The adaptive section (:func:`trussid.campaign.adapt.demo_section`): its Markdown and
    its summary (``summary.json``'s ``adapt``)."""

    markdown: str
    summary: dict


@dataclass
class DemoSummary:
    """Everything the demo reports; ``summary.json`` is :meth:`to_dict`."""

    format_version: int
    provenance: ReportProvenance
    settings: object              # trussid.campaign.demo.DemoSettings
    plant: PlantSummary
    experiments: list             # of ExperimentRow
    models: list                  # of ModelSummary
    files: ReportFiles
    timings_s: dict
    control: ClosedLoopSection | None = None
    adapt: AdaptSection | None = None   # closed-loop identification, adaptive redesign

    def to_dict(self) -> dict:
        """The JSON form: every field by its name; ``control`` is the closed-loop summary
        (``{"error": ...}`` when no controller was designed) and ``adapt`` the adaptive one
        (each left out when not run)."""
        out = json_safe(self)
        for model, typed in zip(out["models"], self.models):
            model["identification"] = typed.identification.to_dict()
        if self.control is None:
            del out["control"]
        elif self.control.summary is None:
            out["control"] = {"error": self.control.error}
        else:
            out["control"] = json_safe(self.control.summary)
        if self.adapt is None:
            del out["adapt"]
        else:
            out["adapt"] = json_safe(self.adapt.summary)
        return out
