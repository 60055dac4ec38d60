"""Shared pieces of the compiled PLID kernels (:mod:`trussid.plid.kernel_direct`,
:mod:`trussid.plid.kernel_sqrt`): the numba decorator and its flags, the sparse form of a
matrix, small dense helpers, and the per-sample bookkeeping.

Without numba (``HAVE_NUMBA`` False) the decorated functions stay plain Python; the
dispatchers in :mod:`trussid.plid.recursion_kernel` then run the reference steps instead.
"""

from __future__ import annotations

import numpy as np

try:
    import numba
    HAVE_NUMBA = True
except ImportError:  # the pure-numpy path of recursion_kernel gives the same results, slower
    numba = None
    HAVE_NUMBA = False

__all__ = ["HAVE_NUMBA", "njit", "csr", "diagonals", "pair_blocks", "state_sequence",
           "mean_square_errors", "mode_signals"]

# fastmath without the finite-math flags: the recursion must carry NaN/inf through (the
# estimator reports a broken run instead of raising), which "nnan"/"ninf" would break.
_FLAGS = {"nsz", "arcp", "contract", "reassoc"}


def njit(func):
    """``numba.njit`` with the kernels' flags and an on-disk cache; ``func`` itself
    without numba."""
    if not HAVE_NUMBA:
        return func
    return numba.njit(cache=True, fastmath=_FLAGS, nogil=True)(func)


def csr(M: np.ndarray):
    """Row pointers, column indices and values of the non-zeros of a dense matrix."""
    M = np.asarray(M, dtype=float)
    nz = M != 0
    ptr = np.concatenate([[0], np.cumsum(nz.sum(axis=1))]).astype(np.int64)
    rows, cols = np.nonzero(nz)
    return ptr, cols.astype(np.int64), M[rows, cols].astype(float)


def diagonals(M: np.ndarray):
    """The non-zero diagonals of a square matrix: offsets ``o`` (column - row) and values
    ``V[k, a] = M[a, a + o_k]`` (zero where ``a + o_k`` is outside), so that
    ``(M x)[a] = sum_k V[k, a] x[a + o_k]``.

    PLID's bases (shifts, 2 x 2 rotation blocks) have one to three diagonals: applied this
    way a product is a few contiguous multiply-adds per row, which vectorise, where the
    row-wise sparse form gathers through an index array.
    """
    M = np.asarray(M, dtype=float)
    n = M.shape[0]
    rows, cols = np.nonzero(M)
    offs = np.unique(cols - rows).astype(np.int64)
    V = np.zeros((offs.size, n))
    for k, o in enumerate(offs):
        a = np.arange(max(0, -o), min(n, n - o))
        V[k, a] = M[a, a + o]
    return offs, V


def pair_blocks(M: np.ndarray) -> np.ndarray:
    """``M``'s 2 x 2 diagonal blocks as rows ``[m00, m01, m10, m11]`` ((n / 2, 4)) when
    ``M`` is block-diagonal in pairs of rows from the first (the rotation basis's ``F``),
    else an empty (0, 4) array.

    The square-root kernel then applies ``M`` pair by pair in one sweep, where by its three
    diagonals it takes three.

    Parameters
    ----------
    M : ndarray (n, n)
        A square matrix (the basis's ``F``, dimensionless).

    Returns
    -------
    ndarray (n / 2, 4) or (0, 4)
        Block ``b``'s entries ``M[2b, 2b], M[2b, 2b + 1], M[2b + 1, 2b], M[2b + 1, 2b + 1]``.
    """
    M = np.asarray(M, dtype=float)
    n = M.shape[0]
    if n % 2 or n == 0:
        return np.zeros((0, 4))
    B = np.zeros_like(M)
    idx = np.arange(0, n, 2)
    blocks = np.stack([M[idx, idx], M[idx, idx + 1], M[idx + 1, idx], M[idx + 1, idx + 1]],
                      axis=1)
    B[idx, idx], B[idx, idx + 1] = blocks[:, 0], blocks[:, 1]
    B[idx + 1, idx], B[idx + 1, idx + 1] = blocks[:, 2], blocks[:, 3]
    if not np.array_equal(B, M):
        return np.zeros((0, 4))
    return np.ascontiguousarray(blocks)


