"""Rigid bodies (RBE2-like), springs and point masses (issue 2, acceptance 5).

Analytic references are written out component by component here (not with the library's
``skew``/``rigid_mass`` helpers), so the tests check the code against the mechanics.
"""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from trussid.fem import ALUMINIUM, Model, Section
from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes


def analytic_mass_about(m, c, I_cg):
    """6x6 mass of a rigid body of mass m, cg at offset c from the reference point.

    Kinetic energy with v_cg = u + theta x c:  translational block m*1; coupling
    m * (u . (theta x c)) gives M_tr[i, j] = m * eps_ijk... written out explicitly; rotational
    block I_cg + m (|c|^2 1 - c c^T) (parallel-axis theorem).
    """
    cx, cy, cz = c
    M = np.zeros((6, 6))
    M[:3, :3] = m * np.eye(3)
    M_tr = m * np.array([[0.0, cz, -cy],
                         [-cz, 0.0, cx],
                         [cy, -cx, 0.0]])
    M[:3, 3:] = M_tr
    M[3:, :3] = M_tr.T
    M[3:, 3:] = I_cg + m * (np.dot(c, c) * np.eye(3) - np.outer(c, c))
    return M


def random_inertia(rng):
    Q = Rotation.random(random_state=7).as_matrix()
    return Q @ np.diag(rng.uniform(0.5, 2.0, 3)) @ Q.T


BODY_XYZ = np.array([[0.0, 0.0, 0.0], [1.2, 0.1, -0.3], [0.4, 0.9, 0.2], [-0.5, 0.3, 0.8], [0.7, -0.6, 0.5]])


@pytest.mark.parametrize("master", range(5))
def test_rigid_body_mass_about_any_node_equals_parallel_axis_matrix_to_1e12(master, rng):
    mass, cg, I_cg = 3.7, np.array([0.3, 0.2, 0.25]), random_inertia(rng)
    m = Model()
    m.add_nodes(np.arange(1, 6), BODY_XYZ)
    m.add_rigid_body(1, master + 1, [i for i in range(1, 6) if i != master + 1], mass=mass, cg=cg, inertia=I_cg)
    s = assemble(m)
    assert s.n_dof == 6  # only the master's six DOFs remain
    expected = analytic_mass_about(mass, cg - BODY_XYZ[master], I_cg)
    assert np.abs(s.M.toarray() - expected).max() <= 1e-12 * np.abs(expected).max()


def test_point_masses_on_slaves_sum_to_the_composite_rigid_inertia_at_the_master(rng):
    """The DOF transformation T carries slave masses to the master exactly."""
    masses = rng.uniform(0.5, 2.0, 4)
    m = Model()
    m.add_nodes(np.arange(1, 6), BODY_XYZ)
    m.add_point_masses(np.arange(2, 6), masses)
    m.add_rigid_body(1, 1, [2, 3, 4, 5])
    s = assemble(m)
    r = BODY_XYZ[1:] - BODY_XYZ[0]
    total = masses.sum()
    cg = (masses[:, None] * r).sum(axis=0) / total
    # Inertia about the composite cg, summed directly over the particles.
    d = r - cg
    I_cg = sum(mi * (np.dot(di, di) * np.eye(3) - np.outer(di, di)) for mi, di in zip(masses, d))
    expected = analytic_mass_about(total, cg, I_cg)
    assert np.abs(s.M.toarray() - expected).max() <= 1e-12 * np.abs(expected).max()


def test_conm2_offset_mass_matrix_equals_analytic(rng):
    I_cg = random_inertia(rng)
    m = Model()
    m.add_nodes([5], [[0.4, -1.0, 2.0]])
    m.add_point_masses([5], 2.5, inertia=I_cg, offset=[0.1, -0.3, 0.2])
    m.add_springs([1], [5], np.ones(6))  # to ground, so the system is well posed
    s = assemble(m)
    expected = analytic_mass_about(2.5, np.array([0.1, -0.3, 0.2]), I_cg)
    assert np.abs(s.M.toarray() - expected).max() <= 1e-14 * np.abs(expected).max()


def test_offset_point_mass_on_springs_matches_hand_derived_coupled_frequencies():
    """Node on grounded springs k (y translation) and kt (z rotation), mass m offset e along x.

    y and rz couple: M = [[m, m e], [m e, I + m e^2]], K = diag(k, kt); solve the 2x2
    characteristic polynomial by hand.
    """
    mass, e, I, k, kt = 2.0, 0.15, 0.01, 4000.0, 90.0
    m = Model()
    m.add_nodes([1], [[0.0, 0.0, 0.0]])
    m.add_point_masses([1], mass, inertia=np.diag([I, I, I]), offset=[e, 0.0, 0.0])
    # Other components get distinct stiff springs so they separate from the pair.
    m.add_springs([1], [1], [1e7, k, 2e7, 3e5, 4e5, kt])
    f = solve_modes(m, 6).frequencies_hz
    a = mass * (I + mass * e**2) - (mass * e) ** 2
    b = -(k * (I + mass * e**2) + kt * mass)
    c = k * kt
    w2 = np.sort(np.roots([a, b, c]).real)
    expected = np.sqrt(w2) / (2 * np.pi)
    assert np.allclose(f[:2], expected, rtol=1e-12)


