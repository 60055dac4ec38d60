"""The closed-loop report of a graded controller (:class:`trussid.lqg.grading.Robustness`):
its typed summary (:class:`trussid.campaign.summary.ClosedLoopSummary`), the Markdown
rendered from that summary alone, the figures, and the files ``trussid closed-loop`` writes.

The demo's closed-loop section and ``trussid closed-loop`` render with the same functions,
so the same controller on the same plant reads the same in both.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from trussid._util.files import atomic_path
from trussid._util.jsonio import json_safe
from trussid.lqg.baselines import decentralised
from trussid.lqg.grading import CHECKS, Checks, LoopEvaluation, Robustness, check
from trussid.lqg.loop import Loop
from trussid.lqg.modal import freq_damping
from trussid.plid.frf import frequency_response
from trussid.plots import bode_figure, damping_map_figure, decay_figure, save_figure, sigma_figure

from .summary import ClosedLoopSummary, ControllerSummary, DesignSummary, ProcedureSummary

__all__ = ["impulse_envelope", "figures", "closed_loop_summary", "closed_loop_markdown",
           "write_report"]


def impulse_envelope(sys, n: int) -> np.ndarray:
    """``20 log10 ||h[k]||_F`` of a discrete system's impulse response, k = 1..n, as a
    running maximum over 16-sample windows (the envelope of the ringing) [dB].

    Parameters
    ----------
    sys : control.StateSpace
        Discrete.
    n : int
        Samples.
    """
    A, B, C = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C))
    X = B.copy()
    e = np.empty(n)
    for k in range(n):  # n x m products: cheap, and no n x n power is formed
        e[k] = np.linalg.norm(C @ X)
        X = A @ X
    w = 16
    pad = np.concatenate([e, np.full(w - 1, e[-1])])
    env = np.lib.stride_tricks.sliding_window_view(pad, w).max(axis=1)
    with np.errstate(divide="ignore"):
        return 20 * np.log10(np.maximum(env, 1e-300))


def figures(study: Robustness, prefix: str = "") -> dict:
    """The nominal loop's figures: ``{file name: Figure}`` (sigma and Bode of the D/A
    disturbance to the sensors, impulse decay, damping map).

    Parameters
    ----------
    study : trussid.lqg.grading.Robustness
    prefix : str
        Put before every file name.
    """
    label, plant = study.plants[0]
    ctrl = study.controller
    st = study.settings
    loop = Loop.of(plant, ctrl)
    ol, cl = loop.open_loop, loop.disturbance_to_sensors
    nyq = 0.5 / plant.dt
    f = np.linspace(min(20.0, 0.02 * nyq), nyq, 3000)
    fo, _ = freq_damping(np.linalg.eigvals(np.asarray(ol.A)), plant.dt)
    f = np.unique(np.concatenate([f, fo[(fo > f[0]) & (fo < nyq)]]))
    H_ol, H_cl = frequency_response(ol, f), frequency_response(cl, f)
    curves = [("open loop", f, H_ol), ("LQG", f, H_cl)]
    base = study.baselines
    if base:
        best = max(base, key=lambda k: base[k].rows[label].dominant_min or -1)
        b = base[best]
        bc = decentralised(best, b.gain, ctrl.dt, list(ctrl.input_labels),
                           list(ctrl.output_labels), tuple(b.band))
        if b.rows[label].stable:
            curves.append((f"{best} (baseline)", f,
                           frequency_response(Loop.of(plant, bc).disturbance_to_sensors, f)))
    figs = {}
    figs[f"{prefix}sigma.png"] = sigma_figure(
        curves, f"{label}: actuator disturbance to sensors",
        f"largest singular value [{st.output_unit}/{st.input_unit}]")
    names_in = list(ctrl.output_labels)
    figs[f"{prefix}bode_{names_in[0]}.png"] = bode_figure(
        [("open loop", f, H_ol), ("LQG closed loop", f, H_cl)], 0, f"d_{names_in[0]}",
        list(ctrl.input_labels), f"{label}: open vs closed loop",
        unit=f"{st.output_unit}/{st.input_unit}")
    n = int(1.5 / plant.dt)
    t = np.arange(1, n + 1) * plant.dt
    figs[f"{prefix}impulse.png"] = decay_figure(
        [("open loop", t, impulse_envelope(ol, n)), ("LQG", t, impulse_envelope(cl, n))],
        f"{label}: impulse decay, actuator disturbance to sensors (all channels)")
    lam_ol = np.linalg.eigvals(np.asarray(ol.A))
    lam_cl = loop.poles
    lam_c = np.linalg.eigvals(np.asarray(ctrl.A)) if ctrl.nstates else np.array([])
    sets = [("open loop", *freq_damping(lam_ol, plant.dt), "o"),
            ("closed loop", *freq_damping(lam_cl, plant.dt), "x"),
            ("controller alone", *freq_damping(lam_c, plant.dt), "+")]
    figs[f"{prefix}poles.png"] = damping_map_figure(sets, f"{label}: poles",
                                                    (0.0, 0.5 / plant.dt))
    return figs


def closed_loop_summary(study: Robustness) -> ClosedLoopSummary:
    """The typed summary of a study (everything but the systems).

    Parameters
    ----------
    study : trussid.lqg.grading.Robustness
    """
    des = study.design
    design = None
    if des is not None:
        design = DesignSummary(
            form=des.form, target_modes=tuple(des.target_modes),
            design_states=int(des.design_model.nstates),
            target_damping=float(des.info["target_damping"]),
            estimator=str(des.info["estimator_choice"].get("chosen", "")),
            info={k: v for k, v in des.info.items() if k != "model_modes"},
            procedure=_procedure_summary(des.procedure))
    c = study.controller
    return ClosedLoopSummary(
        nominal=study.nominal, settings=study.settings, rows=dict(study.rows),
        checks=dict(study.checks), baselines=dict(study.baselines),
        timings_s=dict(study.timings_s),
        controller=ControllerSummary(int(c.nstates), list(c.input_labels),
                                     list(c.output_labels)),
        design=design, design_file=study.design_info)


def _procedure_summary(proc) -> ProcedureSummary | None:
    """The typed summary of a :class:`trussid.lqg.procedure.Procedure` (None: none)."""
    if proc is None:
        return None
    return ProcedureSummary(attempts=len(proc.attempts), disk_gain_db=float(proc.disk_gain_db),
                            asked=float(proc.asked), outcomes=tuple(proc.outcomes),
                            lines=tuple(proc.lines()), warning=proc.warning())


def _pct(x, digits=2):
    return "-" if x is None else f"{100 * x:.{digits}f}"


def _num(x, fmt=".1f"):
    return "-" if x is None else format(x, fmt)


def closed_loop_markdown(s: ClosedLoopSummary, heading: str = "##",
                         figure_files=()) -> str:
    """The closed-loop report (Markdown) of a summary: damping table, margins, robustness,
    baselines, the acceptance codes explained, then the figures by file name.

    Parameters
    ----------
    s : ClosedLoopSummary
    heading : str
        The section's heading level.
    figure_files : sequence of str
        Figures to link at the end.
    """
    # Long: one report, its sections in order; every figure is read from the summary.
    h = heading
    nom = s.nominal
    ctrl = s.controller
    des = s.design
    L = [f"{h} Closed loop: active damping", ""]
    if des is not None:
        tm = ", ".join(f"{t.frequency_hz:.1f} Hz" for t in des.target_modes)
        L += [f"LQG ({des.form} form: " + ("u[k] uses y up to k-1" if des.form == "predictor"
                                              else "u[k] uses y[k], no computation delay")
              + f") designed from the identified model and its identification record only; "
              f"design model restricted to {tm} ({des.design_states} states), "
              f"state feedback tuned to {100 * des.target_damping:.1f} % damping on "
              f"them, estimator: {des.estimator}. "
              f"Controller: {ctrl.states} states.", ""]
        proc = des.procedure
        if proc is not None:  # how the default procedure got there (issue 32)
            L += [f"Design procedure: {proc.attempts} designs tried, the best stable one "
                  f"with a {proc.disk_gain_db:.1f} dB MIMO disk margin on the identified model "
                  f"kept; per target mode (asked {100 * proc.asked:.1f} %):", "",
                  *[f"- {line.strip()}" for line in proc.lines], ""]
            if proc.warning:
                L += [f"**Warning**: {proc.warning}.", ""]
    else:
        di = s.design_file or {}   # a controller file's own JSON (trussid control)
        tm = ", ".join(f"{t['frequency_hz']:.1f} Hz" for t in di.get("target_modes", []))
        L += [f"Controller: {ctrl.states} states, {len(ctrl.sensors)} sensors in, "
              f"{len(ctrl.actuators)} actuators out"
              + (f"; {di.get('form')} form, designed by `trussid control` from {di.get('model')} "
                 f"and {di.get('data')} for the modes at {tm}" if di else "") + ".", ""]
    st = s.settings
    lo, hi = st.band
    dominant_rule = ("the plant modes nearest the design's target modes, "
                     if st.targets_hz else "residue >= 25 % of the largest, ")
    L += [f"{h}# Damping per mode on the {nom} truth", "",
          f"Open-loop plant modes in {lo:g}-{hi:g} Hz; *tracked*: the closed-loop pole matched to "
          "the mode; *worst visible*: the least damped among it and the controller poles "
          "near it whose residue from the D/A to the sensors is at least 10 % of the mode's "
          f"open-loop residue. Dominant modes ({dominant_rule}in bold).", "",
          "| f open [Hz] | damping open [%] | f closed [Hz] | tracked [%] | worst visible [%] "
          "| visible controller poles | ratio to open |",
          "| --- | --- | --- | --- | --- | --- | --- |"]
    for r in s.rows[nom].rows:
        b = "**" if r.dominant else ""
        L.append(f"| {b}{r.frequency_hz:.1f}{b} | {_pct(r.damping_open, 3)} | "
                 f"{r.frequency_closed:.1f} | {_pct(r.damping_tracked, 3)} | "
                 f"{b}{_pct(r.damping_worst_visible, 3)}{b} | "
                 f"{r.visible_controller_poles} | "
                 f"{r.damping_worst_visible / r.damping_open:.2f} |")
    iu_, ou_ = st.input_unit, st.output_unit
    conv = ("ideal converters" if st.bits is None else f"{st.bits}-bit converters")
    exc = ", ".join(f"{v:.3g}" for v in np.ravel(st.excitation_rms))
    noise = ", ".join(f"{v:.3g}" for v in np.ravel(st.noise_rms))
    watch = list(st.watch_hz)
    L += ["", f"{h}# Robustness: the same controller on perturbed truths", "",
          "Dominant: worst visible damping of each dominant mode. Others: least ratio of "
          f"closed- to open-loop damping among the other modes in {lo:g}-{hi:g} Hz. Disk "
          "margins (balanced, at the plant input): MIMO (all channels at once, mu) and loop "
          "at a time. H2: disturbance at the actuators to the sensors, closed over open loop. "
          f"Command: RMS per channel [{iu_}] in a closed-loop simulation ({conv}) under "
          f"white 0-{st.excitation_band_hz:g} Hz noise of {exc} {iu_} RMS added at the "
          f"actuators, plus sensor noise of {noise} {ou_} RMS.", "",
          "| truth | stable | dominant worst [%] | others min ratio | MIMO disk GM [dB] / PM "
          f"[deg] | loop GMs [dB] | H2 change [dB] | command RMS [{iu_}] | "
          + "".join(f"{f:g} Hz [%] | " for f in watch) + "acceptance |",
          "| --- " * (9 + len(watch)) + "|"]
    L += [_robust_row(lab, r, s.checks[lab], watch) for lab, r in s.rows.items()]
    L += [""] + _codes(st.thresholds)
    if s.baselines:
        L += ["", f"{h}# Baselines: decentralised acceleration feedback", "",
              "Each channel fed back from its own accelerometer, gain tuned on the identified "
              "model (the gain that maximises the least dominant-mode damping on the model, "
              "halved). Same columns as above.", "",
              "| baseline | gain | truth | stable | dominant worst [%] | others min ratio | "
              "MIMO disk GM [dB] / PM [deg] | loop GMs [dB] | H2 change [dB] | "
              f"command RMS [{iu_}] | " + "".join(f"{f:g} Hz [%] | " for f in watch)
              + "acceptance |",
              "| --- " * (11 + len(watch)) + "|"]
        for kind, b in s.baselines.items():
            for j, (lab, r) in enumerate(b.rows.items()):
                L.append(f"| {kind} | {b.gain:.3g} | " + _robust_row(
                    lab, r, check(r, nominal=(j == 0), thresholds=st.thresholds), watch)[2:])
    L += ["", "Timings [s]: " + ", ".join(f"{k} {v:.1f}" for k, v in s.timings_s.items()), ""]
    md = "\n".join(L)
    if figure_files:
        md += "\n" + "\n".join(f"![{name}]({name})" for name in figure_files) + "\n"
    return md


def _codes(T) -> list:
    """The acceptance codes of the tables, each with what it checks and its thresholds."""
    limits = {
        "2_dominant": f"{100 * T.dominant_nominal:g} % nominal, "
                      f"{100 * T.dominant_perturbed:g} % perturbed",
        "3_others": f"{T.other_ratio_nominal:g} nominal, {T.other_ratio_perturbed:g} perturbed",
        "4_mimo": f"{T.mimo_gm_nominal_db:g} dB / {T.mimo_pm_nominal_deg:g} deg nominal, "
                  f"{T.mimo_gm_perturbed_db:g} dB perturbed",
        "4_loops": f"{T.loop_gm_db:g} dB",
        "5_h2": None if T.h2_reduction_db is None else f"{T.h2_reduction_db:g} dB, nominal only",
        "5_command": None if T.command_rms_v is None else f"{T.command_rms_v:g}, nominal only",
    }
    return ["Acceptance codes (a failed one is listed after FAIL): "
            + "; ".join(f"`{code}` {text}" + (f" ({limits[code]})" if limits.get(code) else "")
                        for code, text in CHECKS.items()
                        if code not in limits or limits[code] is not None) + "."]


def _robust_row(label, r: LoopEvaluation, ok: Checks, watch=(118.0, 138.0)) -> str:
    m = r.margins
    mimo = "-" if not m else f"{m.mimo.gain_db:.2f} / {m.mimo.phase_deg:.1f}"
    loops = "-" if not m else ", ".join(f"{lp.gain_db:.1f}" for lp in m.loops)
    dom = ", ".join(_pct(d.worst) for d in r.dominant) or "-"
    cmd = "-" if not r.command_rms_v else ", ".join(f"{v:.2f}" for v in r.command_rms_v)
    failed = ok.failed
    verdict = "pass" if not failed else "FAIL " + ", ".join(failed)
    return (f"| {label} | {'yes' if r.stable else 'NO'} | {dom} | "
            f"{_num(r.other_min_ratio, '.2f')} | {mimo} | {loops} | "
            f"{_num(r.h2_ratio_db)} | {cmd} | "
            + "".join(f"{_pct(r.watched_damping(f))} | " for f in watch)
            + f"{verdict} |")


def write_report(out, study: Robustness) -> list:
    """``report.md``, the figures and ``summary.json`` into the directory ``out`` (each file
    atomically). Returns the file names.

    Parameters
    ----------
    out : str or Path
    study : trussid.lqg.grading.Robustness
    """
    out = Path(out)
    figs = figures(study, prefix="")
    summ = closed_loop_summary(study)
    md = closed_loop_markdown(summ, "##", list(figs))
    out.mkdir(parents=True, exist_ok=True)
    for name, fig in figs.items():
        save_figure(fig, out / name)
    with atomic_path(out / "summary.json") as tmp:
        tmp.write_text(json.dumps(json_safe(summ), indent=2) + "\n")
    with atomic_path(out / "report.md") as tmp:
        tmp.write_text("# trussid closed-loop report\n\n" + md)
    return ["report.md", "summary.json", *figs]
