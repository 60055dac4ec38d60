"""PLID recursion in square-root form: the covariance is carried as ``P = L L^T``, never formed.

Same model and moments as :mod:`trussid.plid.recursion_direct` (see ``docs/plid.md``); only the
arithmetic differs.

- ``L`` is lower triangular with ``z = [theta; x]`` (parameters first), stored in Fortran
  order (so that BLAS trmm updates its leading columns in place).
- Measurement update: outputs are whitened by the Cholesky factor of ``R`` and processed
  one at a time with Carlson's triangular rank-one update (Carlson 1973,
  "Fast triangular formulation of the square root filter", AIAA J. 11(9)). For
  ``M = I - f f^T / (1 + f^T f)`` its lower-triangular factor is
  ``T = diag(d) + tril(f beta^T, -1)`` with ``a_j = 1 + sum_{i>=j} f_i^2``,
  ``d_j = sqrt(a_{j+1} / a_j)`` and ``beta_j = -f_j / sqrt(a_j a_{j+1})`` (ratios of
  positive sums: no cancellation, which is why it keeps definiteness). The p factors are
  multiplied together on their semiseparable generators and applied as one triangular
  product ``L <- L T`` (BLAS trmm). A QR array update of the (n + q + p)-square pre-array
  would cost O((n + q)^3) per sample with no structure to exploit.
  The posterior output noise is ``v = y - C x`` exactly, so "appending v to the state"
  needs no extra columns: its factor rows are ``-C L_x``.
- Time update: ``F = [[I, 0], [Phi, A_hat]]`` leaves the theta rows of ``L`` unchanged
  (still triangular), so only the n x rows are rebuilt: ``L_xt <- Phi L_tt + A_hat L_xt``
  and ``L_xx`` from the LQ factorisation of ``[A_hat L_xx, W]`` with ``W W^T`` the noise and
  second-order moment terms, O(n^2 (2n)) plus O(n q (p + m)) for the products. (That
  n x n sum is formed from factor rows and factored; it is a covariance, so it is PSD up
  to round-off, which ``psd_factor`` clips.)
- A parameter drift ``Q_theta`` changes the theta rows too; it is applied by an LQ of
  ``[L_tt, Q_theta^(1/2)]`` whose rotation is carried into the x rows (O(q^3): the
  drift option costs time in this form).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg.blas import dtrmm

from trussid.plid.recursion_common import Problem, psd_factor

__all__ = ["SqrtState", "sqrt_init", "sqrt_step", "sqrt_covariance"]


@dataclass
class SqrtState:
    """Estimate ``z = [theta; x]`` (one-step prediction) and lower-triangular ``L``."""

    z: np.ndarray
    L: np.ndarray
    # whitening of the outputs and the per-output data the measurement update needs
    Rw: np.ndarray          # inverse Cholesky factor of R, (p, p)
    Hw: np.ndarray          # Rw @ C, (p, n)
    J: int                  # columns of L the measurement update touches


def sqrt_init(pb: Problem, z0: np.ndarray, P0: np.ndarray) -> SqrtState:
    """Start from a prior mean ``z0`` and covariance ``P0`` (factored here)."""
    L = np.asfortranarray(psd_factor(np.asarray(P0, dtype=float)))
    if not np.allclose(L, np.tril(L)):
        # psd_factor fell back to a symmetric root: re-triangularise it.
        L = np.asfortranarray(np.linalg.qr(L.T, mode="r").T)
    Rw = np.linalg.inv(np.linalg.cholesky(pb.R))
    Hw = Rw @ pb.C
    J = pb.q + int(np.flatnonzero(np.any(Hw != 0, axis=0)).max()) + 1
    return SqrtState(np.array(z0, dtype=float), L, Rw, Hw, J)


def sqrt_covariance(st: SqrtState) -> np.ndarray:
    """The covariance ``L L^T`` of ``z`` (formed only on request)."""
    return st.L @ st.L.T


def _rcumsum_excl(a: np.ndarray) -> np.ndarray:
    """``out[j] = sum_{i > j} a[i]`` along axis 0."""
    out = np.zeros_like(a)
    out[:-1] = np.cumsum(a[:0:-1], axis=0)[::-1]
    return out


def _fcumsum_excl(a: np.ndarray) -> np.ndarray:
    """``out[i] = sum_{j < i} a[j]`` along axis 0."""
    out = np.zeros_like(a)
    np.cumsum(a[:-1], axis=0, out=out[1:])
    return out


def _measurement(pb: Problem, st: SqrtState, yw: np.ndarray) -> None:
    """All p (whitened) scalar Carlson updates, applied to L in one triangular product.

    Scalar update k multiplies L by ``T_k = diag(d_k) + tril(f_k beta_k^T, -1)``. The
    ``f_k`` of the later updates, the gains and the product ``T = T_1 ... T_p`` are all
    worked out on its generators (``T = diag(D) + tril(U V^T, -1)``, rank p), which costs
    O((n + q) p^2) vector work; then ``L <- L T`` is one BLAS ``trmm``. Doing the p updates
    on L itself costs p column-wise cumulative sums over the whole factor, which numpy does
    several times slower than BLAS does the product.
    """
    q, p = pb.q, pb.p
    z, L = st.z, st.L
    J = st.J
    LJ = L[:, :J]
    Gm = st.Hw @ L[q:, :J]                      # rows g_k = L^T h_k, (p, J)
    D = np.ones(J)
    U = np.empty((J, p))
    V = np.empty((J, p))
    # State correction so far is L[:, :J] @ wsum; output k sees Hw_k x + g_k . wsum.
    wsum = np.zeros(J)
    hx = st.Hw @ z[q:]
    ff = np.zeros(J + 1)                       # f_j^2 with a zero sentinel at J
    for k in range(p):
        g = Gm[k]
        Uk, Vk = U[:, :k], V[:, :k]
        if k:
            # f = (T_1 ... T_{k-1})^T g
            f = D * g
            f += np.einsum("jr,jr->j", Vk, _rcumsum_excl(g[:, None] * Uk))
        else:
            f = g
        np.multiply(f, f, out=ff[:J])
        a_ext = np.cumsum(ff[::-1])[::-1]
        a_ext += 1.0                               # a_j = 1 + sum_{i >= j} f_i^2, a_J = 1
        a, a1 = a_ext[:J], a_ext[1:]
        s = np.sqrt(a * a1)
        d = a1 / s                                 # sqrt(a_{j+1} / a_j)
        beta = f / s
        beta *= -1.0
        if k:
            Vf = Vk * f[:, None]
            w = D * f                              # (T_1 .. T_{k-1}) f
            w += np.einsum("jr,jr->j", Uk, _fcumsum_excl(Vf))
            Vk *= d[:, None]
            Vk -= np.cumsum(Vf, axis=0) * beta[:, None]
        else:
            w = f
        innov = yw[k] - hx[k] - g @ wsum
        wsum += w * (innov / a[0])
        U[:, k] = w
        V[:, k] = beta
        D *= d
    z += LJ @ wsum
    # T = diag(D) + tril(U V^T, -1), built Fortran-ordered for trmm (which reads only
    # the lower triangle).
    W = V @ U.T                                  # W[j, i] = V_j . U_i = T[i, j]
    W.flat[::J + 1] = D
    dtrmm(1.0, W.T, LJ, side=1, lower=1, overwrite_b=1)


def _lq_lower(M: np.ndarray) -> np.ndarray:
    """Lower-triangular ``L`` (rows of M) with ``L L^T = M M^T``."""
    return np.linalg.qr(M.T, mode="r").T


def sqrt_step(pb: Problem, st: SqrtState, u: np.ndarray, y: np.ndarray,
              e: np.ndarray) -> None:
    """Process one sample (scaled units): measurement then time update, in place.

    ``e`` receives the innovation ``y - C x^-`` (p,).
    """
    n, p, m, q = pb.n, pb.p, pb.m, pb.q
    z, L = st.z, st.L
    sel = pb.sel
    if sel is not None:
        np.subtract(y, z[q + sel], out=e)
    else:
        np.subtract(y, pb.C @ z[q:], out=e)
    _measurement(pb, st, st.Rw @ y)

    np_ = n * p
    th = z[:q]
    x = z[q:]
    Abar = th[:np_].reshape(p, n).T
    Bm = th[np_:].reshape(m, n).T
    if sel is not None:
        yc = x[sel]
        Ahat = pb.F.copy()
        Ahat[:, sel] += Abar
        CL = L[q + sel, :]                         # factor rows of C x (= -v)
    else:
        yc = pb.C @ x
        Ahat = pb.F + Abar @ pb.C
        CL = pb.C @ L[q:, :]
    coef = np.concatenate((yc, u))
    Sv = CL @ CL.T
    # The a-rows of L are zero beyond column n p (lower triangular, a first).
    LA = L[:np_, :np_]
    PAXC = LA @ CL[:, :np_].T                      # P[a, x] C^T, (n p, p)
    c3 = PAXC.reshape(p, n, p)

    x_new = pb.F @ x + Abar @ yc + Bm @ u
    for j in range(p):
        x_new += c3[j, :, j]

    # Second-order term sum_jl Sv[j,l] L_aj L_al^T = sum_k G_k G_k^T with Sv = Ws Ws^T and
    # G_k = sum_j Ws[j,k] L_aj; plus sum_jl c_jl c_lj^T, input noise and Q.
    G = (psd_factor(Sv).T @ np.ascontiguousarray(LA).reshape(p, n * np_)).reshape(p, n, np_)
    W = G[0] @ G[0].T
    for k in range(1, p):
        W += G[k] @ G[k].T
    W += c3.transpose(1, 0, 2).reshape(n, p * p) @ c3.transpose(1, 2, 0).reshape(n, p * p).T
    if pb.N is not None:
        LB3 = L[np_:q, :q].reshape(m, n, q)
        W += np.tensordot(LB3, np.tensordot(pb.N, LB3, axes=(1, 0)), axes=([0, 2], [0, 2]))
        W += Bm @ pb.N @ Bm.T
    W += pb.Q
    Wf = psd_factor(0.5 * (W + W.T))

    # New x rows: Phi L_t + A_hat L_xt, with Phi L_t = sum_k coef_k L[block k, :q] as one
    # matmul over a (q, p + m, n) view of the (Fortran-ordered) factor, no copy.
    Lxt_new = Ahat @ L[q:, :q]
    Lxt_new += np.matmul(coef, L[:q, :q].T.reshape(q, p + m, n)).T
    Lt = L[:q, :q]
    AL = Ahat @ L[q:, q:]

    if pb.Q_theta is None:
        L[q:, :q] = Lxt_new
        L[q:, q:] = _lq_lower(np.hstack((AL, Wf)))
    else:
        # Theta rows change too: LQ of [L_tt, Qth^(1/2)], carry the rotation into x rows.
        pre = np.hstack((Lt, np.diag(np.sqrt(pb.Q_theta))))
        Qm, Rm = np.linalg.qr(pre.T, mode="complete")
        L[:q, :q] = Rm[:q].T
        X = np.hstack((Lxt_new, np.zeros((n, q)))) @ Qm   # rotated x rows, (n, 2q)
        L[q:, :q] = X[:, :q]
        L[q:, q:] = _lq_lower(np.hstack((X[:, q:], AL, Wf)))
    z[q:] = x_new
