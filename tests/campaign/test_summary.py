"""The demo's summary is one typed object: ``summary.json`` and ``report.md`` both come from
a :class:`DemoSummary`, so a renamed field fails here, not silently in a report (issue 22,
acceptance item 4).

The summary below is built by hand with a distinct value in every reported figure; the
report must show each of them, and ``summary.json`` must hold exactly the dataclasses'
fields.
"""

import dataclasses

import pytest

from trussid.campaign.demo import demo_settings
from trussid.campaign.report import report_markdown
from trussid.campaign.summary import (AdaptSection, AuditedIdentifiedMode, AuditedTrueMode,
                                      ClosedLoopSection, ClosedLoopSummary, ControllerSummary,
                                      DemoSummary, DesignSummary, ExperimentRow, ModeAudit,
                                      ModelIdentification, ModelSummary, PlantSummary,
                                      ReportFiles,
                                      ReportProvenance)
from trussid.geometry.lab import LabSpec
from trussid.lqg.design import TargetMode
from trussid.lqg.evaluate import ChannelMargin, DiskMargins, Margin, ModeRow
from trussid.lqg.grading import (Checks, Converters, DominantMode, LoopEvaluation, LoopSettings,
                                 WatchedMode)
from trussid.plid.metrics import PoleMatch
from trussid.plid.multipass import PassRecord, Provenance, Stabilised


def _audit():
    return ModeAudit(
        band_hz=[50.0, 350.0], excited_band_hz=[0.0, 400.0],
        true_modes_in_band=[AuditedTrueMode(166.0, 0.0025, True, 166.2, 0.0024),
                            AuditedTrueMode(57.9, 0.0025, False, None, None)],
        found=1, total=2, missing=[57.9], filter_poles_in_band=1,
        spurious=[AuditedIdentifiedMode(441.5, 0.00013, None, True, False)],
        lightly_damped=[AuditedIdentifiedMode(166.2, 0.0024, 166.0, False, True)],
        rules={"structural_damping_max": 0.5, "found_within": 0.05, "light_damping_below": 0.01})


def _model(name="mimo", kind="MIMO"):
    return ModelSummary(
        name=name, kind=kind, states=18, inputs=3, outputs=3,
        input_names=["ch1", "ch2", "ch3"], output_names=["acc1", "acc2", "acc3"],
        signal_to_prediction_error_db=33.74, signal_to_prediction_error_db_per_output=[32.2, 34.4, 34.1],
        signal_to_prediction_error_db_mean_normalised=30.13, prediction_skip_samples=40,
        predictor_gain="kalman", frf_max_error_db=5.86, frf_rms_error_db=1.23,
        frf_max_error_deg=47.5, frf_rms_error_deg=8.9, frf_error_per_channel=[],
        frf_band_hz=[50.0, 350.0],
        frf_error_vs_h1={"max_db": 1.0, "rms_db": 0.5, "max_deg": 3.0, "rms_deg": 1.0},
        h1_error_vs_true={"max_db": 2.0, "rms_db": 0.77, "max_deg": 4.0, "rms_deg": 2.0},
        simulation_fit_db=24.21, simulation_fit_db_per_output=[24.0, 25.0, 23.0], seconds=12.3,
        method="PLID (direct form)", unstable_poles=0,
        stabilised=Stabilised(applied=True, reflected_poles=2),
        poles=[PoleMatch(true_frequency_hz=166.0, true_damping=0.0025, frequency_hz=166.2,
                         damping=0.0024, frequency_error_percent=0.12)],
        poles_in_band_matched=1, poles_in_band_true=1, validation_output_rms_v=[1.0, 1.1, 1.2],
        h1_coherence={"excited_band_hz": [0.0, 400.0], "mean_in_excited_band": [0.987, 0.9, 0.9],
                      "mean_above_excited_band": [0.123, 0.1, 0.1]},
        modes_check=_audit(),
        identification=_identification())


