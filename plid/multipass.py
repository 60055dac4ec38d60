"""Multi-pass batch PLID and the complete identification recipe ``identify``.

A *pass* is one :class:`trussid.plid.estimator.PLID` run over the whole record. Later passes start
from the previous pass's model (converted exactly into the same basis) with a re-inflated
parameter covariance, and with their own state noise ``Q`` and parameter drift
``Q_theta``, so a schedule can shrink them pass by pass (``docs/plid.md``).

:func:`identify` is what ``trussid identify`` runs. Its two starts (measured in
``benchmarks/results/plid_thesis.md``):

- ``start="subspace"`` (default): a quick N4SID estimate with D = 0
  (:func:`trussid.plid.subspace.subspace_prior`) is the prior; the observer basis is a rotation
  basis at the prior's pole frequencies (:mod:`trussid.plid.bases`); one PLID pass with ``Q = 0``
  and a tight parameter prior refines it. At 42 states it beat the best N4SID by 2.7-4x
  in FRF error and 11-18 dB in simulation; at 24 states it won on simulation (+5 dB)
  but not on FRF dB error.
- ``start="scratch"``: no prior; a rotation basis at the prominent peaks of the output
  spectrum and four passes with shrinking ``Q`` and a tightening prior
  (:data:`SCRATCH_SCHEDULE`). It reached the subspace start's accuracy at 24 states and
  beat N4SID at 40 block rows at 42 states (60 dB), but failed at 30 dB.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import control
import numpy as np

from trussid.plid.bases import basis_for, data_frequencies, model_frequencies
from trussid.plid.canonical import ObserverBasis
from trussid.plid._validate import as_2d
from trussid.plid.errors import IdentificationError
from trussid.plid.estimator import PLID, PLIDResult, PLIDWarning

__all__ = ["Pass", "multipass", "identify", "identify_reduced", "fit_model", "default_via",
           "Identification", "Candidate", "RECIPES",
           "SCRATCH_SCHEDULE", "check_data"]


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

    Returns
    -------
    result : PLIDResult
        Of the last pass.
    history : list of dict
        Per pass: its settings, seconds, whether it stayed finite.
    """
    history = []
    res = None
    current = prior
    for k, ps in enumerate(schedule):
        t0 = time.perf_counter()
        est = PLID(order, form=form, dt=dt, Q=ps.Q, R=R, N=N, Q_theta=ps.Q_theta,
                   prior=current, prior_theta_var=ps.prior_theta_var, basis=basis,
                   history_every=history_every, progress=progress)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", PLIDWarning)
            r = est.fit(u, y)
        history.append({"pass": k, "Q": ps.Q, "Q_theta": ps.Q_theta,
                        "prior_theta_var": ps.prior_theta_var, "finite": r.finite,
                        "seconds": time.perf_counter() - t0})
        if not r.finite:
            break
        res = r
        current = r.model
    if res is None:
        raise IdentificationError("PLID diverged in its first pass (estimate not finite)")
    return res, history


@dataclass
class Identification:
    """What :func:`identify` produced."""

    result: PLIDResult
    model: control.StateSpace
    K: np.ndarray | None          # one-step predictor gain of ``model`` (original units)
    start: str
    basis: ObserverBasis
    R: np.ndarray
    prior: control.StateSpace | None
    info: dict = field(default_factory=dict)


def check_data(u, y, dt) -> tuple[np.ndarray, np.ndarray]:
    """``u, y`` as (N, m), (N, p) float arrays, checked as :meth:`PLID.fit` checks them.

    Raises :class:`trussid.plid.errors.DataError` naming the problem (a sampling interval
    that is not a positive number, a length mismatch, a non-finite value with its sample
    and column) before any library sees the data: numpy's concatenation error, nfoursid's
    "nulls" and a ZeroDivisionError leaked through before (newcomer audit A13, A14, A18).
    """
    from trussid.plid.errors import DataError

    try:
        dt_ok = float(dt) > 0 and np.isfinite(float(dt))
    except (TypeError, ValueError):
        dt_ok = False
    if not dt_ok:
        raise DataError(f"dt (the sampling interval) must be a positive number of seconds, "
                        f"got {dt!r}")
    u = as_2d(u, "u", finite=True)
    y = as_2d(y, "y", finite=True)
    if u.shape[0] != y.shape[0]:
        raise DataError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    return u, y


