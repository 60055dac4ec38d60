"""The complete identification recipe :func:`identify` (a fit at one order).

It runs the PLID passes of :mod:`trussid.plid.passes` after choosing a prior and a basis, then
decides the direct term, reflects unstable poles in and chooses the one-step predictor.
:func:`identify` is what ``trussid identify`` runs. Its two starts (measured in
``benchmarks/results/plid_thesis.md``):

- ``start="subspace"`` (default): a quick N4SID estimate with D = 0
  (:func:`trussid.plid.subspace.subspace_prior`) is the prior, or, when a direct term is
  asked for or the data show one, N4SID's model with D
  (:func:`trussid.plid.feedthrough.direct_prior`); the observer basis is a rotation
  basis at the prior's pole frequencies (:mod:`trussid.plid.bases`); one PLID pass with ``Q = 0``
  and a tight parameter prior refines it. At 42 states it beat the best N4SID by 2.7-4x
  in FRF error and 11-18 dB in simulation; at 24 states it won on simulation (+5 dB)
  but not on FRF dB error.
- ``start="scratch"``: no prior; a rotation basis at the prominent peaks of the output
  spectrum and four passes with shrinking ``Q`` and a tightening prior
  (:data:`trussid.plid.passes.SCRATCH_SCHEDULE`). It reached the subspace start's accuracy at 24 states and
  beat N4SID at 40 block rows at 42 states (60 dB), but failed at 30 dB.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import replace

import control
import numpy as np

from trussid.plid._steps import (count_unstable, noise_estimate, pem_gain, reflect_unstable,
                                 reflected_note, with_direct_term)
from trussid.plid._validate import as_2d
from trussid.plid.bases import basis_for, data_frequencies, model_frequencies
from trussid.plid.closedloop import FEEDBACK_SHARE, feedback_share, identify_closed_loop
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.estimator import PLIDWarning
from trussid.plid.feedthrough import direct_prior
from trussid.plid.metrics import (best_predictor, default_noise_covariances, one_step_predict,
                                  predictor_gains)
from trussid.plid.passes import SCRATCH_SCHEDULE, Pass, multipass
from trussid.plid.provenance import (DirectTerm, DirectTermTest, Identification, Provenance,
                                     Stabilised)
from trussid.plid.reduce import balanced_truncation
from trussid.plid.subspace import (cached_n4sid, default_block_rows, direct_term_test,
                                   output_error_fit, subspace_prior)

__all__ = ["identify", "check_data", "PREDICTORS"]


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



def identify(u, y, order: int, dt: float, *, start: str = "subspace", R=None,
             form: str = "direct", radius: float = 0.97, block_rows=None,
             schedule=None, prior_theta_var: float = 1e-4, Q: float = 0.0,
             direct="auto", stabilise: bool = True, predictor: str = "pem",
             progress: bool | None = None, closed_loop: bool = False,
             reference=None) -> Identification:
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
        Scratch start passes (default :data:`trussid.plid.passes.SCRATCH_SCHEDULE`); for the subspace start
        the default is one pass ``Pass(Q, 0, prior_theta_var)``.
    prior_theta_var, Q : float
        Subspace start: the parameter prior variance and state noise of its pass.
    direct : {"auto", True, False}
        Estimate a direct term ``D``. ``"auto"`` (default) decides on the identification
        data (:func:`trussid.plid.subspace.direct_term_test`: held-out output error with
        and without ``D``, ``A, C`` fixed to the strictly proper N4SID prior of the first
        block-row count, before the block-row sweep, so that only the prior that is used
        is swept; ``provenance.direct.test.block_rows``); a strictly proper plant
        (e.g. seen through anti-aliasing filters) gets ``D = 0``, an accelerometer
        driven by a force input typically not. With ``D``, the prior is N4SID's model
        with D (:func:`trussid.plid.feedthrough.direct_prior`), PLID runs on ``y - D0 u``
        (``D0`` from that prior, which makes the data strictly proper, so the recursion is
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
    progress : bool or None
        A tqdm bar over the PLID passes (None: shown when the record is long).
    closed_loop : bool
        The record was taken under feedback (the input depends on past outputs). Then
        N4SID and PLID's output-error passes are biased, and the recipe is instead
        :func:`trussid.plid.closedloop.identify_closed_loop`: a predictor-based subspace
        prior (PBSID) refined by the prediction error of the innovations model (the direct
        method, consistent under feedback), ``D = 0`` (``direct`` must not be True);
        ``start``, ``R``, ``form``, ``radius``, ``block_rows``, ``schedule``, ``Q`` and
        ``prior_theta_var`` do not apply, and ``result`` and ``basis`` are None.
        ``provenance.closed_loop`` records the steps.
    reference : array (N, m) or (N, 1), optional
        The reference (dither) channel(s) of the record: a record whose inputs the
        reference explains less than ``1 - FEEDBACK_SHARE`` of
        (:func:`trussid.plid.closedloop.feedback_share`) is treated as closed loop.

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
    # Long: the recipe's steps in order (checks, closed-loop branch, prior, passes, direct
    # term, stabilisation, predictor), each a few lines sharing the same arrays.
    u, y = check_data(u, y, dt)
    p = y.shape[1]
    fs = 1.0 / dt
    if direct not in ("auto", True, False):
        raise IdentificationError(f"direct must be 'auto', True or False, got {direct!r}")
    if int(order) != order or order < 1:
        raise IdentificationError(f"order must be a positive integer, got {order!r}")
    _check_predictor(predictor)
    share, decided_by = None, "told"
    if reference is not None:
        share = feedback_share(u, reference)
        if not closed_loop and np.any(share > FEEDBACK_SHARE):
            closed_loop, decided_by = True, "reference channel"
    if closed_loop:
        return _identify_closed_loop(u, y, int(order), dt, direct, stabilise, decided_by,
                                     share)
    kw = dict(start=start, R=R, form=form, radius=radius, block_rows=block_rows,
              schedule=schedule, prior_theta_var=prior_theta_var, Q=Q, direct=direct,
              stabilise=stabilise, predictor=predictor, progress=progress)
    if order % p:
        return _identify_by_reduction(u, y, int(order), dt, kw)

    prov = Provenance()
    t0 = time.perf_counter()
    use_d, test, D0 = direct is True, None, None
    y_fit, d_start, fits = y, None, {}  # fits: N4SID runs shared by the two priors
    if start == "subspace":
        if direct == "auto":
            # decided before the block-row sweep, on the strictly proper prior of the first
            # block-row count, so that only the prior that is used is swept (one N4SID run
            # and one output-error refit fewer per identify; the test's decision was the
            # same on every block-row count of the four measured sets). The test reads the
            # prior's A, C only (it fits B and D itself): the prior's own refit of B is
            # left to the sweep, which runs only if that prior is used
            first = _first_block_rows(u, y, order, block_rows)
            test = direct_term_test(cached_n4sid(u, y, order, first, dt, fits).stable_zero_d,
                                    u, y)
            test["block_rows"] = first
            use_d = test["direct"]
        if use_d:
            # N4SID's own model with D (plid.feedthrough: the strictly proper prior's C is
            # biased by the feed-through, 1.4-4.2 dB below it in one-step prediction)
            proper = None    # the strictly proper prior, swept only if a restart needs it
            with_d, prov.subspace = direct_prior(u, y, order, dt, block_rows, fits=fits)
            prov.subspace_seconds = time.perf_counter() - t0
            prior, D0, y_fit, basis, R = _start_with_d(with_d, u, y, order, radius, kw["R"])
            d_start = "N4SID with D (plid.feedthrough.direct_prior)"
        else:
            prior, prov.subspace = subspace_prior(u, y, order, dt, block_rows, fits=fits)
            prov.subspace_seconds = time.perf_counter() - t0
            basis = basis_for(order, p, fs, model_frequencies(prior, order // 2, fs), radius)
            R = noise_estimate(prior, u, y_fit) if R is None else R
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
    if d_start and count_unstable(res.model):
        alt = _strictly_proper_restart(u, y, order, dt, res, proper, sched, dict(kw, fits=fits))
        if alt is not None:
            (prior, D0, y_fit, basis, R), res, hist, d_start = alt
    prov.passes = hist
    # wall and CPU seconds of the PLID recursion alone (the CPU figure is the one that
    # stays meaningful on a shared, loaded machine)
    prov.recursion_seconds = time.perf_counter() - t1
    prov.recursion_cpu_seconds = time.process_time() - c1
    R = np.atleast_1d(np.asarray(R, float))
    model, n_unstable = res.model, count_unstable(res.model)
    if stabilise and n_unstable:
        model = reflect_unstable(model)
    prov.stabilised = Stabilised(bool(stabilise and n_unstable), n_unstable if stabilise else 0)
    if stabilise and n_unstable:
        warnings.warn(PLIDWarning(reflected_note(n_unstable)), stacklevel=2)
    stable = count_unstable(model) == 0
    if start == "scratch" and direct == "auto" and stable:
        test = direct_term_test(model, u, y)
        use_d = test["direct"]
    model, use_d, D_std = with_direct_term(model, u, y, use_d, stable, D0)
    prov.direct = _direct_info(direct, use_d, test, model, D_std, d_start)
    K, prov.predictor = _best_gain(model, u, y, R, {"estimator": res.K})
    if predictor == "pem":
        K, prov.predictor = pem_gain(model, u, y, K, prov.predictor)
    prov.seconds = time.perf_counter() - t0
    return Identification(res, model, K, start, basis, R, prior, prov)


#: How :func:`identify` finds the one-step predictor gain (its ``predictor`` argument).
PREDICTORS = ("pem", "candidates")


def _check_predictor(predictor) -> None:
    if predictor not in PREDICTORS:
        raise IdentificationError(f"predictor must be one of {', '.join(PREDICTORS)}, "
                                  f"got {predictor!r}")




def _strictly_proper_restart(u, y, order, dt, res, strictly_proper, sched, kw):
    """PLID from the prior with D left poles outside the unit circle (``res``): the fit from
    the strictly proper prior (A, C of N4SID's D = 0 model, B and D refitted), judged as
    :func:`trussid.plid.reduced.identify_reduced` judges its candidates, a model without
    reflected poles first. ``(start, result, passes, why)`` of that fit when it is stable,
    else None (the first fit stands).

    On the force grid's 3-output record at order 54 (two shakers, three accelerometers,
    ``benchmarks/results/plid_feedthrough_demo.md``) the start with D left 2 unstable poles;
    reflected, the via-54 reduction lost 1.5 dB of one-step prediction against the strictly
    proper start's stable fit.
    """
    n_bad = count_unstable(res.model)
    if strictly_proper is None:
        strictly_proper, _ = subspace_prior(u, y, order, dt, kw["block_rows"], fits=kw["fits"])
    alt_d, _, _ = output_error_fit(strictly_proper, u, y, direct=True, d_std=False)
    alt = _start_with_d(alt_d, u, y, order, kw["radius"], kw["R"])
    try:
        alt_res, alt_hist = multipass(u, alt[2], order, dt, sched, basis=alt[3], prior=alt[0],
                                      R=alt[4], form=kw["form"], progress=kw["progress"])
    except IdentificationError:  # the alternative diverged: the first fit stands
        return None
    if not alt_res.finite or count_unstable(alt_res.model):
        return None
    why = (f"the strictly proper N4SID prior, B and D refitted: PLID from N4SID with D left "
           f"{n_bad} pole(s) outside the unit circle, from this prior none")
    return alt, alt_res, alt_hist, why


def _first_block_rows(u, y, order, block_rows) -> int:
    """The first block-row count a prior's sweep tries (given or default)."""
    if block_rows is None:
        return default_block_rows(u.shape[0], order, u.shape[1], y.shape[1])[0]
    return int(np.atleast_1d(block_rows)[0])


