"""The PLID recursions compiled: many samples per call, with the problem's structure used.

:func:`run_direct` and :func:`run_sqrt` process a block of samples with the arithmetic of
:func:`trussid.plid.recursion_direct.direct_step` and
:func:`trussid.plid.recursion_sqrt.sqrt_step` (the references; same model, same moments,
equal to rounding: the tests check 1e-9 relative), in one numba-compiled loop that

- applies ``C`` (a selector or a sum of block components) as a sparse sum and ``F``
  (block-diagonal rotations, a shift) in CSR form, so that ``A_hat X = F X + Abar (C X)``
  costs O((nnz F + n p) cols) instead of O(n^2 cols);
- reads ``P C^T`` as rows of the symmetric ``P`` (contiguous);
- square-root form: applies the product of the p Carlson factors
  ``T = diag(D) + tril(U V^T, -1)`` by a right-to-left running sum, O(d J p), where the
  reference calls a dense triangular product (BLAS trmm, O(d J^2 / 2));
- allocates nothing per sample.

Why compiled: the numpy steps are bound by about 40 small numpy calls per sample, not by
arithmetic (the project's PLID research notes, section 1: 175 us per sample of which two
BLAS calls carry 69 % of the flops in 22 % of the time). Compiling the same dense
arithmetic gained nothing (the first attempt, recorded in ``recursion_direct``); using the
structure is what gains. ``benchmarks/bench_plid.py`` times both beside each other.

Without numba (``HAVE_NUMBA`` False) the same functions run the reference steps sample by
sample: same results, at the reference speed. The kernels are compiled on first use and
cached on disk (``cache=True``): the first call in a fresh environment costs the compile
(a few CPU seconds, see the benchmark), later processes load it.
"""

from __future__ import annotations

import numpy as np

from trussid.plid.recursion_common import Problem, psd_factor
from trussid.plid.recursion_direct import DirectState, direct_step
from trussid.plid.recursion_sqrt import SqrtState, sqrt_step

try:
    import numba
    HAVE_NUMBA = True
except ImportError:  # the pure-numpy path below gives the same results, slower
    numba = None
    HAVE_NUMBA = False

__all__ = ["HAVE_NUMBA", "KernelRun", "run_direct", "run_sqrt", "compiled"]

# fastmath without the finite-math flags: the recursion must carry NaN/inf through (the
# estimator reports a broken run instead of raising), which "nnan"/"ninf" would break.
_FLAGS = {"nsz", "arcp", "contract", "reassoc"}


def _njit(func):
    if not HAVE_NUMBA:
        return func
    return numba.njit(cache=True, fastmath=_FLAGS, nogil=True)(func)


def _csr(M: np.ndarray):
    """Row pointers, column indices and values of the non-zeros of a dense matrix."""
    M = np.asarray(M, dtype=float)
    nz = M != 0
    ptr = np.concatenate([[0], np.cumsum(nz.sum(axis=1))]).astype(np.int64)
    rows, cols = np.nonzero(nz)
    return ptr, cols.astype(np.int64), M[rows, cols].astype(float)


class KernelRun:
    """What one block of samples left besides the state: the innovations go to ``E``.

    Attributes
    ----------
    first_bad : int
        Direct form: index (within the block) of the first sample after which a variance
        was not positive, -1 if none.
    failed : int
        Index of the first sample whose step could not be completed (a singular
        innovation covariance or a non-finite moment, where the reference step raises):
        as :class:`~trussid.plid.estimator.PLID` does, the estimate was set to NaN there.
        -1 if none.
    """

    __slots__ = ("first_bad", "failed")

    def __init__(self, first_bad: int = -1, failed: int = -1):
        self.first_bad = first_bad
        self.failed = failed


# ---------------------------------------------------------------------- small helpers
@_njit
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


@_njit
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


