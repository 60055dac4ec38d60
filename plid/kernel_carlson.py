"""The measurement update of the compiled square-root PLID recursion
(:func:`trussid.plid.kernel_sqrt.sqrt_kernel`): Carlson's triangular square-root update
(N. A. Carlson, "Fast triangular formulation of the square root filter", AIAA J. 11(9),
1973), one whitened output at a time, its p factors multiplied on their semiseparable
generators, and the row-dot products of the factor that both updates use.

Its own module so that the time update and the loop (:mod:`trussid.plid.kernel_sqrt`)
stay readable; the stage profile is in that module's docstring.
"""

from __future__ import annotations

import numpy as np

from trussid.plid.kernel_common import njit

__all__ = ["_rows_dot3", "_sqrt_measurement"]


@njit
def _sqrt_measurement(z, L, Hw, yw, q, J, Gm, D, U, V, wsum, f, a, w, acc_r, M, col):
    """All p whitened Carlson updates on their generators, then ``L[:, :J] <- L T``."""
    # Long: the p scalar updates share their generators (f, a, w, V) and the product with
    # L uses them all; split, the same work arrays would only be passed around.
    p, n = Hw.shape
    d = L.shape[0]
    # rows g_k = L^T h_k: each column of L's x rows read once for all outputs (p <= 3)
    if p == 3:
        _rows_dot3(Hw, L, q, J, Gm)
    else:
        for j in range(J):
            Lx = L[q:, j]
            for k in range(p):
                hk = Hw[k]
                acc = 0.0
                for i in range(n):
                    acc += hk[i] * Lx[i]
                Gm[k, j] = acc
    for j in range(J):
        D[j] = 1.0
        wsum[j] = 0.0
    for k in range(p):
        hx = 0.0
        for i in range(n):
            hx += Hw[k, i] * z[q + i]
        # f = (T_1 ... T_{k-1})^T g: D g + V_j . (sum_{i > j} g_i U_i). The running sums
        # are the loop's carried dependency: for the first three outputs they are locals
        # (registers), where the array acc_r would put a store and a reload on that chain
        # every iteration (LLVM cannot prove acc_r apart from V and U); same arithmetic in
        # the same order
        # In the same backward pass: a_j = 1 + sum_{i >= j} f_i^2 and g . wsum (the
        # innovation's share of the earlier outputs' correction), one sweep instead of three
        a[J] = 1.0
        sq = 0.0
        gw = 0.0
        if k < 3:
            c0 = 0.0
            c1 = 0.0
            for j in range(J - 1, -1, -1):
                g = Gm[k, j]
                fj = D[j] * g
                if k >= 1:
                    fj += V[j, 0] * c0
                if k == 2:
                    fj += V[j, 1] * c1
                if k >= 1:
                    c0 += g * U[j, 0]
                if k == 2:
                    c1 += g * U[j, 1]
                f[j] = fj
                sq += fj * fj
                a[j] = sq + 1.0
                gw += g * wsum[j]
        else:
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
                sq += fj * fj
                a[j] = sq + 1.0
                gw += g * wsum[j]
        # w = (T_1 ... T_{k-1}) f and the new V columns, one forward pass (locals for the
        # first three outputs, as above)
        if k < 3:
            c0 = 0.0
            c1 = 0.0
            for j in range(J):
                s = np.sqrt(a[j] * a[j + 1])
                dj = a[j + 1] / s
                fj = f[j]
                bj = -fj / s
                wj = D[j] * fj
                if k >= 1:
                    wj += U[j, 0] * c0
                    c0 += V[j, 0] * fj
                    V[j, 0] = V[j, 0] * dj - c0 * bj
                if k == 2:
                    wj += U[j, 1] * c1
                    c1 += V[j, 1] * fj
                    V[j, 1] = V[j, 1] * dj - c1 * bj
                w[j] = wj
                V[j, k] = bj
                D[j] *= dj
        else:
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
        sc = (yw[k] - hx - gw) / a[0]
        for j in range(J):
            wsum[j] += w[j] * sc
            U[j, k] = w[j]
    # L T column by column from the right: (L T)[:, j] = D_j L[:, j] + M_j V_j with
    # M_j = sum_{i > j} L[:, i] U_i^T (p x d, stored transposed), accumulated as j decreases;
    # the state correction z += L[:, :J] wsum (old L) rides along in the same sweep.
    for r in range(p):
        for i in range(d):
            M[r, i] = 0.0
    j = J - 1
    if p == 3:
        while j >= 3:
            _lt_quad3(L, M, z, j, D, wsum, U, V)
            j -= 4
        while j >= 1:
            _lt_pair3(L, M, z, j, D, wsum, U, V)
            j -= 2
    while j >= 0:
        _lt_column(L, col, M, z, j, D[j], wsum[j], U[j], V[j], p)
        j -= 1



