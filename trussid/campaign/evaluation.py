"""All metrics of one identified model of the campaign (:func:`evaluate`): validation
prediction and simulation, FRF errors against the true plant and the H1 estimate, matched
poles with their intervals and MAC, and what the model lacks and adds (:func:`mode_audit`).
"""

from __future__ import annotations

import numpy as np

from trussid.campaign.identified import Identified
from trussid.campaign.plan import DemoSettings
from trussid.campaign.records import Record
from trussid.campaign.structure import STRUCTURAL_DAMPING_MAX
from trussid.campaign.summary import (AuditedIdentifiedMode, AuditedTrueMode, ModeAudit,
                                      ModeCheck, ModelSummary)
from trussid.plid.evaluate import compare
from trussid.plid.frf import frequency_response, h1
from trussid.plid.modal import mac, modal_table

__all__ = ["evaluate", "mode_audit", "h1_estimate", "FOUND_TOLERANCE", "LIGHT_DAMPING"]


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