@njit
def _inv_small(S, Si):
    """Gauss-Jordan inverse with partial pivoting of a small matrix; False when singular
    (the case ``np.linalg.inv`` raises for)."""
    p = S.shape[0]
    M = S.copy()
    for i in range(p):
        for j in range(p):
            Si[i, j] = 1.0 if i == j else 0.0
    for c in range(p):
        piv = c
        big = abs(M[c, c])
        for r in range(c + 1, p):
            if abs(M[r, c]) > big:
                big = abs(M[r, c])
                piv = r
        if big == 0.0:
            return False
        if piv != c:
            for j in range(p):
                t = M[c, j]
                M[c, j] = M[piv, j]
                M[piv, j] = t
                t = Si[c, j]
                Si[c, j] = Si[piv, j]
                Si[piv, j] = t
        d = 1.0 / M[c, c]
        for j in range(p):
            M[c, j] *= d
            Si[c, j] *= d
        for r in range(p):
            if r != c:
                f = M[r, c]
                if f != 0.0:
                    for j in range(p):
                        M[r, j] -= f * M[c, j]
                        Si[r, j] -= f * Si[c, j]
    return True


@njit
def _psd_factor(M, out):
    """``out out^T = M``: Cholesky, else the clipped symmetric root (as
    :func:`trussid.plid.recursion_common.psd_factor`). False when M is not finite."""
    k = M.shape[0]
    for i in range(k):
        for j in range(k):
            if not np.isfinite(M[i, j]):
                return False
            out[i, j] = 0.0
    ok = True
    for j in range(k):
        s = M[j, j]
        for t in range(j):
            s -= out[j, t] * out[j, t]
        if not s > 0.0:
            ok = False
            break
        d = np.sqrt(s)
        out[j, j] = d
        oj = out[j, :j]
        # two rows per sweep of row j (the sweeps are short: their count is the cost)
        i = j + 1
        while i + 1 < k:
            oa = out[i, :j]
            ob = out[i + 1, :j]
            sa = M[i, j]
            sb = M[i + 1, j]
            for t in range(j):
                sa -= oa[t] * oj[t]
                sb -= ob[t] * oj[t]
            out[i, j] = sa / d
            out[i + 1, j] = sb / d
            i += 2
        if i < k:
            oa = out[i, :j]
            sa = M[i, j]
            for t in range(j):
                sa -= oa[t] * oj[t]
            out[i, j] = sa / d
    if ok:
        return True
    Ms = 0.5 * (M + M.T)
    w, V = np.linalg.eigh(Ms)
    for i in range(k):
        for j in range(k):
            out[i, j] = V[i, j] * np.sqrt(max(w[j], 0.0))
    return True


@njit
def _bookkeep(z, P, k, k_done, q, d, track, hist, hist_every, hrow, out):
    """After a sample: the first non-positive variance (direct form) and theta's history."""
    if track and out[0] < 0:
        for i in range(d):
            if not P[i, i] > 0.0:
                out[0] = k
                break
    if hist_every > 0 and (k_done + k + 1) % hist_every == 0:
        for i in range(q):
            hist[hrow, i] = z[i]


def _state_sequence(At, Bu, x, X):
    """``X[k] = x_k`` of ``x_{k+1} = A x_k + Bu[k]``, ``At = A^T`` (see
    :func:`state_sequence`); ``x`` is overwritten."""
    n = x.shape[0]
    xn = np.empty(n)
    for k in range(Bu.shape[0]):
        for i in range(n):
            X[k, i] = x[i]
            xn[i] = Bu[k, i]
        # row i of At added to every xn[j] in turn: a contiguous multiply-add that the
        # compiler vectorises, where a dot product over i (a reduction) may not be without
        # reassociation; each xn[j] still sums Bu[k, j], then the terms in the order of i,
        # so the result is the same to the bit (30 states: 1.2 -> 0.7 ms per 3068 samples)
        for i in range(n):
            xi = x[i]
            for j in range(n):
                xn[j] += xi * At[i, j]
        for j in range(n):
            x[j] = xn[j]


