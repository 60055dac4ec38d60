"""Multi-pass batch PLID: the pass schedule (:class:`Pass`, :data:`SCRATCH_SCHEDULE`) and
:func:`multipass`, which runs it.

A *pass* is one :class:`trussid.plid.estimator.PLID` run over the whole record. Later passes start
from the previous pass's model (converted exactly into the same basis) with a re-inflated
parameter covariance, and with their own state noise ``Q`` and parameter drift
``Q_theta``, so a schedule can shrink them pass by pass (``docs/plid.md``). The recipes that
use it are :func:`trussid.plid.recipe.identify` and
:func:`trussid.plid.reduced.identify_reduced`.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, replace

import control

from trussid.plid.canonical import ObserverBasis
from trussid.plid.errors import IdentificationError
from trussid.plid.estimator import PLID, PLIDWarning

__all__ = ["Pass", "PassRecord", "SCRATCH_SCHEDULE", "multipass"]


@dataclass(frozen=True)
class Pass:
    """Settings of one pass (scaled units, see :class:`trussid.plid.estimator.PLID`)."""

    Q: float = 0.0
    Q_theta: float = 0.0
    prior_theta_var: float = 1e4


SCRATCH_SCHEDULE = (Pass(1e-6, 0.0, 1e4), Pass(1e-7, 0.0, 1e-2), Pass(1e-8, 0.0, 1e-3),
                    Pass(0.0, 0.0, 1e-4))


def multipass(u, y, order: int, dt: float, schedule, *, basis: ObserverBasis | None = None,
              prior: control.StateSpace | None = None, R=1e-4, N=0.0, form: str = "direct",
              progress: bool | None = False, history_every: int = 0):
    """Run the passes of ``schedule`` in turn.

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
        Data.
    order : int
    dt : float
        Sample time [s].
    schedule : sequence of Pass
    basis : ObserverBasis, optional
        Default the block shift.
    prior : control.StateSpace, optional
        Start of the first pass (else theta = 0).
    R, N : covariances (scaled units) for every pass.
    form : {"direct", "sqrt"}
    progress : bool or None
        A tqdm bar per pass (None: shown when the pass is slow).
    history_every : int
        Keep the parameter estimate every this many samples (0: none kept).

    Returns
    -------
    result : PLIDResult
        Of the last pass.
    history : list of PassRecord
        Per pass: its settings (with its form), seconds, whether it stayed finite. A first
        pass that diverged is restarted from the same prior in the square-root form, then
        also with a 100 times tighter parameter prior; each attempt has its record, the
        restarts with their ``restart`` reason.
    """
    history = []
    res = None
    current = prior
    for k, ps in enumerate(schedule):
        r, rec = _pass(u, y, order, dt, ps, k, current, basis, R, N, form, progress,
                       history_every)
        if not r.finite and k == 0:
            # Safeguard of the first pass (issue 34): the direct form can lose positive
            # definiteness and diverge (a measured drive record, "PLID diverged in its
            # first pass"); the square-root form cannot, and a tighter parameter prior
            # keeps the estimate near its start. Restart from the same prior, and say so.
            for retry_form, var, why in _RESTARTS:
                if form == "sqrt" and retry_form == "sqrt" and var == 1.0:
                    continue
                history.append(rec)
                ps2 = Pass(ps.Q, ps.Q_theta, ps.prior_theta_var * var)
                r, rec = _pass(u, y, order, dt, ps2, k, current, basis, R, N, retry_form,
                               progress, history_every)
                rec = replace(rec, restart=why)
                if r.finite:
                    break
        history.append(rec)
        if not r.finite:
            break
        res = r
        current = r.model
    if res is None:
        raise IdentificationError("PLID diverged in its first pass (estimate not finite), "
                                  "also when restarted from its prior in the square-root "
                                  "form with a tighter parameter prior")
    return res, history


#: Restarts of a first pass that diverged: (form, factor on prior_theta_var, reason).
_RESTARTS = (
    ("sqrt", 1.0, "the pass diverged (estimate not finite): restarted from the same prior "
                  "in the square-root form, which keeps the covariance positive definite"),
    ("sqrt", 1e-2, "the pass diverged again: restarted from the same prior in the "
                   "square-root form with a 100 times tighter parameter prior"),
)


@dataclass(frozen=True)
class PassRecord:
    """One PLID pass as it ran (:func:`multipass`).

    Attributes
    ----------
    index : int
        Its place in the schedule (0 first; a restarted first pass has several records).
    form : str
        The estimator's form (``"direct"`` or ``"sqrt"``).
    Q, Q_theta, prior_theta_var : float
        Its settings (:class:`Pass`).
    finite : bool
        Whether its estimate stayed finite.
    seconds : float or None
        Wall seconds it took (None: not timed).
    restart : str or None
        Why it is a restart of a first pass that diverged (None: it is not one).
    """

    index: int
    form: str
    Q: float
    Q_theta: float = 0.0
    prior_theta_var: float | None = None
    finite: bool = True
    seconds: float | None = None
    restart: str | None = None

    def json_form(self) -> dict:
        """The JSON record of the pass (``pass`` for ``index``; ``restart`` only when set)."""
        out = {"pass": self.index, "form": self.form, "Q": self.Q, "Q_theta": self.Q_theta,
               "prior_theta_var": self.prior_theta_var, "finite": self.finite,
               "seconds": self.seconds}
        if self.restart is not None:
            out["restart"] = self.restart
        return out


def _pass(u, y, order, dt, ps, k, current, basis, R, N, form, progress, history_every):
    """One PLID pass and its history record."""
    t0 = time.perf_counter()
    est = PLID(order, form=form, dt=dt, Q=ps.Q, R=R, N=N, Q_theta=ps.Q_theta,
               prior=current, prior_theta_var=ps.prior_theta_var, basis=basis,
               history_every=history_every, progress=progress)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PLIDWarning)
        r = est.fit(u, y)
    return r, PassRecord(k, form, ps.Q, ps.Q_theta, ps.prior_theta_var, bool(r.finite),
                         time.perf_counter() - t0)
