"""Order reduction of a discrete model by balanced truncation.

python-control's ``balred`` needs slycot, which is not installed here (and not a project
dependency), so this is the square-root balanced truncation (Laub et al. 1987; Tombs and
Postlethwaite 1987) on scipy: Gramians from ``solve_discrete_lyapunov``, their factors,
and one SVD. The Hankel singular values come out of the same SVD; the truncation error
satisfies ``sigma_{r+1} <= ||G - G_r||_inf <= 2 sum_{i>r} sigma_i`` (Al-Saggaf and
Franklin 1987, discrete time).

Unstable models: the Gramians do not exist, so the model is split by an ordered real Schur
form into a stable part and an unstable part (decoupled with a Sylvester equation); only
the stable part is reduced and the unstable part is kept whole.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from trussid.plid._validate import as_2d
from trussid.plid.errors import IdentificationError

__all__ = ["ReductionResult", "hankel_singular_values", "balanced_truncation", "state_covariance"]


@dataclass
class ReductionResult:
    """Outcome of :func:`balanced_truncation`.

    Attributes
    ----------
    model : control.StateSpace
        Reduced model (discrete, same dt, same D).
    hsv : ndarray
        Hankel singular values of the stable part, descending.
    n_unstable : int
        States of the unstable part, kept unreduced.
    error_bound : float
        ``2 * sum`` of the discarded Hankel singular values (bound on the H-infinity error).
    """

    model: control.StateSpace
    hsv: np.ndarray
    n_unstable: int
    error_bound: float


def _factor(W: np.ndarray) -> np.ndarray:
    """``L`` with ``L L^T = W`` for a symmetric PSD Gramian (rank-deficient allowed)."""
    W = 0.5 * (W + W.T)
    w, V = np.linalg.eigh(W)
    return V * np.sqrt(np.clip(w, 0.0, None))


def _split(A, B, C, radius=1.0):
    """Stable/unstable decomposition ``A -> blockdiag(As, Au)`` with matching B, C."""
    T, Z, ns = scipy.linalg.schur(A, output="real", sort=lambda re, im: np.hypot(re, im) < radius)
    n = A.shape[0]
    if ns == n:
        return (T, Z.T @ B, C @ Z), None, ns
    if ns == 0:
        return None, (T, Z.T @ B, C @ Z), ns
    T11, T12, T22 = T[:ns, :ns], T[:ns, ns:], T[ns:, ns:]
    # [I X; 0 I] decouples: T11 X - X T22 = -T12
    X = scipy.linalg.solve_sylvester(T11, -T22, -T12)
    Bt = Z.T @ B
    Ct = C @ Z
    Bs = Bt[:ns] - X @ Bt[ns:]
    Cu = Ct[:, ns:] + Ct[:, :ns] @ X
    return (T11, Bs, Ct[:, :ns]), (T22, Bt[ns:], Cu), ns


def hankel_singular_values(sys: control.StateSpace) -> np.ndarray:
    """Hankel singular values of a stable discrete model, descending."""
    A, B, C = (np.asarray(M, float) for M in (sys.A, sys.B, sys.C))
    if np.max(np.abs(np.linalg.eigvals(A)), initial=0) >= 1:
        raise IdentificationError("Hankel singular values need a stable model (all |poles| < 1)")
    Lc = _factor(scipy.linalg.solve_discrete_lyapunov(A, B @ B.T))
    Lo = _factor(scipy.linalg.solve_discrete_lyapunov(A.T, C.T @ C))
    return scipy.linalg.svdvals(Lo.T @ Lc)


def state_covariance(A, B, u) -> np.ndarray:
    """``(1/N) sum_k x_k x_k^T`` of ``x[k+1] = A x[k] + B u[k]`` from rest: the
    controllability Gramian of ``(A, B)`` weighted by the spectrum of the input ``u``
    (for white unit-variance ``u`` and a long record it tends to the usual Gramian)."""
    A, B = np.asarray(A, float), np.asarray(B, float)
    u = as_2d(u, "u")
    n = A.shape[0]
    # control.forced_response would do; this avoids building an output map of n rows.
    x = np.zeros(n)
    Bu = u @ B.T
    X = np.empty((u.shape[0], n))
    for k in range(u.shape[0]):  # the recursion itself: nothing to vectorise over samples
        X[k] = x
        x = A @ x + Bu[k]
    return X.T @ X / u.shape[0]


def balanced_truncation(sys: control.StateSpace, order: int, u=None) -> ReductionResult:
    """Reduce a discrete model to ``order`` states by square-root balanced truncation.

    Parameters
    ----------
    sys : control.StateSpace
        Discrete-time model; unstable modes are kept unreduced.
    order : int
        Total states of the reduced model (at least the number of unstable states).
    u : array (N, m), optional
        An input record. When given, the controllability Gramian is replaced by the state
        covariance under this input (:func:`state_covariance`), i.e. the truncation is
        weighted by the input's spectrum: states that only a band the input does not reach
        would excite (an identified model's noise modes above a band-limited excitation)
        rank low even when their white-noise Hankel singular values are large. ``hsv`` then
        holds these input-weighted values and ``error_bound`` is ``nan`` (the H-infinity
        bound holds for the unweighted truncation only).

    Examples
    --------
    Two well separated modes cut to the stronger one: the 50 Hz mode stays (its frequency moves
    by the truncated mode's coupling), the Hankel singular values say what was dropped:

    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import balanced_truncation, modal_table
    >>> s = control.tf("s")
    >>> G = sum(g * (2 * np.pi * f) ** 2 / (s**2 + 0.04 * 2 * np.pi * f * s + (2 * np.pi * f) ** 2)
    ...         for f, g in ((50.0, 1.0), (120.0, 0.5)))
    >>> r = balanced_truncation(control.c2d(control.ss(G), 1e-3), 2)
    >>> r.model.nstates, np.round(modal_table(r.model).frequencies_hz, 2)
    (2, array([49.87]))
    >>> print(np.round(r.hsv, 2))
    [12.74 12.23  6.26  6.02]
    """
    if not isinstance(sys, control.StateSpace) or not control.isdtime(sys, strict=True):
        raise IdentificationError("balanced_truncation needs a discrete-time control.StateSpace")
    A, B, C, D = (np.asarray(M, float) for M in (sys.A, sys.B, sys.C, sys.D))
    n = A.shape[0]
    if int(order) != order or not 0 < order <= n:
        raise IdentificationError(f"reduced order must be between 1 and {n}, got {order!r}")
    stable, unstable, ns = _split(A, B, C)
    nu = n - ns
    if order < nu:
        raise IdentificationError(
            f"the model has {nu} unstable states, which are kept; order must be at least {nu}"
        )
    r = order - nu
    if ns == 0:
        return ReductionResult(sys, np.array([]), nu, 0.0)
    As, Bs, Cs = stable
    if u is None:
        Wc = scipy.linalg.solve_discrete_lyapunov(As, Bs @ Bs.T)
    else:
        u = as_2d(u, "u")
        if u.shape[1] != B.shape[1]:
            raise IdentificationError(
                f"u has {u.shape[1]} columns but the model has {B.shape[1]} inputs")
        Wc = state_covariance(As, Bs, u)
    Lc = _factor(Wc)
    Lo = _factor(scipy.linalg.solve_discrete_lyapunov(As.T, Cs.T @ Cs))
    U, s, Vt = scipy.linalg.svd(Lo.T @ Lc)
    if r > 0 and s[r - 1] <= s[0] * 1e-14:
        raise IdentificationError(
            f"order {order} keeps Hankel singular values at round-off level; choose a lower order"
        )
    bound = 2.0 * float(np.sum(s[r:])) if u is None else float("nan")
    if r == 0:
        Ar = np.zeros((0, 0))
        Br = np.zeros((0, B.shape[1]))
        Cr = np.zeros((C.shape[0], 0))
    else:
        isq = 1.0 / np.sqrt(s[:r])
        Tl = (U[:, :r] * isq).T @ Lo.T              # (r, ns)
        Tr = Lc @ (Vt[:r].T * isq)                   # (ns, r)
        Ar, Br, Cr = Tl @ As @ Tr, Tl @ Bs, Cs @ Tr
    if nu:
        Au, Bu, Cu = unstable
        Ar = scipy.linalg.block_diag(Ar, Au)
        Br = np.vstack([Br, Bu])
        Cr = np.hstack([Cr, Cu])
    return ReductionResult(control.ss(Ar, Br, Cr, D, sys.dt), s, nu, bound)
