"""Element matrices, one element at a time and all at once, against mechanics."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trussid.fem import ModelError
from trussid.fem.constraints import rigid_body_modes
from trussid.fem.elements import frame_matrices, local_axes

E, G, RHO = 70e9, 26e9, 2700.0
A, IY, IZ, J, ASY, ASZ = 3.0e-4, 2.0e-8, 5.0e-8, 4.5e-8, 2.5e-4, 1.5e-4


def element(L=0.7, theory="euler-bernoulli", mass="consistent", rod=False, nsm=0.0, R=None, n=1):
    args = [np.full(n, v) for v in (L, A, IY, IZ, J, E, G, RHO)]
    return frame_matrices(*args, nsm=nsm, Asy=ASY, Asz=ASZ, rod=rod, R=R, theory=theory, mass=mass)


def random_elements(rng, n=6):
    a = rng.normal(size=(n, 3))
    b = a + rng.normal(size=(n, 3))
    v = rng.normal(size=(n, 3))
    return a, b, v


def test_local_axes_follow_the_nastran_v_vector_convention():
    L, R = local_axes(np.array([[1.0, 1.0, 1.0]]), np.array([[1.0, 3.0, 1.0]]), np.array([[0.0, 1.0, 1.0]]))
    assert L[0] == pytest.approx(2.0)
    ex, ey, ez = R[0]
    assert np.allclose(ex, [0, 1, 0])  # A to B
    assert np.allclose(ey, [0, 0, 1])  # v minus its axial part
    assert np.allclose(ez, [1, 0, 0])  # x cross y


def test_rotation_matrices_are_proper_orthonormal(rng):
    a, b, v = random_elements(rng)
    _, R = local_axes(a, b, v)
    assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-14)
    assert np.allclose(np.linalg.det(R), 1.0)


@pytest.mark.parametrize("theory", ["euler-bernoulli", "timoshenko"])
@pytest.mark.parametrize("rod", [False, True])
def test_global_stiffness_is_symmetric_with_exactly_the_rigid_motions_as_null_space(theory, rod, rng):
    a, b, v = random_elements(rng)
    L, R = local_axes(a, b, v)
    K, M = frame_matrices(L, A, IY, IZ, J, E, G, RHO, Asy=ASY, Asz=ASZ, rod=rod, R=R, theory=theory)
    assert np.allclose(K, K.transpose(0, 2, 1), rtol=0, atol=1e-9 * np.abs(K).max())
    assert np.allclose(M, M.transpose(0, 2, 1), rtol=0, atol=1e-12 * np.abs(M).max())
    for i in range(len(L)):
        Rb = rigid_body_modes(np.array([a[i], b[i]]))
        assert np.abs(K[i] @ Rb).max() <= 1e-9 * np.abs(K[i]).max()
        w = np.linalg.eigvalsh(K[i])
        rank = 2 if rod else 6  # rod: axial + torsion; frame: also two planes of bending
        assert np.sum(w > 1e-9 * w.max()) == rank and w.min() > -1e-9 * w.max()


def test_cantilever_flexibility_of_one_element_is_exact():
    """Fix end A, invert the end-B stiffness: the classical cantilever flexibilities."""
    L = 0.7
    K, _ = element(L)
    F = np.linalg.inv(K[0][6:, 6:])
    assert F[0, 0] == pytest.approx(L / (E * A), rel=1e-12)
    assert F[3, 3] == pytest.approx(L / (G * J), rel=1e-12)
    assert F[1, 1] == pytest.approx(L**3 / (3 * E * IZ), rel=1e-12)  # v under a y force
    assert F[1, 5] == pytest.approx(L**2 / (2 * E * IZ), rel=1e-12)  # rz under a y force
    assert F[2, 2] == pytest.approx(L**3 / (3 * E * IY), rel=1e-12)
    assert F[2, 4] == pytest.approx(-L**2 / (2 * E * IY), rel=1e-12)  # ry = -dw/dx
    assert F[4, 4] == pytest.approx(L / (E * IY), rel=1e-12)


def test_timoshenko_adds_exactly_the_shear_flexibility():
    L = 0.3
    K, _ = element(L, theory="timoshenko")
    F = np.linalg.inv(K[0][6:, 6:])
    assert F[1, 1] == pytest.approx(L**3 / (3 * E * IZ) + L / (G * ASY), rel=1e-12)
    assert F[2, 2] == pytest.approx(L**3 / (3 * E * IY) + L / (G * ASZ), rel=1e-12)
    assert F[5, 5] == pytest.approx(L / (E * IZ), rel=1e-12)  # rotation: no shear part


def test_timoshenko_with_infinite_shear_area_equals_euler_bernoulli_stiffness():
    L = 0.4
    args = [np.full(1, v) for v in (L, A, IY, IZ, J, E, G, RHO)]
    Kt, _ = frame_matrices(*args, Asy=np.inf, Asz=np.inf, theory="timoshenko")
    Ke, _ = frame_matrices(*args)
    assert np.array_equal(Kt, Ke)


@pytest.mark.parametrize("mass", ["consistent", "lumped"])
@pytest.mark.parametrize("rod", [False, True])
def test_rigid_translation_carries_the_whole_mass_including_nsm(mass, rod, rng):
    a, b, v = random_elements(rng)
    L, R = local_axes(a, b, v)
    nsm = 0.37
    _, M = frame_matrices(L, A, IY, IZ, J, E, G, RHO, nsm=nsm, rod=rod, R=R, mass=mass)
    for i in range(len(L)):
        Rb = rigid_body_modes(np.array([a[i], b[i]]), origin=0.5 * (a[i] + b[i]))
        T = Rb[:, :3]  # unit translations x, y, z
        total = (RHO * A + nsm) * L[i]
        assert np.allclose(T.T @ M[i] @ T, total * np.eye(3), rtol=0, atol=1e-13 * total)


def test_consistent_mass_reproduces_rigid_rotation_inertia():
    """About the element's centre: perpendicular axes rho A L^3 / 12 (+ rho I L with
    Timoshenko's rotary inertia), the element axis rho (Iy + Iz) L."""
    L = 0.7
    a, b = np.zeros(3), np.array([L, 0, 0])
    Rb = rigid_body_modes(np.array([a, b]), origin=0.5 * (a + b))
    for theory in ("euler-bernoulli", "timoshenko"):
        _, M = element(L, theory=theory)
        Jm = Rb[:, 3:].T @ M[0] @ Rb[:, 3:]
        rot = theory == "timoshenko"
        assert Jm[0, 0] == pytest.approx(RHO * (IY + IZ) * L, rel=1e-12)
        assert Jm[1, 1] == pytest.approx(RHO * A * L**3 / 12 + (RHO * IY * L if rot else 0.0), rel=1e-12)
        assert Jm[2, 2] == pytest.approx(RHO * A * L**3 / 12 + (RHO * IZ * L if rot else 0.0), rel=1e-12)


