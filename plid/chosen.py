"""The reduced-order recipe's winner made ready for a report: :func:`choose_model`.

:func:`trussid.plid.reduced.identify_reduced` returns the candidate with the best one-step
prediction on the identification record. A report (``trussid demo``) needs two things more,
each an identification step and so done here, not by the report:

- a model that can be simulated: when no candidate is stable (none was measured on the
  testbed), the poles outside the unit circle are reflected in
  (:func:`trussid.plid.stability.stabilise` keeps the magnitude response) and the predictor is
  chosen afresh;
- the parameter history of the winning PLID pass (for a convergence plot): when the recipe
  kept none, its last pass is run again with one (same basis, prior and settings, so the
  same estimate).

A direct term needs nothing here: :func:`trussid.plid.recipe.identify` starts from N4SID's own
model with ``D`` when the data show a feed-through (:mod:`trussid.plid.feedthrough`), so the
"N4SID with D" candidate this module once set against PLID's winner is gone (issue 34: on
three feed-through plants the prior with ``D`` predicts within 1 dB of N4SID-with-D,
``tests/plid/test_feedthrough.py``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import control
import numpy as np

from trussid.plid.estimator import PLID, PLIDWarning
from trussid.plid.frontend import fit_model
from trussid.plid.metrics import choose_predictor
from trussid.plid.passes import PassRecord
from trussid.plid.provenance import Identification, Stabilised
from trussid.plid.reduced import default_via
from trussid.plid.stability import stabilise
from trussid.plid.uncertainty import mode_intervals

__all__ = ["ChosenModel", "choose_model"]


@dataclass(frozen=True)
class ChosenModel:
    """What :func:`choose_model` returns.

    Attributes
    ----------
    identification : Identification
        The recipe's result (its ``model`` may differ from ``model`` below).
    model : control.StateSpace
        The model kept: stable (poles reflected in here when the recipe's winner was not).
    K : array (n, p)
        Its one-step predictor gain.
    K_source : str
        Where ``K`` came from.
    method : str
        One line on how ``model`` was identified.
    chosen : str
        The kept candidate's label.
    stabilised : Stabilised
        Whether poles were reflected in, by the recipe or here.
    predictor : dict
        How the recipe's predictor was chosen (:func:`trussid.plid.metrics.choose_predictor`),
        or how it was chosen afresh after stabilising here.
    theta_history : array (k, q)
        Parameter history of the winning PLID pass.
    history_index : array (k,)
        Sample index of each row of ``theta_history``.
    modes : list of trussid.plid.uncertainty.ModeInterval
        The 95 % intervals of ``model``'s modes.
    """

    identification: Identification
    model: control.StateSpace
    K: np.ndarray
    K_source: str
    method: str
    chosen: str
    stabilised: Stabilised
    predictor: dict
    theta_history: np.ndarray
    history_index: np.ndarray
    modes: list


def choose_model(u, y, order: int, dt: float, *, block_rows=None, via=None,
                 progress: bool = False, log=None, direct=False) -> ChosenModel:
    """Identify an order-``order`` model by :func:`trussid.plid.reduced.identify_reduced` and
    make it ready for a report (module docstring).

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
        The identification record.
    order : int
        States of the model.
    dt : float
        Sample time [s].
    block_rows : sequence of int, optional
        Block rows of the N4SID prior (default chosen by the recipe).
    via : sequence of int, optional
        Higher orders reduced to ``order``; default
        :func:`trussid.plid.reduced.default_via`.
    progress : bool
        Progress bars of the PLID passes.
    log : callable, optional
        Called with one line per candidate.
    direct : {False, True, "auto"}
        Direct term of the recipe (:func:`trussid.plid.recipe.identify`: with one, its prior
        is N4SID's model with D).

    Returns
    -------
    ChosenModel
    """
    with warnings.catch_warnings():
        # The candidates' PLID passes warn when a pass loses positive definiteness; the
        # recipe handles that (a failed candidate is dropped) and its provenance lists them.
        warnings.simplefilter("ignore", PLIDWarning)
        p = np.asarray(y).reshape(len(y), -1).shape[1]
        idn = fit_model(u, y, order, dt, start="subspace",
                        via=default_via(order, p) if via is None else via, progress=progress,
                        log=log, block_rows=None if block_rows is None else list(block_rows),
                        direct=direct)
    res, model, prov = idn.result, idn.model, idn.provenance
    chosen = prov.chosen or ""
    stab = prov.stabilised or Stabilised()
    if np.max(np.abs(np.linalg.eigvals(np.asarray(model.A)))) >= 1:
        st = stabilise(model)
        model = st.model
        stab = Stabilised(bool(st.applied), int(np.size(st.reflected)))
        K, K_source, kinfo = choose_predictor(model, u, y)
    else:
        K, kinfo = idn.K, prov.predictor or {}
        K_source = kinfo.get("chosen", "")
    method = f"PLID ({res.form} form, {idn.start} start; {chosen})"
    hist, hidx = res.theta_history, res.history_index
    if hist.shape[0] < 2 and idn.prior is not None:
        hist, hidx = _history_of_last_pass(idn, u, y, res.model.nstates, dt)
    return ChosenModel(idn, model, K, K_source, method, chosen, stab, kinfo, hist, hidx,
                       mode_intervals(model, res.model, res.theta_cov))


def _history_of_last_pass(idn: Identification, u, y, order, dt):
    passes = idn.provenance.passes
    last = passes[-1] if passes else PassRecord(0, idn.result.form, 0.0)
    est = PLID(order, form=idn.result.form, dt=dt, Q=last.Q, R=idn.R, Q_theta=last.Q_theta,
               prior=idn.prior,
               prior_theta_var=1e-4 if last.prior_theta_var is None else last.prior_theta_var,
               basis=idn.basis, history_every=10, progress=False)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PLIDWarning)  # as in choose_model
        r = est.fit(u, y)
    return r.theta_history, r.history_index