@njit
def _rows_dot3(H, L, q, cols, out):
    """``out[k, j] = H[k] . L[q:, j]`` for three rows ``H[k]`` and the columns ``j < cols``
    of L's x rows: each column read once for the three rows, two columns per sweep (the
    columns are n long: per sweep, the set-up and the reductions' final sums weigh as
    much as the multiply-adds)."""
    n = H.shape[1]
    h0 = H[0]
    h1 = H[1]
    h2 = H[2]
    j = 0
    while j + 1 < cols:
        La = L[q:, j]
        Lb = L[q:, j + 1]
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        b0 = 0.0
        b1 = 0.0
        b2 = 0.0
        for i in range(n):
            la = La[i]
            lb = Lb[i]
            a0 += h0[i] * la
            a1 += h1[i] * la
            a2 += h2[i] * la
            b0 += h0[i] * lb
            b1 += h1[i] * lb
            b2 += h2[i] * lb
        out[0, j] = a0
        out[1, j] = a1
        out[2, j] = a2
        out[0, j + 1] = b0
        out[1, j + 1] = b1
        out[2, j + 1] = b2
        j += 2
    if j < cols:
        Lx = L[q:, j]
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        for i in range(n):
            li = Lx[i]
            a0 += h0[i] * li
            a1 += h1[i] * li
            a2 += h2[i] * li
        out[0, j] = a0
        out[1, j] = a1
        out[2, j] = a2

@njit
def _lt_quad3(L, M, z, j, D, wsum, U, V):
    """Columns j .. j - 3 of ``L T`` (three outputs) in one sweep, as four calls of
    :func:`_lt_column` in that order: the running sums ``M`` and ``z`` are read and written
    once per four columns (per two in :func:`_lt_pair3`), which halves the sweep's loads
    and stores again (its stores, not its multiply-adds, were the limit).

    Rows j - 3 .. j - 1 hold only some of the four columns (L is lower triangular; ``M``
    is still zero there): those few entries are updated one by one first.
    """
    for r in range(j - 3, j):
        for c in range(r, j - 4, -1):        # the columns row r has, right to left
            lrc = L[r, c]
            L[r, c] = D[c] * lrc + M[0, r] * V[c, 0] + M[1, r] * V[c, 1] + M[2, r] * V[c, 2]
            M[0, r] += lrc * U[c, 0]
            M[1, r] += lrc * U[c, 1]
            M[2, r] += lrc * U[c, 2]
            z[r] += lrc * wsum[c]
    La = L[j:, j]
    Lb = L[j:, j - 1]
    Lc = L[j:, j - 2]
    Ld = L[j:, j - 3]
    M0 = M[0, j:]
    M1 = M[1, j:]
    M2 = M[2, j:]
    zj = z[j:]
    da, db, dc, dd = D[j], D[j - 1], D[j - 2], D[j - 3]
    wa, wb, wc, wd = wsum[j], wsum[j - 1], wsum[j - 2], wsum[j - 3]
    va0, va1, va2 = V[j, 0], V[j, 1], V[j, 2]
    vb0, vb1, vb2 = V[j - 1, 0], V[j - 1, 1], V[j - 1, 2]
    vc0, vc1, vc2 = V[j - 2, 0], V[j - 2, 1], V[j - 2, 2]
    vd0, vd1, vd2 = V[j - 3, 0], V[j - 3, 1], V[j - 3, 2]
    ua0, ua1, ua2 = U[j, 0], U[j, 1], U[j, 2]
    ub0, ub1, ub2 = U[j - 1, 0], U[j - 1, 1], U[j - 1, 2]
    uc0, uc1, uc2 = U[j - 2, 0], U[j - 2, 1], U[j - 2, 2]
    ud0, ud1, ud2 = U[j - 3, 0], U[j - 3, 1], U[j - 3, 2]
    for i in range(La.size):
        la = La[i]
        lb = Lb[i]
        lc = Lc[i]
        ld = Ld[i]
        m0 = M0[i]
        m1 = M1[i]
        m2 = M2[i]
        La[i] = da * la + m0 * va0 + m1 * va1 + m2 * va2
        m0 += la * ua0
        m1 += la * ua1
        m2 += la * ua2
        Lb[i] = db * lb + m0 * vb0 + m1 * vb1 + m2 * vb2
        m0 += lb * ub0
        m1 += lb * ub1
        m2 += lb * ub2
        Lc[i] = dc * lc + m0 * vc0 + m1 * vc1 + m2 * vc2
        m0 += lc * uc0
        m1 += lc * uc1
        m2 += lc * uc2
        Ld[i] = dd * ld + m0 * vd0 + m1 * vd1 + m2 * vd2
        M0[i] = m0 + ld * ud0
        M1[i] = m1 + ld * ud1
        M2[i] = m2 + ld * ud2
        zj[i] += la * wa + lb * wb + lc * wc + ld * wd

