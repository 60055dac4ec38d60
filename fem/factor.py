"""Sparse direct factorisation of symmetric positive definite matrices (K, K - sigma M).

Two back ends behind one class, :class:`SPDFactor`:

- **CHOLMOD** (SuiteSparse's supernodal Cholesky, through the ``cvxopt`` package, whose
  wheels bundle it) on a **METIS nested-dissection** ordering of the *node* graph (through
  ``pymetis``). Nested dissection is what keeps the fill of 3-D frames (lattices) near its
  lower bound; a supernodal Cholesky stores one triangle and runs in dense BLAS-3 blocks.
  Measured on the 2.8e4-DOF cubic lattice, one BLAS thread: SuperLU (below) 7.0 s and
  650 MB peak, CHOLMOD with its own AMD ordering 1.9 s / 370 MB, CHOLMOD on the METIS node
  ordering 0.77 s / 260 MB; on the 1.4e5-DOF lattice 22 s / 1.8 GB (SuperLU: several
  minutes and several GB).
- **SuperLU** (``scipy.sparse.linalg.splu``), scipy's only sparse direct solver: the
  pure-scipy fallback when cvxopt or pymetis is not installed, and the diagnostic path, since
  it factors semi-definite and indefinite matrices without pivoting and reports every pivot
  in a known order (CHOLMOD stops at the first non-positive pivot and hides its
  permutation).

Both are hand-wired here because scipy has no sparse Cholesky; the orderings are the
libraries' own (METIS, SuperLU's minimum degree), only applied to the node graph.
"""

from __future__ import annotations

import functools

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

from trussid._util.threads import forget_blas_libraries

#: Back ends of :class:`SPDFactor`: "auto" uses CHOLMOD when cvxopt and pymetis import, and
#: SuperLU otherwise or when CHOLMOD finds the matrix not positive definite.
BACKENDS = ("auto", "cholmod", "superlu")


@functools.lru_cache(maxsize=1)
def cholmod_available() -> bool:
    """Whether the CHOLMOD back end can be used (cvxopt and pymetis import).

    The first call imports them, and so loads cvxopt's own OpenBLAS: call it before a
    ``trussid._util.threads.blas_threads`` block so that the limit reaches that library too
    (:func:`trussid.fem.modal.solve_modes` and :func:`trussid.fem.static.solve_static` do).
    """
    try:
        import cvxopt.cholmod  # noqa: F401 (deferred: optional back end)
        import pymetis  # noqa: F401 (deferred: optional back end)
    except ImportError:
        return False

    forget_blas_libraries()
    return True


def _group_pattern(A: sp.csc_matrix, groups) -> tuple[np.ndarray, sp.csr_matrix]:
    """Group index of every row, and the group graph's adjacency pattern (no diagonal)."""
    uniq, g = np.unique(np.asarray(groups), return_inverse=True)
    n = A.shape[0]
    P = sp.csr_matrix((np.ones(n), (g, np.arange(n))), shape=(len(uniq), n))
    pattern = A.copy()
    pattern.data = np.abs(pattern.data)
    G = (P @ pattern @ P.T).tocsr()
    return g, G


def _grouped_order(g: np.ndarray, group_pos: np.ndarray) -> np.ndarray:
    """DOF permutation that visits the groups in ``group_pos`` order, a group's rows together."""
    return np.lexsort((np.arange(len(g)), group_pos[g]))


def _metis_order(A: sp.csc_matrix, groups) -> np.ndarray | None:
    """METIS nested dissection of the node graph, expanded to DOFs (None: no groups)."""
    import pymetis  # deferred: optional back end

    if groups is None:
        return None
    g, G = _group_pattern(A, groups)
    G.setdiag(0)
    G.eliminate_zeros()
    if G.shape[0] < 2 or G.nnz == 0:
        return None
    adj = pymetis.CSRAdjacency(G.indptr.astype(np.int64), G.indices.astype(np.int64))
    _, iperm = pymetis.nested_dissection(adjacency=adj)  # iperm[i]: new position of node i
    return _grouped_order(g, np.asarray(iperm))


