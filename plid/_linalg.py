"""Private linear algebra shared by :mod:`trussid.plid.subspace` and :mod:`trussid.plid.metrics`:
regressors of a model's output with fixed poles, and the least-squares solver for them."""

from __future__ import annotations

import numpy as np
import scipy.linalg
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
    """Least squares by pivoted QR (LAPACK gelsy): several times faster than numpy's
    SVD-based solver on these tall regressor matrices, and rank-revealing as well."""
    return scipy.linalg.lstsq(M, b, lapack_driver="gelsy", check_finite=False)[0]