def _identification():
    prov = Provenance(chosen="direct 18", candidates=[
        {"label": "direct 18", "identification_ratio_db": 31.42, "seconds": 2.5}],
        passes=[PassRecord(0, "direct", 0.0)], predictor={"chosen": "kalman"}, seconds=3.5)
    return ModelIdentification(recipe="trussid.plid.multipass.identify_reduced",
                               start="subspace", basis="rotation", R=[1e-4], provenance=prov,
                               stabilised=Stabilised(), predictor={"chosen": "kalman"},
                               chosen="direct 18")


def _evaluation(cls=LoopEvaluation, **renamed):
    values = dict(
        stable=True, spectral_radius=0.99913,
        rows=(ModeRow(166.0, 0.0025, 1.5, 165.4, 0.0721, 0.0711, 1, True),
              ModeRow(227.2, 0.0025, 0.2, 227.3, 0.0027, 0.0026, 0, False)),
        dominant=(DominantMode(166.0, 0.0711, 0.0721),), dominant_min=0.0711,
        other_min_ratio=1.04, other_worst_mode_hz=227.2,
        watched=(WatchedMode(118.0, 0.00293), WatchedMode(138.0, 0.00864)),
        margins=DiskMargins(Margin(0.9, 8.76, 48.3, 170.0),
                            (ChannelMargin(1.1, 11.1, 52.0, 171.0, channel="ch1"),), 2000, 10),
        h2_open=1.0, h2_closed=0.21, h2_ratio_db=-13.57, command_rms_v=[0.42, 0.43],
        command_peak_v=[1.5, 1.6], dac_clipped=[0, 0], adc_clipped=[0, 0],
        y_rms_closed=[0.1, 0.1], converters=Converters(1600.0, [1e-3] * 2, [1e-3] * 2, 12, 10.0),
        seconds=1.0)
    for new, old in renamed.items():
        values[new] = values.pop(old)
    return cls(**values)


def _control(evaluation=None):
    return ClosedLoopSummary(
        nominal="nominal", settings=LoopSettings(bits=12, full_scale=10.0, sample_rate=1600.0),
        rows={"nominal": evaluation or _evaluation()},
        checks={"nominal": Checks(True, True, True, True, True, True, False)},
        baselines={}, timings_s={"evaluation": 4.25},
        controller=ControllerSummary(6, ["acc1", "acc2"], ["ch1", "ch2"]),
        design=DesignSummary("predictor", (TargetMode(3, 166.1, 0.0025, 1.0, True, 0.07, 1e-3),),
                             6, 0.07, "kalman Q/R ratio 100", {"lqr_iterations": 12}))


def _summary(model=None, control=None):
    lab = LabSpec()
    return DemoSummary(
        format_version=1,
        provenance=ReportProvenance("0.1", "abc123", 1997, "trussid demo --quick", "host", "Linux", 2,
                              "3.12", [0.5, 0.4, 0.3], "2026-01-01 00:00:00 UTC"),
        settings=demo_settings(True),
        plant=PlantSummary(states=400, inputs=["ch1", "ch2", "ch3"],
                           outputs=["acc1", "acc2", "acc3"], sample_rate_hz=1600.0, modes=190,
                           mode_frequencies_hz=[1.0, 2.0], modal_damping=0.0025,
                           accelerometer_sensitivity_v_per_g=0.1, conditioning_gain=2000.0,
                           converter_bits=12, converter_full_scale_v=10.0,
                           sensor_noise_g_rms=1e-5, sensor_noise_v_rms=0.002, lab=lab),
        experiments=[ExperimentRow(
            model="mimo", purpose="identification", samples=6000, sample_rate_hz=1600.0,
            driven_channels=["ch1", "ch2", "ch3"], seed=1997, excitation="white",
            excitation_rms_v=2.5, excitation_band_hz=[0.0, 400.0], dac_clipped=[1, 2, 3],
            adc_clipped=[7, 8, 9], conditioner_steps=[0.5, 1.0, 2.0],
            adc_full_scale_v=[20.0, 10.0, 5.0], dac_lsb_v=[lab.lsb] * 3, adc_lsb_v=[lab.lsb] * 3,
            adc_bits=[12, 12, 12], output_rms_v=[1.0, 1.0, 1.0],
            output_rms_fraction_of_range=[0.17, 0.23, 0.29], sensor_snr_db=[61.5, 62.5, 63.5],
            quantisation_snr_db=[64.1, 65.1, 66.1])],
        models=[model or _model()],
        files=ReportFiles(data=["data_mimo_ide.npz"], models=["model_mimo.npz"],
                          figures=["bode_mimo_ch1.png"]),
        timings_s={"plant": 1.0, "experiments": 2.0, "identification": 3.0, "evaluation": 4.0,
                   "report": 5.0, "total": 15.0},
        control=ClosedLoopSection(control or _control(), ["control_poles.png"]))


