"""One model of the campaign identified from its record (:func:`identify_model`): the
project's reduced-order recipe, its winner made ready for the report by
:func:`trussid.plid.chosen.choose_model`, and the typed record of how it was made.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from trussid.campaign.summary import ModelIdentification
from trussid.plid.chosen import choose_model

__all__ = ["Identified", "identify_model"]


@dataclass
class Identified:
    """An identified model with what the report needs from the identification."""

    model: object                      # discrete control.StateSpace
    K: np.ndarray                      # one-step predictor gain used for prediction
    K_source: str
    seconds: float
    method: str
    innovations: np.ndarray            # (N, p) of the (last) PLID pass
    theta_history: np.ndarray          # (k, q)
    history_index: np.ndarray          # (k,)
    info: ModelIdentification
    modes: list = field(default_factory=list)  # plid.uncertainty.ModeInterval per mode


def identify_model(u, y, order: int, dt: float, *, block_rows=None, via=None,
                   progress: bool = False, log=None, direct=False) -> Identified:
    """Identify an order-``order`` model from one record: the one switchable call.

    Runs the project's identification recipe for under-modelled structures,
    :func:`trussid.plid.reduced.identify_reduced`: the PLID recipe
    :func:`trussid.plid.recipe.identify` (an N4SID prior in a rotation observer basis, refined
    by PLID; with ``direct``, when the data show a feed-through, N4SID's model with D:
    :mod:`trussid.plid.feedthrough`) at ``order`` and at the higher orders ``via``, the latter
    reduced to ``order`` by input-weighted balanced truncation and refined by PLID; the
    candidate with the best one-step prediction on the identification record wins, with its
    predictor gain (:func:`trussid.plid.metrics.choose_predictor`). Measured in
    ``benchmarks/results/plid_thesis.md``. :func:`trussid.plid.chosen.choose_model` makes the
    winner simulable and keeps the parameter history of the winning PLID pass for the
    convergence plot.
    """
    t0 = time.perf_counter()
    ch = choose_model(u, y, order, dt, block_rows=block_rows, via=via, progress=progress,
                      log=log, direct=direct)
    idn = ch.identification
    info = ModelIdentification(
        recipe="trussid.plid.multipass.identify_reduced", start=idn.start,
        basis=getattr(idn.basis, "name", ""), R=np.asarray(idn.R).tolist(),
        provenance=idn.provenance, stabilised=ch.stabilised, predictor=ch.predictor,
        chosen=ch.chosen)
    return Identified(ch.model, ch.K, ch.K_source, time.perf_counter() - t0, ch.method,
                      idn.result.innovations, ch.theta_history, ch.history_index, info,
                      ch.modes)
