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
from dataclasses import dataclass, field, fields, replace

import control
import numpy as np
from tqdm.auto import tqdm

from trussid.plid.bases import basis_for, data_frequencies, model_frequencies
from trussid.plid.canonical import ObserverBasis
from trussid.plid._validate import as_2d
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.estimator import PLID, PLIDResult, PLIDWarning
from trussid.plid.experiment import simulate
from trussid.plid.metrics import (best_predictor, choose_predictor, default_noise_covariances,
                                  predictor_gain)
from trussid.plid.pem import refine_gain
from trussid.plid.reduce import balanced_truncation
from trussid.plid.stability import stabilise
from trussid.plid.subspace import (SubspaceChoice, direct_term_test, output_error_fit,
                                   subspace_prior)

__all__ = ["Pass", "multipass", "identify", "identify_reduced", "fit_model", "default_via",
           "Identification", "Provenance", "Stabilised", "DirectTerm", "Candidate", "RECIPES",
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
class Stabilised:
    """Whether poles outside the unit circle were reflected in (:func:`trussid.plid.stabilise`)."""

    applied: bool = False
    reflected_poles: int = 0


@dataclass
class DirectTerm:
    """How the direct term D was decided, and its estimate.

    Attributes
    ----------
    mode : {"auto", True, False}
        What was asked for.
    estimated : bool
        Whether D was estimated (else D = 0, or the prior's D).
    test : dict or None
        The held-out evidence of :func:`trussid.plid.subspace.direct_term_test`
        (``held_out_nmse_without``, ``held_out_nmse_with``, ``margin``, ``folds``).
    D, D_std : list of lists
        The direct term (p x m) and its standard errors (None when not estimated).
    """

    mode: object
    estimated: bool
    test: dict | None
    D: list
    D_std: list | None


@dataclass
class Provenance:
    """How an identification was made: what the recipe ran, tried, chose and measured.

    Every field is None (or empty) when the recipe that made the model has no such step;
    :meth:`as_dict` keeps the steps that ran, for a JSON record.

    Attributes
    ----------
    subspace : SubspaceChoice or None
        The N4SID prior's choice of block rows (:func:`trussid.plid.subspace.subspace_prior`).
    subspace_seconds, recursion_seconds, recursion_cpu_seconds, seconds : float or None
        Wall seconds of the prior, wall and CPU seconds of the PLID recursion alone (the
        CPU figure stays meaningful on a loaded machine), wall seconds of the whole fit.
    passes : list of dict
        The PLID passes run (``Q``, ``Q_theta``, ``prior_theta_var``, ...).
    stabilised : Stabilised or None
    direct : DirectTerm or None
    predictor : dict or None
        How the one-step predictor gain was chosen
        (:func:`trussid.plid.metrics.best_predictor`: ``chosen``, ``identification_ratio_db``,
        ``skip``, ...).
    structure : str or None
        An order that is not a multiple of the outputs: how the model was reduced to it.
    candidates, chosen, via : list, str, list or None
        :func:`identify_reduced`: every candidate's row, the winner's label, the via orders.
    K_source : str or None
        Where the returned predictor gain came from (:func:`fit_model`).
    warnings : list of str
        The estimator's warnings (:func:`fit_model`).
    """

    subspace: SubspaceChoice | None = None
    subspace_seconds: float | None = None
    passes: list = field(default_factory=list)
    recursion_seconds: float | None = None
    recursion_cpu_seconds: float | None = None
    stabilised: Stabilised | None = None
    direct: DirectTerm | None = None
    predictor: dict | None = None
    seconds: float | None = None
    structure: str | None = None
    candidates: list | None = None
    chosen: str | None = None
    via: list | None = None
    K_source: str | None = None
    warnings: list = field(default_factory=list)

    def as_dict(self) -> dict:
        """The fields that are set (not None), in declaration order, nested dataclasses as
        they are (:func:`trussid._util.jsonio.json_safe` turns them into dicts)."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if getattr(self, f.name) is not None}


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
    provenance: Provenance = field(default_factory=Provenance)


def check_data(u, y, dt) -> tuple[np.ndarray, np.ndarray]:
    """``u, y`` as (N, m), (N, p) float arrays, checked as :meth:`PLID.fit` checks them.

    Raises :class:`trussid.plid.errors.DataError` naming the problem (a sampling interval
    that is not a positive number, a length mismatch, a non-finite value with its sample
    and column) before any library sees the data: numpy's concatenation error, nfoursid's
    "nulls" and a ZeroDivisionError leaked through before (newcomer audit A13, A14, A18).
    """

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

    e = y - simulate(model, u)
    return np.maximum(np.mean(e ** 2, axis=0) / np.mean(y ** 2, axis=0), floor)


def identify(u, y, order: int, dt: float, *, start: str = "subspace", R=None,
             form: str = "direct", radius: float = 0.97, block_rows=None,
             schedule=None, prior_theta_var: float = 1e-4, Q: float = 0.0,
             direct="auto", stabilise: bool = True, predictor: str = "pem",
             progress: bool | None = None) -> Identification:
    """Identify an order-``order`` model: the recipe that won the benchmarks.

    Parameters
    ----------
    u, y : arrays (N, m), (N, p)
    order : int
        Any order from 1 up. A multiple of the number of outputs ``p`` is identified
        directly (PLID's observer form gives every output ``order / p`` states); any
        other order is identified at the next multiple of ``p`` (at least ``p``) and
        reduced to ``order`` states by input-weighted balanced truncation, ``B`` (and
        ``D``) refitted by output error (``provenance.structure`` says so).
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
    direct : {"auto", True, False}
        Estimate a direct term ``D``. ``"auto"`` (default) decides on the identification
        data (:func:`trussid.plid.subspace.direct_term_test`: held-out output error with
        and without ``D``, ``A, C`` of the subspace prior fixed); a strictly proper plant
        (e.g. seen through anti-aliasing filters) gets ``D = 0``, an accelerometer
        driven by a force input typically not. With ``D``, PLID runs on ``y - D0 u``
        (``D0`` from the prior, which makes the data strictly proper, so the recursion is
        unchanged) and ``B, D`` are then refitted by output error with PLID's ``A, C``.
        ``provenance.direct`` records the choice and the evidence.
    stabilise : bool
        Reflect any pole outside the unit circle into it (:mod:`trussid.plid.stability`;
        ``provenance.stabilised`` says whether and how many).
    predictor : {"pem", "candidates"}
        How the one-step predictor gain ``K`` is found. ``"candidates"``: the candidate
        with the best one-step prediction of the identification data
        (:func:`trussid.plid.metrics.best_predictor`: ``K = 0``, i.e. free-run simulation,
        the recursion's own gain and steady-state Kalman gains). ``"pem"`` (default): that
        candidate refined by prediction error with ``A, B, C, D`` fixed and the predictor
        kept stable (:func:`trussid.plid.pem.refine_gain`); the plant and its simulation
        fit are unchanged.

    Returns
    -------
    Identification
        ``K`` the predictor gain; ``provenance.predictor`` lists the candidates with their
        scores and, for ``"pem"``, the refinement (``provenance.predictor["pem"]``).

    Examples
    --------
    Two modes, 50 and 120 Hz at 2 % damping, sampled at 1 kHz: PLID recovers them from 2000
    samples of white-noise response.

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import excitation, identify, modal_table, simulate
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.04 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> plant = control.c2d(control.ss(G), 1e-3)
    >>> u = excitation("white", 2000, fs=1000.0, seed=1)
    >>> y = simulate(plant, u)
    >>> fit = identify(u, y, order=4, dt=1e-3, progress=False)
    >>> modes = modal_table(fit.model)
    >>> print(np.round(modes.frequencies_hz, 2), np.round(100 * modes.damping, 2))
    [ 50. 120.] [2. 2.]
    """
    u, y = check_data(u, y, dt)
    p = y.shape[1]
    fs = 1.0 / dt
    if direct not in ("auto", True, False):
        raise IdentificationError(f"direct must be 'auto', True or False, got {direct!r}")
    if int(order) != order or order < 1:
        raise IdentificationError(f"order must be a positive integer, got {order!r}")
    _check_predictor(predictor)
    kw = dict(start=start, R=R, form=form, radius=radius, block_rows=block_rows,
              schedule=schedule, prior_theta_var=prior_theta_var, Q=Q, direct=direct,
              stabilise=stabilise, predictor=predictor, progress=progress)
    if order % p:
        return _identify_by_reduction(u, y, int(order), dt, kw)

    prov = Provenance()
    t0 = time.perf_counter()
    use_d, test, D0 = direct is True, None, None
    y_fit = y
    if start == "subspace":
        prior, pinfo = subspace_prior(u, y, order, dt, block_rows=block_rows)
        prov.subspace = pinfo
        prov.subspace_seconds = time.perf_counter() - t0
        if direct == "auto":
            test = direct_term_test(prior, u, y)
            use_d = test["direct"]
        if use_d:
            # D0 u is taken off the outputs: PLID then sees strictly proper data
            with_d, _, _ = output_error_fit(prior, u, y, direct=True)
            D0 = np.asarray(with_d.D, float)
            y_fit = y - u @ D0.T
            prior = control.ss(with_d.A, with_d.B, with_d.C, np.zeros_like(D0), dt)
        freqs = model_frequencies(prior, order // 2, fs)
        basis = basis_for(order, p, fs, freqs, radius)
        if R is None:
            R = _noise_estimate(prior, u, y_fit)
        sched = schedule or (Pass(Q, 0.0, prior_theta_var),)
    elif start == "scratch":
        prior = None
        freqs = data_frequencies(u, y, fs, order // 2)
        basis = basis_for(order, p, fs, freqs, radius)
        R = 1e-4 if R is None else R
        sched = schedule or SCRATCH_SCHEDULE
    else:
        raise IdentificationError(f"start must be 'subspace' or 'scratch', got {start!r}")
    t1, c1 = time.perf_counter(), time.process_time()
    res, hist = multipass(u, y_fit, order, dt, sched, basis=basis, prior=prior, R=R, form=form,
                          progress=progress)
    prov.passes = hist
    # wall and CPU seconds of the PLID recursion alone (the CPU figure is the one that
    # stays meaningful on a shared, loaded machine)
    prov.recursion_seconds = time.perf_counter() - t1
    prov.recursion_cpu_seconds = time.process_time() - c1
    R = np.atleast_1d(np.asarray(R, float))
    model, n_unstable = res.model, _count_unstable(res.model)
    if stabilise and n_unstable:
        model = _stable(model)
    prov.stabilised = Stabilised(bool(stabilise and n_unstable), n_unstable if stabilise else 0)
    if stabilise and n_unstable:
        warnings.warn(PLIDWarning(_reflected_note(n_unstable)), stacklevel=2)
    stable = _count_unstable(model) == 0
    if start == "scratch" and direct == "auto" and stable:
        test = direct_term_test(model, u, y)
        use_d = test["direct"]
    model, use_d, D_std = _with_direct_term(model, u, y, use_d, stable, D0)
    prov.direct = _direct_info(direct, use_d, test, model, D_std)
    K, prov.predictor = _best_gain(model, u, y, R, {"estimator": res.K})
    if predictor == "pem":
        K, prov.predictor = _pem_gain(model, u, y, K, prov.predictor)
    prov.seconds = time.perf_counter() - t0
    return Identification(res, model, K, start, basis, R, prior, prov)


#: How :func:`identify` finds the one-step predictor gain (its ``predictor`` argument).
PREDICTORS = ("pem", "candidates")


def _check_predictor(predictor) -> None:
    if predictor not in PREDICTORS:
        raise IdentificationError(f"predictor must be one of {', '.join(PREDICTORS)}, "
                                  f"got {predictor!r}")


def _pem_gain(model, u, y, K, kinfo):
    """``K`` refined by prediction error (:func:`trussid.plid.pem.refine_gain`) from the
    chosen candidate; the candidate itself when the model or its predictor is unstable.

    Measured on the four measured sets of ``benchmarks/bench_realdata.py`` (validation
    one-step fit, candidates -> refined): subframe 96.9 -> 97.8 %, robot arm 98.3 -> 99.2,
    flutter 71.1 -> 99.2, CD arm 80.3 -> 90.9, for 0.04-0.5 CPU s.
    """
    if K is None or _count_unstable(model):
        return K, kinfo
    try:
        fit = refine_gain(model, u, y, K)
    except (DataError, np.linalg.LinAlgError) as exc:
        return K, dict(kinfo, pem={"error": str(exc)})
    kinfo = dict(kinfo)
    start = kinfo.get("chosen")
    kinfo["chosen"] = f"prediction error ({fit.iterations} iterations from {start})"
    kinfo["pem"] = {"start": start, "iterations": fit.iterations, "converged": fit.converged,
                    "logdet_start": fit.logdet_start, "logdet_end": fit.logdet_end,
                    "predictor_spectral_radius": fit.spectral_radius,
                    "cpu_seconds": fit.cpu_seconds}
    return fit.K, kinfo


def _reflected_note(count: int) -> str:
    return (f"{count} identified pole(s) lay outside the unit circle and were reflected in "
            "(stabilised, magnitude response kept): the data did not pin them down; check "
            "them in the modal table, or try another order")


def _with_direct_term(model, u, y, use_d: bool, stable: bool, D0):
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


def _count_unstable(model) -> int:
    A = np.asarray(model.A, float)
    return int(np.sum(np.abs(np.linalg.eigvals(A)) >= 1)) if A.size else 0


def _direct_info(mode, used, test, model, D_std) -> DirectTerm:
    return DirectTerm(mode=mode, estimated=bool(used),
                      test=None if test is None else {
                          "held_out_nmse_without": test["held_out_nmse"]["without"],
                          "held_out_nmse_with": test["held_out_nmse"]["with"],
                          "margin": test["margin"], "folds": test["folds"]},
                      D=np.asarray(model.D, float).tolist(),
                      D_std=None if D_std is None else np.asarray(D_std).tolist())


def _best_gain(model, u, y, R, own):
    """:func:`trussid.plid.metrics.best_predictor` with the recursion's gain and the former
    default (1 % input noise and the estimated ``R``) among the candidates; the former
    default alone when no predictor of the model is stable."""

    cands = dict(own)
    cands["kalman, 1 % input noise and estimated R"] = _default_gain(model, u, y, R)
    try:
        # refine=False: the least-squares refinement of K (refine_predictor_gain) was
        # measured on the four measured sets of benchmarks/bench_realdata.py and gained
        # under 0.01 dB of identification one-step ratio over the best of these
        # candidates, at a quarter of the fit's time on the subframe set
        K, _, kinfo = best_predictor(model, u, y, cands, refine=False)
    except DataError as exc:
        return cands["kalman, 1 % input noise and estimated R"], {"chosen": None,
                                                                  "error": str(exc)}
    return K, kinfo


def _identify_by_reduction(u, y, order, dt, kw):
    """An order that is not a multiple of the outputs: identify at the next multiple (at
    least ``p``), reduce by input-weighted balanced truncation, refit ``B`` (and ``D``)."""

    p = y.shape[1]
    t0 = time.perf_counter()
    hi = max(p, -(-order // p) * p)
    # the higher-order model's own predictor is not used: only the reduced one gets one
    high = identify(u, y, hi, dt, **dict(kw, predictor="candidates"))
    try:
        base = _stable(high.model)
        try:
            red = balanced_truncation(base, order, u=u).model
        except IdentificationError:
            # the input-weighted Gramian can leave states at round-off level (an input
            # that does not excite them); the plain balanced truncation then still works
            red = balanced_truncation(base, order).model
        red = _stable(red)
        use_d = high.provenance.direct.estimated
        red, _, D_std = output_error_fit(red, u, y, direct=use_d)
    except (IdentificationError, np.linalg.LinAlgError) as exc:
        raise IdentificationError(
            f"order {order} is not a multiple of the {p} outputs, and reducing the "
            f"order-{hi} model to it failed ({exc}); try order {hi}") from None
    prov = replace(high.provenance)
    prov.structure = (f"identified at order {hi} (PLID's observer form needs a multiple "
                      f"of the {p} outputs) and reduced to {order} states by "
                      "input-weighted balanced truncation, B and D refitted by output error")
    prov.direct = _direct_info(kw["direct"], use_d, None, red, D_std)
    prov.direct.test = high.provenance.direct.test
    K, prov.predictor = _best_gain(red, u, y, high.R, {})
    if kw["predictor"] == "pem":
        K, prov.predictor = _pem_gain(red, u, y, K, prov.predictor)
    prov.seconds = time.perf_counter() - t0
    return Identification(high.result, red, K, high.start, high.basis, high.R, high.prior, prov)


def _default_gain(model, u, y, R):
    """The former default predictor gain: a steady-state Kalman gain with 1 % input noise
    through ``B`` and the estimated output noise ``R`` (None without a solution)."""

    Qd, _ = default_noise_covariances(model, u, y)
    sy2 = np.mean(y ** 2, axis=0)
    Rd = np.diag(np.broadcast_to(R, sy2.shape) * sy2)
    try:
        return predictor_gain(model, Qd, Rd)
    except Exception:  # noqa: BLE001 - no stabilising solution (e.g. an unstable mode)
        return None


def _stable(model):
    """``model`` with any pole outside the unit circle reflected in (plid.stabilise)."""

    return stabilise(model).model


def default_via(order: int, p: int) -> tuple:
    """Higher orders tried by :func:`identify_reduced`: 2 and 2.4 times ``order``, rounded
    up to multiples of the ``p`` outputs (30 -> 60, 72 for three outputs)."""
    return tuple(sorted({int(p * np.ceil(k * order / p)) for k in (2.0, 2.4)}))


def identify_reduced(u, y, order: int, dt: float, *, via=None, start: str = "subspace",
                     block_rows=None, form: str = "direct", prior_theta_var: float = 1e-4,
                     direct="auto", progress: bool | None = None,
                     log=None) -> Identification:
    """Identify an under-modelling order-``order`` model through higher-order fits.

    When the structure has more significant states than ``order`` (the FE testbed's
    30-state SIMO models of a 141-state plant), an order-``order`` fit converges to one of
    many poor local compromises, where a higher-order model captures the dynamics and a
    reduction then chooses what to keep. The candidates, all of ``order`` states:

    1. :func:`identify` at ``order`` itself (the direct fit);
    2. for each order ``h`` in ``via``: :func:`identify` at ``h``, then balanced truncation
       weighted by the spectrum of the identification input
       (:func:`trussid.plid.reduce.balanced_truncation` with ``u``: a band-limited excitation
       leaves the higher-order fit with noise modes outside the band, which an unweighted
       truncation would keep), ``B`` (and ``D`` where the fit at ``h`` found a direct
       term) refitted by output error, refined by one PLID pass (``Q = 0``, the
       :func:`identify` refinement) in a rotation basis at its pole frequencies. The
       unrefined reduction does not compete (it won on one-step prediction while
       simulating far worse than the direct fit).

    Each stable candidate gets its one-step predictor (:func:`trussid.plid.metrics.choose_predictor`);
    among the candidates that simulate the identification record at least as well as the
    direct fit (within 0.1 dB), the one with the best one-step ratio on the
    *identification* record is returned, its gain then refined by prediction error
    (:func:`trussid.plid.pem.refine_gain`)
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
    direct : {"auto", True, False}
        As :func:`identify`, for every fit (default ``"auto"``: decided on the data by
        each fit's held-out test; the FE testbed seen through its filters gets none).
    log : callable, optional
        Called with a one-line message as each fit finishes (a terminal progress report).

    Returns
    -------
    Identification
        Of the winner, ``K`` its chosen one-step predictor gain. ``result`` is the PLID
        pass that produced it (for a reduced model that was not refined: the pass at the
        higher order, with that pass's ``basis``, ``R`` and ``prior``).
        ``provenance.candidates`` lists every candidate (label, states, stable,
        identification one-step ratio [dB], seconds), ``provenance.chosen`` the winner's
        label and ``provenance.predictor`` how its predictor was chosen.
    """
    u, y = check_data(u, y, dt)
    p = y.shape[1]
    via = default_via(order, p) if via is None else tuple(int(h) for h in via)
    bad = [h for h in via if h <= order or h % p]
    if bad:
        raise IdentificationError(
            f"via orders must exceed order {order} and be multiples of the {p} outputs; "
            f"got {bad}")
    # Candidates are compared as identified (this function stabilises them itself); the
    # reductions and their output-error refits are strictly proper unless ``direct``.
    kw = dict(start=start, block_rows=block_rows, form=form,
              prior_theta_var=prior_theta_var, progress=progress, direct=direct,
              stabilise=False, predictor="candidates")
    t_all = time.perf_counter()

    # One bar over the candidates (the PLID passes inside show their own when slow): the
    # whole search took 77 s silent in the API on a 6000-sample record (newcomer audit).
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
    prov = replace(best.idn.provenance)
    if best.passes is not None:
        prov.passes = best.passes
    prov.candidates = [c.row(order) for c in cands]
    prov.chosen = best.label_shown
    prov.via = list(via)
    prov.predictor = best.kinfo
    prov.stabilised = Stabilised(best.reflected_poles > 0, best.reflected_poles)
    prov.seconds = time.perf_counter() - t_all
    K = best.K if best.K is not None else best.idn.K
    if best.reflected_poles:
        warnings.warn(PLIDWarning(_reflected_note(best.reflected_poles)), stacklevel=2)
    if best.stable:
        K, prov.predictor = _pem_gain(best.model, u, y, K, prov.predictor or {})
    return Identification(best.result, best.model, K, best.idn.start, best.basis,
                          np.atleast_1d(np.asarray(best.R, float)), best.prior, prov)


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
    simulation_db: float = -np.inf

    @property
    def label_shown(self) -> str:
        return self.label + (", stabilised" if self.reflected_poles else "")

    def row(self, order: int) -> dict:
        row = {"label": self.label_shown, "states": order, "stable": self.stable,
               "identification_ratio_db": self.score,
               "identification_simulation_db": (self.simulation_db
                                                 if np.isfinite(self.simulation_db) else None),
               "seconds": self.seconds}
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
    """The fit at order ``h`` reduced to ``order`` and refined by PLID (one candidate).

    The reduction alone does not compete: unrefined, it won on one-step prediction while
    simulating far worse than :func:`identify` at ``order`` (an accelerometer plant:
    64 % against 99.6 %, ``tests/plid/test_multipass.py``). Where the fit at ``h`` found a
    direct term, the reduction keeps one (``B, D`` refitted by output error), the PLID pass
    runs on ``y - D0 u`` and ``B, D`` are refitted after it, as :func:`identify` does.
    """

    t0 = time.perf_counter()
    try:
        high = identify(u, y, h, dt, **kw)
        use_d = bool(high.provenance.direct.estimated)
        red = balanced_truncation(_stable(high.model), order, u=u).model
        # Weighted truncation does not guarantee stability (unlike the plain one), and
        # the output-error refit needs it.
        red, _, _ = output_error_fit(_stable(red), u, y, direct=use_d)
    except IdentificationError as exc:  # e.g. more unstable states than ``order``
        return [Candidate(f"via {h}, refined", None, time.perf_counter() - t0,
                          error=str(exc))]
    D0 = np.asarray(red.D, float)
    y_fit = y - u @ D0.T if use_d else y
    prior = control.ss(red.A, red.B, red.C, np.zeros_like(D0), dt)
    p = y.shape[1]
    basis = basis_for(order, p, 1.0 / dt, model_frequencies(prior, order // 2, 1.0 / dt))
    R = _noise_estimate(prior, u, y_fit)
    try:
        res, hist = multipass(u, y_fit, order, dt, (Pass(0.0, 0.0, prior_theta_var),),
                              basis=basis, prior=prior, R=R, form=form, progress=progress)
    except IdentificationError as exc:
        return [Candidate(f"via {h}, refined", None, time.perf_counter() - t0,
                          error=str(exc))]
    model = res.model
    stable = _count_unstable(model) == 0
    model, _, _ = _with_direct_term(model, u, y, use_d, stable, D0 if use_d else None)
    return [Candidate(f"via {h}, refined", model, time.perf_counter() - t0, high, res, basis,
                      R, prior, passes=hist)]


def _score(c: Candidate, u, y, order: int) -> None:
    """Stabilise ``c`` if needed and score its best one-step predictor on ``u, y``."""

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
    c.simulation_db = _simulation_db(c.model, u, y)


def _simulation_db(model, u, y) -> float:
    """Mean-normalised simulation ratio [dB] of ``model`` on ``u, y`` from rest."""
    with np.errstate(all="ignore"):
        e = y - simulate(model, u)
        r = -10 * np.log10(np.mean(np.mean(e ** 2, 0) / np.mean(y ** 2, 0)))
    return float(r) if np.isfinite(r) else -np.inf


def _winner(cands: list) -> Candidate:
    """The best one-step predictor on the identification record among the candidates that
    simulate it at least as well as the direct fit (the first candidate): a reduced model
    may predict one step ahead better and still be the worse plant model. A candidate whose
    unstable poles had to be reflected in (its phase is no longer the data's) competes only
    when no other candidate has a stable predictor: on the demo's 36-state MIMO record the
    reflected direct fit predicted best, and no LQG designed from it was stable on it."""
    scored = [c for c in cands if c.score is not None]
    clean = [c for c in scored if not c.reflected_poles]
    if clean:
        scored = clean
    if scored and cands[0] in scored:
        floor = cands[0].simulation_db - 0.1
        scored = [c for c in scored if c is cands[0] or c.simulation_db >= floor]
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
              block_rows=None, direct=None, progress: bool | None = None,
              log=None) -> Identification:
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
    direct : {None, "auto", True, False}
        Direct term (:func:`identify`); None: ``"auto"``. Not for the plain fit.

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
    form = form or ("sqrt" if start == "plain" else "direct")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", PLIDWarning)
        if start == "plain":
            R = 1e-4 if R is None else R
            res = PLID(order, form=form, dt=dt, Q=Q, R=R, passes=passes,
                       progress=progress).fit(u, y)
            idn = Identification(res, res.model, res.K, "plain", res.basis,
                                 np.atleast_1d(np.asarray(R, float)), None,
                                 Provenance(passes=[{"Q": Q}] * passes, K_source=res.K_source))
        elif via is not None:
            idn = identify_reduced(u, y, order, dt, via=via, start=start, form=form,
                                   block_rows=block_rows, progress=progress, log=log,
                                   direct="auto" if direct is None else direct)
            idn.provenance.K_source = (idn.provenance.predictor or {}).get("chosen")
        else:
            idn = identify(u, y, order, dt, start=start, R=R, form=form, block_rows=block_rows,
                           direct="auto" if direct is None else direct, progress=progress)
            idn.provenance.K_source = (idn.provenance.predictor or {}).get("chosen")
    idn.provenance.warnings = [str(w.message) for w in caught
                               if issubclass(w.category, PLIDWarning)]
    if not idn.result.finite:
        raise IdentificationError(
            f"PLID ({form} form) diverged on {len(u)} samples: the estimate is not finite; "
            "try the sqrt form, a larger Q or R, or another order")
    if idn.K is None:
        res = idn.result
        B = np.asarray(idn.model.B)
        idn.K = predictor_gain(idn.model, res.Q + B @ res.N @ B.T, res.R)
        idn.provenance.K_source = "steady state of the estimator's noise model"
    return idn
