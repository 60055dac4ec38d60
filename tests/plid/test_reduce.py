"""Balanced truncation: Hankel singular values and the error bounds."""

import control
import numpy as np
import pytest

from trussid.plid.errors import IdentificationError
from trussid.plid.reduce import balanced_truncation, hankel_singular_values

Z = np.exp(1j * np.linspace(0, np.pi, 600))


def _hinf_on_grid(sys):
    return max(np.linalg.norm(np.atleast_2d(np.asarray(sys(z))), 2) for z in Z)


@pytest.fixture
def stable_plant(modal_plant, rng):
    return modal_plant([40.0, 120.0, 300.0, 520.0], [0.05, 0.03, 0.02, 0.02], 2, 2, 1600, rng)


def test_hankel_singular_values_equal_those_of_the_hankel_matrix(modal_plant, rng):
    # Independent: the singular values of the block Hankel matrix of Markov parameters
    # C A^(i+j) B converge to the Hankel singular values (well damped here, so that
    # 2 x 300 Markov parameters cover the decay to 1e-12).
    plant = modal_plant([60.0, 150.0, 300.0, 520.0], [0.3] * 4, 2, 2, 1600, rng)
    A, B, C = (np.asarray(M) for M in (plant.A, plant.B, plant.C))
    markov = [C @ np.linalg.matrix_power(A, k) @ B for k in range(600)]
    K = 300
    Hk = np.block([[markov[i + j] for j in range(K)] for i in range(K)])
    sv = np.linalg.svd(Hk, compute_uv=False)[:8]
    hsv = hankel_singular_values(plant)
    assert np.allclose(hsv, sv, rtol=1e-8)


@pytest.mark.parametrize("r", [2, 4, 6])
def test_truncation_error_lies_between_the_hankel_bounds(stable_plant, r):
    res = balanced_truncation(stable_plant, r)
    assert res.model.nstates == r
    err = _hinf_on_grid(stable_plant - res.model)
    assert res.hsv[r] * (1 - 1e-6) <= err <= res.error_bound
    assert np.isclose(res.error_bound, 2 * res.hsv[r:].sum())


def test_unstable_part_is_kept_and_only_the_stable_part_reduced(stable_plant, rng):
    th = 0.3
    Au = 1.02 * np.array([[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]])
    Bu, Cu = rng.standard_normal((2, 2)), rng.standard_normal((2, 2))
    As = np.asarray(stable_plant.A)
    big = control.ss(np.block([[As, np.zeros((8, 2))], [np.zeros((2, 8)), Au]]),
                     np.vstack([stable_plant.B, Bu]), np.hstack([stable_plant.C, Cu]),
                     0, stable_plant.dt)
    res = balanced_truncation(big, 6)
    assert res.n_unstable == 2 and res.model.nstates == 6
    poles = control.poles(res.model)
    assert np.allclose(np.sort(np.abs(poles[np.abs(poles) > 1])), [1.02, 1.02])
    # the difference is the stable part's truncation error, within its bound
    err = _hinf_on_grid(big - res.model)
    assert err <= res.error_bound
    assert np.allclose(res.hsv, hankel_singular_values(stable_plant), rtol=1e-8)


def test_order_below_the_unstable_part_is_refused():
    A = np.diag([1.1, 1.2, 0.5, 0.3])
    sys = control.ss(A, np.ones((4, 1)), np.ones((1, 4)), 0, 1)
    with pytest.raises(IdentificationError, match="2 unstable states"):
        balanced_truncation(sys, 1)


# --------------------------------------------------------------------------- input-weighted


def test_state_covariance_under_white_input_tends_to_the_controllability_gramian(
        stable_plant, rng):
    # Independent: the Lyapunov solution A W A^T - W + B B^T = 0 is the covariance of the
    # state driven by unit white noise. Sampling spread of a 200000-sample estimate of a
    # 0.02-damped state's variance: correlation time ~ 1/(2 pi zeta f dt) ~ 40 samples,
    # relative std ~ sqrt(2 * 40 / 2e5) = 2 %; allow 10 % of the largest entry.
    from trussid.plid.reduce import state_covariance

    A, B = np.asarray(stable_plant.A), np.asarray(stable_plant.B)
    u = rng.standard_normal((200_000, B.shape[1]))
    W = scipy_lyap(A, B @ B.T)
    P = state_covariance(A, B, u)
    assert np.max(np.abs(P - W)) < 0.1 * np.max(np.abs(W))


def scipy_lyap(A, Q):
    import scipy.linalg

    return scipy.linalg.solve_discrete_lyapunov(A, Q)


def test_input_weighting_keeps_the_mode_the_input_excites(modal_plant, rng):
    # A strong 600 Hz mode and a weak 100 Hz one; the input has no power above 250 Hz.
    # Unweighted truncation to 2 states keeps 600 Hz (largest Hankel singular value);
    # weighted by the input it keeps 100 Hz, the mode that carries the response.
    import scipy.signal

    from trussid.plid.metrics import modal_parameters

    plant = modal_plant([100.0, 600.0], [0.01, 0.01], 1, 1, 1600, rng)
    A, B, C = (np.asarray(M) for M in (plant.A, plant.B, plant.C))
    # make the 600 Hz mode dominate under white input
    C = C.copy()
    C[:, 2:] *= 30.0 / np.linalg.norm(C[:, 2:])
    C[:, :2] *= 1.0 / np.linalg.norm(C[:, :2])
    plant = control.ss(A, B, C, plant.D, plant.dt)
    sos = scipy.signal.butter(8, 250.0, fs=1600.0, output="sos")
    u = scipy.signal.sosfilt(sos, rng.standard_normal(20000))[:, None]
    f_plain = modal_parameters(balanced_truncation(plant, 2).model)[0]
    weighted = balanced_truncation(plant, 2, u=u)
    f_weighted = modal_parameters(weighted.model)[0]
    assert np.allclose(f_plain, 600.0, rtol=0.02)
    assert np.allclose(f_weighted, 100.0, rtol=0.02)
    assert np.isnan(weighted.error_bound)


def test_input_weighting_refuses_an_input_of_the_wrong_width(stable_plant, rng):
    with pytest.raises(IdentificationError, match="columns"):
        balanced_truncation(stable_plant, 2, u=rng.standard_normal((100, 3)))
