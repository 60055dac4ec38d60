"""The demo's report (``report.md``), rendered from its typed summary
(:class:`trussid.campaign.summary.DemoSummary`) by attribute, in the order of the report."""

from __future__ import annotations

import math

from trussid.campaign.loop_report import closed_loop_markdown
from trussid.campaign.structure import STRUCTURAL_DAMPING_MAX
from trussid.campaign.summary import ClosedLoopSection, DemoSummary, ReportProvenance

__all__ = ["report_markdown", "provenance_lines", "lacks_lines"]


def _f(x, fmt=".2f"):
    # summary.json holds a non-finite number as null; the report shows both as "-"
    return "-" if x is None or not math.isfinite(x) else format(x, fmt)


def report_markdown(s: DemoSummary) -> str:
    """The human-readable report (Markdown) from the summary, the closed-loop section
    included (attributes of the typed summary only: a renamed field fails here)."""
    # Long: a report template, read best top to bottom in the order of the report.
    st, pl = s.settings, s.plant
    testbed = pl.structure == "the default testbed"
    L = ["# trussid demo: PLID on the simulated " + ("testbed" if testbed else "structure"), ""]
    L += provenance_lines(s.provenance)
    L += [f"Run: {'quick' if st.quick else 'full'}; total {s.timings_s['total']:.1f} s "
          f"(plant {s.timings_s['plant']:.1f} s, experiments "
          f"{s.timings_s['experiments']:.1f} s, identification "
          f"{s.timings_s['identification']:.1f} s, evaluation "
          f"{s.timings_s['evaluation']:.1f} s).", ""]
    if not testbed:
        L += ["## Plant", "",
              f"{pl.structure[0].upper() + pl.structure[1:]}, {pl.modes} modes below Nyquist, "
              f"modal damping {100 * pl.modal_damping:.2f} %; discrete plant of {pl.states} "
              f"states, {len(pl.inputs)} commands ({', '.join(pl.inputs)}) to "
              f"{len(pl.outputs)} sensors ({', '.join(pl.outputs)}) at "
              f"{pl.sample_rate_hz:g} Hz, in the IO file's units; {pl.converter_bits}-bit "
              f"converters, +-{pl.converter_full_scale_v:g} units (lab: {pl.lab_source}); "
              "sensor noise 60 dB under each output in the all-channel record.", ""]
    L += [] if not testbed else ["## Plant", "",
          f"Default testbed, {pl.modes} modes below Nyquist, modal damping "
          f"{100 * pl.modal_damping:.2f} %; discrete plant of {pl.states} states, "
          f"{len(pl.inputs)} D/A channels ({', '.join(pl.inputs)}) to "
          f"{len(pl.outputs)} accelerometers ({', '.join(pl.outputs)}) at "
          f"{pl.sample_rate_hz:g} Hz, with the smoothing filter, amplifier and "
          f"{pl.lab.filters.lowpass_cutoff:g} Hz "
          f"low-pass. Accelerometers {1000 * pl.accelerometer_sensitivity_v_per_g:.0f} mV/g, "
          f"signal conditioner gain {pl.conditioning_gain:g} V/V; "
          f"{pl.converter_bits}-bit converters, +-{pl.converter_full_scale_v:g} V; "
          f"sensor noise {1e6 * pl.sensor_noise_g_rms:.0f} ug RMS "
          f"({1e3 * pl.sensor_noise_v_rms:.2f} mV at the nominal gain).", ""]
    L += ["## Experiments", "",
          f"Excitation: {st.excitation} noise, {st.excitation_band[0]:g}-"
          f"{st.excitation_band[1]:g} Hz, {st.excitation_rms:g} V RMS per driven "
          "channel. Conditioners ranged in 1-2-5 steps to about "
          f"{st.range_target:.2f} of full scale at most.", "",
          "| record | samples | driven | D/A clipped | A/D clipped | gain steps | "
          "RMS / range | sensor SNR [dB] | quantisation SNR [dB] |",
          "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in s.experiments:
        L.append(f"| {r.model} {r.purpose} | {r.samples} | "
                 f"{', '.join(r.driven_channels)} | {sum(r.dac_clipped)} | "
                 f"{', '.join(map(str, r.adc_clipped))} | "
                 f"{', '.join(f'{g:g}' for g in r.conditioner_steps)} | "
                 f"{', '.join(f'{v:.2f}' for v in r.output_rms_fraction_of_range)} | "
                 f"{', '.join(f'{v:.1f}' for v in r.sensor_snr_db)} | "
                 f"{', '.join(f'{v:.1f}' for v in r.quantisation_snr_db)} |")
    L += ["", "## Identified models", "",
          "One-step signal-to-prediction-error ratio (SPE) on the validation record, as the "
          "thesis defines it: the RMS of the sensor signals over the RMS of the one-step "
          "prediction error, over all sensors and samples (`10 log10(sum y^2 / sum e^2)`, "
          "volts at the A/D; `plid.metrics`). Beside it, per output, and the mean of the "
          "normalised error powers (`-10 log10(mean_j MS(e_j)/MS(y_j))`, dominated by the "
          "weakest output: in a SIMO record the two accelerometers away from the driven "
          "vertex are limited by sensor noise to 38-50 dB). FRF errors are against the "
          f"true plant over {st.frf_band[0]:g}-{st.frf_band[1]:g} Hz.", "",
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
    for m in s.models:
        mc = m.modes_check
        L.append(f"| {m.name} | {m.kind} | {m.states} | {m.inputs} x "
                 f"{m.outputs} | {_f(m.signal_to_prediction_error_db)} | "
                 f"{', '.join(_f(v, '.1f') for v in m.signal_to_prediction_error_db_per_output)}"
                 f" | {_f(m.signal_to_prediction_error_db_mean_normalised)} | "
                 f"{_f(m.simulation_fit_db)} | "
                 f"{_f(m.frf_max_error_db)} / {_f(m.frf_rms_error_db)} | "
                 f"{_f(m.frf_max_error_deg, '.1f')} / {_f(m.frf_rms_error_deg, '.1f')} | "
                 f"{_f(m.h1_error_vs_true['rms_db'])} | "
                 f"{mc.found} / {mc.total} | "
                 f"{m.seconds:.1f} |")
    L += lacks_lines(s)
    L += ["", "## How each model was identified", "",
          "`plid.multipass.identify_reduced`: PLID at the model's order and at higher "
          "orders reduced to it (input-weighted balanced truncation, then one PLID pass); "
          "the candidate with the best one-step ratio on the *identification* record is "
          "kept (marked). Candidates with poles outside the unit circle compete with those "
          "poles reflected in (`stabilised`).", ""]
    for m in s.models:
        ident = m.identification
        L += [f"**{m.name}**: {m.method}", "",
              "| candidate | one-step, identification record (in-sample) [dB] | seconds |",
              "| --- | --- | --- |"]
        for r in ident.candidates:
            mark = " (kept)" if r.get("label") == ident.chosen else ""
            score = r.get("identification_ratio_db")
            txt = _f(score) if score is not None else (r.get("error") or "unstable")
            L.append(f"| {r.get('label', '')}{mark} | {txt} | {r.get('seconds', 0):.1f} |")
        L.append("")
        scan = ident.order_scan
        if scan:  # the order chosen from the data (issue 32)
            L += [f"Order {scan.chosen} chosen from the data ({scan.rule}; runners-up "
                  f"{', '.join(map(str, scan.runners_up)) or 'none'}; "
                  f"{scan.cpu_seconds:.1f} s CPU of a {scan.cpu_budget_s:g} s budget). "
                  "The validation column is shown only, never used to choose.", "",
                  "| states | one-step, held-back [dB] | one-step, validation [dB] | note |",
                  "| --- | --- | --- | --- |"]
            for r in scan.rows:
                mark = " (chosen)" if r.order == scan.chosen else ""
                L.append(f"| {r.order}{mark} | {_f(r.held_back_db)} | "
                         f"{_f(r.validation_db)} | {r.note} |")
            L.append("")
    L += ["", "## Figures", ""]
    for m in s.models:
        n = m.name
        bodes = [f for f in s.files.figures if f.startswith(f"bode_{n}")]
        L += [f"### {n}", ""]
        L += [f"![Bode overlay]({b})" for b in bodes]
        L += ["", f"![poles and zeros](poles_{n}.png)", "",
              f"![measured vs predicted](trace_{n}.png)", "",
              "Poles in the FRF band (true -> identified), with the identified mode's 95 % "
              "intervals (first-order propagation of the PLID pass's parameter covariance, "
              "`plid.uncertainty`) and the MAC of the FE mode shape against the identified "
              "one at the sensors (`plid.modal.mac`):", "",
              "| true f [Hz] | true damping | identified f [Hz] | 95 % interval f [Hz] | "
              "identified damping | 95 % interval damping | MAC |",
              "| --- | --- | --- | --- | --- | --- | --- |"]
        lo, hi = st.frf_band
        checks = {(round(c.true_frequency_hz, 9), round(c.frequency_hz, 9)): c
                  for c in m.mode_checks}
        not_modes = 0
        for r in m.poles:
            if (r.true_frequency_hz is not None and lo <= r.true_frequency_hz <= hi
                    and r.true_damping > STRUCTURAL_DAMPING_MAX):
                not_modes += 1  # a filter's or amplifier's pole, not a structural mode
            elif r.true_frequency_hz is not None and lo <= r.true_frequency_hz <= hi:
                c = (checks.get((round(r.true_frequency_hz, 9), round(r.frequency_hz, 9)))
                     if r.frequency_hz is not None else None)
                fi = c.frequency_ci95_hz if c else None
                zi = c.damping_ratio_ci95 if c else None
                L.append(f"| {r.true_frequency_hz:.2f} | {r.true_damping:.5f} | "
                         f"{_f(r.frequency_hz)} | "
                         f"{f'{fi[0]:.2f}-{fi[1]:.2f}' if fi else '-'} | "
                         f"{_f(r.damping, '.5f')} | "
                         f"{f'{zi[0]:.5f}-{zi[1]:.5f}' if zi else '-'} | "
                         f"{_f(c.mac if c else None, '.3f')} |")
        if not_modes:
            L += ["", f"Not listed: {not_modes} true pole(s) in the band damped above "
                      f"{STRUCTURAL_DAMPING_MAX:g} (the lab's filter and amplifier poles, not "
                      "structural modes)."]
        L.append("")
    L += ["### Convergence", "", "![convergence](convergence.png)", "",
          "The top panel is the *mean-normalised* one-step ratio of each model's last PLID "
          "pass on its identification record (in-sample), not the headline SPE of the table "
          "above.", ""]
    L += ["## Files", "", "Data: " + ", ".join(s.files.data), "",
          "Models: " + ", ".join(s.files.models), "",
          "All metrics: `summary.json`.", ""]
    md = "\n".join(L)
    return (md + ("\n" + control_markdown(s.control) if s.control is not None else "")
            + ("\n" + s.adapt.markdown if s.adapt is not None else ""))


def control_markdown(section: ClosedLoopSection) -> str:
    """The closed-loop section, rendered from its typed summary (or why there is none)."""
    if section.summary is None:
        return f"## Closed loop: active damping\n\nNo controller designed: {section.error}.\n"
    return closed_loop_markdown(section.summary, "##", section.figures)


def provenance_lines(pv: ReportProvenance) -> list:
    """The report's provenance paragraph."""
    load = pv.load_average_start
    return ["## Provenance", "",
            f"trussid {pv.trussid_version}, commit {pv.commit or 'unknown'}; "
            f"seed {pv.seed}; command `{pv.command or '(from Python)'}`; "
            f"machine {pv.machine} ({pv.platform}, {pv.cpus} CPUs, Python "
            f"{pv.python}), load average "
            f"{'-' if not load else ', '.join(f'{v:.2f}' for v in load)} at the start; "
            f"{pv.date_utc}. The seconds below depend on that load.", ""]


def lacks_lines(s: DemoSummary) -> list:
    """What each model lacks (true modes missing) and adds (spurious or lightly damped
    poles anywhere, reflected poles), and the H1 coherence."""
    # Long: one report section, read top to bottom.
    L = ["", "## What the models lack, and what they add", ""]
    for m in s.models:
        mc = m.modes_check
        lo, hi = mc.band_hz
        xlo, xhi = mc.excited_band_hz
        L += [f"**{m.name}**: found {mc.found} of the {mc.total} true structural "
              f"modes in {lo:g}-{hi:g} Hz ({mc.filter_poles_in_band} filter/amplifier "
              "poles in the band are not counted)."]
        if mc.missing:
            L += [f"Missing ({len(mc.missing)}): "
                  + ", ".join(f"{f:.2f} Hz" for f in mc.missing) + "."]
        else:
            L += ["Missing: none."]
        st = m.stabilised
        if st.applied:
            L += [f"Stabilised: {st.reflected_poles} unstable pole(s) reflected into "
                  "the unit circle (magnitude kept, phase changed)."]
        if m.unstable_poles:
            L += [f"**Unstable**: {m.unstable_poles} pole(s) on or outside the unit circle."]
        rows = {(e.frequency_hz, e.damping): e for e in mc.spurious + mc.lightly_damped}
        L += [""]
        if rows:
            L += ["Spurious modes (no true mode within 5 %) and lightly damped modes "
                  f"(damping under {100 * mc.rules['light_damping_below']:g} %), anywhere "
                  f"up to Nyquist (excited band {xlo:g}-{xhi:g} Hz):", "",
                  "| identified f [Hz] | damping [%] | nearest true mode [Hz] | spurious | "
                  "in excited band |", "| --- | --- | --- | --- | --- |"]
            for (f, z), e in sorted(rows.items()):
                near = "-" if e.nearest_true_hz is None else f"{e.nearest_true_hz:.2f}"
                L.append(f"| {f:.2f} | {100 * z:.3f} | {near} | "
                         f"{'yes' if e.spurious else 'no'} | "
                         f"{'yes' if e.in_excited_band else '**no**'} |")
        else:
            L += ["No spurious or lightly damped identified modes."]
        coh = m.h1_coherence
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