def _mean_square_errors(AT, KT, C, drive, r, skip, out):
    """``out[i, l]``: mean over samples ``skip..N-1`` of the squared one-step error of output
    ``l`` of the predictor ``x_{k+1} = A_i^p x_k + drive_k + K_i r_k``, ``e_k = r_k - C x_k``
    from ``x_0 = 0``, for each candidate ``i`` (``AT[i] = (A_i^p)^T``, ``KT[i] = K_i^T``);
    ``r = y - D u``, ``drive = u B^T`` (see :func:`mean_square_errors`)."""
    c, n = AT.shape[0], AT.shape[1]
    p, N = C.shape[0], drive.shape[0]
    x = np.empty(n)
    xn = np.empty(n)
    for i in range(c):
        for j in range(n):
            x[j] = 0.0
        for k in range(N):
            if k >= skip:
                for l in range(p):
                    acc = r[k, l]
                    for j in range(n):
                        acc -= C[l, j] * x[j]
                    out[i, l] += acc * acc
            for j in range(n):
                xn[j] = drive[k, j]
            for l in range(p):
                rl = r[k, l]
                for j in range(n):
                    xn[j] += rl * KT[i, l, j]
            for a in range(n):
                xa = x[a]
                for j in range(n):
                    xn[j] += xa * AT[i, a, j]
            for j in range(n):
                x[j] = xn[j]
    for i in range(c):
        for l in range(p):
            out[i, l] /= max(N - skip, 1)


# no fastmath here: a plain simulation is compared with other simulations to rounding
_state_sequence_compiled = (numba.njit(cache=True, nogil=True)(_state_sequence)
                            if HAVE_NUMBA else None)
_mean_square_errors_compiled = (numba.njit(cache=True, nogil=True)(_mean_square_errors)
                                if HAVE_NUMBA else None)


def _mode_signals(lam, E, F):
    """Rows ``c nk + s`` of ``F``: ``E[:, c]`` through ``1 / (z - lam_s)``; rows
    ``p nk + s``: ``lam_s^k`` (see :func:`mode_signals`)."""
    nk, N, p = lam.shape[0], E.shape[0], E.shape[1]
    for s in range(nk):
        ls = lam[s]
        for c in range(p):
            row = c * nk + s
            f = 0j
            for k in range(N):
                F[row, k] = f
                f = ls * f + E[k, c]
        row = p * nk + s
        pw = 1.0 + 0j
        for k in range(N):
            F[row, k] = pw
            pw = pw * ls


_mode_signals_compiled = (numba.njit(cache=True, nogil=True)(_mode_signals)
                          if HAVE_NUMBA else None)


