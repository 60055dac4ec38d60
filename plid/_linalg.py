"""Private linear algebra shared by :mod:`trussid.plid.subspace` and :mod:`trussid.plid.metrics`:
regressors of a model's output with fixed poles, and the least-squares solver for them."""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.signal

__all__ = ["mode_filter", "modal_regressors", "lstsq"]


def mode_filter(lam: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``f[s, k] = sum_{i<k} lam_s^(k-1-i) v[i]``: ``v`` (N,) through ``1/(z - lam_s)``."""
    f = np.empty((lam.size, v.size), dtype=complex)
    vc = v.astype(complex)
    for s, ls in enumerate(lam):
        f[s] = scipy.signal.lfilter([0.0, 1.0], [1.0, -ls], vc)
    return f


def _one_of_each_pair(lam: np.ndarray):
    """Indices of the real eigenvalues and of one of each complex-conjugate pair, and the
    weight (1 or 2) that makes the real part of the sum over them the sum over all."""
    keep = np.flatnonzero(lam.imag >= 0)
    return keep, np.where(lam[keep].imag > 0, 2.0, 1.0)


def modal_regressors(A, C, u, x0=True, direct=False):
    """Regressor matrix (N, p, k) for ``y = sum_j G_j(B[:, j]) [+ D u] [+ C A^k x0]`` with
    ``A, C`` fixed: columns ``vec(B)`` (column-major), then ``x0`` (n), then ``vec(D)``
    (row-major: ``D[l, j]`` at ``l * m + j``).

    A real ``A``'s complex modes come in conjugate pairs whose filtered signals and mode
    shapes are conjugates (LAPACK returns the pair's eigenvectors as exact conjugates), so
    each pair contributes twice the real part of one member: only one of each pair is
    filtered and multiplied (half the work of the whole identify front end's regressors).
    """
    lam, V = np.linalg.eig(A)
    Vi = np.linalg.inv(V)
    keep, wt = _one_of_each_pair(lam)
    lam_k = lam[keep]
    CVw = (C @ V)[:, keep] * wt                     # (p, n_kept), pair weights folded in
    Vi_k = Vi[keep]
    N, m = u.shape
    p, n = C.shape
    cols = []

    def through(f):                                 # f (n_kept, N) modal signals -> (N, p, n)
        # y[k] = CV diag(f[:, k]) Vi b: the regressor of b[t] is (CV * f[:, k]) @ Vi[:, t]
        out = np.empty((N, p, n))
        for r in range(p):
            out[:, r, :] = ((f.T * CVw[r]) @ Vi_k).real
        return out

    for j in range(m):
        cols.append(through(mode_filter(lam_k, u[:, j])))
    if x0:
        with np.errstate(divide="ignore"):
            loglam = np.log(lam_k.astype(complex))
        cols.append(through(np.exp(loglam[:, None] * np.arange(N)[None, :])))
    if direct:
        Dr = np.zeros((N, p, p, m))
        for l in range(p):
            Dr[:, l, l, :] = u
        cols.append(Dr.reshape(N, p, p * m))
    return np.concatenate(cols, axis=2)


def lstsq(M, b):
    """Least squares ``min |M x - b|`` for the tall regressor matrices of this package.

    By the normal equations of the column-equilibrated ``M`` (one BLAS product and a
    Cholesky factorisation) when their triangular factor is well conditioned, else by
    pivoted QR (LAPACK gelsy), which is rank-revealing. Why not gelsy always: on the
    15342 x 96 regressors of the subframe record it took 59-73 ms per call against 6 ms,
    and ``identify`` solves 13 of them (issue 34's profile,
    ``benchmarks/results/plid_subframe_profile_lean_before.txt``). The normal equations
    lose accuracy as ``cond(M)^2``: with the factor's reciprocal condition number above
    ``1e-6`` (so ``cond(M) < 1e6``) the solution differs from gelsy's by at most about
    ``1e-4`` relative and the residual not measurably (measured 2e-14 to 2e-7 relative in
    the solution, residuals equal to 1e-14, on the four measured sets, where ``cond(M)``
    was 3 to 7e4).
    """
    M = np.asarray(M, float)
    b = np.asarray(b, float)
    if M.ndim == 2 and M.shape[0] >= M.shape[1] > 0 and np.all(np.isfinite(M)):
        scale = np.sqrt(np.einsum("ij,ij->j", M, M))
        scale[scale == 0] = 1.0
        Ms = M / scale
        G = Ms.T @ Ms
        c, info = scipy.linalg.lapack.dpotrf(G, lower=0, clean=1)
        if info == 0:
            rcond, info2 = scipy.linalg.lapack.dtrcon(c, norm="1", uplo="U", diag="N")
            if info2 == 0 and rcond > 1e-6:
                x = scipy.linalg.cho_solve((c, False), Ms.T @ b, check_finite=False)
                return x / (scale if x.ndim == 1 else scale[:, None])
    return scipy.linalg.lstsq(M, b, lapack_driver="gelsy", check_finite=False)[0]
