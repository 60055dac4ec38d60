"""Batched steady-state Kalman predictor gains: several filter Riccati equations that share
``A``, ``C`` and ``R`` solved together (:func:`doubling_gains`, used by
:func:`trussid.plid.metrics.predictor_gains` for :func:`~trussid.plid.metrics.best_predictor`'s
candidate gains)."""

from __future__ import annotations

import numpy as np

__all__ = ["doubling_gains"]


def doubling_gains(A, C, Qs, R) -> list:
    """One-step predictor gains ``K = A P C^T (C P C^T + R)^-1`` of the filter Riccati
    equations of ``(A, C)`` for each state-noise covariance in ``Qs``, solved side by side.

    The structure-preserving doubling algorithm (Chu, Fan and Lin, "A structure-preserving
    doubling algorithm for continuous-time algebraic Riccati equations", and its discrete
    form SDA-1: ``A_{k+1} = A_k (I + G_k H_k)^-1 A_k``, ``G_{k+1} = G_k + A_k (I + G_k
    H_k)^-1 G_k A_k^T``, ``H_{k+1} = H_k + A_k^T H_k (I + G_k H_k)^-1 A_k`` with ``A_0 =
    A^T``, ``G_0 = C^T R^-1 C``, ``H_0 = Q``; ``H_k`` converges quadratically to ``P``) on
    stacked arrays. Written here because scipy's ``solve_discrete_are`` solves one
    equation at a time with balancing and a QZ decomposition: the 14 candidate gains of
    ``best_predictor`` took 14 such solves, about 85 % of its time on the flutter set
    (``benchmarks/results/plid_predictor_profile_before.txt``). Accuracy: a relative
    Riccati residual of at most 1.5e-10 on a 0.25 %-damped plant with tiny ``Q`` (scipy's
    QZ: 1e-15), i.e. gains equal to scipy's to 7e-5 relative there and to 1e-8 on
    better-conditioned equations (``tests/plid/test_metrics.py``): candidates and starts
    for the prediction-error refinement, which does not depend on such differences.

    Parameters
    ----------
    A : array (n, n)
        Discrete state matrix.
    C : array (p, n)
        Output matrix.
    Qs : sequence of arrays (n, n)
        State-noise covariances.
    R : array (p, p)
        Output-noise covariance (positive definite).

    Returns
    -------
    list
        Per ``Q``: the gain ``K`` (n, p), or None where the doubling did not settle (no
        stabilising solution, or too slow a convergence).
    """
    A, C = np.asarray(A, float), np.asarray(C, float)
    R = np.asarray(R, float)
    Qs = np.asarray(Qs, float)
    c, n = Qs.shape[0], A.shape[0]
    if c == 0:
        return []
    with np.errstate(all="ignore"):
        G = np.broadcast_to(C.T @ np.linalg.solve(R, C), (c, n, n)).copy()
        Ak = np.broadcast_to(A.T, (c, n, n)).copy()
        H = Qs.copy()
        eye = np.eye(n)
        done = np.zeros(c, bool)
        for _ in range(60):
            M = eye + G @ H
            try:
                S = np.linalg.solve(M, np.concatenate([Ak, G], axis=2))
            except np.linalg.LinAlgError:
                break
            S1, S2 = S[:, :, :n], S[:, :, n:]
            AkT = np.transpose(Ak, (0, 2, 1))
            Hn = H + AkT @ H @ S1
            G = G + Ak @ S2 @ AkT
            Ak = Ak @ S1
            Hn = 0.5 * (Hn + np.transpose(Hn, (0, 2, 1)))
            G = 0.5 * (G + np.transpose(G, (0, 2, 1)))
            step = np.linalg.norm(Hn - H, axis=(1, 2))
            H = Hn
            done = np.isfinite(step) & (step <= 1e-13 * np.linalg.norm(H, axis=(1, 2)))
            if done.all() or not np.all(np.isfinite(H)):
                break
        PCt = H @ C.T                                             # (c, n, p)
        K = A @ PCt @ np.linalg.inv(C @ PCt + R)
    return [K[i] if done[i] and np.all(np.isfinite(K[i])) and np.all(np.isfinite(H[i]))
            else None for i in range(c)]
