"""The direct-form PLID recursion compiled (the loop of
:func:`trussid.plid.recursion_kernel.run_direct`; its reference is
:func:`trussid.plid.recursion_direct.direct_step`, see :mod:`trussid.plid.recursion_kernel`
for what the compiled form changes and why)."""

from __future__ import annotations

import numpy as np

from trussid.plid.kernel_common import _bookkeep, _inv_small, njit

__all__ = ["direct_kernel"]


@njit
def direct_kernel(z, P, Fp, Fi, Fx, Cp, Ci, Cx, R, Q, N, has_N, qth, has_qth,
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
        # P -= K PH^T (all of P: contiguous rows; mirroring a triangle is strided), up to
        # three outputs per sweep over a row: P (253 KiB at 180 entries) is read and
        # written once instead of once per output
        for i in range(d):
            Pi = P[i]
            r = 0
            while r < p:
                if r + 2 < p:
                    f0 = K[i, r]
                    f1 = K[i, r + 1]
                    f2 = K[i, r + 2]
                    h0 = PH[r]
                    h1 = PH[r + 1]
                    h2 = PH[r + 2]
                    for j in range(d):
                        Pi[j] -= f0 * h0[j] + f1 * h1[j] + f2 * h2[j]
                    r += 3
                elif r + 1 < p:
                    f0 = K[i, r]
                    f1 = K[i, r + 1]
                    h0 = PH[r]
                    h1 = PH[r + 1]
                    for j in range(d):
                        Pi[j] -= f0 * h0[j] + f1 * h1[j]
                    r += 2
                else:
                    f0 = K[i, r]
                    h0 = PH[r]
                    for j in range(d):
                        Pi[j] -= f0 * h0[j]
                    r += 1
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
