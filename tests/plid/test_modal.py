"""Modal conventions: MAC, the modal parameter table against a closed-form 2-DOF system,
poles as frequency and damping, pairing of two sets of modes."""

import control
import numpy as np
import pytest
import scipy.linalg

from trussid.plid.errors import DataError
from trussid.plid.modal import mac, modal_table, mode_groups, pair_modes, pole_parameters


def test_mac_of_identical_shapes_is_one_to_1e_12(rng):
    phi = rng.standard_normal((28, 12)) + 1j * rng.standard_normal((28, 12))
    np.testing.assert_allclose(np.diag(mac(phi, phi)), 1.0, rtol=0, atol=1e-12)
    # any complex scaling of a shape leaves it the same shape
    scaled = phi * (rng.standard_normal(12) + 1j * rng.standard_normal(12))
    np.testing.assert_allclose(np.diag(mac(phi, scaled)), 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(mac(phi), mac(phi).T, atol=1e-15)


def test_mac_of_orthogonal_shapes_is_zero_and_of_a_45_degree_pair_one_half(rng):
    q, _ = np.linalg.qr(rng.standard_normal((6, 6)) + 1j * rng.standard_normal((6, 6)))
    np.testing.assert_allclose(mac(q), np.eye(6), atol=1e-12)
    assert mac(np.array([1.0, 0.0]), np.array([1.0, 1.0]))[0, 0] == pytest.approx(0.5)


def test_mac_refuses_shapes_at_different_dofs_or_zero_shapes():
    with pytest.raises(DataError, match="same DOFs: got 3 and 4 rows"):
        mac(np.ones((3, 2)), np.ones((4, 2)))
    with pytest.raises(DataError, match="mode 2 of the second set is zero"):
        mac(np.ones((3, 2)), np.column_stack([np.ones(3), np.zeros(3)]))


def two_dof(alpha=0.5, beta=2e-4):
    """Two masses, three springs, proportional damping C = alpha M + beta K; outputs the
    two displacements, inputs forces on both masses."""
    M = np.diag([2.0, 1.0])
    K = np.array([[3e4, -1e4], [-1e4, 1e4]])
    Cd = alpha * M + beta * K
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-np.linalg.solve(M, K), -np.linalg.solve(M, Cd)]])
    B = np.vstack([np.zeros((2, 2)), np.linalg.inv(M)])
    C = np.hstack([np.eye(2), np.zeros((2, 2))])
    sys = control.ss(A, B, C, np.zeros((2, 2)), inputs=["F1", "F2"], outputs=["x1", "x2"])
    w2, phi = scipy.linalg.eigh(K, M)  # undamped normal modes (closed form for 2 DOF)
    wn = np.sqrt(w2)
    zeta = (alpha / wn + beta * wn) / 2  # proportional damping, modal damping ratios
    return sys, wn, zeta, phi


def test_modal_table_matches_the_closed_form_of_a_proportionally_damped_2dof_system():
    sys, wn, zeta, phi = two_dof()
    modes = modal_table(sys)
    np.testing.assert_allclose(modes.frequencies_hz, wn / (2 * np.pi), rtol=1e-12)
    np.testing.assert_allclose(modes.damping, zeta, rtol=1e-10)
    # proportional damping: the complex modes are the real normal modes
    np.testing.assert_allclose(np.diag(mac(modes.shapes, phi)), 1.0, atol=1e-12)
    assert modes.labels == ["x1", "x2"] and modes.input_names == ["F1", "F2"]
    assert np.max(np.abs(modes.shapes), axis=0) == pytest.approx([1.0, 1.0])


def test_shapes_times_participation_rebuild_the_frequency_response():
    """H(s) = sum over poles of R_k / (s - s_k) with R_k = shape_k participation_k, each
    mode counted with its conjugate: checked against python-control's own evaluation."""
    sys, *_ = two_dof(alpha=3.0, beta=1e-4)
    modes = modal_table(sys)
    for f in (3.0, 17.0, 41.0):
        s = 2j * np.pi * f
        H = np.zeros((2, 2), complex)
        for k in range(modes.n_modes):
            R = np.outer(modes.shapes[:, k], modes.participation[k])
            H += R / (s - modes.poles[k]) + R.conj() / (s - modes.poles[k].conj())
        np.testing.assert_allclose(H, sys(s), rtol=1e-10)


