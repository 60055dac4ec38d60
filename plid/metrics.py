"""How good an identified model is: prediction, frequency-response, simulation and pole metrics.

Definitions (used by ``trussid identify``, ``compare`` and the demo report)
-------------------------------------------------------------------------
One-step signal-to-prediction-error ratio [dB]
    Run the model's one-step (Kalman) predictor over validation data from x0 = 0,
    x[k+1] = A x[k] + B u[k] + K (y[k] - C x[k] - D u[k]),  yhat[k] = C x[k] + D u[k].
    Per output channel j: ``20 log10( RMS(y_j) / RMS(y_j - yhat_j) )``, where RMS(y_j) is
    the RMS of the measured sensor signal (mean not removed). Overall (``overall``): the
    thesis's figure, "the sensor signal RMS was 46 dB higher than the sensor error"
    (Vallone 1997, ch. 2), the RMS over all sensors and samples:
    ``10 log10( sum_jk y_j[k]^2 / sum_jk e_j[k]^2 )``. It weighs the channels by their
    signal power in the data's units (for the testbed all are volts at the A/D), so it
    needs channels in comparable units. ``mean_normalised``:
    ``-10 log10( mean_j ( MS(e_j) / MS(y_j) ) )``, the mean of the normalised error
    powers, independent of channel units and dominated by the worst channel.
    The first ``skip`` samples (the predictor's start-up from x0 = 0) are left out.
Simulation fit [dB]
    The same ratios for the model simulated open loop (no K) against the noise-free output
    of validation data, ``overall`` being the mean-normalised one; also the NRMSE fit ``100 (1 - ||e|| / ||y - mean(y)||)`` [%].
FRF error
    Per channel (output i, input j) over a band: magnitude error
    ``20 log10|H_model| - 20 log10|H_ref|`` [dB] and phase error ``angle(H_model / H_ref)``
    [deg], reported as max of the absolute value and RMS over the frequency grid.
Poles
    Discrete poles z map to s = ln(z) / dt; frequency |s| / 2 pi [Hz], damping -Re(s)/|s|.
    Identified and true poles (one of each complex pair) are matched by minimum total
    s-plane distance (Hungarian assignment, :func:`trussid.plid.modal.assign_pairs`).
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from trussid.plid._linalg import lstsq, modal_regressors
from trussid.plid.errors import DataError
from trussid.plid.experiment import simulate
from trussid.plid.frf import FRF, frequency_response
from trussid.plid.kernel_common import mean_square_errors
from trussid.plid.modal import assign_pairs, pole_parameters, s_plane
from trussid.plid.riccati import doubling_gains


def _check_sizes(sys, u, y=None):
    u = np.asarray(u, dtype=float)
    u = u[:, None] if u.ndim == 1 else u
    if u.shape[1] != sys.ninputs:
        raise DataError(f"the model has {sys.ninputs} inputs but the data has {u.shape[1]}")
    if y is None:
        return u, None
    y = np.asarray(y, dtype=float)
    y = y[:, None] if y.ndim == 1 else y
    if y.shape[1] != sys.noutputs:
        raise DataError(f"the model has {sys.noutputs} outputs but the data has {y.shape[1]}")
    if y.shape[0] != u.shape[0]:
        raise DataError(f"u has {u.shape[0]} samples, y has {y.shape[0]}")
    return u, y


def predictor_gain(sys: control.StateSpace, Q, R) -> np.ndarray:
    """Steady-state one-step Kalman predictor gain K = A P C^T (C P C^T + R)^-1.

    P solves the filter Riccati equation P = A P A^T - A P C^T (C P C^T + R)^-1 C P A^T + Q
    (scipy.linalg.solve_discrete_are on the dual problem). Q (n x n) state-noise and
    R (p x p) output-noise covariances.
    """
    A, C = np.asarray(sys.A), np.asarray(sys.C)
    try:
        P = scipy.linalg.solve_discrete_are(A.T, C.T, np.asarray(Q, float), np.asarray(R, float))
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise DataError(f"no steady-state predictor for this model and noise ({exc})") from None
    return A @ P @ C.T @ np.linalg.inv(C @ P @ C.T + R)


def default_noise_covariances(sys, u, y, rel: float = 1e-2):
    """Noise covariances for a predictor when none are known: input noise and output noise
    each at ``rel`` of the channel RMS (Q = B diag(sigma_u^2) B^T + tiny ridge, R = diag)."""
    su = rel * np.sqrt(np.mean(np.asarray(u) ** 2, axis=0))
    sy = rel * np.sqrt(np.mean(np.asarray(y) ** 2, axis=0))
    B = np.asarray(sys.B)
    Q = B @ np.diag(su**2) @ B.T
    Q = Q + 1e-9 * (np.trace(Q) / max(Q.shape[0], 1) or 1.0) * np.eye(Q.shape[0])
    R = np.diag(np.maximum(sy**2, 1e-300))
    return Q, R


#: State-to-output noise ratios tried by :func:`choose_predictor`.
PREDICTOR_RATIOS = (100.0, 10.0, 1.0, 0.1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6)


def choose_predictor(model: control.StateSpace, u, y, candidates=None,
                     ratios=PREDICTOR_RATIOS):
    """One-step predictor gain for ``model``, chosen on the (identification) data given.

    Candidates: the gains in ``candidates`` (``{label: K}``, e.g. the estimator's own) whose
    predictor ``A - K C`` is stable, and steady-state Kalman gains with output noise
    ``R = diag(RMS(y_j)^2)`` and state noise ``Q = a (B diag(RMS(u_j)^2) B^T + 1e-3 tr/n I)``
    for each ratio ``a`` (only the ratio of Q to R matters to K). An identified model's own
    error acts as noise of a level not known beforehand, so the candidate with the best
    one-step ratio (``overall``, module docstring) on ``u, y`` is kept, every candidate
    scored on the same samples (after the longest :func:`prediction_burn_in` of them); give
    it the identification record, never the validation record.

    Returns
    -------
    K : ndarray (n, p)
    label : str
    info : dict
        ``{"chosen": label, "skip": samples left out, "identification_ratio_db": {label: dB}}``.
    """
    u, y = _check_sizes(model, u, y)
    A, B, C = (np.asarray(M, dtype=float) for M in (model.A, model.B, model.C))
    n = A.shape[0]
    Qin = B @ np.diag(np.mean(u ** 2, axis=0)) @ B.T
    Qin = Qin + 1e-3 * (np.trace(Qin) / max(n, 1)) * np.eye(n)
    R = np.diag(np.maximum(np.mean(y ** 2, axis=0), 1e-300))
    cands = []
    for label, K in (candidates or {}).items():
        K = None if K is None else np.asarray(K, dtype=float)
        if (K is not None and K.shape == (n, C.shape[0]) and np.all(np.isfinite(K))
                and np.max(np.abs(np.linalg.eigvals(A - K @ C)), initial=0) < 1):
            cands.append((label, K))
    for a in ratios:
        try:
            cands.append((f"kalman Q/R ratio {a:g}", predictor_gain(model, a * Qin, R)))
        except (DataError, np.linalg.LinAlgError):  # no stabilising solution: skip it
            continue
    if not cands:
        raise DataError("no stable one-step predictor for this model")
    # The same samples for every candidate: past the slowest candidate's start-up.
    skip = max(prediction_burn_in(model, K, u.shape[0]) for _, K in cands)
    scores = []
    for label, K in cands:
        with np.errstate(all="ignore"):
            r = prediction_ratio_db(model, u, y, K=K, skip=skip).overall
        scores.append(r if np.isfinite(r) else -np.inf)
    best = int(np.argmax(scores))
    return cands[best][1], cands[best][0], {
        "chosen": cands[best][0], "skip": int(skip),
        "identification_ratio_db": {lab: sc for (lab, _), sc in zip(cands, scores)}}


def _one_step_scores(model, u, y, Ks, skip) -> list[float]:
    """Mean-normalised one-step ratios [dB] of several gains ``Ks`` of one model
    (:func:`trussid.plid.kernel_common.mean_square_errors`)."""
    A, B, C, D = (np.asarray(M, dtype=float) for M in (model.A, model.B, model.C, model.D))
    ms_e = mean_square_errors(A, B, C, D, Ks, u, y, skip)        # (c, p)
    with np.errstate(all="ignore"):
        out = -10 * np.log10(np.mean(ms_e / np.mean(y[skip:] ** 2, axis=0), axis=1))
    return [float(v) if np.isfinite(v) else -np.inf for v in out]


def _stable_predictor(A, C, K) -> bool:
    return bool(np.all(np.isfinite(K))
                and np.max(np.abs(np.linalg.eigvals(A - K @ C)), initial=0) < 1)


def _long_ar_innovations(r: np.ndarray, lags: int) -> np.ndarray:
    """Innovations of ``r`` (N, p) from a long vector autoregression fitted by least
    squares (the first step of Hannan and Rissanen's ARMA estimation); zero before ``lags``."""
    N, p = r.shape
    lags = int(max(1, min(lags, (N // 4) // max(p, 1))))
    Phi = np.hstack([r[lags - i - 1:N - i - 1] for i in range(lags)])   # (N - lags, p lags)
    coef = lstsq(Phi, r[lags:])
    e = np.zeros_like(r)
    e[lags:] = r[lags:] - Phi @ coef
    return e


def refine_predictor_gain(model: control.StateSpace, u, y, K0=None, iterations: int = 2):
    """Least-squares estimates of a predictor gain with ``A, B, C, D`` fixed.

    In innovations form ``y = G(u) + (C (zI - A)^-1 K + I) e``: given innovations ``e``, the
    output residual ``y - G(u) - e`` is linear in ``K`` (and the initial state), so ``K``
    follows by least squares on one-pole filters of ``e``
    (:func:`trussid.plid.subspace.output_error_fit`'s regressors with ``e`` as the input).
    The first innovations are those of a long autoregression of the output-error residual
    (Hannan-Rissanen), or of the predictor with ``K0`` when given; each further iteration
    recomputes them with the new ``K`` (extended least squares). ``A`` must be stable and
    diagonalisable.

    Returns
    -------
    list of ndarray (n, p)
        The gain after each iteration whose predictor ``A - K C`` is stable.
    """

    u, y = _check_sizes(model, u, y)
    A, C = np.asarray(model.A, float), np.asarray(model.C, float)
    n, p = A.shape[0], C.shape[0]
    if n == 0 or np.max(np.abs(np.linalg.eigvals(A))) >= 1:
        return []
    w = 1.0 / np.sqrt(np.maximum(np.mean(y ** 2, axis=0), 1e-300))
    y_u = simulate(model, u)
    if K0 is None:
        e = _long_ar_innovations(y - y_u, 2 * n + 10)
    else:
        e = y - one_step_predict(model, u, y, K=np.asarray(K0, float))
    out, K = [], None
    for it in range(iterations):
        if it:
            e = y - one_step_predict(model, u, y, K=K)
        R = modal_regressors(A, C, e, x0=True)          # (N, p, n p + n)
        Rm = (R * w[None, :, None]).reshape(-1, R.shape[2])
        theta = lstsq(Rm, ((y - y_u - e) * w).ravel())
        K = theta[: n * p].reshape(p, n).T
        if not _stable_predictor(A, C, K):
            break
        out.append(K)
    return out


def predictor_gains(sys: control.StateSpace, Qs, R) -> list:
    """:func:`predictor_gain` for several state-noise covariances, solved side by side by
    :func:`trussid.plid.riccati.doubling_gains` where it settles (why, and its accuracy: there).

    Parameters
    ----------
    sys : control.StateSpace
        Discrete model (``A``, ``C`` used).
    Qs : sequence of arrays (n, n)
        State-noise covariances.
    R : array (p, p)
        Output-noise covariance (positive definite).

    Returns
    -------
    list
        Per ``Q``: the gain ``K`` (n, p), or None where no stabilising solution exists.
    """
    out = doubling_gains(np.asarray(sys.A, float), np.asarray(sys.C, float), Qs, R)
    for i in [i for i, K in enumerate(out) if K is None]:
        with contextlib.suppress(DataError):     # no stabilising solution: stays None
            out[i] = predictor_gain(sys, np.asarray(Qs[i], float), R)
    return out


#: Candidates of :func:`best_predictor` whose scores lie within this [dB] of the best are
#: tied (the earlier one is chosen): a relative change of 2e-10 in the mean-square error.
SCORE_TIE_DB = 1e-9

#: Isotropic state-to-output noise ratios tried by :func:`best_predictor`.
ISOTROPIC_RATIOS = (1e-4, 1e-2, 1.0, 1e2, 1e4)


def best_predictor(model: control.StateSpace, u, y, candidates=None,
                   ratios=PREDICTOR_RATIOS, refine: bool = True,
                   iso_ratios=ISOTROPIC_RATIOS):
    """The one-step predictor gain that predicts the (identification) data best.

    Candidates: ``K = 0`` (the predictor is then the free-run simulation, so the choice is
    never worse than simulation on these data), the gains in ``candidates``
    (``{label: K}``, e.g. the estimator's own), the steady-state Kalman gains of
    :func:`choose_predictor` (one per state-to-output noise ratio), steady-state Kalman
    gains with isotropic state noise (``Q = a tr(R) / tr(C C^T) I`` for each ratio in
    ``iso_ratios``), and, from the best of
    these and from a long autoregression of the output error, :func:`refine_predictor_gain`.
    Only gains with a stable predictor ``A - K C``
    compete. The score is the mean-normalised one-step ratio (module docstring: every
    output counts alike, whatever its units), every candidate scored on the same samples
    (after the longest :func:`prediction_burn_in` of them); scores within
    :data:`SCORE_TIE_DB` of the best are tied and the earlier candidate is chosen. Give it
    the identification record, never the validation record.

    Returns
    -------
    K : ndarray (n, p)
    label : str
    info : dict
        ``{"chosen": label, "criterion": "mean_normalised",
        "identification_ratio_db": {label: dB}}``.
    """
    u, y = _check_sizes(model, u, y)
    A, B, C = (np.asarray(M, dtype=float) for M in (model.A, model.B, model.C))
    n, p = A.shape[0], C.shape[0]
    cands = [("none (free-run simulation)", np.zeros((n, p)))]
    for label, K in (candidates or {}).items():
        K = None if K is None else np.asarray(K, dtype=float)
        if K is not None and K.shape == (n, p):
            cands.append((label, K))
    Qin = B @ np.diag(np.mean(u ** 2, axis=0)) @ B.T
    Qin = Qin + 1e-3 * (np.trace(Qin) / max(n, 1)) * np.eye(n)
    R = np.diag(np.maximum(np.mean(y ** 2, axis=0), 1e-300))
    # State noise in every direction, not only through B: disturbances that do not enter
    # where the input does (measured on the flutter set of bench_realdata: 14.9 -> 28.2 dB
    # one-step on the identification data). Scaled so that C Q C^T ~ a R.
    iso = np.trace(R) / max(np.trace(C @ C.T), 1e-300) * np.eye(n)
    labels = ([f"kalman Q/R ratio {a:g}" for a in ratios]
              + [f"kalman isotropic Q/R ratio {a:g}" for a in iso_ratios])
    Qs = [a * Qin for a in ratios] + [a * iso for a in iso_ratios]
    # None: no stabilising solution for that ratio, skipped
    cands += [(lab, K) for lab, K in zip(labels, predictor_gains(model, Qs, R)) if K is not None]
    # only gains with a stable predictor compete; every predictor's spectral radius from one
    # stacked eigenvalue call (one call per gain for the check and again for the burn-in
    # was a quarter of this function's time on the small measured sets)
    cands = [(lab, K) for lab, K in cands if np.all(np.isfinite(K))]
    rho = (np.max(np.abs(np.linalg.eigvals(A[None] - np.array([K for _, K in cands]) @ C)),
                  axis=1, initial=0.0) if cands and n else np.zeros(len(cands)))
    cands = [c for c, r in zip(cands, rho) if r < 1]
    if not cands:
        raise DataError("no stable one-step predictor for this model")
    # the same samples for every candidate: past the slowest candidate's start-up
    skip = max(_burn_in(float(r), n, u.shape[0]) for r in rho[rho < 1]) if n else 0
    scores = dict(zip([c[0] for c in cands],
                      _one_step_scores(model, u, y, [c[1] for c in cands], skip)))
    # ties to rounding go to the earlier candidate (K = 0 first): on the CD-arm set the
    # recursion's own gain (1.8e-10, against B up to 5e3) and K = 0 scored 14.85106333 dB
    # both, and which was "higher" flipped with the BLAS summation order of the prior
    top = max(scores[c[0]] for c in cands)
    best = next(i for i, c in enumerate(cands) if scores[c[0]] >= top - SCORE_TIE_DB)
    label, K = cands[best]
    if refine:
        refined, labs = [], []
        for start, K0 in (("long autoregression", None), (cands[best][0], K)):
            try:
                ks = refine_predictor_gain(model, u, y, K0)
            except (np.linalg.LinAlgError, ValueError):
                ks = []
            refined += ks
            labs += [f"least squares, {i + 1} iteration(s) from {start}" for i in range(len(ks))]
        if refined:
            scores.update(zip(labs, _one_step_scores(model, u, y, refined, skip)))
        for lab, Kr in zip(labs, refined):
            if scores[lab] > scores[label]:
                label, K = lab, Kr
    return K, label, {"chosen": label, "criterion": "mean_normalised", "skip": int(skip),
                      "identification_ratio_db": scores}


def one_step_predict(sys: control.StateSpace, u, y, K=None, Q=None, R=None) -> np.ndarray:
    """One-step-ahead output predictions yhat[k] (given data up to k-1), shape (N, p).

    ``K`` is the predictor gain; if None, the steady-state gain from ``Q``, ``R``
    (default :func:`default_noise_covariances`).
    """
    if not control.isdtime(sys, strict=True):
        raise DataError("one-step prediction needs a discrete model (dt > 0)")
    u, y = _check_sizes(sys, u, y)
    A, B, C, D = (np.asarray(M, dtype=float) for M in (sys.A, sys.B, sys.C, sys.D))
    n, p = A.shape[0], C.shape[0]
    if K is None:
        dQ, dR = default_noise_covariances(sys, u, y)
        K = predictor_gain(sys, dQ if Q is None else Q, dR if R is None else R)
    K = np.asarray(K, dtype=float)
    if K.shape != (n, p):
        raise DataError(f"predictor gain K has shape {K.shape}, the model needs {(n, p)}")
    # The predictor is itself an LTI system driven by [u, y].
    pred = control.ss(A - K @ C, np.hstack([B - K @ D, K]), C,
                      np.hstack([D, np.zeros((p, p))]), sys.dt)
    return simulate(pred, np.hstack([u, y]))


def _ratio_db(ref, err, skip):
    """Per-channel, pooled and mean-normalised ratios [dB] (module docstring)."""
    ref, err = ref[skip:], err[skip:]
    ms_ref = np.mean(ref**2, axis=0)
    ms_err = np.mean(err**2, axis=0)
    with np.errstate(divide="ignore"):
        per = 10 * np.log10(ms_ref / ms_err)
        pooled = 10 * np.log10(np.sum(ms_ref) / np.sum(ms_err))
        normalised = -10 * np.log10(np.mean(ms_err / ms_ref))
    return per, float(pooled), float(normalised)


@dataclass(frozen=True)
class PredictionScore:
    """One-step signal-to-prediction-error ratios [dB] on a record (module docstring).

    The one shape of that result: :func:`prediction_ratio_db` returns it and
    :func:`trussid.plid.evaluate.compare` reports it.

    Attributes
    ----------
    overall : float
        The thesis's ratio: signal power over error power, all outputs pooled.
    per_output : list of float
    mean_normalised : float
        ``-10 log10(mean_j MS(e_j) / MS(y_j))``, dominated by the weakest output.
    skip : int
        Samples left out at the start (:func:`prediction_burn_in`).
    gain : str
        Where the predictor gain came from ("" when the caller did not say).
    """

    overall: float
    per_output: list
    mean_normalised: float
    skip: int
    gain: str = ""


@dataclass(frozen=True)
class SimulationScore:
    """Free-run simulation from x0 = 0 against a record's outputs [dB and %].

    The one shape of that result: :func:`simulation_fit` returns it and
    :func:`trussid.plid.evaluate.compare` reports it.

    Attributes
    ----------
    overall : float
        The mean-normalised ratio [dB] (module docstring).
    per_output : list of float
        Ratio per output [dB].
    nrmse_percent : list of float
        NRMSE fit per output [%].
    skip : int
        Samples left out at the start.
    against : str
        Which outputs the simulation was set against (noise-free or measured; "" when the
        caller did not say).
    """

    overall: float
    per_output: list
    nrmse_percent: list
    skip: int
    against: str = ""


def prediction_ratio_db(sys, u, y, K=None, Q=None, R=None, skip: int = 0) -> PredictionScore:
    """One-step signal-to-prediction-error ratio [dB] (see the module docstring).

    Parameters
    ----------
    sys : control.StateSpace
        Discrete model.
    u, y : arrays (N, m), (N, p)
        Record.
    K : array (n, p), optional
        Predictor gain; default the steady-state gain of ``Q``, ``R``.
    Q, R : arrays, optional
        Noise covariances of the default gain.
    skip : int
        Samples left out at the start (the predictor's start-up).

    Returns
    -------
    PredictionScore
        Its ``gain`` is empty (the caller knows where ``K`` came from).
    """
    u, y = _check_sizes(sys, u, y)
    if not 0 <= skip < u.shape[0]:
        raise DataError(f"skip={skip} leaves no samples of {u.shape[0]}")
    yhat = one_step_predict(sys, u, y, K, Q, R)
    per, overall, normalised = _ratio_db(y, y - yhat, skip)
    return PredictionScore(overall, per.tolist(), normalised, int(skip))


def simulation_fit(sys, u, y_clean, skip: int = 0) -> SimulationScore:
    """Open-loop simulation of ``sys`` from x0 = 0 against noise-free outputs.

    Parameters
    ----------
    sys : control.StateSpace
        Model.
    u, y_clean : arrays (N, m), (N, p)
        Inputs and the outputs to match.
    skip : int
        Samples left out at the start.

    Returns
    -------
    SimulationScore
        Its ``against`` is empty (the caller knows what ``y_clean`` is).
    """
    u, y_clean = _check_sizes(sys, u, y_clean)
    ysim = simulate(sys, u)
    e = (y_clean - ysim)[skip:]
    per, _, overall = _ratio_db(y_clean, y_clean - ysim, skip)
    yc = y_clean[skip:]
    nrmse = 100 * (1 - np.linalg.norm(e, axis=0) / np.linalg.norm(yc - yc.mean(axis=0), axis=0))
    return SimulationScore(overall, per.tolist(), nrmse.tolist(), int(skip))


def modal_parameters(sys) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frequencies [Hz], damping ratios and s-plane poles of ``sys``, one per complex pair.

    The s-plane poles come from :func:`control.damp` (``s = ln(z) / dt`` for a discrete
    model). Poles with negative imaginary part are dropped (they mirror the kept ones); real
    poles are kept. Sorted by frequency. Works for continuous and discrete models.
    """
    if not sys.nstates:
        return np.zeros(0), np.zeros(0), np.zeros(0, dtype=complex)
    with np.errstate(divide="ignore"):  # a pole at z = 0 maps to s = -inf
        _, _, poles = control.damp(sys, doprint=False)
    s = s_plane(poles, sys.dt if control.isdtime(sys, strict=True) else None)
    keep = s.imag >= -1e-12 * np.maximum(np.abs(s), 1)
    s = s[keep]
    s = np.where(np.abs(s.imag) < 1e-12 * np.maximum(np.abs(s), 1), s.real + 0j, s)
    f, zeta, _ = pole_parameters(s)
    order = np.argsort(np.abs(s), kind="stable")
    return f[order], zeta[order], s[order]


def prediction_burn_in(model, K, n_samples: int) -> int:
    """Samples left out of a prediction ratio while the predictor forgets x0 = 0.

    The one burn-in rule of the project (``trussid identify``, ``compare``, the demo and
    :func:`choose_predictor` all use it): until the slowest pole of the predictor ``A - K C``
    has decayed by 60 dB, at least 10 samples per state and at most a quarter of the record.
    On the 0.25 %-damped testbed the predictor's slowest pole can take 1000 samples.

    Parameters
    ----------
    model : control.StateSpace
        Discrete model.
    K : array (n, p) or None
        Predictor gain; ``None``: the open-loop model's own poles (simulation).
    n_samples : int
    """
    A, C = np.asarray(model.A, dtype=float), np.asarray(model.C, dtype=float)
    n = A.shape[0]
    if n == 0:
        return 0
    F = A if K is None else A - np.asarray(K, dtype=float) @ C
    return _burn_in(float(np.max(np.abs(np.linalg.eigvals(F)))), n, n_samples)


def _burn_in(rho: float, n: int, n_samples: int) -> int:
    """:func:`prediction_burn_in` of a predictor with spectral radius ``rho`` and ``n``
    states."""
    k = int(np.ceil(np.log(1e-3) / np.log(rho))) if 0 < rho < 1 else n_samples
    return int(min(max(k, 10 * n), n_samples // 4))


@dataclass(frozen=True)
class PoleMatch:
    """One row of a pole comparison: a true pole, its identified match, or both.

    Attributes
    ----------
    true_frequency_hz, true_damping : float or None
        The true pole's frequency [Hz] and damping ratio [-]; None for an identified pole
        that matches no true one (or when there is no truth).
    frequency_hz, damping : float or None
        The identified pole's; None for a true pole that nothing identified matches.
    frequency_error_percent : float or None
        ``100 (f - f_true) / f_true`` of a matched pair.
    """

    true_frequency_hz: float | None = None
    true_damping: float | None = None
    frequency_hz: float | None = None
    damping: float | None = None
    frequency_error_percent: float | None = None

    @property
    def matched(self) -> bool:
        """A true pole with its identified match."""
        return self.true_frequency_hz is not None and self.frequency_hz is not None


def compare_poles(identified, truth, max_relative_distance: float | None = 0.5) -> list[PoleMatch]:
    """Match identified poles to true ones and list frequencies and damping side by side.

    Parameters
    ----------
    identified, truth : control.StateSpace
    max_relative_distance : float or None
        A pair found by the assignment counts as a match only if the s-plane distance is at
        most this fraction of the true pole's magnitude; farther pairs are reported as an
        unmatched true pole and an extra identified one (None: keep every pair).

    Returns
    -------
    list of PoleMatch
        One per true pole (sorted by true frequency), its identified fields None when
        unmatched; unmatched identified poles follow with the true fields None.
    """
    fi, zi, si = modal_parameters(identified)
    ft, zt, st = modal_parameters(truth)
    rows = []
    match = {}
    if si.size and st.size:
        cost = np.abs(si[:, None] - st[None, :])
        for i, j in enumerate(assign_pairs(cost).tolist()):
            if j >= 0 and (max_relative_distance is None
                           or cost[i, j] <= max_relative_distance * abs(st[j])):
                match[j] = i
    for j in range(st.size):
        i = match.get(j)
        if i is None:
            rows.append(PoleMatch(true_frequency_hz=float(ft[j]), true_damping=float(zt[j])))
        else:
            rows.append(PoleMatch(float(ft[j]), float(zt[j]), float(fi[i]), float(zi[i]),
                                  float(100 * (fi[i] - ft[j]) / ft[j]) if ft[j] > 0 else None))
    used = set(match.values())
    rows += [PoleMatch(frequency_hz=float(fi[i]), damping=float(zi[i]))
             for i in range(si.size) if i not in used]
    return rows


@dataclass(frozen=True)
class FRFScore:
    """Magnitude [dB] and phase [deg] error against a reference over ``band`` [Hz].

    The one shape of that result: :func:`frf_error` returns it and
    :func:`trussid.plid.evaluate.compare` reports it.

    Attributes
    ----------
    max_db, rms_db : float
        Largest absolute and RMS magnitude error over every channel and frequency [dB].
    max_deg, rms_deg : float
        The same for the phase [deg].
    per_channel : dict
        The same four figures per channel, each a nested list (outputs x inputs), by name.
    band : tuple of float
        The frequencies [Hz] actually compared, lowest and highest.
    reference : str
        What the model was set against ("" when the caller did not say).
    """

    max_db: float
    rms_db: float
    max_deg: float
    rms_deg: float
    per_channel: dict
    band: tuple
    reference: str = ""


def frf_error(model, reference, band=None, n_freq: int = 400) -> FRFScore:
    """Magnitude [dB] and phase [deg] error of ``model`` against ``reference`` over a band.

    Parameters
    ----------
    model : control.StateSpace
    reference : control.StateSpace or FRF
        The truth (a plant) or an estimate (e.g. H1) on its own frequency grid.
    band : (float, float), optional
        [Hz]; default the whole range (0, Nyquist) of the model (or of the FRF grid).
    n_freq : int
        Grid size when the reference is a model (a linear grid, plus the reference's modal
        frequencies inside the band so that resonance peaks are not stepped over).

    Returns
    -------
    FRFScore
        Its ``reference`` is empty (the caller knows what ``reference`` is).
    """
    if isinstance(reference, FRF):
        f = np.asarray(reference.f, dtype=float)
        lo, hi = band if band is not None else (f.min(), f.max())
        keep = (f >= lo) & (f <= hi) & (f > 0)
        if not keep.any():
            raise DataError(f"no reference frequency inside the band ({lo:g}, {hi:g}) Hz")
        f, H_ref = f[keep], reference.H[keep]
    else:
        if (reference.ninputs, reference.noutputs) != (model.ninputs, model.noutputs):
            raise DataError(f"the model has {model.ninputs} inputs and {model.noutputs} "
                            f"outputs, the reference {reference.ninputs} and "
                            f"{reference.noutputs}")
        nyq = 0.5 / model.dt if control.isdtime(model, strict=True) else None
        if band is None:
            if nyq is None:
                raise DataError("give a band for a continuous model")
            band = (0.0, nyq)
        lo, hi = (float(b) for b in band)
        if not 0 <= lo < hi:
            raise DataError(f"band ({lo:g}, {hi:g}) Hz must have 0 <= low < high")
        if nyq is not None and hi > nyq * (1 + 1e-12):
            raise DataError(f"band upper edge {hi:g} Hz is above the Nyquist frequency "
                            f"{nyq:g} Hz")
        grid = np.linspace(max(lo, 1e-9 * hi), hi * (1 - 1e-9), n_freq)
        fr, _, _ = modal_parameters(reference)
        f = np.unique(np.concatenate([grid, fr[(fr > lo) & (fr < hi)]]))
        H_ref = frequency_response(reference, f)
    if H_ref.shape[1:] != (model.noutputs, model.ninputs):
        raise DataError(f"reference FRF is {H_ref.shape[1]} x {H_ref.shape[2]}, the model "
                        f"{model.noutputs} x {model.ninputs}")
    H = frequency_response(model, f)
    with np.errstate(divide="ignore", invalid="ignore"):
        mag = 20 * np.log10(np.abs(H)) - 20 * np.log10(np.abs(H_ref))
        ph = np.degrees(np.angle(H / H_ref))
    per_channel = {key: fn(arr).tolist() for key, arr, fn in (
        ("max_db", mag, lambda a: np.max(np.abs(a), axis=0)),
        ("rms_db", mag, lambda a: np.sqrt(np.mean(a**2, axis=0))),
        ("max_deg", ph, lambda a: np.max(np.abs(a), axis=0)),
        ("rms_deg", ph, lambda a: np.sqrt(np.mean(a**2, axis=0))))}
    return FRFScore(float(np.max(np.abs(mag))), float(np.sqrt(np.mean(mag**2))),
                    float(np.max(np.abs(ph))), float(np.sqrt(np.mean(ph**2))), per_channel,
                    (float(f.min()), float(f.max())))


__all__ = ["PoleMatch", "PredictionScore", "SimulationScore", "FRFScore", "predictor_gain",
           "default_noise_covariances", "one_step_predict", "prediction_ratio_db",
           "choose_predictor", "simulation_fit", "modal_parameters", "compare_poles", "frf_error",
           "prediction_burn_in", "s_plane", "best_predictor", "refine_predictor_gain"]