def test_rigid_block_on_four_corner_springs_matches_hand_derived_frequencies():
    """Block of mass m, cg at the origin in the plane of four corner springs at (+-a, +-b, 0)
    with stiffness (kx, ky, kz). The six modes decouple:
    x: 4 kx / m, y: 4 ky / m, z: 4 kz / m, roll: 4 kz b^2 / Ixx, pitch: 4 kz a^2 / Iyy,
    yaw: 4 (kx b^2 + ky a^2) / Izz. The master is an off-body node, not the cg.
    """
    mass, a, b = 12.0, 0.4, 0.25
    Ixx, Iyy, Izz = 0.35, 0.6, 0.8
    kx, ky, kz = 2.0e4, 3.0e4, 5.0e4
    corners = np.array([[a, b, 0], [-a, b, 0], [-a, -b, 0], [a, -b, 0]], float)
    m = Model()
    m.add_nodes([10, 1, 2, 3, 4], np.r_[[[0.3, -0.2, 0.5]], corners])
    m.add_rigid_body(7, 10, [1, 2, 3, 4], mass=mass, cg=[0, 0, 0], inertia=np.diag([Ixx, Iyy, Izz]))
    m.add_springs([1, 2, 3, 4], [1, 2, 3, 4], [kx, ky, kz, 0, 0, 0])
    f = solve_modes(m, 6).frequencies_hz
    w2 = [4 * kx / mass, 4 * ky / mass, 4 * kz / mass, 4 * kz * b**2 / Ixx, 4 * kz * a**2 / Iyy,
          4 * (kx * b**2 + ky * a**2) / Izz]
    expected = np.sort(np.sqrt(w2)) / (2 * np.pi)
    assert np.allclose(f, expected, rtol=1e-10)


def test_two_bodies_chained_by_springs_match_two_dof_frequencies():
    """ground -k1- body 1 -k2- body 2, cg at each master, per component a 2-DOF chain:
    det([[k1 + k2 - w^2 m1, -k2], [-k2, k2 - w^2 m2]]) = 0."""
    m1, m2, J1, J2 = 3.0, 1.5, 0.02, 0.01
    k1 = np.array([1e5, 2e5, 3e5, 400.0, 500.0, 600.0])
    k2 = np.array([7e4, 6e4, 5e4, 300.0, 200.0, 100.0])
    m = Model()
    m.add_nodes([1, 2, 11, 12], [[0, 0, 0], [0, 0, 1.0], [0.1, 0, 0], [0.1, 0, 1.0]])
    m.add_rigid_body(1, 1, [11], mass=m1, inertia=np.eye(3) * J1)
    m.add_rigid_body(2, 2, [12], mass=m2, inertia=np.eye(3) * J2)
    m.add_springs([1], [1], k1)  # body 1 to ground at its master
    m.add_springs([2], [[1, 2]], k2)  # between the two masters (coincident axes in x, y)
    f = solve_modes(m, 12).frequencies_hz
    expected = []
    for comp in range(6):
        ma, mb = (m1, m2) if comp < 3 else (J1, J2)
        a, b, c = ma * mb, -((k1[comp] + k2[comp]) * mb + k2[comp] * ma), k1[comp] * k2[comp]
        expected += list(np.sqrt(np.roots([a, b, c]).real) / (2 * np.pi))
    # Like NASTRAN's CELAS/CBUSH without offsets, a spring couples like components of its
    # two nodes directly (no lever arm between them), so each component is its own chain.
    assert np.allclose(f, np.sort(expected), rtol=1e-10)