def _start_with_d(with_d, u, y, order, radius, R):
    """``(prior, D0, y_fit, basis, R)`` of a PLID pass from a prior with D: ``D0 u`` is taken
    off the outputs, so PLID sees strictly proper data from the prior's strictly proper
    part; ``R`` estimated from it unless given."""
    dt = with_d.dt
    D0 = np.asarray(with_d.D, float)
    y_fit = y - u @ D0.T
    prior = control.ss(with_d.A, with_d.B, with_d.C, np.zeros_like(D0), dt)
    basis = basis_for(order, y.shape[1], 1.0 / dt,
                      model_frequencies(prior, order // 2, 1.0 / dt), radius)
    if R is None:
        R = noise_estimate(prior, u, y_fit)
    return prior, D0, y_fit, basis, R


def _identify_closed_loop(u, y, order, dt, direct, stabilise, decided_by, share):
    """:func:`trussid.plid.closedloop.identify_closed_loop`, stabilised, with its provenance."""
    if direct is True:
        raise IdentificationError("closed_loop: the closed-loop recipe estimates no direct "
                                  "term (D = 0); use direct='auto' or False")
    t0 = time.perf_counter()
    model, K, prior, info = identify_closed_loop(u, y, order, dt, decided_by=decided_by,
                                                 share=share)
    prov = Provenance(closed_loop=info)
    n_unstable = count_unstable(model)
    if stabilise and n_unstable:
        model = reflect_unstable(model)
        warnings.warn(PLIDWarning(reflected_note(n_unstable)), stacklevel=3)
        # the refined gain belonged to the unreflected model: refit it for this one
        K, prov.predictor = _best_gain(model, u, y, 1e-4, {})
        K, prov.predictor = pem_gain(model, u, y, K, prov.predictor)
    else:
        prov.predictor = {"chosen": "prediction error (closed loop, with the model)"}
    prov.stabilised = Stabilised(bool(stabilise and n_unstable), n_unstable if stabilise else 0)
    prov.direct = _direct_info(direct, False, None, model, None)
    prov.seconds = time.perf_counter() - t0
    e = y - one_step_predict(model, u, y, K=K)
    R = np.mean(e ** 2, axis=0) / np.mean(y ** 2, axis=0)
    return Identification(None, model, K, "closed-loop", None, R, prior, prov)


def _direct_info(mode, used, test, model, D_std, start=None) -> DirectTerm:
    return DirectTerm(mode=mode, estimated=bool(used),
                      test=None if test is None else DirectTermTest(
                          test["held_out_nmse"]["without"], test["held_out_nmse"]["with"],
                          test["margin"], test["folds"], test.get("block_rows")),
                      D=np.asarray(model.D, float).tolist(),
                      D_std=None if D_std is None else np.asarray(D_std).tolist(),
                      start=start)


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
        base = reflect_unstable(high.model)
        try:
            red = balanced_truncation(base, order, u=u).model
        except IdentificationError:
            # the input-weighted Gramian can leave states at round-off level (an input
            # that does not excite them); the plain balanced truncation then still works
            red = balanced_truncation(base, order).model
        red = reflect_unstable(red)
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
    prov.direct.start = high.provenance.direct.start
    K, prov.predictor = _best_gain(red, u, y, high.R, {})
    if kw["predictor"] == "pem":
        K, prov.predictor = pem_gain(red, u, y, K, prov.predictor)
    prov.seconds = time.perf_counter() - t0
    return Identification(high.result, red, K, high.start, high.basis, high.R, high.prior, prov)


def _default_gain(model, u, y, R):
    """The former default predictor gain: a steady-state Kalman gain with 1 % input noise
    through ``B`` and the estimated output noise ``R`` (None without a solution)."""

    Qd, _ = default_noise_covariances(model, u, y)
    sy2 = np.mean(y ** 2, axis=0)
    Rd = np.diag(np.broadcast_to(R, sy2.shape) * sy2)
    try:
        # the doubling solve (scipy's QZ solve where it does not settle): the QZ solve was
        # a tenth of identify's CPU time on the flutter set (issue 34's gain profile)
        return predictor_gains(model, [Qd], Rd)[0]
    except Exception:  # noqa: BLE001 - no stabilising solution (e.g. an unstable mode)
        return None