def test_lumped_mass_is_diagonal_translational_halves():
    L = 0.7
    _, M = element(L, mass="lumped", nsm=0.2)
    half = 0.5 * (RHO * A + 0.2) * L
    assert np.array_equal(M[0], np.diag([half] * 3 + [0.0] * 3 + [half] * 3 + [0.0] * 3))


def test_vectorised_matrices_equal_one_at_a_time(rng):
    a, b, v = random_elements(rng, n=5)
    L, R = local_axes(a, b, v)
    K, M = frame_matrices(L, A, IY, IZ, J, E, G, RHO, Asy=ASY, Asz=ASZ, R=R, theory="timoshenko")
    for i in range(5):
        Ki, Mi = frame_matrices(L[i:i + 1], A, IY, IZ, J, E, G, RHO, Asy=ASY, Asz=ASZ, R=R[i:i + 1],
                                theory="timoshenko")
        Lam = np.kron(np.eye(4), R[i])
        Kl, Ml = frame_matrices(L[i:i + 1], A, IY, IZ, J, E, G, RHO, Asy=ASY, Asz=ASZ, theory="timoshenko")
        assert np.array_equal(K[i], Ki[0])
        assert np.allclose(K[i], Lam.T @ Kl[0] @ Lam, rtol=0, atol=1e-10 * np.abs(K[i]).max())
        assert np.allclose(M[i], Lam.T @ Ml[0] @ Lam, rtol=0, atol=1e-14 * np.abs(M[i]).max())


def test_rotating_the_element_with_its_v_vector_rotates_its_matrices(rng):
    a, b, v = random_elements(rng, n=1)
    Q = Rotation.from_euler("xyz", [10, 20, 30], degrees=True).as_matrix()
    L1, R1 = local_axes(a, b, v)
    L2, R2 = local_axes(a @ Q.T, b @ Q.T, v @ Q.T)
    K1, _ = frame_matrices(L1, A, IY, IZ, J, E, G, RHO, R=R1)
    K2, _ = frame_matrices(L2, A, IY, IZ, J, E, G, RHO, R=R2)
    Qb = np.kron(np.eye(4), Q)
    assert np.allclose(K2[0], Qb @ K1[0] @ Qb.T, rtol=0, atol=1e-9 * np.abs(K1).max())


def test_local_axes_errors_name_the_element():
    with pytest.raises(ModelError, match="element 42: zero length"):
        local_axes(np.ones((1, 3)), np.ones((1, 3)), np.array([[0, 0, 1.0]]), ids=np.array([42]))
    with pytest.raises(ModelError, match="element 43: orientation vector .* parallel"):
        local_axes(np.zeros((1, 3)), np.array([[0, 0, 2.0]]), np.array([[0, 0, -1.0]]), ids=np.array([43]))


@pytest.mark.parametrize("theory", ["euler-bernoulli", "timoshenko"])
def test_rod_ignores_undefined_bending_properties(theory):
    """Rods from decks may carry I = 0 or NaN and no shear area: no NaN may leak out."""
    args = [np.full(1, v) for v in (0.5, A, np.nan, 0.0, J, E, G, RHO)]
    K, M = frame_matrices(*args, Asy=0.0, Asz=np.nan, rod=True, theory=theory)
    Kr, Mr = frame_matrices(*[np.full(1, v) for v in (0.5, A, IY, IZ, J, E, G, RHO)], rod=True, theory=theory)
    assert np.array_equal(K, Kr) and np.array_equal(M, Mr)
