"""Subspace and output-error building blocks (trussid.plid.subspace): N4SID's own steps, the
output-error refit with a direct term, and the data-driven test for a direct term."""

import control
import numpy as np
import pytest

from trussid.plid.errors import IdentificationError
from trussid.plid.subspace import _hankel, direct_term_test, n4sid, output_error_fit

from tests.plid.plants import accelerometer_plant, record

FS = 1000.0


def test_hankel_matrix_has_nfoursids_layout():
    from nfoursid.utils import Utils

    a = np.arange(30.0).reshape(10, 3)
    np.testing.assert_array_equal(_hankel(a, 4), Utils.block_hankel_matrix(a, 4))


def test_n4sid_refuses_too_few_block_rows_for_the_order():
    u = np.random.default_rng(0).standard_normal((400, 1))
    with pytest.raises(IdentificationError, match="at most order"):
        n4sid(u, u, 6, 3, 1.0)


def test_output_error_fit_recovers_B_and_D_exactly_on_noiseless_data():
    plant = accelerometer_plant()
    u, _ = record(plant, 600, 300, seed=1)
    y = np.atleast_2d(control.forced_response(plant, U=u.T).outputs).T
    wrong = control.ss(plant.A, np.ones_like(plant.B), plant.C, 0 * plant.D, plant.dt)
    fit, y_sim, D_std = output_error_fit(wrong, u, y, direct=True)
    np.testing.assert_allclose(fit.D, plant.D, rtol=1e-7, atol=1e-9 * np.abs(plant.D).max())
    np.testing.assert_allclose(fit.B, plant.B, rtol=1e-6, atol=1e-9 * np.abs(plant.B).max())
    np.testing.assert_allclose(y_sim, y, atol=1e-8 * np.abs(y).max())
    assert D_std.shape == plant.D.shape


def test_direct_term_test_asks_for_D_on_an_accelerometer_and_not_on_a_strictly_proper_plant():
    acc = accelerometer_plant()
    u, y = record(acc, 3000, 40, seed=2)
    assert direct_term_test(acc, u, y)["direct"]
    proper = control.ss(acc.A, acc.B, acc.C, 0 * acc.D, acc.dt)
    u, y = record(proper, 3000, 40, seed=2)
    test = direct_term_test(proper, u, y)
    assert not test["direct"]
    # with no feed-through in the data, D only fits noise: the held-out error does not drop
    assert test["held_out_nmse"]["with"] > 0.95 * test["held_out_nmse"]["without"]


def test_output_error_fit_refuses_an_unstable_model():
    unstable = control.ss([[1.01]], [[1.0]], [[1.0]], 0, 1.0)
    u = np.ones((50, 1))
    with pytest.raises(IdentificationError, match="stable"):
        output_error_fit(unstable, u, u)