# ---------------------------------------------------------------------- direct form
@_njit
def _direct_kernel(z, P, Fp, Fi, Fx, Cp, Ci, Cx, R, Q, N, has_N, qth, has_qth,
                   us, ys, E, hist, hist_every, k_done, n, p, m, track, out):
    # Long: one compiled loop over the samples is the point of this module (a call per
    # sample would cost more than the arithmetic); its stages follow direct_step's.
    q = n * (p + m)
    d = q + n
    np_ = n * p
    nb = p + m
    PH = np.empty((p, d))
    K = np.empty((d, p))
    S = np.empty((p, p))
    Si = np.empty((p, p))
    GP = np.empty((n, d))
    CP = np.empty((p, d))
    Pxx = np.empty((n, n))
    Abar = np.empty((n, p))
    Bm = np.empty((n, m))
    coef = np.empty(nb)
    xn = np.empty(n)
    Sv = np.empty((p, p))
    c3 = np.empty((p, n, p))
    tmp = np.empty((n, p))
    hrow = 0
    out[0] = -1
    out[1] = -1
    for k in range(us.shape[0]):
        # ---- measurement update: e = y - C x, PH = (P C^T)^T read as rows of P
        for r in range(p):
            acc = 0.0
            for t in range(Cp[r], Cp[r + 1]):
                acc += Cx[t] * z[q + Ci[t]]
            E[k, r] = ys[k, r] - acc
        for r in range(p):
            for i in range(d):
                PH[r, i] = 0.0
            for t in range(Cp[r], Cp[r + 1]):
                c = Cx[t]
                row = q + Ci[t]
                for i in range(d):
                    PH[r, i] += c * P[row, i]
        for r in range(p):
            for l in range(p):
                acc = R[r, l]
                for t in range(Cp[l], Cp[l + 1]):
                    acc += Cx[t] * PH[r, q + Ci[t]]
                S[r, l] = acc
        if not _inv_small(S, Si):
            # where np.linalg.inv raises; PLID._one then marks the estimate NaN
            if out[1] < 0:
                out[1] = k
            for i in range(d):
                z[i] = np.nan
            _bookkeep(z, P, k, k_done, q, d, track, hist, hist_every, hrow, out)
            if hist_every > 0 and (k_done + k + 1) % hist_every == 0:
                hrow += 1
            continue
        for i in range(d):
            for r in range(p):
                acc = 0.0
                for l in range(p):
                    acc += PH[l, i] * Si[l, r]
                K[i, r] = acc
        for i in range(d):
            acc = 0.0
            for r in range(p):
                acc += K[i, r] * E[k, r]
            z[i] += acc
        # P -= K PH^T (all of P: contiguous rows; mirroring a triangle is strided)
        for i in range(d):
            for r in range(p):
                f = K[i, r]
                for j in range(d):
                    P[i, j] -= f * PH[r, j]
        # ---- time update
        for c in range(p):
            for a in range(n):
                Abar[a, c] = z[c * n + a]
        for j in range(m):
            for a in range(n):
                Bm[a, j] = z[np_ + j * n + a]
        for r in range(p):
            acc = 0.0
            for t in range(Cp[r], Cp[r + 1]):
                acc += Cx[t] * z[q + Ci[t]]
            coef[r] = acc
        for j in range(m):
            coef[p + j] = us[k, j]
        # CP = C P[x, :] = (P C^T)^T after the update: its a-columns give c3, x-columns Sv
        for r in range(p):
            for i in range(d):
                CP[r, i] = 0.0
            for t in range(Cp[r], Cp[r + 1]):
                c = Cx[t]
                row = q + Ci[t]
                for i in range(d):
                    CP[r, i] += c * P[row, i]
        for j in range(p):
            for a in range(n):
                for l in range(p):
                    c3[j, a, l] = CP[l, j * n + a]
        for r in range(p):
            for l in range(p):
                acc = 0.0
                for t in range(Cp[l], Cp[l + 1]):
                    acc += Cx[t] * CP[r, q + Ci[t]]
                Sv[l, r] = acc
        for a in range(n):
            acc = 0.0
            for t in range(Fp[a], Fp[a + 1]):
                acc += Fx[t] * z[q + Fi[t]]
            for c in range(p):
                acc += Abar[a, c] * coef[c]
            for j in range(m):
                acc += Bm[a, j] * coef[p + j]
            for j in range(p):
                acc += c3[j, a, j]
            xn[a] = acc
        # GP = F P[x, :] + Abar (C P[x, :]) + sum_b coef_b P[block b, :]
        for a in range(n):
            for i in range(d):
                GP[a, i] = 0.0
            for t in range(Fp[a], Fp[a + 1]):
                f = Fx[t]
                row = q + Fi[t]
                for i in range(d):
                    GP[a, i] += f * P[row, i]
            for c in range(p):
                f = Abar[a, c]
                for i in range(d):
                    GP[a, i] += f * CP[c, i]
            for b in range(nb):
                f = coef[b]
                row = b * n + a
                for i in range(d):
                    GP[a, i] += f * P[row, i]
        # Pxx = GP[:, x] A_hat^T + sum_b coef_b GP[:, block b]
        for a in range(n):
            for c in range(p):
                acc = 0.0
                for t in range(Cp[c], Cp[c + 1]):
                    acc += Cx[t] * GP[a, q + Ci[t]]
                tmp[a, c] = acc
        for a in range(n):
            for b2 in range(n):
                acc = Q[a, b2]
                for t in range(Fp[b2], Fp[b2 + 1]):
                    acc += GP[a, q + Fi[t]] * Fx[t]
                for c in range(p):
                    acc += tmp[a, c] * Abar[b2, c]
                for b in range(nb):
                    acc += coef[b] * GP[a, b * n + b2]
                Pxx[a, b2] = acc
        # Isserlis: sum_jl Sv[j, l] P[a_j, a_l] + sum_jl c3[j, :, l] c3[l, :, j]^T
        for j in range(p):
            for l in range(p):
                f = Sv[j, l]
                c0 = l * n
                for a in range(n):
                    ra = j * n + a
                    g = c3[j, a, l]
                    for b2 in range(n):
                        Pxx[a, b2] += f * P[ra, c0 + b2] + g * c3[l, b2, j]
        if has_N:
            # input noise: sum_jl N[j, l] (P[b_j, b_l] + b_j b_l^T)
            for j in range(m):
                for l in range(m):
                    f = N[j, l]
                    r0 = np_ + j * n
                    c0 = np_ + l * n
                    for a in range(n):
                        for b2 in range(n):
                            Pxx[a, b2] += f * (P[r0 + a, c0 + b2] + Bm[a, j] * Bm[b2, l])
        # write back
        for a in range(n):
            for i in range(q):
                P[q + a, i] = GP[a, i]
        for i in range(q):
            for a in range(n):
                P[i, q + a] = GP[a, i]
        for a in range(n):
            for b2 in range(n):
                P[q + a, q + b2] = 0.5 * (Pxx[a, b2] + Pxx[b2, a])
        if has_qth:
            for i in range(q):
                P[i, i] += qth[i]
        for a in range(n):
            z[q + a] = xn[a]
        _bookkeep(z, P, k, k_done, q, d, track, hist, hist_every, hrow, out)
        if hist_every > 0 and (k_done + k + 1) % hist_every == 0:
            hrow += 1


