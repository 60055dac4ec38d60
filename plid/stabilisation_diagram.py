"""The stabilisation diagram: models over a range of orders, each pole marked stable in
frequency, damping and mode shape against the model one order step below, as modal analysts
choose order and poles (the figure: :func:`trussid.plots.stabilisation_figure`)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import control
import numpy as np
from tqdm.auto import tqdm

from trussid.plid.data import ModeShapes
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.modal import mac, modal_table
from trussid.plid.recipe import identify as plid_identify
from trussid.plid.uncertainty import mode_intervals

__all__ = ["Stabilisation", "mark_stability", "stabilisation"]


@dataclass
class Stabilisation:
    """Poles of models over a range of orders, each marked against the order below.

    Attributes
    ----------
    orders : list of int
        Orders that gave a model.
    modes : list of ModeShapes
        Per order, its physical modes (0 < damping < 1, one per pair).
    status : list of ndarray of str
        Per order and mode: ``"new"`` (no pole near it at the order below), ``"f"``
        (frequency stable), ``"fd"`` (frequency and damping), ``"fv"`` (frequency and
        shape) or ``"s"`` (all three: stable).
    runs : list of ndarray of int
        Per order and mode: over how many consecutive order steps (ending here) the pole
        has been stable in all three (0 for any other status). Modal analysts trust a
        column of stable poles, not one stable step: a noise pole can match once.
    failed : list of (int, str)
        Orders that gave no model, with the reason.
    tolerances : dict
        ``f`` and ``damping`` (relative), ``mac`` (lowest MAC).
    models : list
        The identified models, by order.
    seconds : list of float
    frequency_std, damping_std : list of ndarray
        Per order and mode: the first-order standard deviation of its frequency [Hz] and
        damping ratio (:func:`trussid.plid.uncertainty.mode_intervals`, from the PLID pass's
        parameter covariance); NaN where there is none (an ``identify`` that returns a bare
        model, a reflected pole). The figure draws ``Z95`` times them as error bars.
    """

    orders: list
    modes: list
    status: list
    runs: list = field(default_factory=list)
    failed: list = field(default_factory=list)
    tolerances: dict = field(default_factory=dict)
    models: list = field(default_factory=list)
    seconds: list = field(default_factory=list)
    frequency_std: list = field(default_factory=list)
    damping_std: list = field(default_factory=list)

    def stable_poles(self, order: int | None = None, min_run: int = 1) -> ModeShapes:
        """The modes stable in all three at ``order`` (default: the highest order) over at
        least ``min_run`` consecutive order steps."""
        k = len(self.orders) - 1 if order is None else self.orders.index(order)
        return self.modes[k].select(self.runs[k] >= max(min_run, 1))


def mark_stability(prev: ModeShapes | None, cur: ModeShapes, tol_f: float, tol_zeta: float,
                   tol_mac: float, return_match: bool = False):
    """Status of each mode of ``cur`` against the nearest-frequency mode of ``prev``
    (and, with ``return_match``, the index of that mode, -1 where none is near)."""
    status = np.array(["new"] * cur.n_modes, dtype=object)
    match = np.full(cur.n_modes, -1)
    if prev is None or prev.n_modes == 0 or cur.n_modes == 0:
        return (status, match) if return_match else status
    macs = mac(cur.shapes, prev.shapes)
    for k in range(cur.n_modes):
        j = int(np.argmin(np.abs(prev.frequencies_hz - cur.frequencies_hz[k])))
        df = abs(cur.frequencies_hz[k] - prev.frequencies_hz[j]) / max(prev.frequencies_hz[j],
                                                                        1e-300)
        if df > tol_f:
            continue
        match[k] = j
        dz = abs(cur.damping[k] - prev.damping[j]) / max(prev.damping[j], 1e-300)
        d_ok, v_ok = dz <= tol_zeta, macs[k, j] >= tol_mac
        status[k] = "s" if d_ok and v_ok else "fd" if d_ok else "fv" if v_ok else "f"
    return (status, match) if return_match else status


def stabilisation(u, y, dt: float, orders, identify=None, tol_f: float = 0.01,
                  tol_zeta: float = 0.05, tol_mac: float = 0.98, progress=None,
                  input_names=None, output_names=None) -> Stabilisation:
    """Identify at each order and mark every pole stable in frequency, damping and shape.

    Parameters
    ----------
    u : ndarray, shape (N, m)
    y : ndarray, shape (N, p)
    dt : float
        Sampling interval [s].
    orders : sequence of int
        Model orders, ascending.
    identify : callable, optional
        ``identify(u, y, order, dt)`` returning a ``control.StateSpace``, or an
        :class:`~trussid.plid.provenance.Identification` (its ``.model``, and the modal
        intervals from its PLID pass); default PLID (:func:`trussid.plid.recipe.identify`).
    tol_f, tol_zeta : float
        Largest relative change of frequency and of damping from the nearest pole one
        order step below for the pole to count as stable in them (defaults 1 % and 5 %, the
        usual values of modal-analysis software).
    tol_mac : float
        Lowest MAC of the shape with that pole's (default 0.98).
    progress : bool or None
        tqdm bar over the orders (None: only on a terminal).
    input_names, output_names : list of str, optional
        Labels of the shapes and participation factors.

    Returns
    -------
    Stabilisation
        An order whose identification fails (:class:`IdentificationError` or
        :class:`DataError`) is listed in ``failed`` with the reason, and the next order is
        compared with the last one that worked.
    """
    if identify is None:
        def identify(u_, y_, n_, dt_):
            return plid_identify(u_, y_, n_, dt_, progress=False)

    orders = [int(n) for n in orders]
    if not orders or sorted(orders) != orders or orders[0] < 1:
        raise IdentificationError(f"stabilisation orders must be ascending positive "
                                  f"integers, got {orders}")
    res = Stabilisation(orders=[], modes=[], status=[],
                        tolerances={"f": tol_f, "damping": tol_zeta, "mac": tol_mac})
    prev = None
    bar = tqdm(orders, desc="stabilisation", unit="order", disable=progress is False
               if progress is not None else None, leave=False)
    for n in bar:
        t0 = time.perf_counter()
        try:
            got = identify(u, y, n, dt)
        except (IdentificationError, DataError) as exc:
            res.failed.append((n, str(exc)))
            continue
        model, intervals = _model_and_intervals(got)
        if output_names is not None or input_names is not None:
            model = control.ss(model.A, model.B, model.C, model.D, model.dt,
                               inputs=input_names, outputs=output_names)
        modes = modal_table(model, physical_only=True)
        res.orders.append(n)
        res.modes.append(modes)
        status, match = mark_stability(prev, modes, tol_f, tol_zeta, tol_mac, True)
        run_prev = res.runs[-1] if res.runs else np.zeros(0, int)
        res.status.append(status)
        res.runs.append(np.array([run_prev[j] + 1 if st == "s" else 0
                                  for st, j in zip(status, match)], dtype=int))
        res.models.append(model)
        fstd, zstd = _stds_of(modes, intervals)
        res.frequency_std.append(fstd)
        res.damping_std.append(zstd)
        res.seconds.append(time.perf_counter() - t0)
        prev = modes
    bar.close()
    if not res.orders:
        raise IdentificationError("no order gave a model: " + "; ".join(
            f"order {n}: {why}" for n, why in res.failed))
    return res


def _model_and_intervals(got):
    """The model an ``identify`` returned, and its modes' intervals when it returned an
    identification (a bare model has none)."""
    if isinstance(got, control.StateSpace):
        return got, []
    return got.model, mode_intervals(got.model, got.result.model, got.result.theta_cov)


def _stds_of(modes: ModeShapes, intervals) -> tuple[np.ndarray, np.ndarray]:
    """Standard deviations of each mode's frequency and damping, matched by frequency
    (the same poles: the modal table and the intervals read them from one model)."""
    fstd = np.full(modes.n_modes, np.nan)
    zstd = np.full(modes.n_modes, np.nan)
    if intervals:
        f_int = np.array([iv.frequency_hz for iv in intervals])
        for k, f in enumerate(modes.frequencies_hz):
            j = int(np.argmin(np.abs(f_int - f)))
            if abs(f_int[j] - f) <= 1e-6 * max(abs(f), 1e-12):
                fstd[k] = intervals[j].frequency_std_hz
                zstd[k] = intervals[j].damping_ratio_std
    return fstd, zstd
