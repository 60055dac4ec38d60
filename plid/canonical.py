"""Observer-form parameterisation of a discrete, strictly proper, order-n MIMO model.

PLID (see ``docs/plid.md``) estimates the free matrices of

    A = F + Abar C,    B free,    C fixed,    D = 0,

where the *basis* ``(F, C)`` is fixed and observable. ``theta = [vec(Abar); vec(B)]``
(column-major), ``q = n (p + m)`` parameters: the minimal count for an order-n, p x m
system. Because ``A x = F x + Abar (C x)`` and ``C x = y - v``, the state equation is
linear in ``theta`` given measured outputs, which is what makes the method pseudo-linear.

The thesis's basis is the block shift (:meth:`ObserverBasis.shift`): p blocks of
``nu = n / p`` states, ``C`` row i selects the first state of block i, ``F = S`` shifts
within each block. Any other fixed observable pair (F, C) keeps the method unchanged
(``docs/plid.md``, "Beyond 12 states"); :class:`ObserverBasis` is that pair, and the
conversions here work for any basis.
"""

from __future__ import annotations

from dataclasses import dataclass

import control
import numpy as np
import scipy.linalg

from trussid.plid.errors import IdentificationError

__all__ = [
    "ObserverBasis",
    "valid_orders_near",
    "check_order",
    "split_theta",
    "join_theta",
    "to_matrices",
    "to_statespace",
    "from_statespace",
]