def test_spring_to_a_fully_supported_node_equals_a_grounded_spring():
    frame = Rotation.from_euler("xyz", [20, -35, 50], degrees=True).as_matrix()
    k = [1e4, 2e4, 3e4, 40.0, 50.0, 60.0]

    def model(grounded):
        m = Model()
        m.add_nodes([1, 2], [[0, 0, 0], [0.5, 0.2, 0.1]])
        m.add_point_masses([1], 2.0, inertia=np.diag([0.01, 0.02, 0.03]))
        if grounded:
            m.add_springs([1], [1], k, frame=frame)
        else:
            m.add_springs([1], [[1, 2]], k, frame=frame)
        m.fix(2)  # in both: the other end of the two-node spring, or an unused node
        return m

    a, b = assemble(model(True)), assemble(model(False))
    assert np.allclose(a.K.toarray(), b.K.toarray(), rtol=0, atol=1e-12 * 3e4)
    # The stiffness is diagonal in the spring frame: F K F^T = diag(k).
    Kl = np.zeros((6, 6))
    Kl[:3, :3] = frame @ a.K.toarray()[:3, :3] @ frame.T
    Kl[3:, 3:] = frame @ a.K.toarray()[3:, 3:] @ frame.T
    assert np.allclose(Kl, np.diag(k), rtol=0, atol=1e-10 * 3e4)


def test_two_node_spring_stores_no_energy_in_common_translation_and_stiffness_k_across():
    m = Model()
    m.add_nodes([1, 2], [[0, 0, 0], [1.0, 0, 0]])
    m.add_springs([1], [[1, 2]], [1e3, 2e3, 3e3, 4.0, 5.0, 6.0])
    m.add_point_masses([1, 2], 1.0, inertia=np.eye(3) * 1e-3)
    s = assemble(m)
    K = s.K.toarray()
    same = np.tile(np.eye(6), (2, 1))  # both nodes move together, component by component
    assert np.abs(K @ same).max() == 0.0
    rel = np.r_[np.zeros(6), np.ones(6)]
    assert np.allclose(rel @ K @ rel, 1e3 + 2e3 + 3e3 + 4 + 5 + 6)


def test_slaves_follow_master_rigidly_through_t_and_partial_dofs_stay_independent():
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [1.0, 2.0, -0.5], [-1.0, 0.5, 0.3]])
    m.add_rigid_body(1, 1, [2], dofs="123456")
    m.add_rigid_body(2, 1, [3], dofs="123")  # translations only: node 3's rotations stay free
    m.add_point_masses([1, 2, 3], 1.0, inertia=np.eye(3))
    s = assemble(m)
    assert s.n_dof == 6 + 3
    u_m, th = np.array([0.1, -0.2, 0.3]), np.array([0.01, 0.02, -0.03])
    q = np.zeros(s.n_dof)
    q[:3], q[3:6] = u_m, th
    q[6:] = [0.5, 0.6, 0.7]  # node 3 rotations
    u = (s.T @ q).reshape(3, 6)
    for node, r in ((1, np.array([1.0, 2.0, -0.5])), (2, np.array([-1.0, 0.5, 0.3]))):
        expected_u = u_m + np.array([th[1] * r[2] - th[2] * r[1], th[2] * r[0] - th[0] * r[2],
                                     th[0] * r[1] - th[1] * r[0]])
        assert np.allclose(u[node, :3], expected_u, rtol=1e-14, atol=1e-15)
    assert np.allclose(u[1, 3:], th) and np.allclose(u[2, 3:], [0.5, 0.6, 0.7])


def test_chained_rigid_bodies_resolve_to_the_first_master():
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [1.0, 0, 0], [1.0, 1.0, 0]])
    m.add_rigid_body(1, 1, [2])
    m.add_rigid_body(2, 2, [3])  # master 2 is itself a slave of body 1
    m.add_point_masses([3], 1.0)
    s = assemble(m)
    assert s.n_dof == 6
    q = np.array([0, 0, 0, 0, 0, 0.01])  # rotate about z at node 1
    u = (s.T @ q).reshape(3, 6)
    assert np.allclose(u[2, :3], [-0.01 * 1.0, 0.01 * 1.0, 0.0])


@pytest.mark.parametrize("method", ["dense", "sparse"])
def test_beam_clamped_to_a_supported_rigid_block_gives_plain_cantilever_frequencies(method):
    """A slender cantilever clamped to a rigid block fixed at its master: the block adds
    nothing, so the frequencies equal the plain cantilever's."""
    sec, L, n = Section.tube(0.01, 0.001), 1.0, 10
    x = np.linspace(0, L, n + 1)

    def model(with_block):
        m = Model()
        m.add_nodes(np.arange(n + 1), np.c_[x, np.zeros((n + 1, 2))])
        m.add_beams(np.arange(n), np.c_[np.arange(n), np.arange(1, n + 1)], sec, ALUMINIUM, orient=[0, 1, 0])
        if with_block:
            m.add_nodes([100], [[-0.3, 0.2, 0.1]])
            m.add_rigid_body(1, 100, [0])
            m.fix(100)
        else:
            m.fix(0)
        return m

    a = solve_modes(model(False), 6, method=method).frequencies_hz
    b = solve_modes(model(True), 6, method=method).frequencies_hz
    assert np.allclose(a, b, rtol=1e-11)
