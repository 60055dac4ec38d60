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

__all__ = ["HAVE_NUMBA", "njit", "csr", "diagonals", "state_sequence"]

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
        for i in range(j + 1, k):
            s = M[i, j]
            for t in range(j):
                s -= out[i, t] * out[j, t]
            out[i, j] = s / d
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
        for j in range(n):
            acc = Bu[k, j]
            for i in range(n):
                acc += x[i] * At[i, j]
            xn[j] = acc
        for j in range(n):
            x[j] = xn[j]


# no fastmath here: a plain simulation is compared with other simulations to rounding
_state_sequence_compiled = (numba.njit(cache=True, nogil=True)(_state_sequence)
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