def valid_orders_near(n: int, p: int) -> tuple[int, int]:
    """The nearest orders below and above ``n`` that are multiples of ``p`` (below >= p)."""
    below = max(p, (n // p) * p)
    above = -(-n // p) * p
    if above == below:
        above = below + p
    return below, above


def check_order(n: int, p: int) -> int:
    """Validate a model order for ``p`` outputs and return the observability index ``n / p``.

    Raises
    ------
    IdentificationError
        If ``n`` is not a positive multiple of ``p`` (uniform observability index); the
        message suggests the nearest valid orders.
    """
    if p < 1:
        raise IdentificationError(f"number of outputs must be at least 1, got {p}")
    if int(n) != n or n < 1:
        raise IdentificationError(f"order must be a positive integer, got {n!r}")
    n = int(n)
    if n % p:
        lo, hi = valid_orders_near(n, p)
        raise IdentificationError(
            f"order {n} is not a multiple of the number of outputs ({p}): the observer form "
            f"gives every output the same observability index n/p; try order {lo} or {hi}"
        )
    return n // p


@dataclass(frozen=True)
class ObserverBasis:
    """A fixed observable pair ``(F, C)``: identified models have ``A = F + Abar C``.

    Attributes
    ----------
    F : ndarray, shape (n, n)
        Fixed part of the state matrix.
    C : ndarray, shape (p, n)
        Fixed output matrix (no parameters).
    name : str
        Label for reports (``"shift"`` for the thesis's block-shift basis).
    """

    F: np.ndarray
    C: np.ndarray
    name: str = "custom"

    def __post_init__(self):
        F = np.array(self.F, dtype=float)
        C = np.atleast_2d(np.array(self.C, dtype=float))
        if F.ndim != 2 or F.shape[0] != F.shape[1]:
            raise IdentificationError(f"basis F must be square, got shape {F.shape}")
        if C.shape[1] != F.shape[0]:
            raise IdentificationError(
                f"basis C has {C.shape[1]} columns but F has {F.shape[0]} states"
            )
        F.setflags(write=False)
        C.setflags(write=False)
        object.__setattr__(self, "F", F)
        object.__setattr__(self, "C", C)

    @property
    def n(self) -> int:
        """Number of states."""
        return self.F.shape[0]

    @property
    def p(self) -> int:
        """Number of outputs."""
        return self.C.shape[0]

    @classmethod
    def shift(cls, n: int, p: int) -> "ObserverBasis":
        """The thesis's block-shift basis: ``F = S``, ``C`` selects each block's first state.

        Parameters
        ----------
        n : int
            Order; must be a multiple of ``p``.
        p : int
            Number of outputs.
        """
        nu = check_order(n, p)
        F = np.zeros((n, n))
        C = np.zeros((p, n))
        for i in range(p):
            s = i * nu
            C[i, s] = 1.0
            for j in range(nu - 1):
                F[s + j, s + j + 1] = 1.0
        return cls(F, C, "shift")

    def n_params(self, m: int) -> int:
        """Number of free parameters ``q = n (p + m)`` for ``m`` inputs."""
        return self.n * (self.p + m)


def split_theta(theta: np.ndarray, n: int, p: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """``theta = [vec(Abar); vec(B)]`` (column-major) -> ``(Abar (n, p), B (n, m))``."""
    theta = np.asarray(theta, dtype=float)
    if theta.shape != (n * (p + m),):
        raise IdentificationError(
            f"theta must have n(p+m) = {n * (p + m)} entries, got shape {theta.shape}"
        )
    Abar = theta[: n * p].reshape(p, n).T
    B = theta[n * p :].reshape(m, n).T
    return Abar.copy(), B.copy()


def join_theta(Abar: np.ndarray, B: np.ndarray) -> np.ndarray:
    """``(Abar, B)`` -> ``theta = [vec(Abar); vec(B)]`` (column-major)."""
    return np.concatenate([np.asarray(Abar, float).ravel(order="F"),
                           np.asarray(B, float).ravel(order="F")])


def to_matrices(theta: np.ndarray, basis: ObserverBasis, m: int):
    """State-space matrices ``(A, B, C)`` of ``theta`` in ``basis`` (``D = 0``)."""
    Abar, B = split_theta(theta, basis.n, basis.p, m)
    return basis.F + Abar @ basis.C, B, basis.C.copy()


def to_statespace(theta: np.ndarray, basis: ObserverBasis, m: int, dt: float):
    """A discrete ``control.StateSpace`` (D = 0, sample time ``dt`` in s) from ``theta``."""
    A, B, C = to_matrices(theta, basis, m)
    return control.ss(A, B, C, np.zeros((basis.p, m)), dt)


def _abcd(sys):
    if isinstance(sys, control.StateSpace):
        return (np.asarray(sys.A, float), np.asarray(sys.B, float),
                np.asarray(sys.C, float), np.asarray(sys.D, float))
    A, B, C, *rest = sys
    D = rest[0] if rest else None
    A, B, C = (np.atleast_2d(np.asarray(a, float)) for a in (A, B, C))
    D = np.zeros((C.shape[0], B.shape[1])) if D is None else np.atleast_2d(np.asarray(D, float))
    return A, B, C, D


def _shift_transform(A: np.ndarray, C: np.ndarray, nu: int):
    """Similarity ``T`` and ``Abar`` taking (A, C) into the block-shift form.

    With ``O = [C; CA; ...; CA^(nu-1)]`` invertible, ``C_i A^nu = alpha_i O`` gives the
    canonical coefficients directly (the criterion ``docs/plid.md`` states), and the rows
    of ``T`` follow from ``T[s+j+1] = T[s+j] A - Abar[s+j] C``.
    """
    p, n = C.shape
    O = np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(nu)])
    rank_tol = max(O.shape) * np.finfo(float).eps * np.linalg.norm(O, 2)
    if np.linalg.matrix_rank(O, tol=rank_tol) < n:
        raise IdentificationError(
            "model cannot be written in the block-shift observer form: "
            "[C; CA; ...; CA^(nu-1)] is singular (some output's observability index differs "
            "from n/p, or the model is not observable)"
        )
    CAnu = C @ np.linalg.matrix_power(A, nu)
    alpha = np.linalg.solve(O.T, CAnu.T).T  # (p, n): coefficients on the rows of O
    Abar = np.zeros((n, p))
    T = np.zeros((n, n))
    for i in range(p):
        s = i * nu
        for k in range(nu):
            # Abar row s+k multiplies C A^(nu-1-k) in the expansion of C_i A^nu.
            r = nu - 1 - k
            Abar[s + k] = alpha[i, r * p:(r + 1) * p]
        T[s] = C[i]
        for j in range(nu - 1):
            T[s + j + 1] = T[s + j] @ A - Abar[s + j] @ C
    return T, Abar


def _general_transform(A: np.ndarray, C: np.ndarray, basis: ObserverBasis):
    """Similarity ``T`` and ``Abar`` for any basis, by Sylvester equations.

    ``T A = (F + Abar C_b) T`` with ``C_b T = C`` means ``T A - F T = Abar C``: for each unit
    ``Abar`` entry this is a Sylvester equation (unique when spec(A) and spec(F) are
    disjoint); ``T`` is linear in ``Abar``, and ``C_b T = C`` fixes ``Abar``.
    """
    n, p = basis.n, basis.p
    F, Cb = basis.F, basis.C
    # (-F) T + T A = e_i C_j for all n p right-hand sides. This is
    # scipy.linalg.solve_sylvester's Bartels-Stewart step by step, with the two real Schur
    # forms computed once instead of once per right-hand side (they were 90 % of its
    # cost: 0.12 of identify's 1.5 CPU s on the subframe record at 30 states).
    r, uf = scipy.linalg.schur(-F, output="real")
    s, va = scipy.linalg.schur(A.T, output="real")
    trsyl, = scipy.linalg.get_lapack_funcs(("trsyl",), (r, s))
    CV = C @ va                                   # u^T (e_i C_j) v = outer(u[i], C_j v)
    Ts = []
    for j in range(p):
        for i in range(n):
            y, scale, info = trsyl(r, s, np.outer(uf[i], CV[j]), tranb="C")
            if info < 0:
                raise np.linalg.LinAlgError(f"illegal value in the {-info}-th argument of trsyl")
            Ts.append(scale * (uf @ y @ va.T))
    M = np.column_stack([(Cb @ T).ravel() for T in Ts])  # (p n, n p)
    cond = np.linalg.cond(M)
    if not np.isfinite(cond) or cond > 1e14:
        raise IdentificationError(
            f"model cannot be written in the '{basis.name}' observer basis "
            f"(conversion system condition {cond:.1e})"
        )
    coef = np.linalg.solve(M, C.ravel())
    Abar = coef.reshape(p, n).T  # coefficient order was (column j, row i)
    T = np.tensordot(coef, np.array(Ts), axes=1)
    return T, Abar


def from_statespace(sys, basis: ObserverBasis, method: str = "auto"):
    """Express a known discrete model in the observer form of ``basis``.

    Parameters
    ----------
    sys : control.StateSpace or tuple (A, B, C[, D])
        Discrete, strictly proper model with ``basis.n`` states and ``basis.p`` outputs.
    basis : ObserverBasis
    method : {"auto", "shift", "sylvester"}
        ``"shift"`` uses the observability-matrix construction (block-shift basis only);
        ``"sylvester"`` works for any basis with spec(A), spec(F) disjoint. ``"auto"``
        picks ``"shift"`` for the shift basis.

    Returns
    -------
    theta : ndarray, shape (q,)
        ``[vec(Abar); vec(B')]``.
    T : ndarray, shape (n, n)
        State transformation, ``x' = T x``.

    Raises
    ------
    IdentificationError
        Wrong dimensions, a direct feed-through term, or no such form exists.
    """
    A, B, C, D = _abcd(sys)
    n, p = basis.n, basis.p
    if A.shape != (n, n) or C.shape != (p, n):
        raise IdentificationError(
            f"model has {A.shape[0]} states and {C.shape[0]} outputs; the basis needs "
            f"{n} states and {p} outputs"
        )
    if np.any(D != 0):
        raise IdentificationError("model has a direct feed-through term D; PLID models have D = 0")
    if method == "auto":
        method = "shift" if basis.name == "shift" else "sylvester"
    if method == "shift":
        nu = check_order(n, p)
        ref = ObserverBasis.shift(n, p)
        if not (np.array_equal(ref.F, basis.F) and np.array_equal(ref.C, basis.C)):
            raise IdentificationError("method 'shift' needs the block-shift basis")
        T, Abar = _shift_transform(A, C, nu)
    elif method == "sylvester":
        T, Abar = _general_transform(A, C, basis)
    else:
        raise IdentificationError(f"unknown conversion method {method!r}")
    return join_theta(Abar, T @ B), T
