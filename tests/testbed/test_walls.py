"""The testbed's modes come from the one eigen solver, :mod:`trussid.fem.modal` (issue 31,
acceptance 4), and equal an independent solution: ARPACK shift-invert with SciPy's own
SuperLU factor (``scipy.sparse.linalg.eigsh``) on the whole assembled ``K``, ``M``."""

import numpy as np
import pytest
import scipy.sparse.linalg as sla

from trussid.fem.assembly import assemble
from trussid.fem.modal import DENSE_MAX_DOF
from trussid.geometry.spec import Testbed
from trussid.testbed.model import build_testbed
from trussid.testbed.walls import solve_testbed_modes, wall_basis, wall_modes

N = 30


def reference(K, M, k):
    """Lowest ``k`` frequencies [Hz] and shapes by eigsh shift-invert at 0 (K is positive
    definite: the testbed hangs on grounded bungees or is clamped).

    The frequencies are the Rayleigh quotients of eigsh's vectors: ARPACK's Ritz values of
    the inverted operator are accurate relative to its largest one, which leaves the
    mode at 138 Hz 1.5e-8 off on the default mesh (the Rayleigh quotient of the vector
    is accurate to the square of its error, and agrees with the dense solution to 1e-11).
    """
    lam, X = sla.eigsh(K.tocsc(), k=k, M=M.tocsc(), sigma=0.0, which="LM", tol=0.0,
                       v0=np.random.default_rng(1).standard_normal(K.shape[0]))
    X = X[:, np.argsort(lam)]
    rq = np.einsum("ij,ij->j", X, K @ X) / np.einsum("ij,ij->j", X, M @ X)
    return np.sqrt(rq) / (2 * np.pi), X


def mac(a, b, M):
    """Mass-weighted modal assurance criterion of matching columns."""
    ab = np.einsum("ij,ij->j", a, M @ b)
    return ab**2 / (np.einsum("ij,ij->j", a, M @ a) * np.einsum("ij,ij->j", b, M @ b))


@pytest.fixture(scope="module", params=[2, 4, 10], ids=lambda e: f"{e} elements per segment")
def case(request):
    tbm = build_testbed(Testbed(), request.param)
    return tbm, assemble(tbm.model)


def test_testbed_modes_equal_an_independent_solve_to_1e9_and_mac_1(case):
    tbm, system = case
    f_ref, X_ref = reference(system.K, system.M, N)
    modes = solve_testbed_modes(tbm, N, system=system)
    assert modes.method == ("dense" if system.n_dof <= DENSE_MAX_DOF else "shift-invert")
    assert np.max(np.abs(modes.frequencies_hz / f_ref - 1)) < 1e-9
    assert mac(modes.shapes, X_ref, system.M).min() > 0.999999
    assert np.allclose(modes.shapes.T @ (system.M @ modes.shapes), np.eye(N), atol=1e-9)


def test_every_mode_below_a_frequency_is_found_by_value(case):
    tbm, system = case
    f_ref, _ = reference(system.K, system.M, 60)
    f_max = 0.5 * (f_ref[44] + f_ref[45])             # 45 modes lie below it
    below = solve_testbed_modes(tbm, 12, system=system, max_frequency_hz=f_max)
    assert len(below) == 45
    assert np.max(np.abs(below.frequencies_hz / f_ref[:45] - 1)) < 1e-9


def test_wall_sweep_modes_equal_an_independent_solve_at_other_walls(case):
    tbm, system = case
    basis = wall_basis(tbm, system)
    walls = np.asarray(tbm.testbed.struts.walls) * np.array([0.7, 1.3, 0.9, 1.1, 1.25, 0.8])
    K, M = (basis.sparse(d) for d in basis.data(walls))
    f_ref, X_ref = reference(K, M, N)
    f, X = wall_modes(basis, walls, N)
    assert np.max(np.abs(f / f_ref - 1)) < 1e-9
    assert mac(X, X_ref, M).min() > 0.999999
    assert np.allclose(X.T @ (M @ X), np.eye(N), atol=1e-9)      # mass-normalised