@_njit
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


def _hist_rows(k_done: int, count: int, every: int) -> int:
    if every <= 0:
        return 0
    return (k_done + count) // every - k_done // every


def _ref_loop(step, pb, st, us, ys, E, hist, every, k_done, track, start, run):
    """The reference steps for samples ``start..`` (the fallback and the after-failure path)."""
    hrow = _hist_rows(k_done, start, every)
    for k in range(start, us.shape[0]):
        try:
            step(pb, st, us[k], ys[k], E[k])
        except (np.linalg.LinAlgError, ValueError):
            # as PLID._one: a broken covariance carries on in NaN, reported by the result
            st.z[:] = np.nan
        if track and run.first_bad < 0 and not np.diagonal(st.P).min() > 0:
            run.first_bad = k
        if every and (k_done + k + 1) % every == 0:
            hist[hrow] = st.z[:pb.q]
            hrow += 1
    return run


def _null(pb: Problem):
    N = pb.N if pb.N is not None else np.zeros((pb.m, pb.m))
    qth = pb.Q_theta if pb.Q_theta is not None else np.zeros(pb.q)
    return np.ascontiguousarray(N, dtype=float), np.ascontiguousarray(qth, dtype=float)


def run_direct(pb: Problem, st: DirectState, us: np.ndarray, ys: np.ndarray, E: np.ndarray,
               hist: np.ndarray, hist_every: int, k_done: int, track: bool = True,
               use_kernel: bool | None = None) -> KernelRun:
    """Direct form over ``us[k], ys[k]`` (scaled units), in place on ``st``.

    Parameters
    ----------
    pb, st : Problem, DirectState
        The problem and the state (updated in place).
    us, ys : ndarray (N, m), (N, p)
        Inputs and outputs, scaled.
    E : ndarray (N, p)
        Receives the innovations ``y_k - C x_k^-``.
    hist : ndarray (rows, q)
        Receives theta after every sample whose running count (``k_done`` + index + 1) is a
        multiple of ``hist_every``; ``rows`` from :func:`history_rows`.
    hist_every : int
        Samples between two rows of ``hist`` (0: no history).
    k_done : int
        Samples processed before this block.
    track : bool
        Record the first sample after which a variance was not positive.
    use_kernel : bool or None
        None: the compiled kernel when numba is there; False: the reference steps.

    Returns
    -------
    KernelRun
    """
    run = KernelRun()
    use = HAVE_NUMBA if use_kernel is None else (use_kernel and HAVE_NUMBA)
    if not use:
        return _ref_loop(direct_step, pb, st, us, ys, E, hist, hist_every, k_done, track, 0, run)
    Fp, Fi, Fx = _csr(pb.F)
    Cp, Ci, Cx = _csr(pb.C)
    N, qth = _null(pb)
    out = np.full(2, -1, dtype=np.int64)
    _direct_kernel(st.z, st.P, Fp, Fi, Fx, Cp, Ci, Cx, np.ascontiguousarray(pb.R),
                   np.ascontiguousarray(pb.Q), N, pb.N is not None, qth,
                   pb.Q_theta is not None, np.ascontiguousarray(us), np.ascontiguousarray(ys),
                   E, hist, int(hist_every), int(k_done), pb.n, pb.p, pb.m, bool(track), out)
    run.first_bad, run.failed = int(out[0]), int(out[1])
    return run


