"""Order-selection help: prediction error and frequency-response change against order.

For each candidate order the data are identified (by default with
:func:`trussid.plid.recipe.identify`; ``method="subspace"`` uses the quick N4SID prior alone)
and two numbers are tabulated:

- the one-step signal-to-prediction-error ratio [dB] on validation data (the last
  ``holdout`` fraction of the record when no separate validation data are given: the
  model is identified on the rest and its predictor runs through the whole record, scored
  on the tail only), see :func:`trussid.plid.metrics.prediction_ratio_db`;
- the frequency-response change from the previous order: RMS over the band and over
  every channel of ``20 log10 |H_n / H_prev|`` [dB].

The order the data support is where the prediction ratio stops rising and the change
drops to the noise level. :func:`trussid.plots.order_figure` draws both against order.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import numpy as np
from tqdm.auto import tqdm

from trussid.plid.canonical import check_order
from trussid.plid._validate import as_2d
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.frf import frequency_response
from trussid.plid.estimator import PLIDWarning
from trussid.plid.metrics import (default_noise_covariances, one_step_predict, prediction_burn_in,
                                  prediction_ratio_db, predictor_gain)
from trussid.plid.recipe import identify
from trussid.plid.subspace import subspace_prior

__all__ = ["OrderRow", "order_table", "format_table", "order_warnings"]

#: Validation prediction this far [dB] below the identification prediction is reported.
OVERFIT_GAP_DB = 6.0


@dataclass
class OrderRow:
    """One candidate order."""

    order: int
    prediction_db: float          # one-step signal-to-prediction-error, validation data
    frf_change_db: float | None   # RMS dB change from the previous order (None for the first)
    unstable_poles: int
    seconds: float
    model: object
    error: str = ""               # why this order gave no model (then prediction_db is nan)
    identification_db: float = float("nan")  # one-step ratio on the identification part


def _split(u, y, holdout):
    k = int(round(u.shape[0] * (1 - holdout)))
    if k < 10 or u.shape[0] - k < 10:
        raise DataError(f"holdout {holdout} leaves too few samples on one side")
    return u[:k], y[:k], u[k:], y[k:]


def order_table(u, y, orders, dt: float, u_val=None, y_val=None, holdout: float = 0.3,
                band=None, method: str = "plid", n_freq: int = 400,
                block_rows=None, progress: bool | None = None) -> list[OrderRow]:
    """Identify at each order and tabulate prediction error and FRF change.

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
        Identification data (all of it when ``u_val, y_val`` are given).
    orders : sequence of int
        Candidate orders (multiples of p), ascending.
    dt : float
        Sample time [s].
    u_val, y_val : arrays, optional
        Validation data; default the last ``holdout`` of the record.
    holdout : float
        Fraction of the record held out for validation when ``u_val, y_val`` are not given.
    band : (lo, hi) Hz, optional
        Band of the FRF change; default (1 %, 49 %) of fs.
    n_freq : int
        Frequencies of the FRF change in ``band``.
    method : {"plid", "subspace"}
        ``"plid"``: :func:`trussid.plid.recipe.identify` (subspace start); ``"subspace"``: the
        N4SID prior only (quicker).
    block_rows : int or list, optional
        N4SID block rows (default: :func:`trussid.plid.subspace.subspace_prior` tries several).
    progress : bool or None
        A tqdm bar over the orders (None: shown for more than one order; each is a full
        identification, seconds to minutes).
    """

    u = as_2d(u, "u")
    y = as_2d(y, "y")
    p = y.shape[1]
    if u_val is None:
        u_all, y_all = u, y
        u, y, u_val, y_val = _split(u, y, holdout)
        start = u.shape[0]
    else:
        u_all = y_all = None
        start = 0
        u_val = as_2d(u_val, "u_val")
        y_val = as_2d(y_val, "y_val")
    orders = sorted(int(n) for n in orders)
    for n in orders:
        check_order(n, p)
    fs = 1.0 / dt
    lo, hi = band if band is not None else (0.01 * fs, 0.49 * fs)
    f = np.linspace(lo, hi, n_freq)
    rows, H_prev = [], None
    show = progress if progress is not None else len(orders) > 1
    for n in tqdm(orders, disable=not show, unit="order", desc="order table"):
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            # A PLID pass that loses positive definiteness warns; the table lists its
            # model (unstable poles and all) rather than stopping.
            warnings.simplefilter("ignore", PLIDWarning)
            if method not in ("plid", "subspace"):
                raise DataError(f"method must be 'plid' or 'subspace', got {method!r}")
            try:
                if method == "plid":
                    ident = identify(u, y, n, dt, block_rows=block_rows, progress=False)
                    model, K = ident.model, ident.K
                else:
                    model, _ = subspace_prior(u, y, n, dt, block_rows=block_rows)
                    K = None
            except IdentificationError as exc:
                # one order that cannot be fitted must not cost the whole table
                rows.append(OrderRow(n, float("nan"), None, 0, time.perf_counter() - t0,
                                     None, str(exc)))
                continue
        sec = time.perf_counter() - t0
        if K is None:
            Qd, Rd = default_noise_covariances(model, u, y)
            K = predictor_gain(model, Qd, Rd)
        if u_all is not None:
            # Held-out tail: run the predictor through the whole record (it uses past data
            # only) so that the tail is not spoiled by a start from x0 = 0.
            yhat = one_step_predict(model, u_all, y_all, K=K)[start:]
            e = y_val - yhat
            pr = -10 * np.log10(np.mean(np.mean(e ** 2, 0) / np.mean(y_val ** 2, 0)))
        else:
            skip = prediction_burn_in(model, K, u_val.shape[0])
            pr = prediction_ratio_db(model, u_val, y_val, K=K, skip=skip).overall
        with np.errstate(all="ignore"):
            pid = prediction_ratio_db(model, u, y, K=K,
                                      skip=prediction_burn_in(model, K, u.shape[0])).overall
        H = frequency_response(model, f)
        change = None
        if H_prev is not None:
            change = float(np.sqrt(np.mean((20 * np.log10(np.abs(H) / np.abs(H_prev))) ** 2)))
        H_prev = H
        unstable = int(np.sum(np.abs(np.linalg.eigvals(np.asarray(model.A))) >= 1))
        rows.append(OrderRow(n, float(pr), change, unstable, sec, model,
                             identification_db=float(pid)))
    return rows


def order_warnings(rows, gap_db: float = OVERFIT_GAP_DB) -> list[str]:
    """What a user would be misled by in an :func:`order_table`, one sentence each.

    - The best validation prediction at the top of the scanned range: the data may support
      more states than were tried.
    - At the best order, the validation prediction more than ``gap_db`` below the
      identification prediction: the model fits the identification record's noise (or the
      record is not stationary), and its in-sample figures overstate it.
    """
    ok = [r for r in rows if not r.error and np.isfinite(r.prediction_db)]
    if not ok:
        return []
    best = max(ok, key=lambda r: r.prediction_db)
    out = []
    if len(ok) > 1 and best.order == max(r.order for r in ok):
        out.append(f"the best validation prediction is at the top of the scanned range "
                   f"(order {best.order}): the data may support more states; scan higher "
                   "orders before choosing")
    gap = best.identification_db - best.prediction_db
    if np.isfinite(gap) and gap > gap_db:
        out.append(f"at order {best.order} the validation prediction ({best.prediction_db:.1f} "
                   f"dB) is {gap:.1f} dB below the identification prediction "
                   f"({best.identification_db:.1f} dB): the model fits noise or the record is "
                   "not stationary; trust the validation figure, not the in-sample one")
    return out


def format_table(rows) -> str:
    """A plain-text table of :func:`order_table` rows."""
    out = ["order  prediction [dB]  FRF change [dB]  unstable  seconds"]
    for r in rows:
        if r.error:
            out.append(f"{r.order:5d}  failed: {r.error}")
            continue
        ch = "-" if r.frf_change_db is None else f"{r.frf_change_db:.3f}"
        out.append(f"{r.order:5d}  {r.prediction_db:15.2f}  {ch:>15s}  {r.unstable_poles:8d}"
                   f"  {r.seconds:7.1f}")
    return "\n".join(out)