class SPDFactor:
    """Sparse direct solver for a symmetric positive definite matrix.

    Parameters
    ----------
    A : scipy.sparse matrix
        Symmetric positive definite (the SuperLU back end also accepts semi-definite ones
        with tiny pivots, for diagnosis).
    groups : (n,) int, optional
        Group (node) of each row; the fill-reducing ordering is computed on the graph of the
        groups, a group's rows kept together (dense 6-column supernodes on frames).
    backend : {"auto", "cholmod", "superlu"}
        "auto": CHOLMOD (see the module notes) when available and ``A`` is found positive
        definite, else SuperLU.

    Raises
    ------
    RuntimeError
        ``A`` is exactly singular (SuperLU), or not positive definite with
        ``backend="cholmod"``.

    Attributes
    ----------
    backend : str
        The back end used: "cholmod" or "superlu".
    """

    def __init__(self, A, groups=None, backend: str = "auto"):
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        A = sp.csc_matrix(A)
        self.n = A.shape[0]
        self._A, self._groups = A, groups
        if backend != "superlu" and cholmod_available():
            try:
                self._cholmod(A, groups)
                return
            except ArithmeticError:  # not positive definite (to round-off)
                if backend == "cholmod":
                    raise RuntimeError("CHOLMOD: the matrix is not positive definite") from None
        elif backend == "cholmod":
            raise RuntimeError("the CHOLMOD back end needs the cvxopt and pymetis packages")
        self._superlu(A, groups)

    # -- CHOLMOD
    def _cholmod_input(self, A: sp.csc_matrix, groups):
        """The lower triangle of ``S A S`` as a cvxopt matrix and the METIS ordering (or None).

        ``S = diag(A_jj^-1/2)``: with a unit diagonal, the pivots are the ratios of the
        pivot to the diagonal entry whatever the (hidden) permutation CHOLMOD settles on, so
        the singularity test :meth:`min_pivot_ratio` needs no second factorisation.
        """
        import cvxopt  # deferred: optional back end

        d = A.diagonal()
        self._scale = 1.0 / np.sqrt(np.where(d > 0, d, 1.0))
        S = sp.diags(self._scale)
        lower = sp.tril(S @ A @ S, format="coo")
        M = cvxopt.spmatrix(cvxopt.matrix(lower.data.astype(float)), cvxopt.matrix(lower.row.astype(np.int64)),
                            cvxopt.matrix(lower.col.astype(np.int64)), (self.n, self.n))
        perm = _metis_order(A, groups)
        return M, None if perm is None else cvxopt.matrix(perm.astype(np.int64))

    def _cholmod(self, A: sp.csc_matrix, groups) -> None:
        import cvxopt.cholmod as cholmod  # deferred: optional back end

        M, p = self._cholmod_input(A, groups)
        # CHOLMOD's default (nmethods = 0) also tries AMD and keeps the better ordering; its
        # module-wide options dict is left untouched (no process-wide side effect).
        F = cholmod.symbolic(M) if p is None else cholmod.symbolic(M, p=p)
        cholmod.numeric(M, F)  # ArithmeticError when not positive definite
        self._F = F
        self.backend = "cholmod"
        self.perm = None
        self.lu = None

    def factor_nnz(self) -> int:
        """Stored factor entries (L for CHOLMOD, L + U for SuperLU).

        The factor's memory and the work of one solve are proportional to it. CHOLMOD only
        gives its factor out by converting it (``cholmod.getfactor`` leaves a symbolic
        one), so this factors the matrix a second time: for tests and reports, not for hot
        paths.
        """
        if self.backend == "cholmod":
            import cvxopt.cholmod as cholmod  # deferred: optional back end

            M, p = self._cholmod_input(self._A, self._groups)
            F = cholmod.symbolic(M) if p is None else cholmod.symbolic(M, p=p)
            cholmod.numeric(M, F)
            return len(cholmod.getfactor(F).V)
        return int(self.lu.L.nnz + self.lu.U.nnz)

    # -- SuperLU
    def _superlu(self, A: sp.csc_matrix, groups) -> None:
        """SuperLU in "symmetric mode" without pivoting (a positive definite matrix needs
        none) on a minimum-degree ordering of the node graph (``A + A^T`` pattern), each
        node's DOFs kept together. Measured (CPU, 2.8e4-DOF cubic lattice): SuperLU's
        defaults 34 s / 8.4e7 factor entries; minimum degree on the DOF graph 7.2 s /
        4.0e7; on the node graph 3.1 s / 2.5e7."""
        opts = dict(diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        self.backend = "superlu"
        self._F = None
        if groups is None:
            self.perm = None
            self.lu = sla.splu(A, permc_spec="MMD_AT_PLUS_A", **opts)
        else:
            g, G = _group_pattern(A, groups)
            # Only the pattern matters to the ordering; a dominant diagonal keeps this small
            # auxiliary factorisation trivially stable.
            G = G + sp.diags(np.full(G.shape[0], 1.0 + 2.0 * abs(G).sum(axis=1).max()))
            node_pos = sla.splu(G.tocsc(), permc_spec="MMD_AT_PLUS_A", **opts).perm_c
            self.perm = _grouped_order(g, node_pos)
            self.lu = sla.splu(A[self.perm][:, self.perm].tocsc(), permc_spec="NATURAL", **opts)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``A^-1 b`` for b of shape (n,) or (n, k)."""
        b = np.asarray(b, dtype=float)
        if self.backend == "cholmod":
            import cvxopt  # deferred: optional back end
            import cvxopt.cholmod as cholmod  # deferred: optional back end

            s = self._scale.reshape((self.n,) + (1,) * (b.ndim - 1))
            B = cvxopt.matrix(np.asfortranarray((s * b).reshape(self.n, -1)))
            cholmod.solve(self._F, B)
            return s * np.array(B).reshape(b.shape)
        if self.perm is None:
            return self.lu.solve(b)
        x = np.empty_like(b)
        x[self.perm] = self.lu.solve(np.ascontiguousarray(b[self.perm]))
        return x

    def min_pivot_ratio(self) -> float:
        """Smallest ratio of a pivot to its diagonal entry of ``A`` (1 for a diagonal matrix;
        tiny for a nearly singular one: NASTRAN's MAXRATIO test)."""
        if self.backend == "cholmod":
            import cvxopt.cholmod as cholmod  # deferred: optional back end

            return float(np.min(np.array(cholmod.diag(self._F)) ** 2)) if self.n else 1.0
        d = self._A.diagonal()
        return float(np.min(self.pivots() / np.where(d > 0, d, 1.0))) if self.n else 1.0

    def pivots(self) -> np.ndarray:
        """Diagonal of U in the original DOF order (for singularity diagnosis).

        From SuperLU: a CHOLMOD factor does not reveal its permutation, so the matrix is
        factored again with SuperLU (only on the rare diagnostic path).
        """
        if self.backend == "cholmod":
            return SPDFactor(self._A, self._groups, backend="superlu").pivots()
        # SuperLU factors Pr B Pc with column i of B moved to position perm_c[i].
        d = self.lu.U.diagonal()[self.lu.perm_c]
        if self.perm is None:
            return d
        out = np.empty(self.n)
        out[self.perm] = d
        return out


__all__ = ["SPDFactor", "BACKENDS", "cholmod_available"]
