"""Steps shared by the identification recipes :func:`trussid.plid.recipe.identify` and
:func:`trussid.plid.reduced.identify_reduced` (a private module: not part of the API).
"""

from __future__ import annotations

import control
import numpy as np

from trussid.plid.errors import DataError
from trussid.plid.experiment import simulate
from trussid.plid.pem import refine_gain_from
from trussid.plid.stability import stabilise
from trussid.plid.subspace import output_error_fit


def noise_estimate(model, u, y, floor=1e-10):
    """Output-noise variance per channel in scaled units: the simulation error of a prior
    model on the data (an over-estimate by the prior's own model error)."""

    e = y - simulate(model, u)
    return np.maximum(np.mean(e ** 2, axis=0) / np.mean(y ** 2, axis=0), floor)



def pem_gain(model, u, y, K, kinfo):
    """``K`` refined by prediction error from the chosen candidate and from ``K = 0``, the
    refinement with the lower identification criterion kept
    (:func:`trussid.plid.pem.refine_gain_from`); the candidate itself when the model or its
    predictor is unstable.

    Measured on the four measured sets of ``benchmarks/bench_realdata.py`` (validation
    one-step fit, candidates -> refined): subframe 96.9 -> 97.8 %, robot arm 98.3 -> 99.2,
    flutter 71.1 -> 99.2, CD arm 80.3 -> 90.9, for 0.04-0.5 CPU s. ``K = 0`` as a second
    start: on the demo's MIMO record the best candidate refined to a higher criterion than
    ``K = 0`` (validation one-step 41.4 against 43.6 dB); on the four sets it never wins.
    """
    if K is None or count_unstable(model):
        return K, kinfo
    start = kinfo.get("chosen")
    starts = {str(start): K, ZERO_START: np.zeros_like(np.asarray(K, float))}
    try:
        # tol None: stop once a step is no longer significant (pem.significant_change)
        race = refine_gain_from(model, u, y, starts, tol=None)
    except (DataError, np.linalg.LinAlgError) as exc:
        return K, dict(kinfo, pem={"error": str(exc)})
    fit = race.fit
    kinfo = dict(kinfo)
    kinfo["chosen"] = f"prediction error ({fit.iterations} iterations from {race.start})"
    kinfo["pem"] = {"start": race.start, "iterations": fit.iterations, "converged": fit.converged,
                    "logdet_start": fit.logdet_start, "logdet_end": fit.logdet_end,
                    "race_logdet": race.race_logdet,
                    "predictor_spectral_radius": fit.spectral_radius,
                    "cpu_seconds": fit.cpu_seconds}
    return fit.K, kinfo


#: Label of the second start of :func:`pem_gain` (``K = 0``, the free-run simulation: the
#: label :func:`trussid.plid.metrics.best_predictor` gives that candidate).
ZERO_START = "none (free-run simulation)"


def reflected_note(count: int) -> str:
    return (f"{count} identified pole(s) lay outside the unit circle and were reflected in "
            "(stabilised, magnitude response kept): the data did not pin them down; check "
            "them in the modal table, or try another order")


def with_direct_term(model, u, y, use_d: bool, stable: bool, D0):
    """``(model, use_d, D standard errors)``: B and D refitted by output error when a direct
    term is wanted; an unstable model cannot be refitted, so it keeps the prior's ``D0``."""

    if not use_d:
        return model, False, None
    if stable:
        model, _, D_std = output_error_fit(model, u, y, direct=True)
        return model, True, D_std
    if D0 is not None:
        return control.ss(model.A, model.B, model.C, D0, model.dt), True, None
    return model, False, None


def count_unstable(model) -> int:
    A = np.asarray(model.A, float)
    return int(np.sum(np.abs(np.linalg.eigvals(A)) >= 1)) if A.size else 0



def reflect_unstable(model):
    """``model`` with any pole outside the unit circle reflected in (plid.stabilise)."""

    return stabilise(model).model

