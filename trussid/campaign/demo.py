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

One job per module: :mod:`trussid.campaign.plan` (the settings), :mod:`trussid.campaign.records`
(the records and their summary rows), :mod:`trussid.campaign.identified` (each model
identified, with its typed record), :mod:`trussid.campaign.evaluation` (its metrics and mode
audit); this module runs them in order and writes the report directory (files, figures,
``summary.json``, ``report.md``, ``report.html``), and re-exports their public names.
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from trussid import plots
from trussid._util.errors import UserError
from trussid._util.files import atomic_directory, atomic_path
from trussid.campaign.adapt import demo_section as adapt_demo_section
from trussid.campaign.adapt import write_files as write_adapt_files
from trussid.campaign.control import demo_section
from trussid.campaign.evaluation import evaluate, h1_estimate, mode_audit
from trussid.campaign.html_report import write_report_html
from trussid.campaign.identified import Identified, identify_model
from trussid.campaign.orders import scan_orders
from trussid.campaign.plan import DemoSettings, demo_settings, derived_settings
from trussid.campaign.records import (Record, conditioner_steps, drive, experiment_summary,
                                      run_experiments, take_record)
from trussid.campaign.report import report_markdown
from trussid.campaign.summary import (AdaptSection, DemoSummary, PlantSummary, ReportFiles,
                                      ReportProvenance)
from trussid.geometry.lab import G0, lab_record
from trussid.lqg.grading import LoopSettings
from trussid.plid.datafile import with_channels, write_data
from trussid.plid.modelfile import save_model
from trussid.plots import save_figure
from trussid.testbed.plant import TestbedPlant, testbed_plant


# --------------------------------------------------------------------------- plant


def build_plant(tb=None):
    """The plant of testbed ``tb`` (default: the default testbed) at its lab's sample rate,
    with its lab chain (:class:`trussid.testbed.plant.TestbedPlant`)."""
    return testbed_plant(tb)


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
                               tp.tbm.testbed if isinstance(tp, TestbedPlant) else None,
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
                                  unit="V/V" if isinstance(tp, TestbedPlant) else "IO-file units")
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
    if not isinstance(tp, TestbedPlant):  # a deck's plant: outputs in its own units, no conditioner
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


__all__ = ["DemoSettings", "demo_settings", "build_plant", "run_experiments", "take_record",
           "conditioner_steps", "identify_model", "evaluate",
           "run_demo", "report_markdown", "Identified", "Record", "mode_audit", "provenance"]