# ---------------------------------------------------------------------- square-root form
@_njit
def _sqrt_measurement(z, L, Hw, yw, q, J, Gm, D, U, V, wsum, f, a, w, acc_r):
    """All p whitened Carlson updates on their generators, then ``L[:, :J] <- L T``."""
    # Long: the p scalar updates share their generators (f, a, w, V) and the product with
    # L uses them all; split, the same work arrays would only be passed around.
    p, n = Hw.shape
    d = L.shape[0]
    for k in range(p):
        for j in range(J):
            acc = 0.0
            for i in range(n):
                acc += Hw[k, i] * L[q + i, j]
            Gm[k, j] = acc
    for j in range(J):
        D[j] = 1.0
        wsum[j] = 0.0
    for k in range(p):
        hx = 0.0
        for i in range(n):
            hx += Hw[k, i] * z[q + i]
        # f = (T_1 ... T_{k-1})^T g: D g + V_j . (sum_{i > j} g_i U_i)
        for r in range(k):
            acc_r[r] = 0.0
        for j in range(J - 1, -1, -1):
            g = Gm[k, j]
            fj = D[j] * g
            for r in range(k):
                fj += V[j, r] * acc_r[r]
            for r in range(k):
                acc_r[r] += g * U[j, r]
            f[j] = fj
        # a_j = 1 + sum_{i >= j} f_i^2
        acc = 0.0
        a[J] = 1.0
        for j in range(J - 1, -1, -1):
            acc += f[j] * f[j]
            a[j] = acc + 1.0
        # w = (T_1 ... T_{k-1}) f and the new V columns, one forward pass
        for r in range(k):
            acc_r[r] = 0.0
        for j in range(J):
            s = np.sqrt(a[j] * a[j + 1])
            dj = a[j + 1] / s
            bj = -f[j] / s
            wj = D[j] * f[j]
            for r in range(k):
                wj += U[j, r] * acc_r[r]
                incl = acc_r[r] + V[j, r] * f[j]
                V[j, r] = V[j, r] * dj - incl * bj
                acc_r[r] = incl
            w[j] = wj
            V[j, k] = bj
            D[j] *= dj
        innov = yw[k] - hx
        for j in range(J):
            innov -= Gm[k, j] * wsum[j]
        sc = innov / a[0]
        for j in range(J):
            wsum[j] += w[j] * sc
            U[j, k] = w[j]
    for j in range(J):
        c = wsum[j]
        for i in range(j, d):
            z[i] += L[i, j] * c
    # L T column by column from the right: (L T)[:, j] = D_j L[:, j] + M_j V_j with
    # M_j = sum_{i > j} L[:, i] U_i^T (p x d, stored transposed), accumulated as j decreases.
    M = np.zeros((p, d))
    col = np.empty(d)
    for j in range(J - 1, -1, -1):
        # one-dimensional contiguous views and one store per loop: what lets LLVM vectorise
        Lj = L[j:, j]
        cj = col[j:]
        dj = D[j]
        for i in range(cj.size):
            cj[i] = dj * Lj[i]
        for r in range(p):
            Mr = M[r, j:]
            v = V[j, r]
            for i in range(cj.size):
                cj[i] += Mr[i] * v
        for r in range(p):
            Mr = M[r, j:]
            u = U[j, r]
            for i in range(cj.size):
                Mr[i] += Lj[i] * u
        for i in range(cj.size):
            Lj[i] = cj[i]


