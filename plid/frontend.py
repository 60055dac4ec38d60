"""The one front end over the identification recipes, :func:`fit_model` (``trussid identify``,
the demo): :func:`trussid.plid.recipe.identify`, :func:`trussid.plid.reduced.identify_reduced`
or one plain :class:`trussid.plid.estimator.PLID` fit.
"""

from __future__ import annotations

import warnings

import numpy as np

from trussid.plid.errors import IdentificationError
from trussid.plid.estimator import PLID, PLIDWarning
from trussid.plid.metrics import predictor_gain
from trussid.plid.passes import PassRecord
from trussid.plid.provenance import Identification, Provenance
from trussid.plid.recipe import identify
from trussid.plid.reduced import identify_reduced

__all__ = ["fit_model", "RECIPES"]


RECIPES = ("plain", "subspace", "scratch")


def fit_model(u, y, order: int, dt: float, *, start: str = "subspace", via=None,
              form: str | None = None, R=None, Q: float = 0.0, passes: int = 1,
              block_rows=None, direct=None, progress: bool | None = None,
              log=None, closed_loop: bool = False, reference=None) -> Identification:
    """The one front end over the identification recipes (``trussid identify``, the demo).

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    order : int
    dt : float
        Sample time [s].
    start : {"subspace", "scratch", "plain"}
        ``"subspace"`` and ``"scratch"``: :func:`trussid.plid.recipe.identify` with that start; ``"plain"``: one
        :class:`trussid.plid.estimator.PLID` fit from scratch (``Q``, ``R``, ``passes``).
    via : sequence of int, optional
        Higher orders for :func:`trussid.plid.reduced.identify_reduced` (subspace or scratch start only).
    form : {"direct", "sqrt"}, optional
        Default ``"sqrt"`` for the plain fit (the class's default: it keeps the covariance
        positive definite on long records), ``"direct"`` for the recipes (measured faster
        at equal accuracy, ``benchmarks/results/plid_engine.md``).
    R : float or (p,), optional
        Output-noise variance (scaled units); default estimated by the recipes, 1e-4 plain.
    Q : float
        State-noise variance of the plain fit (scaled units).
    passes : int
        Passes of the plain fit.
    block_rows, progress, log
        As :func:`trussid.plid.reduced.identify_reduced` (``block_rows``: the recipes' N4SID prior).
    direct : {None, "auto", True, False}
        Direct term (:func:`trussid.plid.recipe.identify`); None: ``"auto"``. Not for the plain fit.
    closed_loop : bool
        A closed-loop record: :func:`trussid.plid.recipe.identify`'s closed-loop recipe
        (subspace start only, no ``via``).
    reference : array (N, m) or (N, 1), optional
        Reference (dither) channel(s): closed loop when they show feedback
        (:func:`trussid.plid.recipe.identify`).

    Returns
    -------
    Identification
        ``K`` is always set (the recipe's chosen gain, or the steady-state gain of the plain
        fit's noise model); ``provenance.K_source`` says where it came from,
        ``provenance.warnings`` lists the estimator's warnings.
    """

    if start not in RECIPES:
        raise IdentificationError(f"start must be one of {', '.join(RECIPES)}; got {start!r}")
    if via is not None and start == "plain":
        raise IdentificationError("via works with the subspace or scratch start, not plain")
    if direct is not None and start == "plain":
        raise IdentificationError("a direct term works with the subspace or scratch start, "
                                  "not plain")
    if (closed_loop or reference is not None) and (start != "subspace" or via is not None):
        raise IdentificationError("a closed-loop record is identified by its own recipe: "
                                  "use the subspace start and no via")
    form = form or ("sqrt" if start == "plain" else "direct")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PLIDWarning)
        if start == "plain":
            R = 1e-4 if R is None else R
            res = PLID(order, form=form, dt=dt, Q=Q, R=R, passes=passes,
                       progress=progress).fit(u, y)
            idn = Identification(res, res.model, res.K, "plain", res.basis,
                                 np.atleast_1d(np.asarray(R, float)), None,
                                 Provenance(passes=[PassRecord(k, form, Q) for k in range(passes)],
                                            K_source=res.K_source))
        elif via is not None:
            idn = identify_reduced(u, y, order, dt, via=via, start=start, form=form,
                                   block_rows=block_rows, progress=progress, log=log,
                                   direct="auto" if direct is None else direct)
            idn.provenance.K_source = (idn.provenance.predictor or {}).get("chosen")
        else:
            idn = identify(u, y, order, dt, start=start, R=R, form=form, block_rows=block_rows,
                           direct="auto" if direct is None else direct, progress=progress,
                           closed_loop=closed_loop, reference=reference)
            idn.provenance.K_source = (idn.provenance.predictor or {}).get("chosen")
    idn.provenance.warnings = [str(w.message) for w in caught
                               if issubclass(w.category, PLIDWarning)]
    if idn.result is not None and not idn.result.finite:
        raise IdentificationError(
            f"PLID ({form} form) diverged on {len(u)} samples: the estimate is not finite; "
            "try the sqrt form, a larger Q or R, or another order")
    if idn.K is None:
        res = idn.result
        B = np.asarray(idn.model.B)
        idn.K = predictor_gain(idn.model, res.Q + B @ res.N @ B.T, res.R)
        idn.provenance.K_source = "steady state of the estimator's noise model"
    return idn