#: Figures the report shows, by field, as the report formats them.
SHOWN = {
    "plant": ["400 states", "1600 Hz", "120 Hz", "100 mV/g", "2000 V/V", "12-bit", "+-10 V",
              "10 ug RMS", "2.00 mV"],
    "experiments": ["6000", "| 6 |", "7, 8, 9", "0.5, 1, 2", "0.17, 0.23, 0.29",
                    "61.5, 62.5, 63.5", "64.1, 65.1, 66.1"],
    "models": ["33.74", "32.2, 34.4, 34.1", "30.13", "24.21", "5.86 / 1.23", "47.5 / 8.9",
               "0.77", "1 / 2", "12.3", "PLID (direct form)", "31.42", "166.20", "0.00240",
               "57.90 Hz", "441.50", "2 unstable pole(s) reflected", "0.987", "0.123"],
    "provenance": ["abc123", "seed 1997", "trussid demo --quick", "0.50, 0.40, 0.30"],
    "files": ["data_mimo_ide.npz", "model_mimo.npz", "bode_mimo_ch1.png"],
    "control": ["## Closed loop: active damping", "166.1 Hz", "kalman Q/R ratio 100",
                "Controller: 6 states", "165.4", "7.210", "**7.110**", "| 1 |", "1.04",
                "8.76 / 48.3", "11.1", "-13.6", "0.42, 0.43", "0.29 | 0.86", "FAIL 5_command",
                "`5_command` the command RMS", "evaluation 4.2", "control_poles.png"],
}


def test_the_report_shows_every_figure_of_the_summary():
    md = report_markdown(_summary())
    missing = [(part, text) for part, shown in SHOWN.items() for text in shown if text not in md]
    assert missing == []


def _fields(obj, path="") -> dict:
    """``{json path: value}`` of every dataclass field, recursively (the JSON's schema)."""
    out = {}
    if dataclasses.is_dataclass(obj):
        for f in dataclasses.fields(obj):
            out[f"{path}/{f.name}"] = True
            out.update(_fields(getattr(obj, f.name), f"{path}/{f.name}"))
    elif isinstance(obj, list):
        for k, v in enumerate(obj):
            out.update(_fields(v, f"{path}/{k}"))
    return out


def _keys(obj, path="") -> dict:
    out = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            out[f"{path}/{k}"] = True
            out.update(_keys(v, f"{path}/{k}"))
    elif isinstance(obj, list):
        for k, v in enumerate(obj):
            out.update(_keys(v, f"{path}/{k}"))
    return out


def test_summary_json_holds_exactly_the_typed_fields():
    s = _summary()
    # the closed-loop sections (control, adapt) are plain dicts of their own
    # the identification's JSON is its own flat layout (the next test)
    typed = (set(_fields(s)) - {"/control", "/adapt"}
             - {k for k in _fields(s)
                if k.startswith(("/control/", "/adapt/", "/models/0/identification/"))})
    keys = {k for k in _keys(s.to_dict())
            if not any(k.startswith(p + "/") for p in
                       # plain dicts inside the typed object keep their own keys
                       ("/timings_s", "/control", "/models/0/frf_error_vs_h1",
                        "/models/0/h1_error_vs_true",
                        "/models/0/h1_coherence", "/models/0/identification",
                        "/models/0/modes_check/rules"))}
    assert keys - {"/control"} == typed
    assert s.to_dict()["control"]["nominal"] == "nominal"
    assert "control" not in dataclasses.replace(s, control=None).to_dict()
    none = ClosedLoopSection(None, [], "the model has no lightly damped mode")
    assert dataclasses.replace(s, control=none).to_dict()["control"] == {
        "error": "the model has no lightly damped mode"}
    assert "No controller designed: the model has no lightly damped mode" in report_markdown(
        dataclasses.replace(s, control=none))
    assert "adapt" not in s.to_dict()
    with_adapt = dataclasses.replace(s, adapt=AdaptSection("## Closed-loop id\n", {"a": 1}))
    assert with_adapt.to_dict()["adapt"] == {"a": 1}
    assert "## Closed-loop id" in report_markdown(with_adapt)