@_njit
def _sqrt_time(z, L, uk, Fp, Fi, Fx, Cp, Ci, Cx, Q, Wn, has_N, n, p, m, Abar, AbarT, Bm, coef,
               xn, CL, Sv, Ws, c3, Gt, W, Wf, col, pre):
    """The square-root time update of one sample (as sqrt_step's); False at a non-finite
    moment, where the reference raises.

    ``L`` is Fortran-ordered (the measurement update works on its columns), so every loop
    here runs its innermost index down a column: the factor rows the reference multiplies
    as matrices are read column by column.
    """
    # Long: the moments, the new x rows and the LQ of the x block are one step of the
    # reference; split further they would only pass the same work arrays around.
    q = n * (p + m)
    d = q + n
    np_ = n * p
    nb = p + m
    for c in range(p):
        for a in range(n):
            Abar[a, c] = z[c * n + a]
            AbarT[c, a] = z[c * n + a]
    for j in range(m):
        for a in range(n):
            Bm[a, j] = z[np_ + j * n + a]
    for r in range(p):
        acc = 0.0
        for t in range(Cp[r], Cp[r + 1]):
            acc += Cx[t] * z[q + Ci[t]]
        coef[r] = acc
    for j in range(m):
        coef[p + j] = uk[j]
    # CL = C L[x, :] (factor rows of C x, i.e. of -v)
    for i in range(d):
        for r in range(p):
            acc = 0.0
            for t in range(Cp[r], Cp[r + 1]):
                acc += Cx[t] * L[q + Ci[t], i]
            CL[r, i] = acc
    for r in range(p):
        for l in range(p):
            acc = 0.0
            for i in range(d):
                acc += CL[r, i] * CL[l, i]
            Sv[r, l] = acc
    # c3[l, j n + a] = (L_A CL_A^T)[j n + a, l] (the reference's c3[j, a, l]); L_A =
    # L[:np, :np] is lower triangular
    for l in range(p):
        c3l = c3[l]
        for ra in range(np_):
            c3l[ra] = 0.0
        for i in range(np_):
            f = CL[l, i]
            Li = L[i:np_, i]
            for t in range(Li.size):
                c3l[i + t] += Li[t] * f
    for a in range(n):
        acc = 0.0
        for t in range(Fp[a], Fp[a + 1]):
            acc += Fx[t] * z[q + Fi[t]]
        for c in range(p):
            acc += Abar[a, c] * coef[c]
        for j in range(m):
            acc += Bm[a, j] * coef[p + j]
        for j in range(p):
            acc += c3[j, j * n + a]
        xn[a] = acc
    # second-order moments: sum_k G_k G_k^T with G_k = sum_j Ws[j, k] L_aj (Sv = Ws Ws^T)
    if not _psd_factor(Sv, Ws):
        return False
    for a in range(n):
        for b2 in range(n):
            W[a, b2] = Q[a, b2]
    _add_block_gram(L, Ws, 0, np_, n, Gt, W)
    for a in range(n):
        for b2 in range(n):
            acc = 0.0
            for j in range(p):
                for l in range(p):
                    acc += c3[l, j * n + a] * c3[j, l * n + b2]
            W[a, b2] += acc
    if has_N:
        # input noise sum_jl N[j, l] (L_bj L_bl^T + b_j b_l^T), with N = Wn Wn^T
        _add_block_gram(L, Wn, np_, q, n, Gt, W)
        for a in range(n):
            for b2 in range(n):
                acc = 0.0
                for k in range(m):
                    ga = 0.0
                    gb = 0.0
                    for j in range(m):
                        ga += Bm[a, j] * Wn[j, k]
                        gb += Bm[b2, j] * Wn[j, k]
                    acc += ga * gb
                W[a, b2] += acc
    for a in range(n):
        for b2 in range(a):
            h = 0.5 * (W[a, b2] + W[b2, a])
            W[a, b2] = h
            W[b2, a] = h
    if not _psd_factor(W, Wf):
        return False
    # new x rows, column by column: L_x <- Phi L_t + A_hat L_x with A_hat = F + Abar C
    for i in range(d):
        Lx = L[q:, i]
        for a in range(n):
            acc = 0.0
            for t in range(Fp[a], Fp[a + 1]):
                acc += Fx[t] * Lx[Fi[t]]
            col[a] = acc
        for c in range(p):
            v = CL[c, i]
            Ac = AbarT[c]
            for a in range(n):
                col[a] += Ac[a] * v
        if i < q:
            for b in range(nb):
                f = coef[b]
                Lb = L[b * n:(b + 1) * n, i]
                for a in range(n):
                    col[a] += f * Lb[a]
            for a in range(n):
                Lx[a] = col[a]
        else:
            for a in range(n):
                pre[a, i - q] = col[a]          # pre = [A_hat L_xx, Wf], n x 2n
    # L_xx from the LQ of [A_hat L_xx, Wf] (the reference: the R of the QR of its transpose)
    for a in range(n):
        for i in range(n):
            pre[a, n + i] = Wf[a, i]
    for a in range(n):
        for i in range(2 * n):
            if not np.isfinite(pre[a, i]):
                return False
    _lq_rows(pre)
    for a in range(n):
        for i in range(n):
            L[q + a, q + i] = pre[a, i] if i <= a else 0.0
    for a in range(n):
        z[q + a] = xn[a]
    return True


