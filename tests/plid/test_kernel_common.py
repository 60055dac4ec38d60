"""Shared pieces of the compiled kernels: the compiled state recursion behind
:func:`trussid.plid.simulate` equals scipy's simulation and the numpy fallback."""

import numpy as np
import scipy.signal

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
