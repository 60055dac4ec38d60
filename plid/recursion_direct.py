"""PLID recursion in direct (covariance) form: one sample per call, in place.

Follows ``docs/plid.md`` exactly, on ``z = [theta; x]``:

1. Measurement update with ``H = [0, C]``; the posterior output noise is then
   ``v = y - C x`` exactly (``Cov(z, v) = -K R = -P+ H^T``, ``S_v = H P+ H^T``), so the joint
   ``[z; v]`` propagation reduces to ``A_hat = F + Abar_hat C`` acting on ``x``.
2. Time update ``x+ = F x + Phi(y - v_hat, u) theta - Abar v - B n + w`` with the mean and
   covariance of the product ``Abar v`` propagated exactly (Isserlis):
   mean ``+ sum_j P[a_j, x] C_j^T``; covariance
   ``sum_jl S_v[j,l] P[a_j,a_l] + Cov(a_j,v_l) Cov(a_l,v_j)^T``, input noise
   ``sum_jl N[j,l] (b_j b_l^T + P[b_j,b_l])``, ``Q`` and ``Q_theta``.

``F P F^T`` uses ``F = [[I, 0], [Phi, A_hat]]`` with ``Phi = [c^T (x) I_n]``: ``Phi X`` is a
sum of ``p + m`` scaled row blocks, never a dense product, so a sample costs
O((n + q) n (p + m)) for the time update and O((n + q)^2 p) for the measurement update.

Speed: this numpy step is the reference. It is bound by about 40 small numpy calls per
sample, not by its flops (the project's PLID research notes, section 1); compiling the same
dense arithmetic gained nothing (issue 16: 207 against 210 us per sample). What
:class:`~trussid.plid.estimator.PLID` runs by default is
:func:`trussid.plid.recursion_kernel.run_direct`, a compiled loop that uses the structure
(sparse ``C``, block-diagonal ``F``, rows of the symmetric ``P``): 2.7-3x this step's speed,
equal to it to rounding (``benchmarks/results/plid_speed_kernel.md``). ``G P`` below is the
x-row block of the transition in one product; the Isserlis term is one (p^2) x (n^2) product.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg.blas import dgemm

from trussid.plid.recursion_common import Problem

__all__ = ["DirectState", "direct_init", "direct_step", "direct_covariance"]


@dataclass
class DirectState:
    """Estimate ``z = [theta; x]`` (one-step prediction) and its covariance ``P``."""

    z: np.ndarray
    P: np.ndarray


def direct_init(pb: Problem, z0: np.ndarray, P0: np.ndarray) -> DirectState:
    """Start from a prior mean ``z0`` and covariance ``P0`` (copied)."""
    return DirectState(np.array(z0, dtype=float), np.array(P0, dtype=float, order="C"))


def direct_covariance(st: DirectState) -> np.ndarray:
    """The covariance of ``z`` (a copy)."""
    return st.P.copy()


def direct_step(pb: Problem, st: DirectState, u: np.ndarray, y: np.ndarray,
                e: np.ndarray) -> None:
    """Process one sample (scaled units): measurement then time update, in place.

    ``e`` receives the innovation ``y - C x^-`` (p,).
    """
    n, p, m, q = pb.n, pb.p, pb.m, pb.q
    z, P = st.z, st.P
    sel = pb.sel
    np_ = n * p
    Cb = pb.C

    # ---- measurement update -------------------------------------------------------
    if sel is not None:
        xs = q + sel
        np.subtract(y, z[xs], out=e)
        PH = P[:, xs]
    else:
        np.subtract(y, Cb @ z[q:], out=e)
        PH = P[:, q:] @ Cb.T
    S = (PH[q:].T @ Cb.T if sel is None else PH[xs]) + pb.R
    K = PH @ np.linalg.inv(S)
    z += K @ e
    # P -= K PH^T in place (BLAS on the Fortran view of the C-ordered array).
    dgemm(-1.0, PH, K, 1.0, P.T, trans_b=True, overwrite_c=True)

    # ---- time update --------------------------------------------------------------
    th = z[:q]
    x = z[q:]
    Abar = th[:np_].reshape(p, n).T
    Bm = th[np_:].reshape(m, n).T
    Pq = P[q:]                                    # rows of x: (n, dim)
    if sel is not None:
        yc = x[sel]
        Ahat = pb.F.copy()
        Ahat[:, sel] += Abar
        PXC = P[:, xs]                            # P[:, x] C^T, (dim, p)
    else:
        yc = Cb @ x
        Ahat = pb.F + Abar @ Cb
        PXC = P[:, q:] @ Cb.T
    coef = np.concatenate((yc, u))
    c3 = PXC[:np_].reshape(p, n, p)               # c3[j, :, l] = -Cov(a_j, v_l)
    Sv = PXC[q:].T @ Cb.T if sel is None else PXC[xs]   # C P_xx C^T

    x_new = pb.F @ x + Abar @ yc + Bm @ u + np.einsum("jaj->a", c3)
    # G = [Phi, Ahat] is the x-row block of the transition; G P = Ahat P[x, :] + Phi P[theta, :]
    # with Phi = coef^T (x) I_n: a weighted sum of the p + m row blocks of P[theta, :].
    GP = Ahat @ Pq
    GP += np.einsum("k,kab->ab", coef, P[:q].reshape(p + m, n, -1))
    Mt = GP[:, :q]                                # the new P[x, theta]
    Pxx = GP[:, q:] @ Ahat.T
    Pxx += np.einsum("k,akb->ab", coef, Mt.reshape(n, p + m, n))

    # second-order moments of Abar v (Isserlis)
    # sum_jl Sv[j, l] P[a_j, a_l]: one (p^2) x (n^2) product
    PAA = P[:np_, :np_].reshape(p, n, p, n).transpose(0, 2, 1, 3).reshape(p * p, n * n)
    Pxx += (Sv.ravel() @ PAA).reshape(n, n)
    c3t = c3.transpose(1, 0, 2).reshape(n, p * p)
    Pxx += c3t @ c3.transpose(1, 2, 0).reshape(n, p * p).T
    if pb.N is not None:
        PBB = P[np_:q, np_:q].reshape(m, n, m, n)
        Pxx += np.einsum("jl,jalb->ab", pb.N, PBB) + Bm @ pb.N @ Bm.T
    Pxx += pb.Q

    P[q:, :q] = Mt
    P[:q, q:] = Mt.T
    P[q:, q:] = 0.5 * (Pxx + Pxx.T)
    if pb.Q_theta is not None:
        idx = np.arange(q)
        P[idx, idx] += pb.Q_theta
    z[q:] = x_new
