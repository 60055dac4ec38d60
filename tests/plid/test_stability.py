"""Stabilisation by pole reflection: stable poles, |H| kept (the all-pass argument)."""

import control
import numpy as np
import pytest

from trussid.plid.errors import IdentificationError
from trussid.plid.stability import stabilise

W = np.linspace(0.01, 3.13, 80)
Z = np.exp(1j * W)


def _resp(sys):
    return np.array([np.asarray(sys(z)) for z in Z])


def test_siso_poles_are_reflected_and_magnitude_kept_exactly():
    p_bad = 1.03 * np.exp(0.3j)
    poles = [p_bad, np.conj(p_bad), 0.9 * np.exp(1j), 0.9 * np.exp(-1j), 0.5]
    H = control.ss(control.zpk([0.3, -0.5 + 0.2j, -0.5 - 0.2j], poles, 2.0, dt=0.01))
    res = stabilise(H)
    assert res.applied and res.magnitude_exact
    assert res.model.nstates == H.nstates and res.model.dt == H.dt
    new = np.sort_complex(control.poles(res.model))
    expected = np.sort_complex(np.r_[1 / np.conj(p_bad), 1 / p_bad, poles[2:]])
    assert np.allclose(new, expected, atol=1e-12)
    h, g = _resp(H).ravel(), _resp(res.model).ravel()
    assert np.max(np.abs(np.abs(g) - np.abs(h)) / np.abs(h)) < 1e-10
    # All-pass argument: G / H is the unit-modulus factor prod (z - p) / (|p| (z - 1/conj p)).
    a = np.prod([(Z - p) / (abs(p) * (Z - 1 / np.conj(p))) for p in (p_bad, np.conj(p_bad))],
                axis=0)
    assert np.allclose(np.abs(a), 1.0, atol=1e-13)
    assert np.max(np.abs(g - h * a) / np.abs(h)) < 1e-10


def test_stable_model_is_returned_unchanged_and_reported():
    H = control.ss(control.zpk([0.2], [0.5, 0.8], 1.0, dt=1))
    res = stabilise(H)
    assert not res.applied and res.model is H and res.reflected.size == 0


def test_mimo_keeps_order_stable_part_and_the_unstable_modes_own_magnitude():
    rng = np.random.default_rng(4)
    p_bad = 1.01 * np.exp(0.6j)

    def rot(r, t):
        return r * np.array([[np.cos(t), np.sin(t)], [-np.sin(t), np.cos(t)]])

    A = np.zeros((6, 6))
    A[:2, :2] = rot(abs(p_bad), np.angle(p_bad))
    A[2:4, 2:4] = rot(0.9, 1.5)
    A[4:, 4:] = rot(0.7, 2.5)
    B, C = rng.standard_normal((6, 2)), rng.standard_normal((3, 6))
    H = control.ss(A, B, C, np.zeros((3, 2)), 1)
    res = stabilise(H)
    assert res.applied and not res.magnitude_exact
    assert res.model.nstates == 6
    assert np.max(np.abs(control.poles(res.model))) < 1
    assert np.allclose(np.abs(res.reflected), abs(p_bad))
    # Residues (C v_k)(w_k^T B) of a model with distinct poles.
    def residue(sys, pole):
        lam, V = np.linalg.eig(np.asarray(sys.A))
        k = np.argmin(np.abs(lam - pole))
        assert abs(lam[k] - pole) < 1e-10
        return np.outer(np.asarray(sys.C) @ V[:, k], np.linalg.solve(V, np.asarray(sys.B))[k])

    # Stable modes untouched (same poles, same residues).
    for p in np.linalg.eigvals(A[2:, 2:]):
        assert np.allclose(residue(res.model, p), residue(H, p), rtol=1e-9, atol=1e-12)
    # Each reflected mode's residue is the original one over |p|, so its own term keeps
    # |R / (e^{jw} - p)| = |R / |p| / (e^{jw} - 1/conj p)| (MIMO: exact |H| would need
    # a higher McMillan degree, so the order is kept instead).
    for p in (p_bad, np.conj(p_bad)):
        assert np.allclose(residue(res.model, 1 / np.conj(p)), residue(H, p) / abs(p),
                           rtol=1e-9, atol=1e-12)


def test_continuous_model_is_refused():
    with pytest.raises(IdentificationError, match="discrete"):
        stabilise(control.ss([[1.0]], [[1.0]], [[1.0]], 0))
