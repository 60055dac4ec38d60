"""Static solution against exact cantilever formulas (issue 2, acceptance 6).

Cubic (and shear-flexible cubic) elements reproduce the exact end-loaded cantilever, so
the tolerance is round-off: 1e-10 relative.
"""

import numpy as np
import pytest

from trussid.fem import ALUMINIUM, Model, ModelError, Section
from trussid.fem.static import solve_static

SEC = Section.general(A=3.1e-4, Iy=2.2e-8, Iz=5.3e-8, J=6.0e-8, Asy=1.9e-4, Asz=2.4e-4, name="bar")
AXIS = np.array([0.6, -0.48, 0.64])  # unit, skew
ORIENT = np.array([0.0, 0.0, 1.0])
L = 1.7
E, G = ALUMINIUM.E, ALUMINIUM.G


def local_axes():
    ey = ORIENT - ORIENT @ AXIS * AXIS
    ey /= np.linalg.norm(ey)
    return AXIS, ey, np.cross(AXIS, ey)


def cantilever(theory="euler-bernoulli", n_el=7):
    m = Model(beam_theory=theory)
    s = np.linspace(0, L, n_el + 1)
    m.add_nodes(np.arange(n_el + 1) + 1, np.array([2.0, 1.0, -1.0]) + s[:, None] * AXIS)
    m.add_beams(np.arange(n_el) + 1, np.c_[np.arange(n_el) + 1, np.arange(n_el) + 2], SEC, ALUMINIUM, orient=ORIENT)
    m.fix(1)
    return m, n_el


def tip_response(m, n_el, force=None, moment=None):
    """Tip displacement and rotation in local axes for a tip load given in local axes."""
    ex, ey, ez = local_axes()
    R = np.array([ex, ey, ez])
    f = np.zeros(m.n_dof)
    if force is not None:
        f[6 * n_el:6 * n_el + 3] = R.T @ force
    if moment is not None:
        f[6 * n_el + 3:6 * n_el + 6] = R.T @ moment
    u = solve_static(m, f)
    return R @ u[6 * n_el:6 * n_el + 3], R @ u[6 * n_el + 3:6 * n_el + 6]


def close(a, b):
    return abs(a - b) <= 1e-10 * abs(b)


@pytest.mark.parametrize("theory", ["euler-bernoulli", "timoshenko"])
def test_tip_force_gives_exact_deflection_and_rotation_in_both_planes(theory):
    m, n = cantilever(theory)
    P = 120.0
    shear = theory == "timoshenko"
    # Force along local y: bending about z (E Iz), tip rotation rz = +P L^2 / (2 E Iz).
    u, r = tip_response(m, n, force=[0, P, 0])
    assert close(u[1], P * L**3 / (3 * E * SEC.Iz) + (P * L / (G * SEC.Asy) if shear else 0.0))
    assert close(r[2], P * L**2 / (2 * E * SEC.Iz))
    # Force along local z: bending about y (E Iy), tip rotation ry = -P L^2 / (2 E Iy).
    u, r = tip_response(m, n, force=[0, 0, P])
    assert close(u[2], P * L**3 / (3 * E * SEC.Iy) + (P * L / (G * SEC.Asz) if shear else 0.0))
    assert close(r[1], -P * L**2 / (2 * E * SEC.Iy))


@pytest.mark.parametrize("theory", ["euler-bernoulli", "timoshenko"])
def test_tip_moment_gives_exact_deflection_and_rotation(theory):
    m, n = cantilever(theory)
    Mo = 35.0
    u, r = tip_response(m, n, moment=[0, 0, Mo])  # about local z: deflects along +y
    assert close(u[1], Mo * L**2 / (2 * E * SEC.Iz)) and close(r[2], Mo * L / (E * SEC.Iz))
    u, r = tip_response(m, n, moment=[0, Mo, 0])  # about local y: deflects along -z
    assert close(u[2], -Mo * L**2 / (2 * E * SEC.Iy)) and close(r[1], Mo * L / (E * SEC.Iy))


def test_axial_force_and_torque_give_exact_extension_and_twist():
    m, n = cantilever()
    u, _ = tip_response(m, n, force=[500.0, 0, 0])
    assert close(u[0], 500.0 * L / (E * SEC.A))
    _, r = tip_response(m, n, moment=[12.0, 0, 0])
    assert close(r[0], 12.0 * L / (G * SEC.J))


def test_several_load_cases_at_once():
    m, n = cantilever()
    f = np.zeros((m.n_dof, 2))
    f[6 * n + 1, 0] = 1.0
    f[6 * n + 2, 1] = 1.0
    u = solve_static(m, f)
    assert u.shape == (m.n_dof, 2)
    assert np.allclose(u[:, 0], solve_static(m, f[:, 0])) and np.allclose(u[:, 1], solve_static(m, f[:, 1]))


def test_load_on_a_rigid_slave_acts_through_its_master():
    """A force F at a slave offset r from a supported spring node equals F and r x F at
    the master: compare against the same load moved by hand."""
    k = [1e4, 2e4, 3e4, 50.0, 60.0, 70.0]
    r = np.array([0.3, -0.2, 0.5])
    F = np.array([2.0, -1.0, 4.0])

    def model():
        m = Model()
        m.add_nodes([1, 2], [[0, 0, 0], r])
        m.add_springs([1], [1], k)
        m.add_rigid_body(1, 1, [2])
        return m

    f1 = np.zeros(12)
    f1[6:9] = F
    f2 = np.zeros(12)
    f2[0:3], f2[3:6] = F, np.cross(r, F)
    u1, u2 = solve_static(model(), f1), solve_static(model(), f2)
    assert np.allclose(u1, u2, rtol=1e-13, atol=0)
    # And the master's displacement is the spring law, component by component.
    assert np.allclose(u2[:6], np.r_[F, np.cross(r, F)] / np.array(k), rtol=1e-13)


def test_unsupported_model_is_a_clear_error():
    m = Model()
    m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    m.add_beams([1], [[1, 2]], SEC, ALUMINIUM, orient=[0, 1, 0])
    with pytest.raises(ModelError, match=r"singular .*node \d+ .*add supports"):
        solve_static(m, np.ones(12))


def test_load_vector_of_wrong_length_is_an_error():
    m, _ = cantilever()
    with pytest.raises(ModelError, match="6 per node"):
        solve_static(m, np.ones(7))
