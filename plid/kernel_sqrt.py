"""The square-root-form PLID recursion compiled (the loop of
:func:`trussid.plid.recursion_kernel.run_sqrt`; its reference is
:func:`trussid.plid.recursion_sqrt.sqrt_step`, see :mod:`trussid.plid.recursion_kernel`
for what the compiled form changes and why).

Algorithms: the measurement update is Carlson's triangular square-root update (N. A.
Carlson, "Fast triangular formulation of the square root filter", AIAA J. 11(9), 1973),
one whitened output at a time, its p factors multiplied on their semiseparable generators;
the time update is the array (pre-array / LQ) form of the square-root covariance filter
(M. Verhaegen and P. Van Dooren, "Numerical aspects of different Kalman filter
implementations", IEEE Trans. Autom. Control 31(10), 1986), triangularised by Householder
reflections that keep the pre-array's triangular half.

Where the time goes (36 states, 3 -> 3, rotation basis; cycles per sample counted stage by
stage beside main's kernel in one process, ``benchmarks/results/plid_speed_i36.md``): of
about 200 thousand ticks, the Carlson product (a sweep over the lower triangle of L, four
columns per sweep) 22 %, the new x rows 22 %, the second-order Gram (a BLAS product) 15 %,
the LQ of the x block 15 %, the Carlson generators 8 %, the rest (C L, L^T h, the moments,
the Cholesky of W) 19 %. The factor's columns of the x rows are n long, so most loops are
short: their count per column (set-up, alias checks, a scalar remainder), more than their
arithmetic, is what the time update pays, hence the fused sweeps (two rows per LQ
reflection sweep, F by its 2 x 2 blocks in one sweep, the Gram's blocks summed per row);
the Carlson product, with four columns per sweep, is near the multiply-add rate.
"""

from __future__ import annotations

import numpy as np

from trussid.plid.kernel_carlson import _rows_dot3, _sqrt_measurement
from trussid.plid.kernel_common import _bookkeep, _psd_factor, njit

__all__ = ["sqrt_kernel"]


