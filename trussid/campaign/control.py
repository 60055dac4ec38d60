"""Closing the loop on the simulated testbed: an LQG designed from an identified model, run
on the FE truth and on perturbed truths, beside decentralised baselines.

The controller never sees the truth: :func:`trussid.lqg.design_lqg` uses the identified
model and its identification record only. The truths are :func:`trussid.testbed.plant.
testbed_plant` with one parameter changed each (:data:`trussid.testbed.perturbed.
PERTURBATIONS`). The grading (settings, thresholds, evaluation, checks) is
:mod:`trussid.lqg.grading`, for any plant; the report is :mod:`trussid.campaign.loop_report`.

Acceptance thresholds of issue 14 (:data:`trussid.lqg.grading.THRESHOLDS`) are checked per
truth and reported as measured, never adjusted.
"""

from __future__ import annotations

import time
from dataclasses import replace

import control
import numpy as np

from trussid.lqg.errors import ControlError
from trussid.lqg.grading import (BASELINE_KINDS, THRESHOLDS, LoopSettings, Robustness, check,
                                 evaluate_loop, plant_loop_settings, robustness)
from trussid.lqg.procedure import design_controller
from trussid.testbed.perturbed import PERTURBATIONS, STRETCH, perturbed_testbed, truths

from .loop_report import closed_loop_summary, figures
from .summary import ClosedLoopSection

# The grading and the truths, under the names this module has always exported.
__all__ = ["control_study", "demo_section", "PERTURBATIONS", "STRETCH", "perturbed_testbed",
           "truths", "THRESHOLDS", "BASELINE_KINDS", "LoopSettings", "plant_loop_settings",
           "evaluate_loop", "check", "design_controller", "robustness"]


def control_study(model, u, y, *, K=None, target_damping: float = 0.07, band=None,
                  form: str = "predictor", stretch: bool = False, baselines: bool = True,
                  settings: LoopSettings, tb=None, plants=None,
                  progress=None) -> Robustness:
    """Design from the identified ``model`` and record ``(u, y)``, evaluate on the truths
    (:func:`truths` of ``tb``, or ``plants``: ``[(label, plant)]``, the first nominal)
    with the converters of ``settings`` (:meth:`LoopSettings.for_lab`).

    Parameters
    ----------
    model : control.StateSpace
        The identified model (discrete, named channels).
    u, y : (N, m), (N, p) float
        Its identification record.
    K, target_damping, band, form
        As :func:`trussid.lqg.design_lqg`.
    stretch : bool
        Add the stretch truths.
    baselines : bool
        Tune and evaluate the decentralised baselines.
    settings : LoopSettings
    tb : trussid.geometry.Testbed, optional
        The testbed whose truths are made (default the default testbed).
    plants : list of (str, control.StateSpace), optional
        The plants instead of the truths.
    progress : callable, optional

    Returns
    -------
    trussid.lqg.grading.Robustness
        With the design and its timings.
    """
    des, base, t_design = design_controller(model, u, y, K=K, target_damping=target_damping,
                                            band=band, form=form, baselines=baselines,
                                            progress=progress)
    t0 = time.perf_counter()
    plants = plants if plants is not None else truths(tb, stretch)
    t_truths = time.perf_counter() - t0
    study = robustness(des.controller, plants, base, settings, progress)
    return replace(study, design=des,
                   timings_s={**t_design, "truths": t_truths, **study.timings_s})


def demo_section(model, K, data, truth, quick: bool, settings: LoopSettings, tb,
                 progress=None, *, lab=None, excitation_rms=None):
    """``trussid demo``'s hook: the LQG from its MIMO model and identification record on
    the FE truth (and, unless ``quick``, on the perturbed truths of testbed ``tb`` with the
    baselines beside it), exercised with ``settings`` (the demo's lab and excitation).
    ``tb`` None: any other structure, on its one true plant behind ``lab``'s converters,
    graded in its own units (:func:`plant_loop_settings`, the record's ``excitation_rms``
    per command; ``settings`` is not used).

    Parameters
    ----------
    model : control.StateSpace
        The MIMO model.
    K : array
        Its one-step predictor gain.
    data : trussid.plid.IOData
        Its identification record.
    truth : control.StateSpace
        The true plant.
    quick : bool
        Nominal truth only, no baselines.
    settings : LoopSettings
    tb : trussid.geometry.Testbed or None
    progress : callable, optional
    lab : trussid.geometry.lab.LabSpec, optional
        Any other structure's lab.
    excitation_rms : float, optional
        Its record's excitation RMS per command.

    Returns
    -------
    section : trussid.campaign.summary.ClosedLoopSection
    figures : dict
        ``{file name: Figure}``.
    """
    m = control.ss(model.A, model.B, model.C, model.D, model.dt,
                   inputs=list(data.input_names), outputs=list(data.output_names))

    plants = [("nominal", truth)] if quick or tb is None else None
    try:
        if tb is not None:
            study = control_study(m, data.u, data.y, K=K, plants=plants, baselines=not quick,
                                  settings=settings, tb=tb, progress=progress)
        else:
            des, base, t_design = design_controller(m, data.u, data.y, K=K,
                                                    baselines=not quick, progress=progress)
            settings = plant_loop_settings(
                truth, input_rms=None if excitation_rms is None else
                np.broadcast_to(excitation_rms, (m.ninputs,)),
                output_rms=np.std(data.y, axis=0),
                target_damping=des.info["target_damping"],
                targets_hz=[t.frequency_hz for t in des.target_modes], lab=lab)
            study = robustness(des.controller, plants, base, settings, progress)
            study = replace(study, design=des, timings_s={**t_design, **study.timings_s})
    except ControlError as exc:  # e.g. a model too small to hold a lightly damped mode
        return ClosedLoopSection(None, [], str(exc)), {}
    figs = figures(study, "control_")
    return ClosedLoopSection(closed_loop_summary(study), list(figs)), figs
