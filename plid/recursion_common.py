"""What the direct and square-root PLID recursions share: the problem constants.

Both recursions run on internally scaled (unit-RMS) data and on the extended state
``z = [theta; x]`` (parameters first, so that a lower-triangular square-root factor has
theta rows that the time update never touches; see ``docs/plid.md``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trussid.plid.canonical import ObserverBasis
from trussid.plid.errors import IdentificationError

__all__ = ["Problem", "psd_factor"]


def _as_cov(value, size: int, name: str, allow_zero: bool = True) -> np.ndarray:
    """A scalar, a vector (diagonal) or a matrix -> a symmetric (size, size) covariance."""
    a = np.asarray(value, dtype=float)
    if a.ndim == 0:
        a = np.eye(size) * float(a)
    elif a.ndim == 1:
        if a.shape != (size,):
            raise IdentificationError(f"{name} must have {size} diagonal entries, got {a.shape[0]}")
        a = np.diag(a)
    elif a.shape != (size, size):
        raise IdentificationError(f"{name} must be {size} x {size}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise IdentificationError(f"{name} has non-finite entries")
    if not np.allclose(a, a.T, rtol=1e-12, atol=0):
        raise IdentificationError(f"{name} must be symmetric")
    a = 0.5 * (a + a.T)
    if size:
        lo = np.linalg.eigvalsh(a).min()
        scale = max(1.0, np.abs(a).max())
        if lo < -1e-12 * scale or (not allow_zero and lo <= 0):
            need = "positive definite" if not allow_zero else "positive semi-definite"
            raise IdentificationError(f"{name} must be {need} (smallest eigenvalue {lo:.3g})")
    return a


def psd_factor(M: np.ndarray) -> np.ndarray:
    """A square factor ``W`` with ``W W^T = M`` for symmetric positive semi-definite ``M``.

    Cholesky when it succeeds; otherwise a symmetric square root with the round-off
    negative eigenvalues clipped (the second-order moment terms are PSD only in exact
    arithmetic, and Q may be zero).
    """
    try:
        return np.linalg.cholesky(M)
    except np.linalg.LinAlgError:
        w, V = np.linalg.eigh(0.5 * (M + M.T))
        return V * np.sqrt(np.clip(w, 0.0, None))


@dataclass
class Problem:
    """Constants of one PLID run, all in scaled (unit-RMS) units.

    Attributes
    ----------
    basis : ObserverBasis
        Fixed ``(F, C)``; ``A = F + Abar C``.
    m : int
        Number of inputs.
    Q : ndarray (n, n)
        State-noise covariance.
    R : ndarray (p, p)
        Output-noise covariance (positive definite).
    N : ndarray (m, m) or None
        Input-noise covariance (None when zero).
    Q_theta : ndarray (q,) or None
        Diagonal of the parameter random-walk covariance (None when zero).
    """

    basis: ObserverBasis
    m: int
    Q: np.ndarray
    R: np.ndarray
    N: np.ndarray | None
    Q_theta: np.ndarray | None
    # derived
    n: int = field(init=False)
    p: int = field(init=False)
    q: int = field(init=False)
    dim: int = field(init=False)
    F: np.ndarray = field(init=False)
    C: np.ndarray = field(init=False)
    sel: np.ndarray | None = field(init=False)

    def __post_init__(self):
        b = self.basis
        self.n, self.p = b.n, b.p
        self.q = b.n * (b.p + self.m)
        self.dim = self.q + self.n
        self.F = np.ascontiguousarray(b.F)
        self.C = np.ascontiguousarray(b.C)
        # A selector C (one unit entry per row, as in the shift basis) turns C x and
        # P C^T into index gathers: cheaper than products in the per-sample loop.
        C = self.C
        is_sel = np.all((C == 0) | (C == 1)) and np.all(C.sum(axis=1) == 1)
        self.sel = np.argmax(C, axis=1) if is_sel else None
        self.Q = _as_cov(self.Q, self.n, "Q")
        self.R = _as_cov(self.R, self.p, "R", allow_zero=False)
        if self.N is not None:
            self.N = _as_cov(self.N, self.m, "N")
            if not np.any(self.N):
                self.N = None
        if self.Q_theta is not None:
            qt = np.asarray(self.Q_theta, dtype=float)
            qt = np.full(self.q, float(qt)) if qt.ndim == 0 else qt
            if qt.shape != (self.q,) or np.any(qt < 0) or not np.all(np.isfinite(qt)):
                raise IdentificationError(
                    f"Q_theta must be a non-negative scalar or {self.q} diagonal entries"
                )
            self.Q_theta = qt if np.any(qt) else None

    def blocks(self):
        """Index ranges of the regressor blocks: a_1..a_p then b_1..b_m, n rows each."""
        n = self.n
        return [(k * n, (k + 1) * n) for k in range(self.p + self.m)]
