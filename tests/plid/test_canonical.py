"""Observer-form parameterisation: A = F + Abar C, theta = [vec(Abar); vec(B)]."""

import control
import numpy as np
import pytest

from tests.plid.arx import arx_observer_form
from trussid.plid.canonical import (ObserverBasis, check_order, from_statespace, join_theta,
                            split_theta, to_statespace)
from trussid.plid.errors import IdentificationError


def _freqresp(sys, w):
    return np.array([np.asarray(sys(np.exp(1j * wk))) for wk in w])


def test_shift_basis_structure_matches_the_spec():
    b = ObserverBasis.shift(6, 2)
    # C row i selects state s_i = i * nu; S shifts within each block of nu = 3 states.
    assert np.array_equal(b.C, [[1, 0, 0, 0, 0, 0], [0, 0, 0, 1, 0, 0]])
    expected = np.zeros((6, 6))
    for s in (0, 3):
        expected[s, s + 1] = expected[s + 1, s + 2] = 1
    assert np.array_equal(b.F, expected)
    assert b.n_params(m=3) == 6 * (2 + 3)


def test_order_not_multiple_of_outputs_suggests_nearest_valid_orders():
    with pytest.raises(IdentificationError, match=r"order 13 .*multiple.*3.*12 or 15"):
        check_order(13, 3)
    with pytest.raises(IdentificationError, match="order 12 or 15"):
        ObserverBasis.shift(13, 3)
    assert check_order(12, 3) == 4
    assert check_order(5, 1) == 5


def test_theta_is_column_major_abar_then_b():
    Abar = np.arange(6.0).reshape(3, 2)
    B = 10 + np.arange(3.0)[:, None]
    theta = join_theta(Abar, B)
    assert np.array_equal(theta, [0, 2, 4, 1, 3, 5, 10, 11, 12])
    A2, B2 = split_theta(theta, 3, 2, 1)
    assert np.array_equal(A2, Abar) and np.array_equal(B2, B)


@pytest.mark.parametrize("n,m,p", [(4, 1, 1), (12, 1, 3), (12, 3, 3)])
def test_conversion_preserves_the_transfer_function(n, m, p, modal_plant, rng):
    sys = modal_plant(np.linspace(50, 350, n // 2), [0.02] * (n // 2), m, p, 1600, rng)
    basis = ObserverBasis.shift(n, p)
    theta, T = from_statespace(sys, basis)
    back = to_statespace(theta, basis, m, sys.dt)
    w = np.linspace(0.05, 3.0, 40)
    H, G = _freqresp(sys, w), _freqresp(back, w)
    assert np.max(np.abs(G - H)) <= 1e-8 * np.max(np.abs(H))
    # and it is the similarity x' = T x
    assert np.allclose(T @ sys.A, np.asarray(back.A) @ T, atol=1e-9 * np.abs(sys.A).max())


@pytest.mark.parametrize("n,m,p", [(4, 1, 1), (12, 3, 3)])
def test_shift_and_sylvester_constructions_agree(n, m, p, modal_plant, rng):
    sys = modal_plant(np.linspace(50, 350, n // 2), [0.02] * (n // 2), m, p, 1600, rng)
    basis = ObserverBasis.shift(n, p)
    t1, _ = from_statespace(sys, basis, method="shift")
    t2, _ = from_statespace(sys, basis, method="sylvester")
    assert np.linalg.norm(t1 - t2) <= 1e-8 * np.linalg.norm(t1)


@pytest.mark.parametrize("n,m,p", [(4, 1, 1), (12, 1, 3), (12, 3, 3)])
def test_parameters_equal_arx_coefficients_on_noiseless_data(n, m, p, modal_plant,
                                                             simulate, rng):
    # Independent check: eliminating the states of the shift form gives an ARX model whose
    # least-squares coefficients on noiseless data are exactly the canonical parameters.
    sys = modal_plant(np.linspace(50, 350, n // 2), [0.02] * (n // 2), m, p, 1600, rng)
    theta, _ = from_statespace(sys, ObserverBasis.shift(n, p))
    u = rng.standard_normal((2000, m))
    y, _ = simulate(sys, u)
    theta_ls = arx_observer_form(u, y, n)
    assert np.linalg.norm(theta_ls - theta) <= 1e-8 * np.linalg.norm(theta)


def test_custom_basis_is_accepted_and_round_trips(modal_plant, rng):
    # A stable rotation basis, the kind docs/plid.md recommends beyond 12 states.
    sys = modal_plant([80.0, 250.0], [0.02, 0.02], 1, 1, 1600, rng)
    F = np.zeros((4, 4))
    for k, th in enumerate([0.4, 1.2]):
        F[2 * k:2 * k + 2, 2 * k:2 * k + 2] = 0.97 * np.array(
            [[np.cos(th), np.sin(th)], [-np.sin(th), np.cos(th)]])
    basis = ObserverBasis(F, [[1.0, 0, 1.0, 0]], name="rotation")
    theta, _ = from_statespace(sys, basis)
    back = to_statespace(theta, basis, 1, sys.dt)
    w = np.linspace(0.05, 3.0, 40)
    H, G = _freqresp(sys, w), _freqresp(back, w)
    assert np.max(np.abs(G - H)) <= 1e-8 * np.max(np.abs(H))
    assert np.array_equal(np.asarray(back.C), basis.C)


def test_unobservable_model_is_refused_with_a_reason():
    A = np.diag([0.5, 0.6])
    sys = control.ss(A, [[1.0], [1.0]], [[1.0, 0.0]], 0, 1)  # second state unobservable
    with pytest.raises(IdentificationError, match="singular"):
        from_statespace(sys, ObserverBasis.shift(2, 1))


def test_feedthrough_is_refused():
    sys = control.ss([[0.5]], [[1.0]], [[1.0]], [[0.3]], 1)
    with pytest.raises(IdentificationError, match="feed-through"):
        from_statespace(sys, ObserverBasis.shift(1, 1))
