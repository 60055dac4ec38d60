"""Shared pieces of the compiled kernels: the compiled state recursion behind
:func:`trussid.plid.simulate` equals scipy's simulation and the numpy fallback; the
diagonal form of a matrix multiplies as the matrix does."""

import numpy as np
import pytest
import scipy.signal

from trussid.plid.bases import basis_for
from trussid.plid.canonical import ObserverBasis

from trussid.plid import kernel_common as KC


def _system(rng, n=8, m=2):
    A = rng.standard_normal((n, n))
    A *= 0.95 / np.max(np.abs(np.linalg.eigvals(A)))          # stable, spectral radius 0.95
    return A, rng.standard_normal((n, m))


def test_state_sequence_equals_scipys_dlsim():
    rng = np.random.default_rng(7)
    A, B = _system(rng)
    u = rng.standard_normal((500, 2))
    x0 = rng.standard_normal(8)
    X = KC.state_sequence(A, u @ B.T, x0)
    _, _, xs = scipy.signal.dlsim((A, B, np.eye(8), np.zeros((8, 2)), 1.0), u, x0=x0)
    assert np.allclose(X, xs, rtol=1e-12, atol=1e-12 * np.abs(xs).max())


def test_state_sequence_is_the_same_without_numba(monkeypatch):
    rng = np.random.default_rng(8)
    A, B = _system(rng)
    Bu = rng.standard_normal((300, 2)) @ B.T
    x0 = np.ones(8)
    compiled = KC.state_sequence(A, Bu, x0)
    monkeypatch.setattr(KC, "_state_sequence_compiled", None)
    plain = KC.state_sequence(A, Bu, x0)
    assert np.allclose(compiled, plain, rtol=1e-13, atol=1e-13 * np.abs(plain).max())
    assert np.array_equal(x0, np.ones(8))                       # the start is not overwritten


def _apply_diagonals(offs, V, x):
    """``sum_k V[k, a] x[a + o_k]``, the product as the square-root kernel forms it."""
    n = x.shape[0]
    out = np.zeros_like(x)
    for k, o in enumerate(offs):
        lo, hi = max(0, -o), min(n, n - o)
        out[lo:hi] += V[k, lo:hi, None] * x[lo + o:hi + o]
    return out


@pytest.mark.parametrize("name", ["shift", "rotation", "random sparse", "dense"])
def test_diagonals_multiply_as_the_matrix(name):
    rng = np.random.default_rng(3)
    n = 12
    M = {"shift": lambda: ObserverBasis.shift(n, 3).F,
         "rotation": lambda: basis_for(n, 2, 1600.0, [50, 90, 150, 220, 300, 400]).F,
         "random sparse": lambda: rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.15),
         "dense": lambda: rng.standard_normal((n, n))}[name]()
    offs, V = KC.diagonals(M)
    # only the diagonals that hold a non-zero are kept
    assert set(offs.tolist()) == set((np.nonzero(M)[1] - np.nonzero(M)[0]).tolist())
    X = rng.standard_normal((n, 5))
    assert np.allclose(_apply_diagonals(offs, V, X), M @ X, rtol=0, atol=1e-13)


def test_plids_bases_have_at_most_three_diagonals():
    # why the square-root kernel applies F by diagonals: a few contiguous sweeps per column
    for F in (ObserverBasis.shift(30, 3).F,
              basis_for(30, 3, 1600.0, np.linspace(40, 700, 15)).F):
        assert KC.diagonals(F)[0].size <= 3



def _apply_pairs(B, x):
    """``M x`` from the rows ``[m00, m01, m10, m11]`` of M's 2 x 2 diagonal blocks."""
    x0, x1 = x[0::2], x[1::2]
    out = np.empty_like(x)
    out[0::2] = B[:, 0, None] * x0 + B[:, 1, None] * x1
    out[1::2] = B[:, 2, None] * x0 + B[:, 3, None] * x1
    return out


