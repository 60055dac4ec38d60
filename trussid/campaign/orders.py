"""A model's order chosen from its identification record (issue 32): one-step prediction
on held-back data over a scanned range of orders.

Why held-back one-step prediction, and not the stabilisation diagram or a count of the
modes in the excited band: the model is used as a one-step predictor (the LQG's estimator
and the campaign's figure of merit), the structures this serves have more modes below
Nyquist than any affordable model holds, and the right order is then the one that
predicts best what it has not seen, not the number of physical modes (which would ask for
more states than the record supports) nor the orders at which poles stop moving (dense
clusters of member modes never stabilise). The data decide: an order whose extra states
only fit the noise of the first part of the record predicts the held-back part no better.

Each order of the range is fitted by N4SID (with a direct term when the plant has one) on
the first ``1 - held_back`` of the record; its predictor gain is chosen on the same part
(:func:`trussid.plid.metrics.choose_predictor`); it is scored by its one-step
signal-to-prediction-error ratio on the held-back rest (the predictor run through the whole
record, so that the held-back part does not start from an unknown state). The chosen order is the smallest
within ``tolerance_db`` of the best (fewer states: a cheaper identification, fewer
spurious modes for the controller), the runners-up the next best by the held-back score.
The scan stops when it has spent ``cpu_budget_s`` of CPU time (the orders not reached are
reported as not scanned).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from trussid.plid.metrics import choose_predictor, prediction_ratio_db
from trussid.plid.subspace import n4sid


@dataclass(frozen=True)
class OrderRow:
    """One scanned order: one-step ratios [dB] on the held-back part of the identification
    record and (shown only, never used to choose) on the validation record."""

    order: int
    held_back_db: float | None
    validation_db: float | None
    cpu_seconds: float
    note: str = ""


@dataclass(frozen=True)
class OrderChoice:
    """The order the data chose, the runners-up and the scan behind them."""

    chosen: int
    runners_up: tuple
    rows: tuple
    rule: str
    held_back_fraction: float
    block_rows: int
    cpu_seconds: float
    cpu_budget_s: float
    not_scanned: tuple = ()

    def lines(self) -> list:
        """The scan as report lines."""
        out = [f"order scan ({self.rule}; {self.cpu_seconds:.1f} s CPU of a "
               f"{self.cpu_budget_s:g} s budget):"]
        for r in self.rows:
            mark = " <- chosen" if r.order == self.chosen else ""
            hb = "-" if r.held_back_db is None else f"{r.held_back_db:.1f}"
            va = "-" if r.validation_db is None else f"{r.validation_db:.1f}"
            out.append(f"  {r.order:3d} states: held-back {hb} dB, validation {va} dB"
                       f"{' (' + r.note + ')' if r.note else ''}{mark}")
        if self.not_scanned:
            out.append(f"  not scanned (budget): {', '.join(map(str, self.not_scanned))}")
        if self.best_at_top():
            out.append("  the best held-back ratio is at the largest order scanned: a wider "
                       "range may predict better (the model is then limited by the range, "
                       "not by the data)")
        return out

    def best_at_top(self) -> bool:
        """The best held-back ratio came from the largest order that gave a model: the
        scan did not reach the order where more states stop predicting better."""
        scored = [r for r in self.rows if r.held_back_db is not None]
        if len(scored) < 2:
            return False
        best = max(scored, key=lambda r: r.held_back_db)
        return best.order == max(r.order for r in scored)


def scan_orders(u, y, dt: float, orders, *, direct: bool = True, block_rows: int = 40,
                held_back: float = 0.25, tolerance_db: float = 1.0,
                cpu_budget_s: float = 60.0, u_val=None, y_val=None) -> OrderChoice | None:
    """Choose a model order from the record ``(u, y)`` (module docstring).

    Parameters
    ----------
    u, y : (N, m), (N, p) float
        Identification record.
    dt : float
        Sample time [s].
    orders : sequence of int
        Orders scanned (ascending).
    direct : bool
        Fit a direct term (a plant with feed-through).
    block_rows : int
        N4SID block rows (raised to ``ceil(order / p) + 1`` where needed).
    held_back : float
        Fraction of the record at its end kept for scoring.
    tolerance_db : float
        The smallest order within this of the best held-back ratio is chosen [dB].
    cpu_budget_s : float
        CPU time after which no further order is fitted [s].
    u_val, y_val : array, optional
        A validation record: each scanned model's ratio on it is reported beside (not used).

    Returns
    -------
    OrderChoice or None
        None when no order gave a stable model.
    """
    t0 = time.process_time()
    u = np.asarray(u, dtype=float).reshape(len(u), -1)
    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    n_fit = int(round(len(u) * (1 - held_back)))
    p = y.shape[1]
    rows, not_scanned = [], []
    for n in orders:
        if time.process_time() - t0 > cpu_budget_s and rows:
            not_scanned.append(int(n))
            continue
        c0 = time.process_time()
        br = max(int(block_rows), -(-int(n) // p) + 1)
        try:
            fit = n4sid(u[:n_fit], y[:n_fit], int(n), br, dt)
        except (ValueError, np.linalg.LinAlgError) as exc:
            rows.append(OrderRow(int(n), None, None, time.process_time() - c0,
                                 f"N4SID failed: {exc}"))
            continue
        m = fit.with_d if direct else fit.zero_d
        if np.max(np.abs(np.linalg.eigvals(np.asarray(m.A))), initial=0) >= 1:
            rows.append(OrderRow(int(n), None, None, time.process_time() - c0, "unstable"))
            continue
        K, _, kinfo = choose_predictor(m, u[:n_fit], y[:n_fit])
        skip = int(kinfo.get("skip", 0))
        # the predictor runs over the whole record and only its errors on the held-back
        # part are scored: started afresh there, the transient of a 0.5 %-damped mode
        # (hundreds of samples) would decide the score, not the model
        hb = prediction_ratio_db(m, u, y, K=K, skip=max(n_fit, skip)).overall
        va = None
        if u_val is not None:
            va = prediction_ratio_db(m, u_val, y_val, K=K,
                                     skip=min(skip, len(u_val) - 1)).overall
        rows.append(OrderRow(int(n), float(hb), None if va is None else float(va),
                             time.process_time() - c0))
    scored = [r for r in rows if r.held_back_db is not None]
    if not scored:
        return None
    best = max(r.held_back_db for r in scored)
    chosen = min(r.order for r in scored if r.held_back_db >= best - tolerance_db)
    runners = tuple(r.order for r in sorted(scored, key=lambda r: -r.held_back_db)
                    if r.order != chosen)[:3]
    rule = (f"N4SID{' with D' if direct else ''} on the first {100 * (1 - held_back):.0f} % "
            f"of the identification record, one-step ratio on the last "
            f"{100 * held_back:.0f} % (the predictor run through the whole record); the smallest order within {tolerance_db:g} dB of the "
            f"best ({best:.1f} dB)")
    return OrderChoice(chosen, runners, tuple(rows), rule, held_back, int(block_rows),
                       time.process_time() - t0, cpu_budget_s, tuple(not_scanned))
