"""Prediction-error refinement of the one-step predictor gain ``K`` (and, optionally, of the
whole innovations model).

The innovations form of an identified model is ::

    x[k+1] = A x[k] + B u[k] + K e[k],   y[k] = C x[k] + D u[k] + e[k],

and its one-step predictor runs ``x[k+1] = (A - K C) x[k] + (B - K D) u[k] + K y[k]``.
:func:`trussid.plid.recipe.identify` fits ``A, B, C, D`` for simulation (PLID's
criterion); a predictor gain picked from a few one-parameter families of Kalman gains
(:func:`trussid.plid.metrics.best_predictor`) cannot represent a coloured disturbance, and
that is where the one-step fit was lost on measured data (``docs/plid.md``, "The predictor
gain"; the prototype measurements behind ``benchmarks/results/realdata.md``).

:func:`refine_gain` fits ``K`` and the initial state with ``A, B, C, D`` fixed by
Gauss-Newton / Levenberg-Marquardt on the maximum-likelihood criterion of Gaussian
innovations with unknown covariance, ``log det(E^T E / N)`` (MATLAB ``ssest``'s
``OutputWeight`` 'noise'), minimised as a weighted sum of squares whose weight is the
inverse residual covariance re-estimated after every accepted step. The Jacobian is the
project's modal regressors (:func:`trussid.plid._linalg.modal_regressors`): with
``e = y - yhat``, ``d yhat / d K[t, c] = C (zI - A + K C)^-1 e_t`` applied to ``e_c``, and
``d yhat / d x0 = C (A - K C)^k``. A step is rejected when the predictor's spectral radius
would reach ``margin`` (a predictor at the unit circle forgets its start and its errors
never). ``A, B, C, D`` and hence the simulation fit are untouched by construction.

scipy's ``least_squares`` takes the same residual and Jacobian, but it cannot reject a step
on a stability condition, so the Levenberg-Marquardt loop is written out here.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from trussid.plid.bases import basis_for, model_frequencies
from trussid.plid.canonical import from_statespace
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.kernel_common import mode_signals, state_sequence
from trussid.plid._linalg import _one_of_each_pair, lstsq, real_modal_regressors

__all__ = ["GainFit", "GainRace", "refine_gain", "refine_gain_from", "gain_iterations",
           "significant_change"]


@dataclass(frozen=True)
class GainFit:
    """A predictor gain fitted by prediction error (:func:`refine_gain`).

    Attributes
    ----------
    K : ndarray (n, p)
        Predictor gain, in the model's units.
    x0 : ndarray (n,)
        Initial state fitted with it.
    iterations : int
        Accepted Levenberg-Marquardt steps.
    logdet_start, logdet_end : float
        ``log det`` of the innovation covariance (outputs scaled to unit RMS) before and
        after; lower is better.
    spectral_radius : float
        Of the predictor ``A - K C``.
    converged : bool
        The last step changed the criterion by less than the tolerance (else: stopped at
        the iteration limit, or no step improved).
    cpu_seconds : float
    """

    K: np.ndarray
    x0: np.ndarray
    iterations: int
    logdet_start: float
    logdet_end: float
    spectral_radius: float
    converged: bool
    cpu_seconds: float


def _rho(A) -> float:
    """Spectral radius of ``A`` (infinite when ``A`` is not finite).

    LAPACK's ``dgeev`` without eigenvectors called directly, the routine
    ``numpy.linalg.eigvals`` calls: at the 8 states of the flutter and robot-arm sets
    numpy's checks and dispatch were a quarter of the call (37 against 51 us), and
    :func:`_iterate` tests every trial step against the margin (143 tests for 25 accepted
    steps on flutter)."""
    if not np.size(A):
        return 0.0
    if not np.isfinite(A).all():
        return np.inf
    wr, wi, _, _, info = _GEEV(A, compute_vl=0, compute_vr=0)
    if info:                     # no convergence (never seen): numpy's call raises there
        return float(np.max(np.abs(np.linalg.eigvals(A))))
    return math.sqrt(max((wr * wr + wi * wi).tolist()))


_GEEV = scipy.linalg.lapack.dgeev


def _ml_weight(E: np.ndarray, S: np.ndarray | None = None) -> np.ndarray:
    """``W`` with ``W^T W = cov(E)^-1``: ``E W^T`` has unit covariance (``S``: that
    covariance ``E^T E / N`` when the caller has it already)."""
    p = E.shape[1]
    S = (E.T @ E) / E.shape[0] if S is None else S
    S = S + 1e-12 * np.trace(S) / p * np.eye(p)
    return np.linalg.cholesky(np.linalg.inv(S)).T


def _logdet(E: np.ndarray, S: np.ndarray | None = None) -> float:
    return float(np.linalg.slogdet((E.T @ E) / E.shape[0] if S is None else S)[1])


def _reweighted(E: np.ndarray):
    """``(W, weighted cost, log det)`` of residuals ``E`` from one covariance ``E^T E / N``
    (the weight, the cost under it and the criterion were three passes over ``E``)."""
    S = (E.T @ E) / E.shape[0]
    W = _ml_weight(E, S)
    return W, float(np.sum((E @ W.T) ** 2)), _logdet(E, S)


def gain_iterations(n_samples: int, order: int, outputs: int) -> int:
    """Default iteration limit of :func:`refine_gain`: 30 on short records, fewer where one
    iteration is expensive (about ``N p (n p)^2`` flops for the normal equations).

    Measured (the prototype's "iterations needed" runs): the subframe
    (5114 samples, n = 30, p = 3) reaches its one-step fit in 5 iterations (97.80 %, 97.81 %
    after 20); flutter (614 samples, n = 8) creeps from a poor start and needs 30 (77.8 %
    after 5, 98.4 % after 30).
    """
    work = float(n_samples) * outputs * (order * outputs) ** 2
    return int(np.clip(round(3e8 / max(work, 1.0)), 5, 30))


def _observer_coordinates(Ap, C):
    """``(T, T^-1)`` into the rotation observer basis at the pole angles of the predictor
    ``Ap`` (:func:`trussid.plid.bases.basis_for`, radius 0.97), where ``Ap = F + G C``; the
    identity when the order is not a multiple of the outputs or no such form exists.

    Levenberg-Marquardt's diagonal damping is not invariant to the state coordinates, and
    in these it finds far better gains: validation one-step fit on flutter 86.1 % in modal
    coordinates, 99.2 % in these; robot arm 98.5 % against 99.2 % (30 iterations each).
    """
    n, p = Ap.shape[0], C.shape[0]
    eye = np.eye(n)
    if n % p or n == 0:
        return eye, eye
    sys_ = control.ss(Ap, np.zeros((n, 1)), C, np.zeros((p, 1)), 1.0)
    try:
        basis = basis_for(n, p, 1.0, model_frequencies(sys_, n // 2, 1.0), 0.97)
        _, T = from_statespace((Ap, np.zeros((n, 1)), C), basis)
        Ti = np.linalg.inv(T)
    except (IdentificationError, np.linalg.LinAlgError, ValueError):
        return eye, eye
    if not (np.all(np.isfinite(T)) and np.linalg.cond(T) < 1e8):
        return eye, eye
    return T, Ti


def _scaled(model, u, y):
    A, B, C, D = (np.asarray(M, float) for M in (model.A, model.B, model.C, model.D))
    sy = np.sqrt(np.mean(y ** 2, axis=0))
    if np.any(sy <= 0):
        raise DataError(f"output column {int(np.argmin(sy))} is identically zero")
    return A, B, C / sy[:, None], D / sy[:, None], y / sy, sy


def _predict(Ap, Bu, C, Dp, K, u, ys, x0):
    """One-step predictions with predictor matrix ``Ap``; ``Bu = B - K D``.

    The state recursion itself (:func:`trussid.plid.kernel_common.state_sequence`), not
    :func:`trussid.plid.experiment.simulate` of a ``control.ss``: building the
    StateSpace object cost more than the recursion on short records, and the refinement
    evaluates a few hundred predictors on the flutter set.
    """
    X = state_sequence(Ap, u @ Bu.T + ys @ K.T, x0)
    return X @ C.T + u @ Dp.T


def _normal_equations(Ap, C, E, W):
    """``(J^T W^T W J, J^T W^T W e)`` of the weighted residual, ``J`` the Jacobian
    :func:`trussid.plid._linalg.modal_regressors` ``(Ap, C, E, x0=True)`` gives (columns
    ``vec K`` column-major, then ``x0``), computed in modal coordinates without forming
    ``J``.

    With ``Ap = V diag(lam) V^-1``, one of each conjugate pair kept (weight 2 folded into
    ``P = W C V``) and ``f_c[s, k]`` the signal ``e_c`` through ``1 / (z - lam_s)`` (for
    ``x0``: ``lam_s^k``), ``W J_k`` of column block ``c`` is ``Re(P diag(f_c[:, k]) V^-1)``,
    and since ``Re a Re b = Re(a b + conj(a) b) / 2``, block ``(a, b)`` of the Gram matrix
    is ``Re(V^-T (F_a F_b^T o P^T P) V^-1 + V^-H (conj(F_a) F_b^T o P^H P) V^-1) / 2``:
    sums over the record of ``n_kept^2`` products instead of ``q^2 p`` (``q = n p + n``).
    Equal to the explicit product to 1e-14 relative on the four measured sets and the
    demo's MIMO record, and 2.5x faster there on the subframe (30 states, 3 outputs:
    0.026 against 0.067 CPU s per iteration) and the MIMO record (0.089 against 0.224).
    """
    lam, V = np.linalg.eig(Ap)
    Vi = np.linalg.inv(V)
    keep, wt = _one_of_each_pair(lam)
    lam_k = lam[keep]
    CVw = (C @ V)[:, keep] * wt                         # (p, nk)
    Vi_k = Vi[keep]                                     # (nk, n)
    N, p = E.shape
    n, nk = Ap.shape[0], lam_k.size
    F = mode_signals(lam_k, E)                          # (m nk, N), m = p + 1
    m = p + 1
    # the two complex Gram matrices from one real one of [Re F; Im F] (half the flops of
    # two complex products): F F^T = Srr - Sii + i (Sri + Sri^T), conj(F) F^T = Srr + Sii
    # + i (Sri - Sri^T), with Sri = Re F (Im F)^T
    Z = np.concatenate([F.real, F.imag], axis=0)
    S = Z @ Z.T
    mk = m * nk
    Srr, Sii, Sri = S[:mk, :mk], S[mk:, mk:], S[:mk, mk:]
    G = (Srr - Sii) + 1j * (Sri + Sri.T)                # sum_k f f (no conjugate)
    Gh = (Srr + Sii) + 1j * (Sri - Sri.T)
    P = W @ CVw
    PtP, PhP = P.T @ P, P.conj().T @ P
    H = np.empty((m * n, m * n))
    for a in range(m):
        ra = slice(a * nk, (a + 1) * nk)
        for b in range(a, m):
            rb = slice(b * nk, (b + 1) * nk)
            blk = 0.5 * (Vi_k.T @ (G[ra, rb] * PtP) @ Vi_k
                         + Vi_k.conj().T @ (Gh[ra, rb] * PhP) @ Vi_k).real
            H[a * n:(a + 1) * n, b * n:(b + 1) * n] = blk
            H[b * n:(b + 1) * n, a * n:(a + 1) * n] = blk.T
    Q = CVw.T @ (E @ (W.T @ W)).T                       # (nk, N): sum_r CVw[r, s] z_k[r]
    g = (Vi_k.T @ np.sum(F.reshape(m, nk, N) * Q[None], axis=2).T).real.T.ravel()
    return H, g


def _solve(H, g, lm):
    dg = np.diag(H).copy()
    Hd = H.copy()
    Hd[np.diag_indices_from(Hd)] += lm * (dg + 1e-12 * max(float(dg.max()), 1e-300))
    # Cholesky without scipy.linalg.solve's condition warning: the damping keeps Hd
    # positive definite, and a noiseless record makes H nearly singular by nature. LAPACK
    # directly: scipy's cho_factor/cho_solve wrappers cost 4x the factorisation itself at
    # the 16 unknowns of the flutter set (solved some 40 times per refinement)
    if np.all(np.isfinite(Hd)):
        c, info = scipy.linalg.lapack.dpotrf(Hd, lower=0, clean=0, overwrite_a=1)
        if info == 0:
            x, info = scipy.linalg.lapack.dpotrs(c, g, lower=0)
            if info == 0:
                return x
    return np.linalg.lstsq(Hd, g, rcond=None)[0]


def refine_gain(model: control.StateSpace, u, y, K0, *, iterations: int | None = None,
                margin: float = 0.999, tol: float | None = 1e-5) -> GainFit:
    """Predictor gain ``K`` (and x0) by prediction error with ``A, B, C, D`` fixed.

    Parameters
    ----------
    model : control.StateSpace
        Discrete model with a stable ``A`` (an identified, stabilised model).
    u : array (N, m)
    y : array (N, p)
        The identification record (never the validation record).
    K0 : array (n, p)
        Start; its predictor ``A - K0 C`` must be stable (``K0 = 0`` always is for a stable
        ``A``).
    iterations : int, optional
        Iteration limit; default :func:`gain_iterations`.
    margin : float
        Steps that would put the predictor's spectral radius at or beyond ``margin`` are
        rejected (if the start already lies beyond it, the start's radius is the margin).
        0.999 cost at most 0.04 points of one-step fit on the four measured sets; 0.995
        cost up to 4.7 (the prototype's margin table).
    tol : float or None
        Stop when an accepted step lowers the weighted criterion by less than this
        fraction. None: stop when a step is no longer significant
        (:func:`significant_change`).

    Returns
    -------
    GainFit
    """
    c0 = time.process_time()
    run = _start(model, u, y, K0, margin)
    _iterate(run, gain_iterations(*run.ys.shape[:1], *run.C.shape[::-1])
             if iterations is None else int(iterations), tol)
    return _result(run, time.process_time() - c0)


@dataclass
class _Run:
    """One Levenberg-Marquardt refinement in progress (private: :func:`refine_gain` and the
    race of :func:`refine_gain_from` resume it, so that a start that leads the race
    continues exactly as an uninterrupted refinement would)."""

    A: np.ndarray            # model in the observer coordinates, outputs scaled
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    u: np.ndarray
    ys: np.ndarray
    sy: np.ndarray
    Ti: np.ndarray
    margin: float
    K: np.ndarray
    x0: np.ndarray
    E: np.ndarray
    Ap: np.ndarray
    r: float
    W: np.ndarray
    cost: float
    logdet_start: float
    logdet: float = np.nan   # of the current residuals E
    lm: float = 1e-4
    iterations: int = 0
    converged: bool = False


def _evaluate(run: _Run, K_, x0_, W_):
    """``(weighted cost, residuals, predictor matrix, its spectral radius)`` of a gain; an
    infinite cost (and no residuals) beyond the margin or on overflow."""
    Ap = run.A - K_ @ run.C
    r = _rho(Ap)
    if r >= run.margin:
        return np.inf, None, Ap, r
    with np.errstate(all="ignore"):
        E_ = run.ys - _predict(Ap, run.B - K_ @ run.D, run.C, run.D, K_, run.u, run.ys, x0_)
    if not np.all(np.isfinite(E_)):
        return np.inf, None, Ap, r
    return float(np.sum((E_ @ W_.T) ** 2)), E_, Ap, r


def _start(model, u, y, K0, margin, coordinates: bool = True) -> _Run:
    """The refinement's state at its start: ``x0`` by least squares, the
    maximum-likelihood weight, then the observer coordinates (:func:`_to_observer`).
    ``coordinates`` False: left in the model's own coordinates, where the start's
    ``log det`` is the same (the race's probe of a start, :func:`refine_gain_from`: the
    observer coordinates were 35-60 % of a start's cost on the measured sets)."""
    u = np.asarray(u, float)
    y = np.asarray(y, float)
    A, B, C, D, ys, sy = _scaled(model, u, y)
    n, p = C.shape[1], C.shape[0]
    N = u.shape[0]
    if _rho(A) >= 1:
        raise DataError("a predictor gain is fitted for a stable model; stabilise it first")
    K = np.asarray(K0, float) * sy[None, :]          # K acts on scaled outputs
    if K.shape != (n, p):
        raise DataError(f"start gain K0 has shape {K.shape}, the model needs {(n, p)}")
    Ti = np.eye(n)
    rho0 = _rho(A - K @ C)
    if rho0 >= 1:
        raise DataError("the start gain's predictor A - K C is unstable")
    run = _Run(A=A, B=B, C=C, D=D, u=u, ys=ys, sy=sy, Ti=Ti,
               margin=max(float(margin), rho0 + 1e-9), K=K, x0=np.zeros(n), E=None,
               Ap=None, r=rho0, W=np.eye(p), cost=np.inf, logdet_start=np.nan)
    _, E, Ap, _ = _evaluate(run, K, run.x0, run.W)
    W = _ml_weight(E)
    # x0 first (linear, one least squares): otherwise the first step is spent on the start
    # (real modal coordinates and the package's least squares: the complex regressors and
    # an SVD solve were a fifth of a start's time on the subframe record)
    Jx, P = real_modal_regressors(Ap, C, np.zeros((N, 0)), x0=True)
    Jxw = (Jx.transpose(0, 2, 1) @ W.T).transpose(0, 2, 1).reshape(N * p, n)
    run.x0 = P @ lstsq(Jxw, (E @ W.T).ravel())
    _, run.E, run.Ap, run.r = _evaluate(run, K, run.x0, W)
    run.W, run.cost, run.logdet = _reweighted(run.E)
    run.logdet_start = run.logdet
    if coordinates:
        _to_observer(run)
    return run


def _to_observer(run: _Run) -> None:
    """A start (:func:`_start`, made in the model's coordinates) moved into the observer
    coordinates of :func:`_observer_coordinates` (in place); the residuals, weight, cost
    and ``log det`` do not depend on the coordinates."""
    T, Ti = _observer_coordinates(run.Ap, run.C)
    run.A, run.B, run.C, run.K = T @ run.A @ Ti, T @ run.B, run.C @ Ti, T @ run.K
    run.x0, run.Ti = T @ run.x0, run.Ti @ Ti
    run.Ap = run.A - run.K @ run.C


def significant_change(n_samples: int, order: int, outputs: int) -> float:
    """The smallest decrease of ``log det`` of the innovation covariance that a step of
    :func:`refine_gain` must make to go on: ``q / N``, the ``q = n p + n`` parameters
    (``K`` and ``x0``) over the ``N`` samples.

    ``N`` times a decrease of ``log det`` is the likelihood-ratio statistic of Gaussian
    innovations; with the parameters at their optimum it is about chi-squared with ``q``
    degrees of freedom, mean ``q``: a step that gains less than ``q / N`` moves ``K``
    by less than its own estimation error. Measured on the four measured sets of
    ``benchmarks/bench_realdata.py`` (validation one-step fit, the fixed 1e-5 relative
    tolerance -> this stop): robot arm 12 -> 9 iterations, 99.17 -> 99.17 %; flutter 28 ->
    21, 99.22 -> 99.21; CD arm 30 -> 9, 90.90 -> 90.71.
    """
    return (order * outputs + order) / max(int(n_samples), 1)


def _iterate(run: _Run, iterations: int, tol: float | None) -> None:
    """Up to ``iterations`` more accepted Levenberg-Marquardt steps on ``run`` (in place),
    fewer when it converges (``tol`` None: :func:`significant_change`)."""
    n, p = run.C.shape[1], run.C.shape[0]
    least = None if tol is not None else significant_change(run.ys.shape[0], n, p)
    for _ in range(iterations):
        if run.converged:
            return
        H, g = _normal_equations(run.Ap, run.C, run.E, run.W)  # q = n p + n: vec K, x0
        for _retry in range(8):
            d = _solve(H, g, run.lm)
            for _half in range(4):
                # a step that crosses the margin is shortened (the direction is still a
                # descent direction); one that merely fails to descend raises lm
                Kn = run.K + d[:n * p].reshape(p, n).T
                x0n = run.x0 + d[n * p:]
                cn, En, Apn, rn = _evaluate(run, Kn, x0n, run.W)
                if En is not None:
                    break
                d = d / 2
            if cn < run.cost:
                break
            run.lm *= 10.0
        else:
            run.converged = True                     # no step improves: a (local) minimum
            return
        run.lm = max(run.lm / 10.0, 1e-9)
        rel = (run.cost - cn) / run.cost
        before = run.logdet
        run.K, run.x0, run.E, run.Ap, run.r = Kn, x0n, En, Apn, rn
        run.W, run.cost, run.logdet = _reweighted(run.E)
        run.iterations += 1
        if (rel < tol) if least is None else (before - run.logdet < least):
            run.converged = True
            return


def _result(run: _Run, cpu_seconds: float) -> GainFit:
    return GainFit(K=run.Ti @ run.K / run.sy[None, :], x0=run.Ti @ run.x0,
                   iterations=run.iterations, logdet_start=run.logdet_start,
                   logdet_end=run.logdet, spectral_radius=run.r,
                   converged=run.converged, cpu_seconds=cpu_seconds)

#: Iterations every start of :func:`refine_gain_from` gets before the leader is kept.
RACE_ITERATIONS = 2

#: A start of :func:`refine_gain_from` whose ``log det`` at the start lies more than this
#: above the lowest start's is dropped before the race. Measured (start gap -> gap after
#: the 2 race iterations, positive: K = 0 behind the chosen candidate) on the four
#: measured sets of ``benchmarks/bench_realdata.py`` and the demo's four identifications
#: (``benchmarks/results/realdata_i36.md``): robot arm 0.95 -> 0.58, flutter 3.07 -> 2.53,
#: subframe 1.21 -> 3.05, demo SIMO 0.25 -> 0.87, 0.39 -> 1.00, 0.00 -> 0.00 and MIMO
#: 0.15 -> -0.23 (the one record where K = 0 wins). A start gained at most 0.54 on the
#: other in two iterations, so a start 1.0 behind (a factor e in the innovation
#: determinant) is taken as unable to win; on flutter and the subframe it saved the two
#: race iterations of K = 0, and no kept start changed.
RACE_GAP = 1.0

#: Starts of :func:`refine_gain_from` within this of the lowest ``log det`` after the race
#: are tied (when ``tol`` is None; else ``tol`` itself).
TIE_TOL = 1e-5


@dataclass(frozen=True)
class GainRace:
    """The refinement of :func:`refine_gain_from`: the kept start and the race behind it.

    Attributes
    ----------
    start : str
        Label of the start whose refinement is returned.
    fit : GainFit
        That refinement (its ``iterations`` count the race's; its ``cpu_seconds`` are the
        whole race's).
    race_logdet : dict
        ``{label: log det}`` of every distinct start after the race iterations (outputs
        scaled to unit RMS; lower is better), or at its start for a start that did not
        race (:data:`RACE_GAP`); the kept start has the lowest.
    """

    start: str
    fit: GainFit
    race_logdet: dict


def refine_gain_from(model: control.StateSpace, u, y, starts: dict, *,
                     iterations: int | None = None, race: int = RACE_ITERATIONS,
                     margin: float = 0.999, tol: float | None = 1e-5,
                     race_gap: float = RACE_GAP) -> GainRace:
    """:func:`refine_gain` from several starts, the one with the lowest identification
    criterion kept.

    The criterion (``log det`` of the innovation covariance with ``A, B, C, D`` fixed) is
    not convex in ``K``, and Levenberg-Marquardt from different starts stops in different
    places: on the demo's MIMO record (36 states, 3 x 3) the best candidate gain refined to
    ``log det`` -29.16 and K = 0 to -30.27 in the same 5 iterations (validation one-step
    41.4 against 43.6 dB), while on the flutter set K = 0 stalls at -5.0 against -13.7
    from the best candidate. Every distinct start is refined for ``race`` iterations (a
    start more than ``race_gap`` behind the best one at the start does not race); the
    one with the lowest criterion then continues for the rest of the iteration limit
    (successive halving: the losers cost ``race`` iterations each, not a whole refinement).
    The choice reads the identification record only; a start within ``tol`` of the lowest
    criterion after the race (in log det: a relative change of the determinant) counts as
    tied, and ties go to the earlier start.

    Parameters
    ----------
    model : control.StateSpace
        Discrete model with a stable ``A``.
    u : array (N, m)
    y : array (N, p)
        The identification record (never the validation record).
    starts : dict
        ``{label: K0}``, each ``(n, p)`` with a stable predictor; starts equal to an
        earlier one are dropped, and a start whose refinement fails (an unstable start
        predictor) drops out of the race.
    iterations : int, optional
        Iteration limit of the kept refinement, race included; default
        :func:`gain_iterations`.
    race : int
        Iterations every start gets before the leader is chosen.
    race_gap : float
        A start whose ``log det`` at the start (after its initial-state fit) lies more than
        this above the lowest start's does not race (:data:`RACE_GAP`; ``inf``: every
        start races).
    margin : float
        As in :func:`refine_gain`.
    tol : float or None
        As in :func:`refine_gain` (None: the significance stop; ties within
        :data:`TIE_TOL`).

    Returns
    -------
    GainRace
    """
    c0 = time.process_time()
    u = np.asarray(u, float)
    y = np.asarray(y, float)
    n, p = np.asarray(model.C).shape[1], np.asarray(model.C).shape[0]
    iterations = (gain_iterations(u.shape[0], n, p) if iterations is None
                  else int(iterations))
    distinct = []
    for label, K0 in starts.items():
        K0 = np.asarray(K0, float)
        if not any(K0.shape == K.shape and np.array_equal(K0, K) for _, K in distinct):
            distinct.append((label, K0))
    if not distinct:
        raise DataError("no start gain given")
    if len(distinct) == 1:
        label, K0 = distinct[0]
        fit = refine_gain(model, u, y, K0, iterations=iterations, margin=margin, tol=tol)
        return GainRace(label, fit, {label: fit.logdet_end})
    runs, error = {}, None
    first = min(race, iterations)
    for label, K0 in distinct:
        try:
            # every start probed for its start value first (RACE_GAP), in the model's
            # coordinates, and moved into the observer coordinates only if it races
            runs[label] = _start(model, u, y, K0, margin, coordinates=False)
        except (DataError, np.linalg.LinAlgError) as exc:
            error = exc
    if not runs:
        raise DataError(f"no start gain could be refined ({error})")
    # a start too far behind at the start cannot win the race (RACE_GAP): it keeps its
    # start value and drops out; the runs are independent, so the others are unchanged
    heats = {lab: run.logdet for lab, run in runs.items()}
    lowest = min(heats.values())
    for label, _ in distinct:
        if label not in runs:
            continue
        if heats[label] > lowest + race_gap:
            del runs[label]
            continue
        _to_observer(runs[label])
        _iterate(runs[label], first, tol)
        heats[label] = runs[label].logdet
    # ties go to the earlier start (the chosen candidate comes first): two starts that
    # reach the same point differ at rounding level, and a rounding-level winner would make
    # the kept start depend on BLAS summation order
    best = min(heats[lab] for lab in runs)
    tie = TIE_TOL if tol is None else tol
    label = next(lab for lab, h in heats.items() if lab in runs and h <= best + tie)
    _iterate(runs[label], iterations - runs[label].iterations, tol)
    return GainRace(label, _result(runs[label], time.process_time() - c0), heats)