def test_the_rotation_basis_is_applied_by_its_pair_blocks_and_others_are_not():
    rng = np.random.default_rng(4)
    for n, p in ((12, 2), (12, 3), (30, 3)):
        F = basis_for(n, p, 1600.0, np.linspace(40, 700, n // 2)).F
        B = KC.pair_blocks(F)
        assert B.shape == (n // 2, 4)
        X = rng.standard_normal((n, 5))
        assert np.allclose(_apply_pairs(B, X), F @ X, rtol=0, atol=1e-13)
    # not block-diagonal in pairs from the first row: a shift, a real pole per output
    # (odd states per output shift the pairs), a coupling outside the blocks, odd n
    coupled = basis_for(12, 2, 1600.0, np.linspace(40, 700, 6)).F.copy()
    coupled[0, 5] = 0.1
    for F in (ObserverBasis.shift(12, 3).F, basis_for(9, 3, 1600.0, np.linspace(40, 700, 6)).F,
              coupled, np.eye(5)):
        assert KC.pair_blocks(F).shape == (0, 4)


def _predictor_case(seed=11, n=8, m=2, p=3, N=400, c=4):
    rng = np.random.default_rng(seed)
    A, B = _system(rng, n, m)
    C = rng.standard_normal((p, n))
    D = rng.standard_normal((p, m))
    u = rng.standard_normal((N, m))
    y = rng.standard_normal((N, p))
    # small gains keep every predictor A - K C stable
    Ks = 0.05 * rng.standard_normal((c, n, p))
    return A, B, C, D, Ks, u, y


def test_mean_square_errors_equal_those_of_scipys_predictor_simulation():
    A, B, C, D, Ks, u, y = _predictor_case()
    skip = 25
    got = KC.mean_square_errors(A, B, C, D, Ks, u, y, skip)
    for i, K in enumerate(Ks):
        # independently: the predictor as an LTI system driven by [u, y], simulated by scipy
        pred = (A - K @ C, np.hstack([B - K @ D, K]), C, np.hstack([D, np.zeros((3, 3))]), 1.0)
        _, yhat, _ = scipy.signal.dlsim(pred, np.hstack([u, y]))
        want = np.mean((y - yhat)[skip:] ** 2, axis=0)
        assert np.allclose(got[i], want, rtol=1e-11, atol=0)


def test_mean_square_errors_are_the_same_without_numba(monkeypatch):
    A, B, C, D, Ks, u, y = _predictor_case(seed=12)
    compiled = KC.mean_square_errors(A, B, C, D, Ks, u, y, 10)
    monkeypatch.setattr(KC, "_mean_square_errors_compiled", None)
    plain = KC.mean_square_errors(A, B, C, D, Ks, u, y, 10)
    assert np.allclose(compiled, plain, rtol=1e-12, atol=0)


def test_mode_signals_are_the_one_pole_filters_and_the_powers_of_each_pole(monkeypatch):
    rng = np.random.default_rng(13)
    lam = np.array([0.9 * np.exp(0.4j), 0.5 + 0j, -0.7 + 0.1j, 0j])
    E = rng.standard_normal((60, 2))
    F = KC.mode_signals(lam, E)
    assert F.shape == (3 * lam.size, 60)
    # independently, from the definition: f[k] = sum_{i<k} lam^(k-1-i) e[i]; then lam^k
    for c in range(2):
        for s, ls in enumerate(lam):
            want = [sum(ls ** (k - 1 - i) * E[i, c] for i in range(k)) for k in range(60)]
            assert np.allclose(F[c * lam.size + s], want, rtol=1e-12, atol=1e-13)
    for s, ls in enumerate(lam):
        assert np.allclose(F[2 * lam.size + s], ls ** np.arange(60), rtol=1e-12, atol=1e-300)
    monkeypatch.setattr(KC, "_mode_signals_compiled", None)
    assert np.allclose(KC.mode_signals(lam, E), F, rtol=1e-12, atol=1e-13)