@njit
def _sqrt_time(z, L, uk, Fp, Fi, Fx, Fo, Fd, Fb, Cp, Ci, Cx, Cd, Q, Wn, has_N, n, p, m, Abar, AbarT, Bm, coef,
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
    # CL = C L[x, :] (factor rows of C x, i.e. of -v): a selector (shift basis) by its
    # non-zeros; a C with many (rotation basis: a sum of block components) as three dense
    # dot products per read of a column, which vectorise where the gather does not
    if p == 3 and Ci.size > 2 * p:
        _rows_dot3(Cd, L, q, d, CL)
    else:
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
        for ra in range(np_):
            c3[l, ra] = 0.0
    if p == 3:
        # the three outputs in one pass over L_A's triangle (bound by its memory traffic)
        for i in range(np_):
            f0, f1, f2 = CL[0, i], CL[1, i], CL[2, i]
            Li = L[i:np_, i]
            c0 = c3[0, i:]
            c1 = c3[1, i:]
            c2 = c3[2, i:]
            for t in range(Li.size):
                li = Li[t]
                c0[t] += li * f0
                c1[t] += li * f1
                c2[t] += li * f2
    else:
        for l in range(p):
            c3l = c3[l]
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
    # second-order moments: sum_k G_k G_k^T with G_k = sum_j Ws[j, k] L_aj (Sv = Ws Ws^T,
    # Ws upper triangular: G_k = sum_{j <= k} Ws[j, k] L_aj has only (k + 1) n columns)
    if not _upper_factor(Sv, Ws):
        return False
    for a in range(n):
        for b2 in range(n):
            W[a, b2] = Q[a, b2]
    _add_block_gram(L, Ws, 0, np_, n, Gt, W)
    # sum_jl c_jl c_lj^T as p^2 contiguous rank-one updates
    for j in range(p):
        for l in range(p):
            cjl = c3[l, j * n:(j + 1) * n]
            clj = c3[j, l * n:(l + 1) * n]
            for a in range(n):
                Wa = W[a]
                f = cjl[a]
                for b2 in range(n):
                    Wa[b2] += f * clj[b2]
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
        if p == 3:
            A0 = AbarT[0]
            A1 = AbarT[1]
            A2 = AbarT[2]
            v0, v1, v2 = CL[0, i], CL[1, i], CL[2, i]
            for a in range(n):
                col[a] = A0[a] * v0 + A1[a] * v1 + A2[a] * v2
        else:
            for a in range(n):
                col[a] = 0.0
            for c in range(p):
                v = CL[c, i]
                Ac = AbarT[c]
                for a in range(n):
                    col[a] += Ac[a] * v
        pairs = Fb.shape[0] > 0
        # F by its diagonals: contiguous, where the sparse rows would gather
        # (aligned views indexed from 0: an index ``a + o`` numba cannot prove non-negative
        # gets a wrap-around branch that stops LLVM vectorising)
        for k in range(Fo.size):
            o = Fo[k]
            lo = max(0, -o)
            cnt = min(n, n - o) - lo
            Fk = Fd[k, lo:lo + cnt]
            Lo = Lx[lo + o:lo + o + cnt]
            cs = col[lo:lo + cnt]
            for a in range(cnt):
                cs[a] += Fk[a] * Lo[a]
        if i < q:
            # L[block b, i] is zero for blocks above row i (lower triangular)
            # (two blocks per sweep of col)
            b = i // n
            while b + 1 < nb:
                f0 = coef[b]
                f1 = coef[b + 1]
                Lb0 = L[b * n:(b + 1) * n, i]
                Lb1 = L[(b + 1) * n:(b + 2) * n, i]
                for a in range(n):
                    col[a] += f0 * Lb0[a] + f1 * Lb1[a]
                b += 2
            if b < nb:
                f0 = coef[b]
                Lb0 = L[b * n:(b + 1) * n, i]
                for a in range(n):
                    col[a] += f0 * Lb0[a]
            if pairs:
                # F is 2 x 2 blocks on the diagonal (the rotation basis): its product is
                # the last sweep, pair by pair in place (a pair reads only its own two old
                # entries), and writes the column: one sweep where the three diagonals and
                # the copy took four
                for b in range(Fb.shape[0]):
                    x0 = Lx[2 * b]
                    x1 = Lx[2 * b + 1]
                    Lx[2 * b] = col[2 * b] + Fb[b, 0] * x0 + Fb[b, 1] * x1
                    Lx[2 * b + 1] = col[2 * b + 1] + Fb[b, 2] * x0 + Fb[b, 3] * x1
            else:
                for a in range(n):
                    Lx[a] = col[a]
        else:
            # pre = [A_hat L_xx, Wf], n x 2n
            if pairs:
                for b in range(Fb.shape[0]):
                    x0 = Lx[2 * b]
                    x1 = Lx[2 * b + 1]
                    pre[2 * b, i - q] = col[2 * b] + Fb[b, 0] * x0 + Fb[b, 1] * x1
                    pre[2 * b + 1, i - q] = col[2 * b + 1] + Fb[b, 2] * x0 + Fb[b, 3] * x1
            else:
                for a in range(n):
                    pre[a, i - q] = col[a]
    # L_xx from the LQ of [A_hat L_xx, Wf] (the reference: the R of the QR of its transpose)
    for a in range(n):
        for i in range(n):
            pre[a, n + i] = Wf[a, i]
    tri = True
    for a in range(n):
        for i in range(2 * n):
            if not np.isfinite(pre[a, i]):
                return False
        for i in range(a + 1, n):
            if Wf[a, i] != 0.0:
                tri = False
    if tri:
        _lq_tri(pre, n)
    else:
        _lq_rows(pre)               # Wf is the symmetric root of a singular W: no structure
    for i in range(n):
        Li = L[q:, q + i]           # down L's (Fortran-ordered) column
        for a in range(n):
            Li[a] = pre[a, i] if i <= a else 0.0
    for a in range(n):
        z[q + a] = xn[a]
    return True


@njit
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


@njit
def _lq_tri(M, n):
    """As :func:`_lq_rows` for ``M = [A, T]`` (n x 2n) with ``T`` lower triangular.

    Householder reflections from the right keep the structure: row k is non-zero only in
    columns ``k .. n + k`` (A's columns from k on and T's first k + 1, where the previous
    reflections filled nothing new since T's row k already reaches column ``n + k``), which
    is one contiguous range of n + 1 entries. The reflection of row k thus costs
    ``2 (n - k - 1) (n + 1)`` instead of ``2 (n - k - 1) (2 n - k)`` multiply-adds: n^3 in all
    instead of 5 n^3 / 3. Same sign convention as :func:`_lq_rows`.
    """
    v = np.empty(n + 1)
    for k in range(n):
        hi = n + k + 1
        Mk = M[k, k:hi]
        alpha = Mk[0]
        xn2 = 0.0
        for j in range(1, n + 1):
            xn2 += Mk[j] * Mk[j]
        if xn2 == 0.0:
            continue
        nrm = np.sqrt(alpha * alpha + xn2)
        beta = -nrm if alpha >= 0.0 else nrm
        tau = (beta - alpha) / beta
        scale = 1.0 / (alpha - beta)
        v[0] = 1.0
        for j in range(1, n + 1):
            v[j] = Mk[j] * scale
        Mk[0] = beta
        for j in range(1, n + 1):
            Mk[j] = 0.0
        # four (then two) rows per sweep: each read of v serves them all (the sweeps are
        # n + 1 long, so loop overhead, not arithmetic, is what a sweep per row pays for)
        i = k + 1
        while i + 3 < n:
            Ma = M[i, k:hi]
            Mb = M[i + 1, k:hi]
            Mc = M[i + 2, k:hi]
            Md = M[i + 3, k:hi]
            acc = 0.0
            acc1 = 0.0
            acc2 = 0.0
            acc3 = 0.0
            for j in range(n + 1):
                vj = v[j]
                acc += Ma[j] * vj
                acc1 += Mb[j] * vj
                acc2 += Mc[j] * vj
                acc3 += Md[j] * vj
            fa = acc * tau
            fb = acc1 * tau
            fc = acc2 * tau
            fd = acc3 * tau
            for j in range(n + 1):
                vj = v[j]
                Ma[j] -= fa * vj
                Mb[j] -= fb * vj
                Mc[j] -= fc * vj
                Md[j] -= fd * vj
            i += 4
        while i + 1 < n:
            Mi = M[i, k:hi]
            Mj = M[i + 1, k:hi]
            acc = 0.0
            acc1 = 0.0
            for j in range(n + 1):
                acc += Mi[j] * v[j]
                acc1 += Mj[j] * v[j]
            f = acc * tau
            f1 = acc1 * tau
            for j in range(n + 1):
                Mi[j] -= f * v[j]
                Mj[j] -= f1 * v[j]
            i += 2
        if i < n:
            Mi = M[i, k:hi]
            acc = 0.0
            for j in range(n + 1):
                acc += Mi[j] * v[j]
            f = acc * tau
            for j in range(n + 1):
                Mi[j] -= f * v[j]


@njit
def _upper_factor(M, out):
    """``out out^T = M`` with ``out`` upper triangular (Cholesky from the last row up),
    else the clipped symmetric root of :func:`_psd_factor`; False when M is not finite.

    Any factor gives the same second-order moment; the upper one makes the k-th
    combination of the factor's blocks reach only blocks 0..k (see :func:`_add_block_gram`).
    """
    k = M.shape[0]
    for i in range(k):
        for j in range(k):
            if not np.isfinite(M[i, j]):
                return False
            out[i, j] = 0.0
    for j in range(k - 1, -1, -1):
        s = M[j, j]
        for t in range(j + 1, k):
            s -= out[j, t] * out[j, t]
        if not s > 0.0:
            return _psd_factor(M, out)
        dj = np.sqrt(s)
        out[j, j] = dj
        for i in range(j):
            s = M[i, j]
            for t in range(j + 1, k):
                s -= out[i, t] * out[j, t]
            out[i, j] = s / dj
    return True


@njit
def _add_block_gram(L, Wk, r0, r1, n, Gt, W):
    """``W += sum_k G_k G_k^T`` with ``G_k = sum_j Wk[j, k] L[r0 + j n:, :r1]`` over the n-row
    blocks of ``L[r0:r1, :r1]`` (lower triangular: block j is zero beyond column
    ``r0 + (j + 1) n``, so G_k is zero beyond the last block column k of ``Wk`` reaches).
    The non-zero columns of the G_k are stacked transposed in ``Gt`` and the Gram is one
    BLAS product: it carries most of the time update's flops, which scalar loops do 5x
    slower."""
    nbk = (r1 - r0) // n
    nk = Wk.shape[1]
    off = 0
    for kk in range(nk):
        jmax = -1
        for j in range(nbk):
            if Wk[j, kk] != 0.0:
                jmax = j
        if jmax < 0:
            continue
        # G_kk is zero beyond column r0 + (jmax + 1) n: with an upper-triangular Wk
        # (jmax = kk) the stack has n p (p + 1) / 2 rows instead of n p^2
        rows = r0 + (jmax + 1) * n
        G = Gt[off:off + rows]
        off += rows
        # row i of G_kk (column i of the blocks) sums blocks j0 .. jmax, j0 the first
        # whose rows reach column i; written in one to three sweeps of n, not zeroed and
        # then accumulated block by block (each sweep is short: their count is the cost)
        for i in range(rows):
            Gi = G[i]
            j = max(0, (i - r0) // n)
            t = jmax - j + 1
            b0 = r0 + j * n
            f0 = Wk[j, kk]
            L0 = L[b0:b0 + n, i]
            if t >= 3:
                f1 = Wk[j + 1, kk]
                f2 = Wk[j + 2, kk]
                L1 = L[b0 + n:b0 + 2 * n, i]
                L2 = L[b0 + 2 * n:b0 + 3 * n, i]
                for a in range(n):
                    Gi[a] = f0 * L0[a] + f1 * L1[a] + f2 * L2[a]
                j += 3
            elif t == 2:
                f1 = Wk[j + 1, kk]
                L1 = L[b0 + n:b0 + 2 * n, i]
                for a in range(n):
                    Gi[a] = f0 * L0[a] + f1 * L1[a]
                j += 2
            else:
                for a in range(n):
                    Gi[a] = f0 * L0[a]
                j += 1
            while j <= jmax:
                f0 = Wk[j, kk]
                b0 = r0 + j * n
                L0 = L[b0:b0 + n, i]
                for a in range(n):
                    Gi[a] += f0 * L0[a]
                j += 1
    if off:
        Gs = Gt[:off]
        W += np.dot(Gs.T, Gs)


@njit
def sqrt_kernel(z, L, Fp, Fi, Fx, Fo, Fd, Fb, Cp, Ci, Cx, Cd, Rw, Hw, J, Q, Wn, has_N,
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
    Mrun = np.empty((p, d))             # running sums of the Carlson product
    colm = np.empty(d)
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
        _sqrt_measurement(z, L, Hw, yw, q, J, Gm, D, U, V, wsum, fv, av, wv, acc_r, Mrun, colm)
        if not _sqrt_time(z, L, us[k], Fp, Fi, Fx, Fo, Fd, Fb, Cp, Ci, Cx, Cd, Q, Wn, has_N, n, p, m, Abar, AbarT,
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
