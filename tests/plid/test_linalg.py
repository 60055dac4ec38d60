"""The private linear algebra of the identification front end (``plid._linalg``): its
least-squares solver and output regressors."""

import numpy as np
import scipy.linalg

from trussid.plid._linalg import lstsq, modal_regressors, real_modal_regressors


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


def _state_space_response(A, B, C, D, x0, u):
    """y[k] = C x[k] + D u[k], x[k+1] = A x[k] + B u[k]: the plain recursion."""
    x, out = x0.copy(), []
    for uk in u:
        out.append(C @ x + D @ uk)
        x = A @ x + B @ uk
    return np.array(out)


def test_real_modal_regressors_reproduce_the_state_space_response():
    # a real A with real and complex-pair poles; B, x0, D mapped into the regressors'
    # real modal coordinates (theta_state = P theta_modal) give the recursion's output
    rng = np.random.default_rng(6)
    n, m, p, N = 7, 2, 3, 300
    A = rng.standard_normal((n, n))
    A *= 0.95 / np.max(np.abs(np.linalg.eigvals(A)))
    lam = np.linalg.eigvals(A)
    assert np.any(lam.imag > 0) and np.any(lam.imag == 0)
    B, C = rng.standard_normal((n, m)), rng.standard_normal((p, n))
    D, x0, u = rng.standard_normal((p, m)), rng.standard_normal(n), rng.standard_normal((N, m))
    R, P = real_modal_regressors(A, C, u, x0=True, direct=True)
    assert R.shape == (N, p, m * n + n + p * m)
    theta = np.concatenate([np.linalg.solve(P, B).T.ravel(), np.linalg.solve(P, x0),
                            D.ravel()])
    y = _state_space_response(A, B, C, D, x0, u)
    assert np.allclose(R @ theta, y, rtol=0, atol=1e-10 * np.max(np.abs(y)))


def test_real_modal_regressors_span_the_state_coordinates_regressors():
    # the same least-squares fit as in state coordinates (same column space)
    rng = np.random.default_rng(7)
    n, m, p, N = 6, 1, 2, 400
    A = rng.standard_normal((n, n))
    A *= 0.9 / np.max(np.abs(np.linalg.eigvals(A)))
    C, u = rng.standard_normal((p, n)), rng.standard_normal((N, m))
    y = rng.standard_normal((N, p))
    Rs = modal_regressors(A, C, u, x0=True).reshape(N * p, -1)
    Rm = real_modal_regressors(A, C, u, x0=True)[0].reshape(N * p, -1)
    fit_s = Rs @ np.linalg.lstsq(Rs, y.ravel(), rcond=None)[0]
    fit_m = Rm @ np.linalg.lstsq(Rm, y.ravel(), rcond=None)[0]
    assert np.allclose(fit_m, fit_s, atol=1e-10)


def test_real_modal_regressors_with_a_pole_at_the_origin():
    # a pure delay state (eigenvalue 0): its initial state shows at sample 0 only
    A = np.array([[0.0, 0.0], [0.0, 0.5]])
    C = np.array([[1.0, 1.0]])
    u = np.random.default_rng(8).standard_normal((50, 1))
    R, P = real_modal_regressors(A, C, u, x0=True)
    B, x0, D = np.array([[1.0], [2.0]]), np.array([3.0, -1.0]), np.zeros((1, 1))
    theta = np.concatenate([np.linalg.solve(P, B).ravel(), np.linalg.solve(P, x0)])
    assert np.allclose(R @ theta, _state_space_response(A, B, C, D, x0, u), atol=1e-12)
