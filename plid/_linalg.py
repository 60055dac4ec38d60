"""Private linear algebra shared by :mod:`trussid.plid.subspace` and :mod:`trussid.plid.metrics`:
regressors of a model's output with fixed poles, and the least-squares solver for them."""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.signal

__all__ = ["mode_filter", "modal_regressors", "real_modal_regressors", "lstsq"]


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


def real_modal_regressors(A, C, u, x0=True, direct=False, weights=None):
    """Regressors (N, p, k) of the same output model as :func:`modal_regressors`, in real
    modal parameters, and the map ``P`` (n, n) back to state coordinates.

    Columns: per input ``j`` the ``n`` real modal coordinates ``b_j`` of ``B[:, j] = P b_j``,
    then those of ``x0 = P x0_m`` (n), then ``vec(D)`` (row-major) as in
    :func:`modal_regressors`. ``P`` holds ``Re v`` of each real eigenvector and
    ``[Re v, -Im v]`` of one of each complex-conjugate pair, so that the pair's response
    ``2 Re(C v f (a + i c) / 2)`` is ``a Re(C v f) - c Im(C v f)``: a regressor is one mode's
    filtered signal times its output shape, ``O(N p n)`` per input where
    :func:`modal_regressors` multiplies back by ``V^-1`` at ``O(N p n^2)``. The column spaces
    are the same (``P`` is invertible), so a least-squares fit in these parameters gives the
    same fitted output; on the subframe record's 30-state model the regressors took 1.5 ms
    against 25 ms (issue 34's front-end profile).

    Parameters
    ----------
    A : ndarray (n, n)
        The fixed dynamics.
    C : ndarray (p, n)
        The fixed output matrix.
    u : (N, m)
        Inputs.
    x0, direct : bool
        Include the initial-state and the direct-term columns.
    weights : (p,), optional
        Every row of output ``l`` multiplied by ``weights[l]`` (a weighted least squares
        without a copy of the regressors).

    Returns
    -------
    R : ndarray (N, p, k)
    P : ndarray (n, n)
        ``theta_state = P theta_modal`` block by block (``B`` columns and ``x0``).
    """
    lam, V = np.linalg.eig(A)
    keep, _ = _one_of_each_pair(lam)
    lam_k = lam[keep]
    cplx = lam_k.imag > 0
    wts = np.ones(C.shape[0]) if weights is None else np.asarray(weights, float)
    C = C * wts[:, None]
    N, m = u.shape
    p, n = C.shape
    # real coordinate t of mode src[t]: its real part, or (second[t]) minus its imaginary
    # part, pairs adjacent, so that P and the regressors share one column order
    src = np.repeat(np.arange(keep.size), np.where(cplx, 2, 1))
    second = np.zeros(n, bool)
    second[1:] = src[1:] == src[:-1]
    Vk = V[:, keep][:, src]
    P = np.where(second[None, :], -Vk.imag, Vk.real)
    # -Im(z) = Re(i z): the output shape of a minus-imaginary coordinate times i, so that
    # every regressor is the real part of (modal signal x shape)
    CV = (C @ V)[:, keep][:, src] * np.where(second, 1j, 1.0)   # (p, n)
    CVr, CVi = CV.real, CV.imag
    k = (m + (1 if x0 else 0)) * n + (p * m if direct else 0)
    R = np.empty((N, p, k))

    def put(f, col):                                # f (N, n_kept) modal signals
        fr, fi = f.real[:, src], f.imag[:, src]     # (N, n), contiguous
        for r in range(p):                          # per output: 2-D, contiguous operands
            R[:, r, col:col + n] = fr * CVr[r] - fi * CVi[r]

    uc = u.astype(complex)
    F = np.empty((m, N, keep.size), complex)
    for s, ls in enumerate(lam_k):                  # one filter per mode, all inputs at once
        F[:, :, s] = scipy.signal.lfilter([0.0, 1.0], [1.0, -ls], uc, axis=0).T
    for j in range(m):
        put(F[j], j * n)
    col = m * n
    if x0:
        put(_powers(lam_k, N).T, col)
        col += n
    if direct:
        R[:, :, col:] = 0.0
        for l in range(p):
            R[:, l, col + l * m:col + (l + 1) * m] = u * wts[l]
    return R, P


def _powers(lam: np.ndarray, N: int) -> np.ndarray:
    """``lam[:, None] ** arange(N)`` (complex) as an outer product of two short power
    tables (64 steps by blocks of 64): one complex product per entry instead of a complex
    ``exp`` and ``log`` each (3x faster on 17 modes x 5114 samples)."""
    step = 64
    blocks = -(-N // step)
    with np.errstate(divide="ignore", invalid="ignore", under="ignore"):
        loglam = np.log(lam.astype(complex))
        inner = np.exp(loglam[:, None] * np.arange(step)[None, :])
        outer = np.exp(loglam[:, None] * (step * np.arange(blocks))[None, :])
    out = (outer[:, :, None] * inner[:, None, :]).reshape(lam.size, -1)[:, :N]
    zero = lam == 0                                 # log 0: 0 ** k by hand (1, 0, 0, ...)
    out[zero] = 0.0
    out[zero, :1] = 1.0
    return out


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
        # the Gram of M equilibrated afterwards (D^-1 M^T M D^-1 is the equilibrated
        # matrix's Gram): no scaled copy of M, whose product and copy were half of the
        # front end's least-squares time on the subframe record
        G = M.T @ M
        scale = np.sqrt(np.diag(G).copy())
        scale[scale == 0] = 1.0
        G /= scale[:, None]
        G /= scale[None, :]
        c, info = scipy.linalg.lapack.dpotrf(G, lower=0, clean=1, overwrite_a=1)
        if info == 0:
            rcond, info2 = scipy.linalg.lapack.dtrcon(c, norm="1", uplo="U", diag="N")
            if info2 == 0 and rcond > 1e-6:
                sc = scale if b.ndim == 1 else scale[:, None]
                x = scipy.linalg.cho_solve((c, False), (M.T @ b) / sc, check_finite=False)
                return x / sc
    return scipy.linalg.lstsq(M, b, lapack_driver="gelsy", check_finite=False)[0]