def test_discrete_models_give_the_continuous_frequencies_and_damping():
    sys, wn, zeta, _ = two_dof()
    modes = modal_table(control.c2d(sys, 1 / 200.0, "zoh"))
    np.testing.assert_allclose(modes.frequencies_hz, wn / (2 * np.pi), rtol=1e-10)
    np.testing.assert_allclose(modes.damping, zeta, rtol=1e-8)


# --------------------------------------------------------------------- pairing


def test_pairing_by_frequency_is_the_order_preserving_assignment():
    measured = np.array([50.3, 50.1, 80.0])
    model = np.array([49.0, 50.05, 50.35, 79.0, 120.0])
    assert pair_modes(measured, model).tolist() == [2, 1, 3]


def test_mac_overrides_a_closer_frequency():
    """Two modes 0.2 % apart: the shape decides, not the frequency."""
    measured = np.array([50.0])
    model = np.array([50.0, 50.1])
    shapes_meas = np.array([[0.0], [1.0j]])  # complex scale is irrelevant to MAC
    shapes_model = np.array([[1.0, 0.0], [0.0, 2.0]])
    m = mac(shapes_meas, shapes_model)
    np.testing.assert_allclose(m, [[0.0, 1.0]])
    assert pair_modes(measured, model, mac=m).tolist() == [1]


def test_modes_the_sensors_cannot_separate_take_one_measured_mode():
    """Two bending planes of one strut (0.06 Hz apart, same shape at the sensors) form a
    group: two measured modes near them pair with that group and the next strut, not
    both with the one strut."""
    model = np.array([50.0, 50.06, 50.2, 50.26])
    shapes = np.array([[1.0, 0.95, 0.0, 0.05], [0.05, 0.1, 1.0, 0.9]])  # strut A, strut B
    groups = mode_groups(model, shapes, bandwidth_hz=0.25)
    assert groups.tolist() == [0, 0, 1, 1]
    measured = np.array([50.03, 50.05])
    assert pair_modes(measured, model).tolist() == [0, 1]  # frequency alone: one strut twice
    got = pair_modes(measured, model, groups=groups)
    assert sorted(groups[got].tolist()) == [0, 1]


def test_disallowed_pairs_are_left_unpaired():
    allowed = np.array([[True, False], [False, False]])
    assert pair_modes([10.0, 20.0], [10.0, 20.0], allowed=allowed).tolist() == [0, -1]


def test_a_shape_no_sensor_sees_has_mac_zero_when_asked():
    """Pairing asks for MAC 0 where a shape is zero; the default names the mode."""
    got = mac(np.array([[1.0, 0.0], [0.0, 0.0]]), np.eye(2), zero_shape="zero")
    np.testing.assert_array_equal(got, [[1.0, 0.0], [0.0, 0.0]])
    with pytest.raises(DataError, match="mode 2 of the first set"):
        mac(np.array([[1.0, 0.0], [0.0, 0.0]]), np.eye(2))


def test_pole_parameters_are_those_of_the_continuous_pole():
    """z = exp(s dt) with s = -zeta wn + j wn sqrt(1 - zeta^2): frequency wn / 2 pi and
    damping zeta come back, and a continuous pole is taken as it is."""
    wn, zeta, dt = 2 * np.pi * 37.0, 0.02, 1 / 1600
    s = -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)
    f, z, s_back = pole_parameters([np.exp(s * dt)], dt)
    np.testing.assert_allclose([f[0], z[0]], [37.0, 0.02], rtol=1e-12)
    np.testing.assert_allclose(s_back, [s], rtol=1e-12)
    f_c, z_c, _ = pole_parameters([s])
    np.testing.assert_allclose([f_c[0], z_c[0]], [37.0, 0.02], rtol=1e-12)