def test_the_identification_json_puts_the_provenance_beside_the_demo_s_choices():
    """summary.json's ``identification``: the recipe's provenance fields that are set, flat,
    with the choices made after the recipe (stabilised, chosen) taking precedence."""
    ident = dataclasses.replace(_identification(),
                                stabilised=Stabilised(applied=True, reflected_poles=2))
    out = ident.to_dict()
    assert out["chosen"] == "direct 18"
    assert out["passes"] == [{"pass": 0, "form": "direct", "Q": 0.0, "Q_theta": 0.0,
                              "prior_theta_var": None, "finite": True, "seconds": None}]
    assert out["stabilised"] == {"applied": True, "reflected_poles": 2}
    assert out["seconds"] == 3.5 and out["candidates"][0]["identification_ratio_db"] == 31.42
    assert "subspace" not in out  # not set: left out
    assert set(out) == {"recipe", "start", "stabilised", "basis", "R", "predictor", "passes",
                        "candidates", "chosen", "seconds", "warnings"}


def test_renaming_a_reported_field_fails_the_report():
    fields = [(f.name if f.name != "frf_rms_error_db" else "frf_rms_db", f.type)
              for f in dataclasses.fields(ModelSummary)]
    Renamed = dataclasses.make_dataclass("ModelSummary", fields, frozen=True)
    values = dataclasses.asdict(_model())
    values["frf_rms_db"] = values.pop("frf_rms_error_db")
    values["modes_check"] = _audit()
    values["identification"] = _identification()
    renamed = _summary(Renamed(**values))
    with pytest.raises(AttributeError, match="frf_rms_error_db"):
        report_markdown(renamed)


def _typed(obj, path="") -> set:
    """Every JSON path of a typed object, through dataclasses, dicts, lists and tuples."""
    out = set()
    if isinstance(obj, (list, tuple)):  # elements by index, as _keys reads them
        for k, v in enumerate(obj):
            out |= _typed(v, f"{path}/{k}")
        return out
    items = ([(f.name, getattr(obj, f.name)) for f in dataclasses.fields(obj)]
             if dataclasses.is_dataclass(obj) else list(obj.items()) if isinstance(obj, dict)
             else [])
    for k, v in items:
        out.add(f"{path}/{k}")
        out |= _typed(v, f"{path}/{k}")
    return out


def test_the_closed_loop_summary_json_holds_exactly_its_typed_fields():
    s = _summary()
    assert set(_keys(s.to_dict()["control"])) == _typed(s.control.summary)


def test_renaming_a_closed_loop_field_fails_the_report():
    """The closed-loop section is rendered from its typed summary too (issue 31)."""
    fields = [(f.name if f.name != "h2_ratio_db" else "h2_change_db", f.type,
               dataclasses.field(default=f.default))
              if f.default is not dataclasses.MISSING else
              (f.name if f.name != "h2_ratio_db" else "h2_change_db", f.type)
              for f in dataclasses.fields(LoopEvaluation)]
    Renamed = dataclasses.make_dataclass(
        "LoopEvaluation", fields, frozen=True,
        namespace={"watched_damping": LoopEvaluation.watched_damping})
    renamed = _summary(control=_control(_evaluation(Renamed, h2_change_db="h2_ratio_db")))
    with pytest.raises(AttributeError, match="h2_ratio_db"):
        report_markdown(renamed)
