"""trussid.fem.factor: the sparse SPD factorisation behind modes and statics.

Every back end must solve to round-off (checked against a dense solve), report pivots in DOF
order (checked against the closed form of the last pivot), and tell a nearly singular matrix
from a well-conditioned one. "auto" must fall back to SuperLU where CHOLMOD cannot go.
"""

import numpy as np
import pytest
import scipy.sparse as sp

from trussid.fem.factor import SPDFactor, cholmod_available

BACKENDS = ["superlu", pytest.param("cholmod", marks=pytest.mark.skipif(
    not cholmod_available(), reason="cvxopt/pymetis not installed"))]


def _spd(n=80, seed=3):
    B = sp.random(n, n, density=0.05, random_state=seed)
    return (B @ B.T + sp.diags(np.linspace(1.0, 9.0, n))).tocsr()


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("grouped", [False, True])
def test_solves_match_a_dense_solve(backend, grouped):
    A = _spd()
    f = SPDFactor(A, groups=np.arange(80) // 6 if grouped else None, backend=backend)
    assert f.backend == backend
    b = np.random.default_rng(1).standard_normal((80, 3))
    ref = np.linalg.solve(A.toarray(), b)
    assert np.abs(f.solve(b) - ref).max() < 1e-12 * np.abs(ref).max()
    assert np.abs(f.solve(b[:, 0]) - ref[:, 0]).max() < 1e-12 * np.abs(ref).max()


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("grouped", [False, True])
def test_pivots_in_dof_order(backend, grouped):
    """The last pivot of an LDL^T-type elimination is 1 / (A^-1)_jj for the DOF j eliminated
    last; every pivot is positive and at most its diagonal entry. (CHOLMOD hides its
    permutation, so its pivots come from a SuperLU factorisation: same check.)"""
    A = _spd()
    f = SPDFactor(A, groups=np.arange(80) // 6 if grouped else None, backend=backend)
    piv = f.pivots()
    assert np.all(piv > 0) and np.all(piv <= A.diagonal() * (1 + 1e-12))
    g = SPDFactor(A, groups=np.arange(80) // 6 if grouped else None, backend="superlu")
    last = int(g.lu.perm_c.argmax())  # the (permuted) row eliminated last ...
    j = last if g.perm is None else int(g.perm[last])  # ... is this DOF
    assert piv[j] == pytest.approx(1.0 / np.linalg.inv(A.toarray())[j, j], rel=1e-10)
    if backend == "superlu":
        assert f.min_pivot_ratio() == pytest.approx(np.min(piv / A.diagonal()), rel=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_min_pivot_ratio_flags_a_nearly_singular_matrix(backend):
    """A diagonal matrix has every pivot ratio 1; a spring chain with one spring 1e-13 of the
    others has a pivot ratio of order 1e-13 (its Schur complement is that spring)."""
    d = np.linspace(1.0, 5.0, 30)
    assert SPDFactor(sp.diags(d), backend=backend).min_pivot_ratio() == pytest.approx(1.0)
    k = np.ones(30)
    k[17] = 1e-13                    # a nearly broken link between node 16 and 17
    k[0] = 1.0                       # node 0 grounded by spring 0
    main = k + np.r_[k[1:], 0.0]
    A = sp.diags([-k[1:], main, -k[1:]], [-1, 0, 1]).tocsc()
    r = SPDFactor(A, backend=backend).min_pivot_ratio()
    assert r < 1e-10


def test_tridiagonal_fill_is_the_closed_form():
    """No fill on a tridiagonal matrix: L and U have 2n - 1 entries each (SuperLU)."""
    n = 50
    A = sp.diags([-np.ones(n - 1), 2.5 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    assert SPDFactor(A, backend="superlu").factor_nnz() == 2 * (2 * n - 1)


@pytest.mark.skipif(not cholmod_available(), reason="cvxopt/pymetis not installed")
def test_auto_falls_back_to_superlu_on_an_indefinite_matrix():
    A = _spd() - 3.0 * sp.identity(80)
    f = SPDFactor(A, groups=np.arange(80) // 6)
    assert f.backend == "superlu"
    b = np.ones(80)
    assert np.abs(A @ f.solve(b) - b).max() < 1e-9
    with pytest.raises(RuntimeError, match="not positive definite"):
        SPDFactor(A, backend="cholmod")
    assert SPDFactor(_spd(), groups=np.arange(80) // 6).backend == "cholmod"


def test_unknown_backend_is_refused():
    with pytest.raises(ValueError, match="backend"):
        SPDFactor(_spd(), backend="mumps")