@njit
def _lt_pair3(L, M, z, j, D, wsum, U, V):
    """Columns j and j - 1 of ``L T`` (three outputs) in one sweep: as two calls of
    :func:`_lt_column`, but the running sums ``M`` and ``z`` are read and written once per
    two columns (the sweep is bound by memory traffic, not arithmetic).

    Row j - 1 has only column j - 1 (L is lower triangular) and M is still zero there.
    """
    a = j
    b = j - 1
    lb = L[b, b]
    L[b, b] = D[b] * lb
    M[0, b] += lb * U[b, 0]
    M[1, b] += lb * U[b, 1]
    M[2, b] += lb * U[b, 2]
    z[b] += lb * wsum[b]
    La = L[a:, a]
    Lb = L[a:, b]
    M0 = M[0, a:]
    M1 = M[1, a:]
    M2 = M[2, a:]
    za = z[a:]
    da, db = D[a], D[b]
    wa, wb = wsum[a], wsum[b]
    va0, va1, va2 = V[a, 0], V[a, 1], V[a, 2]
    ua0, ua1, ua2 = U[a, 0], U[a, 1], U[a, 2]
    vb0, vb1, vb2 = V[b, 0], V[b, 1], V[b, 2]
    ub0, ub1, ub2 = U[b, 0], U[b, 1], U[b, 2]
    for i in range(La.size):
        la = La[i]
        lb = Lb[i]
        m0 = M0[i]
        m1 = M1[i]
        m2 = M2[i]
        La[i] = da * la + m0 * va0 + m1 * va1 + m2 * va2
        m0 += la * ua0
        m1 += la * ua1
        m2 += la * ua2
        Lb[i] = db * lb + m0 * vb0 + m1 * vb1 + m2 * vb2
        M0[i] = m0 + lb * ub0
        M1[i] = m1 + lb * ub1
        M2[i] = m2 + lb * ub2
        za[i] += la * wa + lb * wb


@njit
def _lt_column(L, col, M, z, j, dj, wj, Uj, Vj, p):
    """Column j of ``L T``: ``L[j:, j] <- dj L[j:, j] + M[:, j:]^T Vj``,
    ``M[:, j:] += Uj L[j:, j]^T`` and ``z[j:] += wj L[j:, j]`` (the old column).

    Up to three outputs (every case PLID's benchmarks run) in one sweep down the column:
    the column and the running sums are read and written once instead of once per output.
    The views are taken here as ``M[r, j:]``, ``L[j:, j]``: numba types those as
    contiguous (a view of a view, ``M[:, j:][r]``, is not), which is what lets LLVM
    vectorise the sweep.
    """
    Lj = L[j:, j]
    zj = z[j:]
    nn = Lj.size
    if p == 3:
        M0 = M[0, j:]
        M1 = M[1, j:]
        M2 = M[2, j:]
        v0, v1, v2 = Vj[0], Vj[1], Vj[2]
        u0, u1, u2 = Uj[0], Uj[1], Uj[2]
        for i in range(nn):
            li = Lj[i]
            Lj[i] = dj * li + M0[i] * v0 + M1[i] * v1 + M2[i] * v2
            M0[i] += li * u0
            M1[i] += li * u1
            M2[i] += li * u2
            zj[i] += li * wj
    elif p == 2:
        M0 = M[0, j:]
        M1 = M[1, j:]
        v0, v1 = Vj[0], Vj[1]
        u0, u1 = Uj[0], Uj[1]
        for i in range(nn):
            li = Lj[i]
            Lj[i] = dj * li + M0[i] * v0 + M1[i] * v1
            M0[i] += li * u0
            M1[i] += li * u1
            zj[i] += li * wj
    elif p == 1:
        M0 = M[0, j:]
        v0 = Vj[0]
        u0 = Uj[0]
        for i in range(nn):
            li = Lj[i]
            Lj[i] = dj * li + M0[i] * v0
            M0[i] += li * u0
            zj[i] += li * wj
    else:
        cj = col[j:]
        for i in range(nn):
            cj[i] = dj * Lj[i]
            zj[i] += Lj[i] * wj
        for r in range(p):
            Mr = M[r, j:]
            v = Vj[r]
            for i in range(nn):
                cj[i] += Mr[i] * v
        for r in range(p):
            Mr = M[r, j:]
            u = Uj[r]
            for i in range(nn):
                Mr[i] += Lj[i] * u
        for i in range(nn):
            Lj[i] = cj[i]