@_njit
def _lq_rows(M):
    """In place: the first columns of ``M`` (r x c, r <= c, C-ordered) become the lower
    triangle ``L`` with ``L L^T = M M^T``: Householder reflections applied from the right,
    LAPACK's sign convention (``dlarfg``: the diagonal is ``-sign(alpha) |x|``), so that
    it equals the reference's ``qr(M.T, mode='r').T``. Written out because only the
    triangle is wanted: numba's ``np.linalg.qr`` also forms Q and copies, 3x the time."""
    r, c = M.shape
    v = np.empty(c)
    for k in range(r):
        Mk = M[k]
        alpha = Mk[k]
        xn2 = 0.0
        for j in range(k + 1, c):
            xn2 += Mk[j] * Mk[j]
        if xn2 == 0.0:
            continue
        nrm = np.sqrt(alpha * alpha + xn2)
        beta = -nrm if alpha >= 0.0 else nrm
        tau = (beta - alpha) / beta
        scale = 1.0 / (alpha - beta)
        v[k] = 1.0
        for j in range(k + 1, c):
            v[j] = Mk[j] * scale
        Mk[k] = beta
        for j in range(k + 1, c):
            Mk[j] = 0.0
        for i in range(k + 1, r):
            Mi = M[i]
            acc = Mi[k]
            for j in range(k + 1, c):
                acc += Mi[j] * v[j]
            acc *= tau
            Mi[k] -= acc
            for j in range(k + 1, c):
                Mi[j] -= acc * v[j]


@_njit
def _add_block_gram(L, Wk, r0, r1, n, Gt, W):
    """``W += sum_k G_k G_k^T`` with ``G_k = sum_j Wk[j, k] L[r0 + j n:, :r1]`` over the n-row
    blocks of ``L[r0:r1, :r1]`` (lower triangular: block j is zero beyond column
    ``r0 + (j + 1) n``). The G_k are stacked transposed in ``Gt`` and the Gram is one BLAS
    product: it carries most of the time update's flops, which scalar loops do 5x slower."""
    nbk = (r1 - r0) // n
    nk = Wk.shape[1]
    for kk in range(nk):
        G = Gt[kk * r1:(kk + 1) * r1]
        for i in range(r1):
            for a in range(n):
                G[i, a] = 0.0
        for j in range(nbk):
            f = Wk[j, kk]
            if f != 0.0:
                base = r0 + j * n
                for i in range(base + n):
                    Li = L[base:base + n, i]
                    Gi = G[i]
                    for a in range(n):
                        Gi[a] += f * Li[a]
    Gs = Gt[:nk * r1]
    W += np.dot(Gs.T, Gs)