def state_sequence(A: np.ndarray, Bu: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """States ``x_0 .. x_{N-1}`` of ``x_{k+1} = A x_k + Bu[k]`` as rows (N, n).

    Compiled when numba is there (a simulation of 5114 samples at 30 states: about 1 ms
    against 14 ms for the numpy loop, which ``identify`` runs a dozen times); else the
    numpy loop.
    """
    A = np.asarray(A, float)
    Bu = np.ascontiguousarray(Bu, dtype=float)
    x = np.array(x0, dtype=float).reshape(-1)
    X = np.empty((Bu.shape[0], x.size))
    At = np.ascontiguousarray(A.T)
    if _state_sequence_compiled is not None and np.all(np.isfinite(At)):
        _state_sequence_compiled(At, Bu, x, X)
        return X
    for k in range(Bu.shape[0]):
        X[k] = x
        x = x @ At + Bu[k]
    return X


def mean_square_errors(A, B, C, D, Ks, u, y, skip: int) -> np.ndarray:
    """Mean-square one-step prediction errors (c, p) of one model ``A, B, C, D`` with each
    predictor gain of ``Ks`` (c, n, p), from ``x_0 = 0``, over samples ``skip`` to the end.

    Compiled when numba is there: one pass per gain that keeps the state in registers and
    never stores the states (the subframe record, 3068 samples at 30 states, 14 gains:
    about 41 -> 15 ms against one :func:`state_sequence` per gain); else one numpy step per
    sample for all gains at once. The two agree to rounding (``tests/plid``).

    Parameters
    ----------
    A, B, C, D : ndarray
        The model, (n, n), (n, m), (p, n), (p, m).
    Ks : ndarray (c, n, p)
        Predictor gains.
    u : ndarray (N, m)
    y : ndarray (N, p)
        The record.
    skip : int
        Samples left out at the start (the predictors' start-up).

    Returns
    -------
    ndarray (c, p)
        Mean-square errors in the units of ``y`` squared; not finite where a predictor
        overflowed.
    """
    Ks = np.asarray(Ks, dtype=float)
    nc, n = Ks.shape[0], A.shape[0]
    AT = np.ascontiguousarray(np.transpose(A[None] - Ks @ C[None], (0, 2, 1)))   # (c, n, n)
    KT = np.ascontiguousarray(np.transpose(Ks, (0, 2, 1)))                       # (c, p, n)
    r = np.ascontiguousarray(y - u @ D.T)                                         # y - D u
    drive = np.ascontiguousarray(u @ B.T)                                         # (N, n)
    with np.errstate(all="ignore"):
        if _mean_square_errors_compiled is not None:
            out = np.zeros((nc, C.shape[0]))
            _mean_square_errors_compiled(AT, KT, np.ascontiguousarray(C, dtype=float),
                                         drive, r, int(skip), out)
            return out
        Kr = np.einsum("kp,cpn->kcn", r, KT)                                      # (N, c, n)
        X = np.empty((u.shape[0], nc, n))
        x = np.zeros((nc, 1, n))
        for k in range(u.shape[0]):
            X[k] = x[:, 0]
            x = x @ AT + (drive[k] + Kr[k])[:, None, :]
        e = r[:, None, :] - X @ C.T                                                # (N, c, p)
        return np.mean(e[skip:] ** 2, axis=0)


def mode_signals(lam: np.ndarray, E: np.ndarray) -> np.ndarray:
    """Every column of ``E`` (N, p) through every one-pole filter ``1 / (z - lam_s)``, and the
    powers ``lam_s^k``: ``F`` ((p + 1) nk, N) complex, row ``c nk + s`` holding
    ``f[k] = sum_{i<k} lam_s^(k-1-i) E[i, c]`` and row ``p nk + s`` holding ``lam_s^k``
    (the modal regressors of a predictor gain and of the initial state,
    :func:`trussid.plid.pem.refine_gain`).

    Compiled when numba is there, one pass per pole for all columns (the subframe record,
    3068 samples, 15 poles, 3 outputs: about 9 -> 0.5 ms against one ``scipy.signal.lfilter``
    per pole and column and ``exp(k log lam)``); else those. The powers by repeated
    multiplication drift by about ``k`` roundings from ``exp(k log lam)``: 1e-12 relative
    over 5000 samples.

    Parameters
    ----------
    lam : ndarray (nk,) complex
        Poles.
    E : ndarray (N, p)
        Signals.

    Returns
    -------
    ndarray ((p + 1) nk, N) complex
    """
    lam = np.ascontiguousarray(lam, dtype=complex)
    E = np.ascontiguousarray(E, dtype=float)
    (N, p), nk = E.shape, lam.size
    if _mode_signals_compiled is not None:
        F = np.empty(((p + 1) * nk, N), dtype=complex)
        _mode_signals_compiled(lam, E, F)
        return F
    import scipy.signal    # the fallback only

    rows = [scipy.signal.lfilter([0.0, 1.0], [1.0, -ls], E[:, c].astype(complex))
            for c in range(p) for ls in lam]
    with np.errstate(divide="ignore", invalid="ignore"):
        powers = np.exp(np.log(lam)[:, None] * np.arange(N)[None, :])
    powers[:, 0] = 1.0                              # lam^0, also for lam = 0
    return np.concatenate([np.reshape(rows, (p * nk, N)), powers], axis=0)
