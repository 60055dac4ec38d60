"""The private least-squares solver of the identification front end (``plid._linalg``)."""

import numpy as np
import scipy.linalg

from trussid.plid._linalg import lstsq


def test_lstsq_equals_a_qr_solution_on_a_well_conditioned_tall_system():
    rng = np.random.default_rng(3)
    M = rng.standard_normal((4000, 60)) * np.logspace(-3, 3, 60)   # badly scaled columns
    b = rng.standard_normal(4000)
    x = lstsq(M, b)
    ref = np.linalg.lstsq(M, b, rcond=None)[0]                      # SVD-based solver
    # compared in the units of the equilibrated columns (the solvers' own error is
    # relative to those): within 1e-9 of the largest entry
    cn = np.linalg.norm(M, axis=0)
    assert np.max(np.abs((x - ref) * cn)) <= 1e-9 * np.max(np.abs(ref * cn))


def test_lstsq_falls_back_to_pivoted_qr_when_the_columns_are_nearly_dependent():
    rng = np.random.default_rng(4)
    M = rng.standard_normal((500, 10))
    M[:, 9] = M[:, 8] + 1e-9 * rng.standard_normal(500)             # cond(M) ~ 1e9
    b = rng.standard_normal(500)
    x = lstsq(M, b)
    ref = scipy.linalg.lstsq(M, b, lapack_driver="gelsy")[0]
    assert np.allclose(x, ref)
    # and its residual is the least-squares one
    res_ref = np.linalg.norm(M @ np.linalg.lstsq(M, b, rcond=None)[0] - b)
    assert np.linalg.norm(M @ x - b) <= res_ref * (1 + 1e-9)


def test_lstsq_solves_several_right_hand_sides():
    rng = np.random.default_rng(5)
    M = rng.standard_normal((300, 8))
    X = rng.standard_normal((8, 3))
    assert np.allclose(lstsq(M, M @ X), X, rtol=1e-10)
