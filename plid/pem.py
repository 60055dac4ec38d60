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

import time
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from trussid.plid.bases import basis_for, model_frequencies
from trussid.plid.canonical import from_statespace
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.experiment import simulate
from trussid.plid._linalg import modal_regressors

__all__ = ["GainFit", "refine_gain", "gain_iterations"]


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
    return float(np.max(np.abs(np.linalg.eigvals(A)), initial=0.0)) if np.size(A) else 0.0


def _ml_weight(E: np.ndarray) -> np.ndarray:
    """``W`` with ``W^T W = cov(E)^-1``: ``E W^T`` has unit covariance."""
    p = E.shape[1]
    S = (E.T @ E) / E.shape[0]
    S = S + 1e-12 * np.trace(S) / p * np.eye(p)
    return np.linalg.cholesky(np.linalg.inv(S)).T


def _logdet(E: np.ndarray) -> float:
    return float(np.linalg.slogdet((E.T @ E) / E.shape[0])[1])


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
    """One-step predictions with predictor matrix ``Ap``; ``Bu = B - K D``."""
    n, p = C.shape[1], C.shape[0]
    pred = control.ss(Ap, np.hstack([Bu, K]), C, np.hstack([Dp, np.zeros((p, p))]), 1.0)
    return simulate(pred, np.hstack([u, ys]), x0)


def _normal_equations(J, E, W):
    """``(J^T W^T W J, J^T W^T W e)`` of the weighted residual; ``J`` (N, p, q)."""
    N, p, q = J.shape
    JW = (J.transpose(0, 2, 1) @ W.T).transpose(0, 2, 1).reshape(N * p, q)   # (W J_k) rows
    rW = (E @ W.T).ravel()
    H = JW.T @ JW
    g = JW.T @ rW
    return H, g


def _solve(H, g, lm):
    dg = np.diag(H).copy()
    Hd = H.copy()
    Hd[np.diag_indices_from(Hd)] += lm * (dg + 1e-12 * max(float(dg.max()), 1e-300))
    try:
        # Cholesky without scipy.linalg.solve's condition warning: the damping keeps Hd
        # positive definite, and a noiseless record makes H nearly singular by nature
        return scipy.linalg.cho_solve(scipy.linalg.cho_factor(Hd, check_finite=False), g,
                                      check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return np.linalg.lstsq(Hd, g, rcond=None)[0]


def refine_gain(model: control.StateSpace, u, y, K0, *, iterations: int | None = None,
                margin: float = 0.999, tol: float = 1e-5) -> GainFit:
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
    tol : float
        Stop when an accepted step lowers the weighted criterion by less than this
        fraction.

    Returns
    -------
    GainFit
    """
    c0 = time.process_time()
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
    T, Ti = _observer_coordinates(A - K @ C, C)
    A, B, C, K = T @ A @ Ti, T @ B, C @ Ti, T @ K
    iterations = gain_iterations(N, n, p) if iterations is None else int(iterations)
    rho0 = _rho(A - K @ C)
    if rho0 >= 1:
        raise DataError("the start gain's predictor A - K C is unstable")
    margin = max(float(margin), rho0 + 1e-9)
    Bu0 = B                                           # B - K D, recomputed per K below

    def evaluate(K_, x0_, W_):
        Ap = A - K_ @ C
        r = _rho(Ap)
        if r >= margin:
            return np.inf, None, Ap, r
        with np.errstate(all="ignore"):
            E_ = ys - _predict(Ap, Bu0 - K_ @ D, C, D, K_, u, ys, x0_)
        if not np.all(np.isfinite(E_)):
            return np.inf, None, Ap, r
        return float(np.sum((E_ @ W_.T) ** 2)), E_, Ap, r

    x0 = np.zeros(n)
    _, E, Ap, r = evaluate(K, x0, np.eye(p))
    W = _ml_weight(E)
    # x0 first (linear, one least squares): otherwise the first step is spent on the start
    Jx = modal_regressors(Ap, C, np.zeros((N, 0)), x0=True)
    Jxw = (Jx.transpose(0, 2, 1) @ W.T).transpose(0, 2, 1).reshape(N * p, n)
    x0 = np.linalg.lstsq(Jxw, (E @ W.T).ravel(), rcond=None)[0]
    cost, E, Ap, r = evaluate(K, x0, W)
    W = _ml_weight(E)
    cost = float(np.sum((E @ W.T) ** 2))
    ld0 = _logdet(E)
    lm, it, converged = 1e-4, 0, False
    for _ in range(iterations):
        J = modal_regressors(Ap, C, E, x0=True)      # (N, p, n p + n): vec K, then x0
        H, g = _normal_equations(J, E, W)
        for _retry in range(8):
            d = _solve(H, g, lm)
            for _half in range(4):
                # a step that crosses the margin is shortened (the direction is still a
                # descent direction); one that merely fails to descend raises lm
                Kn = K + d[:n * p].reshape(p, n).T
                x0n = x0 + d[n * p:]
                cn, En, Apn, rn = evaluate(Kn, x0n, W)
                if En is not None:
                    break
                d = d / 2
            if cn < cost:
                break
            lm *= 10.0
        else:
            converged = True                         # no step improves: a (local) minimum
            break
        lm = max(lm / 10.0, 1e-9)
        rel = (cost - cn) / cost
        K, x0, E, Ap, r = Kn, x0n, En, Apn, rn
        W = _ml_weight(E)
        cost = float(np.sum((E @ W.T) ** 2))
        it += 1
        if rel < tol:
            converged = True
            break
    return GainFit(K=Ti @ K / sy[None, :], x0=Ti @ x0, iterations=it, logdet_start=ld0,
                   logdet_end=_logdet(E), spectral_radius=r, converged=converged,
                   cpu_seconds=time.process_time() - c0)