def _noise_estimate(model, u, y, floor=1e-10):
    """Output-noise variance per channel in scaled units: the simulation error of a prior
    model on the data (an over-estimate by the prior's own model error)."""
    from trussid.plid.experiment import simulate

    e = y - simulate(model, u)
    return np.maximum(np.mean(e ** 2, axis=0) / np.mean(y ** 2, axis=0), floor)


def identify(u, y, order: int, dt: float, *, start: str = "subspace", R=None,
             form: str = "direct", radius: float = 0.97, block_rows=None,
             schedule=None, prior_theta_var: float = 1e-4, Q: float = 0.0,
             progress: bool | None = None) -> Identification:
    """Identify an order-``order`` model: the recipe that won the benchmarks.

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    order : int
        A multiple of the number of outputs.
    dt : float
        Sample time [s].
    start : {"subspace", "scratch"}
        See the module docstring.
    R : float or (p,), optional
        Output-noise variance in scaled units; default estimated (subspace start: the
        prior's simulation error; scratch: 1e-4).
    form : {"direct", "sqrt"}
        PLID recursion.
    radius : float
        Radius of the rotation basis.
    block_rows : int or list, optional
        N4SID block rows (subspace start); default chosen by :func:`subspace_prior`.
    schedule : sequence of Pass, optional
        Scratch start passes (default :data:`SCRATCH_SCHEDULE`); for the subspace start
        the default is one pass ``Pass(Q, 0, prior_theta_var)``.
    prior_theta_var, Q : float
        Subspace start: the parameter prior variance and state noise of its pass.
    """
    u, y = check_data(u, y, dt)
    p = y.shape[1]
    fs = 1.0 / dt
    if order % p:
        from trussid.plid.canonical import check_order
        check_order(order, p)
    info = {}
    t0 = time.perf_counter()
    if start == "subspace":
        from trussid.plid.subspace import subspace_prior

        prior, pinfo = subspace_prior(u, y, order, dt, block_rows=block_rows)
        info["subspace"] = pinfo
        info["subspace_seconds"] = time.perf_counter() - t0
        freqs = model_frequencies(prior, order // 2, fs)
        basis = basis_for(order, p, fs, freqs, radius)
        if R is None:
            R = _noise_estimate(prior, u, y)
        sched = schedule or (Pass(Q, 0.0, prior_theta_var),)
    elif start == "scratch":
        prior = None
        freqs = data_frequencies(u, y, fs, order // 2)
        basis = basis_for(order, p, fs, freqs, radius)
        R = 1e-4 if R is None else R
        sched = schedule or SCRATCH_SCHEDULE
    else:
        raise IdentificationError(f"start must be 'subspace' or 'scratch', got {start!r}")
    res, hist = multipass(u, y, order, dt, sched, basis=basis, prior=prior, R=R, form=form,
                          progress=progress)
    info["passes"] = hist
    R = np.atleast_1d(np.asarray(R, float))
    K = _predictor(res, u, y, R)
    info["seconds"] = time.perf_counter() - t0
    return Identification(res, res.model, K, start, basis, R, prior, info)


def _predictor(res: PLIDResult, u, y, R):
    """One-step predictor gain of the identified model: the recursion's own gain is the
    steady state of ``Q = 0`` passes (no correction at all), so the predictor assumes a
    small state noise instead: 1 % input noise through ``B`` and the estimated ``R``."""
    from trussid.plid.errors import DataError
    from trussid.plid.metrics import default_noise_covariances, predictor_gain

    model = res.model
    Qd, _ = default_noise_covariances(model, u, y)
    sy2 = np.mean(y ** 2, axis=0)
    Rd = np.diag(np.broadcast_to(R, sy2.shape) * sy2)
    try:
        return predictor_gain(model, Qd, Rd)
    except DataError:  # no stabilising solution (e.g. an unstable mode): keep the recursion's
        return res.K


def _stable(model):
    """``model`` with any pole outside the unit circle reflected in (plid.stabilise)."""
    from trussid.plid.stability import stabilise

    return stabilise(model).model


def default_via(order: int, p: int) -> tuple:
    """Higher orders tried by :func:`identify_reduced`: 2 and 2.4 times ``order``, rounded
    up to multiples of the ``p`` outputs (30 -> 60, 72 for three outputs)."""
    return tuple(sorted({int(p * np.ceil(k * order / p)) for k in (2.0, 2.4)}))


def identify_reduced(u, y, order: int, dt: float, *, via=None, start: str = "subspace",
                     block_rows=None, form: str = "direct", prior_theta_var: float = 1e-4,
                     progress: bool | None = None, log=None) -> Identification:
    """Identify an under-modelling order-``order`` model through higher-order fits.

    When the structure has more significant states than ``order`` (the FE testbed's
    30-state SIMO models of a 141-state plant), an order-``order`` fit converges to one of
    many poor local compromises, where a higher-order model captures the dynamics and a
    reduction then chooses what to keep. The candidates, all of ``order`` states:

    1. :func:`identify` at ``order`` itself;
    2. for each order ``h`` in ``via``: :func:`identify` at ``h``, then balanced truncation
       weighted by the spectrum of the identification input
       (:func:`trussid.plid.reduce.balanced_truncation` with ``u``: a band-limited excitation
       leaves the higher-order fit with noise modes outside the band, which an unweighted
       truncation would keep) and ``B`` refitted by output error
       (:func:`trussid.plid.subspace.refit_input_matrix`);
    3. that reduced model refined by one PLID pass (``Q = 0``, the :func:`identify`
       refinement) in a rotation basis at its pole frequencies.

    Each stable candidate gets its one-step predictor (:func:`trussid.plid.metrics.choose_predictor`)
    and the one with the best one-step ratio on the *identification* record is returned
    (all candidates have the same number of parameters, so the in-sample ratio compares
    them fairly; no validation data is used). Measured in
    ``benchmarks/results/plid_thesis.md`` (acceptance 2).

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    order : int
        A multiple of the number of outputs.
    dt : float
        Sample time [s].
    via : sequence of int, optional
        Higher orders (multiples of p, > ``order``); default :func:`default_via`.
    start, block_rows, form, prior_theta_var, progress
        As :func:`identify`, for every fit.
    log : callable, optional
        Called with a one-line message as each fit finishes (a terminal progress report).

    Returns
    -------
    Identification
        Of the winner, ``K`` its chosen one-step predictor gain. ``result`` is the PLID
        pass that produced it (for a reduced model that was not refined: the pass at the
        higher order, with that pass's ``basis``, ``R`` and ``prior``).
        ``info["candidates"]`` lists every candidate (label, states, stable,
        identification one-step ratio [dB], seconds), ``info["chosen"]`` the winner's
        label and ``info["predictor"]`` how its predictor was chosen.
    """
    u, y = check_data(u, y, dt)
    p = y.shape[1]
    via = default_via(order, p) if via is None else tuple(int(h) for h in via)
    bad = [h for h in via if h <= order or h % p]
    if bad:
        raise IdentificationError(
            f"via orders must exceed order {order} and be multiples of the {p} outputs; "
            f"got {bad}")
    kw = dict(start=start, block_rows=block_rows, form=form,
              prior_theta_var=prior_theta_var, progress=progress)
    t_all = time.perf_counter()

    # One bar over the candidates (the PLID passes inside show their own when slow): the
    # whole search took 77 s silent in the API on a 6000-sample record (newcomer audit).
    from tqdm.auto import tqdm

    m = u.shape[1]
    show = (progress if progress is not None
            else u.shape[0] * float(max(via, default=order) * (m + p)) ** 2 > PLID.PROGRESS_WORK)
    bar = tqdm(total=1 + 2 * len(via), disable=not show, unit="candidate",
               desc=f"identify_reduced {order} via {','.join(map(str, via))}")

    def note(c: Candidate) -> Candidate:
        bar.update(1)
        if log is not None:
            log(f"{c.label}: {c.seconds:.1f} s" + (f" (failed: {c.error})" if c.error else ""))
        return c

    cands = [note(_direct_candidate(u, y, order, dt, kw))]
    for h in via:
        cands += [note(c) for c in _via_candidates(u, y, order, h, dt, kw, form, prior_theta_var,
                                                   progress)]
    bar.close()
    for c in cands:
        _score(c, u, y, order)
    best = _winner(cands)
    info = dict(best.idn.info)
    if best.passes is not None:
        info["passes"] = best.passes
    info.update({"candidates": [c.row(order) for c in cands], "chosen": best.label_shown,
                 "via": list(via), "predictor": best.kinfo,
                 "stabilised": {"applied": best.reflected_poles > 0,
                                "reflected_poles": best.reflected_poles},
                 "seconds": time.perf_counter() - t_all})
    K = best.K if best.K is not None else best.idn.K
    return Identification(best.result, best.model, K, best.idn.start, best.basis,
                          np.atleast_1d(np.asarray(best.R, float)), best.prior, info)


@dataclass
class Candidate:
    """One order-``order`` model competing in :func:`identify_reduced`.

    ``idn`` is the :func:`identify` run it came from (at ``order`` or at a higher order);
    ``result``, ``basis``, ``R`` and ``prior`` describe the PLID pass that produced
    ``model``. ``error`` is set (and ``model`` None) when the fit failed. Scoring fills
    ``stable``, ``reflected_poles`` (unstable poles reflected into the unit circle),
    ``K`` and ``kinfo`` (:func:`trussid.plid.metrics.choose_predictor`) and ``score``
    (one-step ratio on the identification record [dB]).
    """

    label: str
    model: control.StateSpace | None
    seconds: float
    idn: Identification | None = None
    result: PLIDResult | None = None
    basis: ObserverBasis | None = None
    R: np.ndarray | float | None = None
    prior: control.StateSpace | None = None
    passes: list | None = None
    error: str = ""
    stable: bool = False
    reflected_poles: int = 0
    K: np.ndarray | None = None
    kinfo: dict | None = None
    score: float | None = None

    @property
    def label_shown(self) -> str:
        return self.label + (", stabilised" if self.reflected_poles else "")

    def row(self, order: int) -> dict:
        row = {"label": self.label_shown, "states": order, "stable": self.stable,
               "identification_ratio_db": self.score, "seconds": self.seconds}
        if self.reflected_poles:
            row["reflected_poles"] = self.reflected_poles
        if self.error:
            row["error"] = self.error
        return row


def _direct_candidate(u, y, order, dt, kw) -> Candidate:
    t0 = time.perf_counter()
    try:
        base = identify(u, y, order, dt, **kw)
    except IdentificationError as exc:  # e.g. the direct form diverged: other candidates
        return Candidate(f"direct {order}", None, time.perf_counter() - t0, error=str(exc))
    return Candidate(f"direct {order}", base.model, time.perf_counter() - t0, base, base.result,
                     base.basis, base.R, base.prior)


def _via_candidates(u, y, order, h, dt, kw, form, prior_theta_var, progress) -> list:
    """The fit at order ``h`` reduced to ``order``, and that reduction refined by PLID."""
    from trussid.plid.reduce import balanced_truncation
    from trussid.plid.subspace import refit_input_matrix

    t0 = time.perf_counter()
    try:
        high = identify(u, y, h, dt, **kw)
        red = balanced_truncation(_stable(high.model), order, u=u).model
        # Weighted truncation does not guarantee stability (unlike the plain one), and
        # the output-error refit needs it.
        red = refit_input_matrix(_stable(red), u, y)
    except IdentificationError as exc:  # e.g. more unstable states than ``order``
        return [Candidate(f"via {h}", None, time.perf_counter() - t0, error=str(exc))]
    t_red = time.perf_counter() - t0
    # Its PLID pass is the one at order h: result, basis, R and prior are that pass's.
    reduced = Candidate(f"via {h}, reduced", red, t_red, high, high.result, high.basis, high.R,
                        high.prior)
    t1 = time.perf_counter()
    p = y.shape[1]
    basis = basis_for(order, p, 1.0 / dt, model_frequencies(red, order // 2, 1.0 / dt))
    R = _noise_estimate(red, u, y)
    try:
        res, hist = multipass(u, y, order, dt, (Pass(0.0, 0.0, prior_theta_var),),
                              basis=basis, prior=red, R=R, form=form, progress=progress)
    except IdentificationError as exc:
        return [reduced, Candidate(f"via {h}, refined", None, time.perf_counter() - t1,
                                   error=str(exc))]
    refined = Candidate(f"via {h}, refined", res.model, t_red + time.perf_counter() - t1, high,
                        res, basis, R, red, passes=hist)
    return [reduced, refined]


def _score(c: Candidate, u, y, order: int) -> None:
    """Stabilise ``c`` if needed and score its best one-step predictor on ``u, y``."""
    from trussid.plid.errors import DataError
    from trussid.plid.metrics import choose_predictor
    from trussid.plid.stability import stabilise

    if c.model is None:
        return
    if np.max(np.abs(np.linalg.eigvals(np.asarray(c.model.A))), initial=0) >= 1:
        # A lightly damped pole just outside the unit circle: the candidate competes
        # with its unstable poles reflected in (magnitude response kept).
        try:
            st = stabilise(c.model)
        except IdentificationError as exc:
            c.error = str(exc)
            return
        c.model, c.reflected_poles = st.model, int(np.size(st.reflected))
    c.stable = True
    own = {}
    if c.result is not None and c.result.model.nstates == order:
        own["estimator"] = c.result.K
    try:
        c.K, _, c.kinfo = choose_predictor(c.model, u, y, own)
    except DataError as exc:  # no stable one-step predictor: not a candidate
        c.error = str(exc)
        return
    c.score = float(c.kinfo["identification_ratio_db"][c.kinfo["chosen"]])


def _winner(cands: list) -> Candidate:
    scored = [c for c in cands if c.score is not None]
    if scored:
        return max(scored, key=lambda c: c.score)  # first of equals: the direct fit
    usable = [c for c in cands if c.model is not None]
    if not usable:
        raise IdentificationError(
            "every candidate failed: " + "; ".join(f"{c.label}: {c.error}" for c in cands))
    # No candidate with a stable predictor: return the first fit (the caller may stabilise it).
    return usable[0]


RECIPES = ("plain", "subspace", "scratch")


def fit_model(u, y, order: int, dt: float, *, start: str = "subspace", via=None,
              form: str | None = None, R=None, Q: float = 0.0, passes: int = 1,
              block_rows=None, progress: bool | None = None, log=None) -> Identification:
    """The one front end over the identification recipes (``trussid identify``, the demo).

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    order : int
    dt : float
        Sample time [s].
    start : {"subspace", "scratch", "plain"}
        ``"subspace"`` and ``"scratch"``: :func:`identify` with that start; ``"plain"``: one
        :class:`trussid.plid.estimator.PLID` fit from scratch (``Q``, ``R``, ``passes``).
    via : sequence of int, optional
        Higher orders for :func:`identify_reduced` (subspace or scratch start only).
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
        As :func:`identify_reduced` (``block_rows``: the recipes' N4SID prior).

    Returns
    -------
    Identification
        ``K`` is always set (the recipe's chosen gain, or the steady-state gain of the plain
        fit's noise model); ``info["K_source"]`` says where it came from,
        ``info["warnings"]`` lists the estimator's warnings.
    """
    from trussid.plid.metrics import predictor_gain

    if start not in RECIPES:
        raise IdentificationError(f"start must be one of {', '.join(RECIPES)}; got {start!r}")
    if via is not None and start == "plain":
        raise IdentificationError("via works with the subspace or scratch start, not plain")
    form = form or ("sqrt" if start == "plain" else "direct")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PLIDWarning)
        if start == "plain":
            R = 1e-4 if R is None else R
            res = PLID(order, form=form, dt=dt, Q=Q, R=R, passes=passes,
                       progress=progress).fit(u, y)
            idn = Identification(res, res.model, res.K, "plain", res.basis,
                                 np.atleast_1d(np.asarray(R, float)), None,
                                 {"passes": [{"Q": Q}] * passes, "K_source": res.K_source})
        elif via is not None:
            idn = identify_reduced(u, y, order, dt, via=via, start=start, form=form,
                                   block_rows=block_rows, progress=progress, log=log)
            idn.info["K_source"] = (idn.info.get("predictor") or {}).get("chosen")
        else:
            idn = identify(u, y, order, dt, start=start, R=R, form=form, block_rows=block_rows,
                           progress=progress)
            idn.info["K_source"] = idn.result.K_source
    idn.info["warnings"] = [str(w.message) for w in caught if issubclass(w.category, PLIDWarning)]
    if not idn.result.finite:
        raise IdentificationError(
            f"PLID ({form} form) diverged on {len(u)} samples: the estimate is not finite; "
            "try the sqrt form, a larger Q or R, or another order")
    if idn.K is None:
        res = idn.result
        B = np.asarray(idn.model.B)
        idn.K = predictor_gain(idn.model, res.Q + B @ res.N @ B.T, res.R)
        idn.info["K_source"] = "steady state of the estimator's noise model"
    return idn