@_njit
def _sqrt_kernel(z, L, Fp, Fi, Fx, Cp, Ci, Cx, Rw, Hw, J, Q, Wn, has_N,
                 us, ys, E, hist, hist_every, k_done, n, p, m, out):
    # Long: one compiled loop over the samples is the point of this module; its stages
    # follow sqrt_step's (measurement, moments, new x rows, LQ of the x block).
    q = n * (p + m)
    d = q + n
    np_ = n * p
    nb = p + m
    Gm = np.empty((p, J))
    D = np.empty(J)
    U = np.empty((J, p))
    V = np.empty((J, p))
    wsum = np.empty(J)
    fv = np.empty(J)
    av = np.empty(J + 1)
    wv = np.empty(J)
    acc_r = np.empty(p)
    yw = np.empty(p)
    Abar = np.empty((n, p))
    Bm = np.empty((n, m))
    coef = np.empty(nb)
    xn = np.empty(n)
    CL = np.empty((p, d))
    Sv = np.empty((p, p))
    Ws = np.empty((p, p))
    c3 = np.empty((p, np_))
    Gt = np.empty((max(p, m) * q, n))
    W = np.empty((n, n))
    Wf = np.empty((n, n))
    col = np.empty(n)
    AbarT = np.empty((p, n))
    pre = np.empty((n, 2 * n))          # [A_hat L_xx, Wf], for the LQ
    hrow = 0
    out[0] = -1
    out[1] = -1
    for k in range(us.shape[0]):
        for r in range(p):
            acc = 0.0
            for t in range(Cp[r], Cp[r + 1]):
                acc += Cx[t] * z[q + Ci[t]]
            E[k, r] = ys[k, r] - acc
        for r in range(p):
            acc = 0.0
            for l in range(p):
                acc += Rw[r, l] * ys[k, l]
            yw[r] = acc
        _sqrt_measurement(z, L, Hw, yw, q, J, Gm, D, U, V, wsum, fv, av, wv, acc_r)
        if not _sqrt_time(z, L, us[k], Fp, Fi, Fx, Cp, Ci, Cx, Q, Wn, has_N, n, p, m, Abar, AbarT,
                          Bm, coef, xn, CL, Sv, Ws, c3, Gt, W, Wf, col, pre):
            # a non-finite moment: where the reference raises and PLID._one marks the
            # estimate NaN (the rest of this sample's time update is skipped, as there)
            if out[1] < 0:
                out[1] = k
            for i in range(d):
                z[i] = np.nan
        _bookkeep(z, L, k, k_done, q, d, False, hist, hist_every, hrow, out)
        if hist_every > 0 and (k_done + k + 1) % hist_every == 0:
            hrow += 1


def run_sqrt(pb: Problem, st: SqrtState, us: np.ndarray, ys: np.ndarray, E: np.ndarray,
             hist: np.ndarray, hist_every: int, k_done: int,
             use_kernel: bool | None = None) -> KernelRun:
    """Square-root form over a block of samples; as :func:`run_direct` (no variance
    tracking: this form keeps the covariance positive semi-definite by construction).

    A parameter drift (``Q_theta``) re-triangularises the theta rows every sample (an
    O(q^3) QR); that option runs the reference steps.
    """
    run = KernelRun()
    use = HAVE_NUMBA if use_kernel is None else (use_kernel and HAVE_NUMBA)
    if not use or pb.Q_theta is not None:
        return _ref_loop(sqrt_step, pb, st, us, ys, E, hist, hist_every, k_done, False, 0, run)
    Fp, Fi, Fx = _csr(pb.F)
    Cp, Ci, Cx = _csr(pb.C)
    N, _ = _null(pb)
    Wn = np.ascontiguousarray(psd_factor(N))
    out = np.full(2, -1, dtype=np.int64)
    if not st.L.flags.f_contiguous:
        st.L = np.asfortranarray(st.L)
    _sqrt_kernel(st.z, st.L, Fp, Fi, Fx, Cp, Ci, Cx, np.ascontiguousarray(st.Rw),
                 np.ascontiguousarray(st.Hw), int(st.J), np.ascontiguousarray(pb.Q), Wn,
                 pb.N is not None, np.ascontiguousarray(us), np.ascontiguousarray(ys), E, hist,
                 int(hist_every), int(k_done), pb.n, pb.p, pb.m, out)
    run.failed = int(out[1])
    return run


def history_rows(k_done: int, count: int, every: int) -> int:
    """Rows of ``hist`` a block of ``count`` samples after ``k_done`` fills."""
    return _hist_rows(k_done, count, every)


def compiled() -> bool:
    """Whether the compiled kernels are in use (numba importable)."""
    return HAVE_NUMBA
