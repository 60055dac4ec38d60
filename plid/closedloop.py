"""Closed-loop records: a predictor-based subspace prior (PBSID) and the detection of feedback.

Under feedback the input is correlated with past noise. Open-loop subspace methods (N4SID,
MOESP: :mod:`trussid.plid.subspace`) assume future inputs uncorrelated with past
disturbances and are biased there: on a measured closed-loop record (a piezo cantilever
under LQ control, excited mostly by an unmeasured push) the default ``trussid identify`` put
the first mode at 10.3 Hz instead of 8.2 Hz (issue 34). Predictor-based methods identify the
one-step *predictor* instead, whose regressors are past inputs and outputs only, so the
feedback does no harm as long as the controller does not use ``y_k`` to form ``u_k`` (a
computation delay, as every sampled controller here has).

:func:`pbsid` is the VARX-based predictor subspace method (PBSID; Chiuso, "The role of vector
autoregressive modeling in predictor-based subspace identification", Automatica 43, 2007;
the overview of van der Veen, van Wingerden, Bergamasco, Lovera and Verhaegen, IET Control
Theory Appl. 7, 2013):

1. a VARX model of ``past`` lags, ``y_k = sum_j C Ak^(j-1) [Bk K] z_(k-j) + D u_k + e_k`` with
   ``z = [u; y]`` and ``Ak = A - K C``, by one least squares;
2. the product of the extended observability and controllability matrices of the
   predictor from its Markov parameters (``Ak^past`` taken as zero), the state sequence
   from the SVD of that product times the past data;
3. ``C, D`` by least squares on the state, then ``A, B, K`` by least squares of the state
   update with the innovations.

Why written here: the maintained Python implementation of a closed-loop subspace method,
``sippy-unipi`` (PARSIM-K, in the project's ``bench`` extra as a comparator), requires casadi,
sympy and tf2ss at install time, and its PARSIM-K simulates the predictor once per
parameter in Python loops (``n (m + p + 1)`` simulations: minutes at 36 states on 10^4
samples); this one is a few dense least squares and one SVD.

:func:`feedback_share` decides whether a record is closed loop from a reference (dither)
channel: the share of the input's power that the reference does not explain.

The prior's measured limits (``tests/plid/test_closedloop.py``'s two-mode plant, velocity feedback, dither
10 % of the control signal, 10^4 samples): open-loop N4SID misses a mode by over 10 % in
frequency; PBSID is within 2.5 % in frequency but up to 82 % off in damping with a velocity
sensor, within 0.6-0.9 % and 36-49 % with a displacement sensor. A velocity or acceleration
output of a force has a zero at ``z = 1``, which puts a predictor pole near it (0.995 on that
plant): the VARX then needs far more lags than the record supports, and its truncation
biases the damping. A PLID pass from this prior (output error, biased under feedback) pulled
the modes off again.

:func:`prediction_error_fit` is therefore the refinement used under feedback (Ljung's direct
method): the one-step prediction error of the whole innovations model ``(A, B, C, K)`` is
minimised, which is consistent under feedback (the noise model ``K`` is free, the plant has
a sample of delay), where an output-error (simulation) criterion such as PLID's passes with
``Q = 0`` is not. It parametrises the *predictor* ``(A - K C, [B - K D, K], C)`` in real
modal form with its poles kept inside the unit circle, so the slow predictor pole of a
velocity or acceleration output costs nothing (the predictor is simulated, not truncated).
:func:`trussid.plid.recipe.identify` with ``closed_loop=True`` runs :func:`closed_loop_prior`
then :func:`prediction_error_fit`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg
import scipy.optimize

from trussid.plid._validate import as_2d
from trussid.plid.errors import DataError, IdentificationError
from trussid.plid.kernel_common import state_sequence
from trussid.plid.pem import refine_gain
from trussid.plid.stability import stabilise

__all__ = ["PBSIDFit", "pbsid", "closed_loop_prior", "feedback_share", "FEEDBACK_SHARE",
           "ClosedLoopPrior", "PredictionErrorFit", "prediction_error_fit", "ClosedLoopFit",
           "identify_closed_loop", "NO_PLID_PASS"]

#: A record whose input is less than this share explained by its reference channel (the rest
#: is feedback) is closed loop (:func:`feedback_share`).
FEEDBACK_SHARE = 0.1
#: Samples the closed-loop recipe's PBSID prior uses at most (:func:`identify_closed_loop`).
PRIOR_SAMPLES = 200000


@dataclass(frozen=True)
class PBSIDFit:
    """What :func:`pbsid` estimated.

    Attributes
    ----------
    model : control.StateSpace
        ``(A, B, C, D)`` of the innovation form, sample time ``dt``.
    K : ndarray (n, p)
        Its Kalman (innovation) gain: ``x+ = A x + B u + K e``, ``y = C x + D u + e``.
    past, future : int
        VARX lags and future horizon used.
    singular_values : ndarray
        Of the weighted observability-times-controllability product (order selection).
    innovation_variance : ndarray (p,)
        Of the VARX residual, per output (original units).
    """

    model: control.StateSpace
    K: np.ndarray
    past: int
    future: int
    singular_values: np.ndarray
    innovation_variance: np.ndarray


def _past_matrix(z: np.ndarray, past: int) -> np.ndarray:
    """(N - past, past * c): row ``k`` holds ``z[k], ..., z[k + past - 1]`` (oldest first): the
    regressor of sample ``k + past``."""
    w = np.lib.stride_tricks.sliding_window_view(z, past, axis=0)  # (N - past + 1, c, past)
    return np.ascontiguousarray(w[:-1].transpose(0, 2, 1).reshape(w.shape[0] - 1, -1))


def pbsid(u, y, n: int, dt: float, *, past: int = 40, future: int | None = None,
          direct: bool = False, ridge: float = 1e-8) -> PBSIDFit:
    """Predictor-based subspace identification (VARX form) of an order-``n`` innovation model.

    Consistent on closed-loop data when the controller has at least one sample of delay
    (module docstring).

    Parameters
    ----------
    u : array (N, m)
        Inputs (the controller's output plus any dither).
    y : array (N, p)
        Outputs.
    n : int
        Order.
    dt : float
        Sample time [s].
    past : int
        VARX lags: long enough that the predictor's impulse response ``Ak^past`` has died
        out (a predictor of a lightly damped plant whose disturbance dominates the noise
        is well damped; 20-80 samples cover the structures measured here).
    future : int, optional
        Future horizon of the observability matrix (default ``past``; at least
        ``n / p + 1``).
    direct : bool
        Estimate a direct term ``D`` (``u_k`` in the VARX; else ``D = 0``).
    ridge : float
        Tikhonov regularisation of the VARX least squares, relative to the mean diagonal
        of its Gram matrix (keeps it solvable when an input is narrow-band).

    Returns
    -------
    PBSIDFit

    Examples
    --------
    A mode at 50 Hz (2 % damping) under proportional output feedback through one sample of
    delay, excited by an unmeasured force and a small dither: PBSID finds the open-loop mode
    (N4SID on the same record: 50.46 Hz at 1.0 % damping).

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid.closedloop import pbsid
    >>> from trussid.plid import modal_table
    >>> w, dt = 2 * np.pi * 50.0, 1e-3
    >>> G = control.c2d(control.ss([[0, 1], [-w**2, -0.04 * w]], [[0, 0], [1, 1]],
    ...                            [[w**2, 0]], 0), dt)
    >>> rng = np.random.default_rng(0)
    >>> N = 8000
    >>> d, r = rng.standard_normal(N), 0.1 * rng.standard_normal(N)
    >>> x, u, y = np.zeros(2), np.zeros(N), np.zeros(N)
    >>> for k in range(N):
    ...     y[k] = (G.C @ x)[0] + 1e-3 * rng.standard_normal()
    ...     u[k] = r[k] - 0.05 * (y[k - 1] if k else 0.0)
    ...     x = G.A @ x + G.B @ np.array([u[k], d[k]])
    >>> modes = modal_table(pbsid(u, y, 2, dt, past=20).model)
    >>> print(np.round(modes.frequencies_hz, 1), np.round(100 * modes.damping, 1))
    [50.1] [2.1]
    """
    u = as_2d(u, "u", finite=True)
    y = as_2d(y, "y", finite=True)
    if u.shape[0] != y.shape[0]:
        raise DataError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    N, m = u.shape
    p = y.shape[1]
    past = int(past)
    f = int(future if future is not None else past)
    if int(n) != n or n < 1:
        raise IdentificationError(f"order must be a positive integer, got {n!r}")
    if f * p < n or past * p < n:
        raise IdentificationError(f"PBSID with past {past} and future {f} and {p} outputs "
                                  f"gives at most order {min(f, past) * p}, not {n}")
    cols = past * (m + p) + (m if direct else 0)
    if N - past < 2 * cols:
        raise DataError(f"PBSID with {past} lags needs at least {past + 2 * cols} samples, "
                        f"got {N}")
    # every channel scaled to unit RMS: the VARX and the SVD weigh channels alike
    su = np.sqrt(np.mean(u ** 2, axis=0))
    sy = np.sqrt(np.mean(y ** 2, axis=0))
    su[su == 0], sy[sy == 0] = 1.0, 1.0
    us, ys = u / su, y / sy
    z = np.hstack([us, ys])
    Z = _past_matrix(z, past)                       # (N - past, past (m + p))
    X = np.hstack([Z, us[past:]]) if direct else Z
    Yt = ys[past:]
    G = X.T @ X
    G[np.diag_indices_from(G)] += ridge * np.trace(G) / G.shape[0]
    theta = scipy.linalg.solve(G, X.T @ Yt, assume_a="pos").T    # (p, cols)
    Xi = theta[:, :past * (m + p)]                  # Markov parameters, oldest lag first
    D = theta[:, past * (m + p):] if direct else np.zeros((p, m))
    res = Yt - X @ theta.T
    # Gamma_f K_past: block row i is C Ak^i [Ak^(past-1) Bbar ... Bbar] = Xi shifted right by
    # i blocks (Ak^past and higher powers taken as zero)
    c = m + p
    GK = np.zeros((f * p, past * c))
    for i in range(f):
        GK[i * p:(i + 1) * p, i * c:] = Xi[:, :(past - i) * c] if i < past else 0.0
    # SVD of GK Z^T through the Cholesky factor of Z^T Z (the same left singular vectors and
    # values, without the (f p) x N product's SVD)
    L = np.linalg.cholesky(Z.T @ Z + 1e-12 * np.trace(Z.T @ Z) * np.eye(Z.shape[1]))
    U, s, _ = np.linalg.svd(GK @ L, full_matrices=False)
    if s[n - 1] <= 0:
        raise IdentificationError(f"PBSID found fewer than {n} states in the data")
    Xs = ((U[:, :n].T @ GK) @ Z.T) / np.sqrt(s[:n])[:, None]   # (n, N - past) states
    # C, D by least squares on the state (D from the VARX when asked for: the state
    # sequence is a function of past data only, so u_k stays exogenous here)
    Yl = Yt.T - D @ us[past:].T
    Cn = scipy.linalg.lstsq(Xs.T, Yl.T, lapack_driver="gelsy")[0].T
    E = Yl - Cn @ Xs                                # innovations
    Reg = np.vstack([Xs[:, :-1], us[past:-1].T, E[:, :-1]])
    ABK = scipy.linalg.lstsq(Reg.T, Xs[:, 1:].T, lapack_driver="gelsy")[0].T
    A, Bn, Kn = ABK[:, :n], ABK[:, n:n + m], ABK[:, n + m:]
    # back to the original units
    B = Bn / su[None, :]
    C = Cn * sy[:, None]
    Dd = D * sy[:, None] / su[None, :]
    K = Kn / sy[None, :]
    model = control.ss(A, B, C, Dd, dt)
    return PBSIDFit(model, K, past, f, s, np.var(res, axis=0) * sy ** 2)


@dataclass(frozen=True)
class ClosedLoopPrior:
    """How :func:`closed_loop_prior` chose its PBSID model (for the provenance).

    Attributes
    ----------
    past : int
        The VARX lags kept.
    candidates : dict of int to float
        One-step prediction ratio [dB] of the PBSID model (with its own gain ``K``) on the
        held-out last quarter of the record, for each ``past`` tried.
    reflected_poles : int
        Poles outside the unit circle reflected in.
    direct : bool
        Whether ``D`` was estimated.
    """

    past: int
    candidates: dict
    reflected_poles: int
    direct: bool


def _one_step_db(model, K, u, y, skip):
    A, B, C, D = (np.asarray(getattr(model, k), float) for k in "ABCD")
    Ak, Bk = A - K @ C, B - K @ D
    if np.max(np.abs(np.linalg.eigvals(Ak)), initial=0) >= 1:
        return -np.inf
    pred = control.ss(Ak, np.hstack([Bk, K]), C, np.hstack([D, np.zeros((C.shape[0],) * 2)]),
                      model.dt)
    yh = control.forced_response(pred, U=np.hstack([u, y]).T).outputs
    yh = np.atleast_2d(yh).T
    e = (y - yh)[skip:]
    return float(-10 * np.log10(np.mean(np.mean(e ** 2, 0) / np.mean(y[skip:] ** 2, 0))))


def closed_loop_prior(u, y, n: int, dt: float, *, direct: bool = False, pasts=None):
    """A closed-loop-consistent order-``n`` prior: :func:`pbsid` at the ``past`` that predicts
    the held-out last quarter of the record best, then fitted again on the whole record.

    Parameters
    ----------
    u : array (N, m)
        Inputs.
    y : array (N, p)
        Outputs.
    n : int
        Order.
    dt : float
        Sample time [s].
    direct : bool
        Estimate ``D``.
    pasts : sequence of int, optional
        VARX lags to try (default 20, 40 and 80, at least ``n / p + 1``, those the record is
        long enough for).

    Returns
    -------
    model : control.StateSpace
        Stable (unstable poles reflected in).
    K : ndarray (n, p)
        PBSID's innovation gain (of the model before reflection).
    info : ClosedLoopPrior
    """
    u = as_2d(u, "u", finite=True)
    y = as_2d(y, "y", finite=True)
    N, m = u.shape
    p = y.shape[1]
    lo = -(-n // p) + 1
    if pasts is None:
        pasts = sorted({max(lo, s) for s in (20, 40, 80)})
    cut = (3 * N) // 4
    pasts = [int(s) for s in pasts
             if cut - s >= 2 * (s * (m + p) + m) and s * p >= n]
    if not pasts:
        raise IdentificationError(f"{N} samples are too few for a closed-loop subspace "
                                  f"estimate of order {n}")
    scores = {}
    for s in pasts:
        try:
            fit = pbsid(u[:cut], y[:cut], n, dt, past=s, direct=direct)
        except (IdentificationError, np.linalg.LinAlgError):
            scores[s] = -np.inf
            continue
        # the held-out quarter's predictor starts from x = 0: skip its transient
        scores[s] = _one_step_db(fit.model, fit.K, u[cut:], y[cut:], min(s, (N - cut) // 4))
    best = max(scores, key=lambda k: scores[k])
    if not np.isfinite(scores[best]):
        raise IdentificationError("the closed-loop subspace estimate failed at every "
                                  f"horizon tried ({', '.join(map(str, pasts))})")
    fit = pbsid(u, y, n, dt, past=best, direct=direct)
    model, reflected = fit.model, 0
    lam = np.abs(np.linalg.eigvals(np.asarray(model.A, float)))
    if np.any(lam >= 1):
        reflected = int(np.sum(lam >= 1))
        model = stabilise(model).model
    return model, fit.K, ClosedLoopPrior(best, {k: float(v) for k, v in scores.items()},
                                         reflected, bool(direct))


def feedback_share(u, r, lags: int = 20) -> np.ndarray:
    """The share of each input's power that its reference channel does not explain.

    Each input column ``u[:, j]`` is fitted by a causal FIR filter of ``lags`` taps of the
    reference ``r`` (least squares); what is left is the feedback (and noise). An open-loop
    record, whose input is its reference through the amplifier, leaves almost nothing
    (under 1 %); under feedback with a small dither it is most of the input.

    Parameters
    ----------
    u : array (N, m)
        Inputs applied to the plant.
    r : array (N, m) or (N, 1)
        Reference (dither) channels, one per input or one for all.
    lags : int
        FIR taps.

    Returns
    -------
    ndarray (m,)
        Per input, 1 - R^2 of the fit (0: the input is the reference; 1: no relation).
    """
    u = as_2d(u, "u", finite=True)
    r = as_2d(r, "reference", finite=True)
    if r.shape[0] != u.shape[0]:
        raise DataError(f"the reference has {r.shape[0]} samples but u has {u.shape[0]}")
    if r.shape[1] not in (1, u.shape[1]):
        raise DataError(f"the reference has {r.shape[1]} columns: give one, or one per "
                        f"input ({u.shape[1]})")
    # row k: r[k - lags + 1], ..., r[k] (the reference reaches the input at once)
    padded = np.vstack([np.zeros((lags - 1, r.shape[1])), r])
    R = np.lib.stride_tricks.sliding_window_view(padded, lags, axis=0).reshape(u.shape[0], -1)
    coef = scipy.linalg.lstsq(R, u, lapack_driver="gelsy")[0]
    e = u - R @ coef
    return np.mean(e ** 2, axis=0) / np.maximum(np.mean(u ** 2, axis=0), 1e-300)


@dataclass(frozen=True)
class PredictionErrorFit:
    """What :func:`prediction_error_fit` estimated (the direct method's refinement).

    Attributes
    ----------
    model : control.StateSpace
        ``(A, B, C, D)`` of the innovation form (``D`` as given, not refitted).
    K : ndarray (n, p)
        Innovation gain: the predictor is ``x+ = (A - K C) x + (B - K D) u + K y``.
    x0 : ndarray (n,)
        Initial predictor state fitted with it.
    cost_start, cost_end : float
        Mean squared one-step prediction error, outputs scaled to unit RMS, before and
        after.
    evaluations : int
        Predictor simulations run (the finite-difference Jacobian included).
    converged : bool
        scipy's ``least_squares`` stopped on a tolerance (else on its evaluation limit).
    predictor_radius : float
        Spectral radius of ``A - K C``.
    cpu_seconds : float
    """

    model: control.StateSpace
    K: np.ndarray
    x0: np.ndarray
    cost_start: float
    cost_end: float
    evaluations: int
    converged: bool
    predictor_radius: float
    cpu_seconds: float


def _real_modal(A: np.ndarray):
    """``(T, lam)``: ``T^-1 A T`` is block diagonal, a 2 x 2 block ``[[a, b], [-b, a]]`` for each
    pair ``a +- i b`` of ``lam`` (upper member listed) and a 1 x 1 block per real one."""
    lam, V = np.linalg.eig(A)
    cols, poles = [], []
    for k in np.argsort(-np.abs(np.angle(lam)), kind="stable"):
        l, v = lam[k], V[:, k]
        if abs(l.imag) <= 1e-12 * max(1.0, abs(l)):
            cols.append(v.real / np.linalg.norm(v.real))
            poles.append(complex(l.real, 0.0))
        elif l.imag > 0:
            v = v / np.linalg.norm(v)
            cols += [v.real, v.imag]
            poles.append(l)
    return np.column_stack(cols), np.array(poles)


def _block(theta_poles: np.ndarray, kinds: np.ndarray, n: int) -> np.ndarray:
    """The predictor matrix in real modal form from its pole parameters: a pair's radius is
    ``1 / (1 + exp(-s))`` and its angle free, a real pole ``tanh(s)``: every pole stays
    strictly inside the unit circle whatever the optimiser tries."""
    M = np.zeros((n, n))
    i = j = 0
    for pair in kinds:
        if pair:
            r = 1.0 / (1.0 + np.exp(-theta_poles[j]))
            a, b = r * np.cos(theta_poles[j + 1]), r * np.sin(theta_poles[j + 1])
            M[i:i + 2, i:i + 2] = [[a, b], [-b, a]]
            i, j = i + 2, j + 2
        else:
            M[i, i] = np.tanh(theta_poles[j])
            i, j = i + 1, j + 1
    return M


def _stable_gain(A, C, K, radius: float = 0.999):
    """``K`` shrunk by the largest factor in ``[0, 1]`` (bisection) that keeps the predictor
    ``A - a K C`` inside ``radius``: a VARX predictor truncated at ``past`` lags can leave one
    slow pole just outside; ``a = 0`` is the stable ``A`` itself (free-run simulation)."""
    def rho(a):
        return np.max(np.abs(np.linalg.eigvals(A - a * K @ C)), initial=0.0)

    rho0 = rho(0.0)
    if rho0 >= 1:
        raise IdentificationError("the start model is unstable: stabilise it before a "
                                  "prediction-error fit")
    # a lightly damped start pole can itself lie beyond radius: keep it then
    radius = max(radius, 0.5 * (1 + rho0))
    if rho(1.0) < radius:
        return K
    lo, hi = 0.0, 1.0
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if rho(mid) < radius else (lo, mid)
    return lo * K


def prediction_error_fit(model: control.StateSpace, K, u, y, *,
                         max_evaluations: int | None = None) -> PredictionErrorFit:
    """Refine an innovations model by minimising its one-step prediction error (the direct
    method: consistent on closed-loop records, module docstring).

    The free parameters are the predictor's poles (real modal form, kept inside the unit
    circle), its input matrix ``T^-1 [B - K D, K]``, its output matrix ``C T`` and its
    initial state; ``D`` stays as given. The criterion is the sum of squared one-step
    prediction errors with every output scaled to unit RMS (a fixed weight: consistent as
    the maximum-likelihood weight is, only less efficient on unequal noise).

    Why written here: no maintained Python package fits a state-space innovations model by
    prediction error (MATLAB's ``ssest``/``pem`` and Julia's ControlSystemIdentification
    ``newpem`` do); scipy's ``least_squares`` (trust region, finite-difference Jacobian) does
    the optimisation, the project's compiled :func:`state_sequence` each predictor run.

    Parameters
    ----------
    model : control.StateSpace
        Start (discrete), e.g. :func:`closed_loop_prior`'s model.
    K : array (n, p)
        Its innovation gain; ``A - K C`` must be stable (PBSID's is by construction of a
        VARX predictor, up to truncation).
    u : array (N, m)
        Inputs.
    y : array (N, p)
        Outputs.
    max_evaluations : int, optional
        Criterion evaluations allowed besides the finite-difference Jacobians, about one
        per Levenberg-Marquardt iteration (default 60).

    Returns
    -------
    PredictionErrorFit
    """
    # Long: scaling, the modal start, its normalisation, the x0 least squares, the
    # optimisation and the way back to original units share a dozen arrays.
    c0 = time.process_time()
    u = as_2d(u, "u", finite=True)
    y = as_2d(y, "y", finite=True)
    A, B, C, D = (np.asarray(M, float) for M in (model.A, model.B, model.C, model.D))
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    K = np.asarray(K, float)
    if K.shape != (n, p):
        raise DataError(f"the gain K has shape {K.shape}, the model needs {(n, p)}")
    if u.shape != (y.shape[0], m) or y.shape[1] != p:
        raise DataError(f"the model has {m} inputs and {p} outputs; the data have "
                        f"{u.shape[1]} and {y.shape[1]} columns")
    su = np.sqrt(np.mean(u ** 2, axis=0))
    sy = np.sqrt(np.mean(y ** 2, axis=0))
    su[su == 0], sy[sy == 0] = 1.0, 1.0
    us, ys = u / su, y / sy
    Bs, Cs, Ds, Ks = B * su[None, :], C / sy[:, None], D * su[None, :] / sy[:, None], K * sy
    Ks = _stable_gain(A, Cs, Ks)
    Ap = A - Ks @ Cs
    T, lam = _real_modal(Ap)
    if np.linalg.cond(T) > 1e10:
        raise IdentificationError("the start's predictor has (nearly) repeated poles: no "
                                  "modal form to refine it in")
    Ti = np.linalg.inv(T)
    kinds = np.abs(lam.imag) > 0
    r = np.clip(np.abs(lam), 1e-6, 1 - 1e-9)
    poles0 = np.concatenate([[np.log(rk / (1 - rk)), np.angle(lk)] if pk
                             else [np.arctanh(np.clip(lk.real, -1 + 1e-9, 1 - 1e-9))]
                             for lk, rk, pk in zip(lam, r, kinds)])
    Zs = np.hstack([us, ys])
    # each block scaled (a scaled rotation commutes with its 2 x 2 block) so that its
    # entries in the output that sees it best are (1, 0), or 1: those are then fixed, which
    # takes the modal form's n-dimensional null space of similarity out of the problem
    # (Levenberg-Marquardt crawled along it: 160 iterations instead of about 20)
    Ct0 = Cs @ T
    fixed = np.zeros((p, n), bool)
    i = 0
    for pair in kinds:
        w = 2 if pair else 1
        o = int(np.argmax(np.linalg.norm(Ct0[:, i:i + w], axis=1)))
        c = Ct0[o, i:i + w]
        if pair:
            S = np.array([[c[0], -c[1]], [c[1], c[0]]]) / (c @ c)
        else:
            S = np.array([[1.0 / c[0]]])
        T[:, i:i + w] = T[:, i:i + w] @ S
        fixed[o, i] = True
        if pair:
            fixed[o, i + 1] = True
        i += w
    Ti = np.linalg.inv(T)
    Ct0 = Cs @ T
    Bz0 = Ti @ np.hstack([Bs - Ks @ Ds, Ks])            # (n, m + p)
    Ct_fixed = np.where(fixed, Ct0, 0.0)
    free = ~fixed
    npl = poles0.size
    nb = n * (m + p)
    nc = int(free.sum())

    def unpack(th):
        M = _block(th[:npl], kinds, n)
        Bz = th[npl:npl + nb].reshape(n, m + p)
        Ct = Ct_fixed.copy()
        Ct[free] = th[npl + nb:npl + nb + nc]
        return M, Bz, Ct, th[npl + nb + nc:]

    def residual(th):
        M, Bz, Ct, x0 = unpack(th)
        X = state_sequence(M, Zs @ Bz.T, x0)
        return (ys - X @ Ct.T - us @ Ds.T).ravel()

    # x0 first: linear in it, one least squares from the start's predictor
    th0 = np.concatenate([poles0, Bz0.ravel(), Ct0[free], np.zeros(n)])
    e0 = residual(th0)
    M0 = unpack(th0)[0]
    Obs = np.empty((y.shape[0], p, n))
    Pk = np.eye(n)
    for k in range(y.shape[0]):          # C M^k: the free response to x0 (n p columns)
        Obs[k] = Ct0 @ Pk
        Pk = M0 @ Pk
        if k > 20 and not np.any(np.abs(Pk) > 1e-14):
            Obs[k + 1:] = 0.0
            break
    x0 = np.linalg.lstsq(Obs.reshape(-1, n), e0, rcond=None)[0]
    th0[npl + nb + nc:] = x0
    cost0 = float(np.mean(residual(th0) ** 2))
    q = th0.size
    budget = int(max_evaluations) if max_evaluations else 60
    sol = scipy.optimize.least_squares(residual, th0, method="lm", x_scale="jac",
                                       max_nfev=budget, xtol=1e-10, ftol=1e-9)
    M, Bz, Ct, x0 = unpack(sol.x)
    Kn = Bz[:, m:]
    Bn = Bz[:, :m] + Kn @ Ds
    An = M + Kn @ Ct
    out = control.ss(An, Bn / su[None, :], Ct * sy[:, None], D, model.dt)
    return PredictionErrorFit(out, Kn / sy[None, :], x0, cost0, float(np.mean(sol.fun ** 2)),
                              int(sol.nfev), bool(sol.status > 0),
                              float(np.max(np.abs(np.linalg.eigvals(M)), initial=0.0)),
                              time.process_time() - c0)


@dataclass(frozen=True)
class ClosedLoopFit:
    """How :func:`trussid.plid.recipe.identify` treated a closed-loop record
    (``Provenance.closed_loop``).

    Attributes
    ----------
    decided_by : str
        ``"told"`` (``closed_loop=True``) or ``"reference channel"`` (the feedback share of
        :func:`feedback_share` above :data:`FEEDBACK_SHARE`).
    feedback_share : list of float or None
        Per input, when a reference channel was given.
    prior : ClosedLoopPrior
        The PBSID prior's choice.
    refinement : str
        What refined the prior: the prediction-error fit (the direct method, consistent
        under feedback), or ``"none"`` with the reason.
    plid_passes : str
        Why no PLID pass ran: its passes with ``Q = 0`` minimise the output (simulation)
        error, which is biased when the input depends on past noise.
    cost_start, cost_end : float
        Mean squared one-step prediction error (outputs at unit RMS) of the prior and of
        the refined model.
    evaluations : int
        Predictor simulations of the refinement.
    converged : bool
    cpu_seconds : float
        Prior and refinement together.
    """

    decided_by: str
    feedback_share: list | None
    prior: ClosedLoopPrior
    refinement: str
    plid_passes: str
    cost_start: float
    cost_end: float
    evaluations: int
    converged: bool
    cpu_seconds: float


#: Why :func:`trussid.plid.recipe.identify` runs no PLID pass on a closed-loop record.
NO_PLID_PASS = ("none: PLID's passes (Q = 0) minimise the output (simulation) error, biased "
                "under feedback; the prediction-error refinement replaces them")


def identify_closed_loop(u, y, order: int, dt: float, *, decided_by: str = "told",
                         share=None, max_evaluations: int | None = None):
    """The closed-loop recipe: :func:`closed_loop_prior` (PBSID, ``D = 0``, on the first
    :data:`PRIOR_SAMPLES`), then :func:`prediction_error_fit` from it on the whole record.

    Parameters
    ----------
    u : array (N, m)
        Inputs.
    y : array (N, p)
        Outputs.
    order : int
        Model order (any: no observer form is involved).
    dt : float
        Sample time [s].
    decided_by : str
        For the provenance: how the record was found to be closed loop.
    share : array (m,), optional
        :func:`feedback_share` of the inputs, when known.
    max_evaluations : int, optional
        :func:`prediction_error_fit`'s budget.

    Returns
    -------
    model : control.StateSpace
        The refined model (``D = 0``), not yet stabilised.
    K : ndarray (n, p)
        Its innovation gain.
    prior : control.StateSpace
        The PBSID prior.
    info : ClosedLoopFit
    """
    c0 = time.process_time()
    # the prior is only the refinement's start: its VARX (O(N past^2 (m + p)^2)) sees the
    # first PRIOR_SAMPLES (measured on the testbed's output-disturbance loop: from 2e5 its
    # modes are within 0.5 %, inside the refinement's basin; at 2e5 it took 56 of 158 CPU s)
    prior, K0, pinfo = closed_loop_prior(u[:PRIOR_SAMPLES], y[:PRIOR_SAMPLES], order, dt)
    A, C = np.asarray(prior.A, float), np.asarray(prior.C, float)
    if np.max(np.abs(np.linalg.eigvals(A - K0 @ C)), initial=0.0) >= 0.999:
        # PBSID's predictor (truncated VARX, or the gain of poles since reflected) is
        # unstable: fit the gain to the prior by prediction error from K = 0 instead of
        # shrinking it (measured: a shrunk gain started the testbed's 8e4-sample record at
        # 16x the criterion and the refinement lost the modes)
        K0 = refine_gain(prior, u, y, np.zeros_like(K0)).K
    fit = prediction_error_fit(prior, K0, u, y, max_evaluations=max_evaluations)
    info = ClosedLoopFit(decided_by, None if share is None else [float(s) for s in share],
                         pinfo, "prediction error of the innovations model (direct method, "
                         f"{fit.evaluations} predictor runs)", NO_PLID_PASS,
                         fit.cost_start, fit.cost_end, fit.evaluations, fit.converged,
                         time.process_time() - c0)
    return fit.model, fit.K, prior, info
