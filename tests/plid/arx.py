"""Ordinary least squares (ARX) in the block-shift observer parameterisation.

With the shift basis, eliminating the states of ``x+ = S x + Abar y + B u`` gives, for
output i with observability index ``nu = n / p`` (block i starting at ``s = i nu``),

    y_i(k) = sum_{j=0}^{nu-1} ( Abar[s+j, :] y(k-1-j) + B[s+j, :] u(k-1-j) ),

an ARX model whose coefficients *are* the canonical parameters. Least squares on it is the
classical baseline PLID is compared with: with output noise the regressors ``y(k-1-j)`` are
noisy, so the estimate is biased (the error PLID's second-order moment terms remove). It
also serves as a quick prior.
"""

from __future__ import annotations

import numpy as np

from trussid.plid.canonical import check_order, join_theta
from trussid.plid.errors import DataError

__all__ = ["arx_observer_form"]


def arx_observer_form(u: np.ndarray, y: np.ndarray, n: int) -> np.ndarray:
    """Least-squares ``theta = [vec(Abar); vec(B)]`` of the order-n shift observer form.

    Parameters
    ----------
    u : array (N, m) or (N,)
        Inputs.
    y : array (N, p) or (N,)
        Outputs.
    n : int
        Order, a multiple of p.

    Returns
    -------
    theta : ndarray (n (p + m),)
    """
    u = np.asarray(u, dtype=float)
    y = np.asarray(y, dtype=float)
    u = u[:, None] if u.ndim == 1 else u
    y = y[:, None] if y.ndim == 1 else y
    if u.shape[0] != y.shape[0]:
        raise DataError(f"u has {u.shape[0]} samples but y has {y.shape[0]}")
    m, p = u.shape[1], y.shape[1]
    nu = check_order(n, p)
    n_s = y.shape[0]
    if n_s - nu < nu * (p + m):
        raise DataError(f"{n_s} samples are too few for an order-{n} ARX fit")
    # Regressor row k: [y(k-1), u(k-1), y(k-2), u(k-2), ...] for k = nu .. N-1.
    lags = [np.hstack([y[nu - 1 - j:n_s - 1 - j], u[nu - 1 - j:n_s - 1 - j]]) for j in range(nu)]
    Phi = np.hstack(lags)                          # (N - nu, nu (p + m))
    coef, *_ = np.linalg.lstsq(Phi, y[nu:], rcond=None)   # (nu (p + m), p)
    coef = coef.reshape(nu, p + m, p)              # [lag j, regressor, output i]
    Abar = np.zeros((n, p))
    B = np.zeros((n, m))
    for i in range(p):
        s = i * nu
        Abar[s:s + nu] = coef[:, :p, i]
        B[s:s + nu] = coef[:, p:, i]
    return join_theta(Abar, B)
