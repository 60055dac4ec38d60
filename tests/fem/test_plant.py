"""The structural plant: PZT strain actuators, sensors, modal superposition, lab chain.

Every check is against an independent computation: the static FE solution, a direct
harmonic solve with the same damping, the closed-form induced-strain beam, and the
zero-order-hold images of the continuous poles.
"""

import control
import numpy as np
import pytest
import scipy.linalg as la

from trussid.fem import ALUMINIUM, Model, ModelError, Section
from trussid.fem.actuators import Wafer, strain_actuator_loads
from trussid.fem.assembly import assemble
from trussid.geometry.lab import LabSpec
from trussid.testbed.chain import LabChain, lab_plant
from trussid.fem.modal import solve_modes
from trussid.fem.plant import modal_plant, residual_flexibility
from trussid.fem.sensors import Sensor, sensor_matrix
from trussid.fem.static import solve_static

INCH = 0.0254
WAFER = Wafer(width=1.0 * INCH, length=2.0 * INCH, thickness=0.02 * INCH,
              youngs_modulus=61e9, d31=-171e-12, relative_permittivity=1700)
BLOCK = 1.0 * INCH          # square host section side
E_HOST = ALUMINIUM.E


def composite(n_wafers=2):
    """Host square bar plus wafers on the +-y faces: (EA, EIz, EIy, offset) exactly."""
    b, t, a = WAFER.width, WAFER.thickness, BLOCK
    offset = a / 2 + t / 2
    EA = E_HOST * a * a + n_wafers * WAFER.youngs_modulus * b * t
    EIz = E_HOST * a**4 / 12 + n_wafers * WAFER.youngs_modulus * (b * t**3 / 12 + b * t * offset**2)
    EIy = E_HOST * a**4 / 12 + n_wafers * WAFER.youngs_modulus * (t * b**3 / 12)
    return EA, EIz, EIy, offset


def cantilever(length=0.5, x1=0.1, n=30, axis=(1.0, 0.0, 0.0), orient=(0.0, 1.0, 0.0)):
    """Square aluminium cantilever along ``axis`` with a wafer pair over [x1, x1 + Lp].

    Returns the model, the covered element ids, and the local-y direction.
    """
    Lp = WAFER.length
    EA, EIz, EIy, _ = composite()
    host = Section.rectangle(BLOCK, BLOCK)
    # Stations so that the wafer ends are nodes.
    xs = np.unique(np.concatenate([np.linspace(0, length, n + 1), np.linspace(x1, x1 + Lp, 5)]))
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    m = Model()
    m.add_nodes(np.arange(1, len(xs) + 1), xs[:, None] * axis)
    mid = 0.5 * (xs[:-1] + xs[1:])
    covered = (mid > x1) & (mid < x1 + Lp)
    ids = np.arange(1, len(xs))
    conn = np.column_stack([ids, ids + 1])
    m.add_beams(ids[~covered], conn[~covered], host, ALUMINIUM, orient=orient)
    sec = {"A": EA / E_HOST, "Iy": EIy / E_HOST, "Iz": EIz / E_HOST, "J": host.J,
           "Asy": np.inf, "Asz": np.inf}
    m.add_beams(ids[covered], conn[covered], sec, ALUMINIUM, orient=orient, label="adapter")
    m.fix(1)
    return m, ids[covered], len(xs)


def test_wafer_capacitance_is_the_parallel_plate_formula():
    eps0 = 8.8541878128e-12
    expected = eps0 * 1700 * (1.0 * INCH) * (2.0 * INCH) / (0.02 * INCH)
    assert WAFER.capacitance == pytest.approx(expected, rel=1e-14)
    assert 30e-9 < WAFER.capacitance < 45e-9      # PZT-5A wafer of this size: tens of nF


def test_pzt_pair_in_bending_matches_closed_form_induced_strain_cantilever():
    length, x1 = 0.5, 0.1
    m, covered, n_nodes = cantilever(length, x1)
    _, EIz, _, offset = composite()
    f = strain_actuator_loads(m, covered, WAFER, offset, face_axis="y", arrangement="bending")
    u = solve_static(m, f).reshape(-1, 6)
    # Closed form (perfect bond, Euler-Bernoulli): the free segment has curvature
    # v'' = -M_T / EI with M_T = 2 E_p b t_p Lambda * offset, Lambda = d31 / t_p per volt.
    Lp = WAFER.length
    M_T = 2 * WAFER.youngs_modulus * WAFER.width * WAFER.d31 * offset
    kappa = -M_T / EIz
    slope = kappa * Lp
    deflection = kappa * Lp * (length - (x1 + Lp / 2))
    assert u[-1, 5] == pytest.approx(slope, rel=1e-2)
    assert u[-1, 1] == pytest.approx(deflection, rel=1e-2)
    # Cubic elements are exact for end moments: the agreement is far better than 1 %.
    assert u[-1, 1] == pytest.approx(deflection, rel=1e-9)
    # Pure bending: no extension and nothing out of plane.
    assert abs(u[-1, 0]) < 1e-12 * abs(deflection)
    assert abs(u[-1, 2]) < 1e-12 * abs(deflection)


def test_pzt_pair_in_extension_matches_composite_section_formula():
    length, x1 = 0.5, 0.1
    m, covered, _ = cantilever(length, x1, axis=(1.0, 2.0, -0.5), orient=(0.0, 0.0, 1.0))
    EA, _, _, offset = composite()
    f = strain_actuator_loads(m, covered, WAFER, offset, arrangement="extension")
    u = solve_static(m, f).reshape(-1, 6)
    axis = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    N_T = 2 * WAFER.youngs_modulus * WAFER.width * WAFER.d31
    expected = N_T * WAFER.length / EA          # free extension of the covered segment
    assert u[-1, :3] @ axis == pytest.approx(expected, rel=1e-12)
    lateral = u[-1, :3] - (u[-1, :3] @ axis) * axis
    # Round-off only: K of a frame has condition ~1e8, so 1e-7 relative is machine precision.
    assert np.linalg.norm(lateral) < 1e-7 * abs(expected)
    assert expected < 0          # d31 < 0: a positive voltage contracts the segment


def frame_with_actuators():
    """A supported 3-D portal frame with two PZT actuators and three sensors."""
    m, covered, n_nodes = cantilever(0.5, 0.1, n=8)
    # Close it into a frame: a second column and a beam across the top.
    top = n_nodes
    m.add_nodes([101, 102], [[0.0, 0.3, 0.0], [0.5, 0.3, 0.0]])
    m.add_beams([201, 202], [[101, 102], [top, 102]], Section.tube(0.01, 0.002), ALUMINIUM,
                orient=(0.0, 0.0, 1.0))
    m.fix(101, "123456")
    m.add_point_masses([102], 0.3)
    _, _, _, offset = composite()
    F = np.column_stack([
        strain_actuator_loads(m, covered, WAFER, offset, arrangement="extension"),
        strain_actuator_loads(m, covered, WAFER, offset, arrangement="bending"),
    ])
    sensors = [Sensor(top, (0, 1, 0), "displacement", name="tip y"),
               Sensor(102, (1, 1, 0), "displacement", sensitivity=2.0, name="corner xy"),
               Sensor(5, (0, 0, 1), "displacement", name="mid z")]
    return m, F, sensors


def test_dc_gain_with_all_modes_equals_static_solution():
    m, F, sensors = frame_with_actuators()
    system = assemble(m)
    modes = solve_modes(system, n_modes=system.n_dof)
    plant = modal_plant(modes, F, sensors, damping=0.0)
    S = sensor_matrix(modes.node_ids, sensors)
    static = S @ solve_static(system, F)
    dc = plant.C @ np.linalg.solve(-plant.A, plant.B) + plant.D
    assert np.abs(dc - static).max() <= 1e-8 * np.abs(static).max()


@pytest.mark.parametrize("quantity", ["displacement", "acceleration"])
def test_frequency_response_equals_direct_harmonic_solve(quantity):
    m, F, sensors = frame_with_actuators()
    sensors = [Sensor(s.node, s.direction, quantity, s.sensitivity, s.name) for s in sensors]
    system = assemble(m)
    modes = solve_modes(system, n_modes=system.n_dof)
    zeta = np.linspace(0.002, 0.05, len(modes.omega))
    plant = modal_plant(modes, F, sensors, damping=zeta)
    # Direct solve on the reduced DOFs with the modal damping matrix M Phi 2ZW Phi^T M.
    K, M = system.K.toarray(), system.M.toarray()
    Phi = modes.shapes
    Cd = M @ Phi @ np.diag(2 * zeta * modes.omega) @ Phi.T @ M
    S = sensor_matrix(modes.node_ids, sensors)
    f_red = system.T.T @ F
    w_max = modes.omega[-1]
    for w in np.geomspace(0.05 * modes.omega[0], 0.9 * w_max, 20):
        u = system.T @ np.linalg.solve(K - w**2 * M + 1j * w * Cd, f_red)
        direct = S @ u * (1.0 if quantity == "displacement" else -(w**2))
        H = plant.C @ np.linalg.solve(1j * w * np.eye(plant.nstates) - plant.A, plant.B) + plant.D
        assert np.abs(H - direct).max() <= 1e-6 * np.abs(direct).max()


def test_static_correction_recovers_dc_gain_with_truncated_modes():
    m, F, sensors = frame_with_actuators()
    system = assemble(m)
    modes = solve_modes(system, n_modes=6)
    exact = sensor_matrix(modes.node_ids, sensors) @ solve_static(system, F)
    bare = modal_plant(modes, F, sensors, damping=0.0)
    fixed = modal_plant(modes, F, sensors, damping=0.0,
                        residual_flexibility=residual_flexibility(system, modes, F, 6))
    err = lambda p: np.abs(control.dcgain(p) - exact).max() / np.abs(exact).max()
    assert err(fixed) < 1e-9
    assert err(bare) > 1e-4          # truncation alone misses the static response


def test_discrete_plant_poles_are_zoh_images_and_strictly_proper():
    m, F, sensors = frame_with_actuators()
    sensors = [Sensor(s.node, s.direction, "acceleration", s.sensitivity, s.name) for s in sensors]
    modes = solve_modes(m, n_modes=4)
    structure = modal_plant(modes, F, sensors, damping=0.0025)
    chain = LabChain.from_lab(LabSpec(), sample_rate=20 * modes.frequencies_hz[3])
    cont, disc = lab_plant(structure, chain, max_mode_hz=modes.frequencies_hz[3])
    T = 1.0 / chain.sample_rate
    pc = np.linalg.eigvals(cont.A)
    pd = np.linalg.eigvals(disc.A)
    images = np.exp(pc * T)
    # Match each discrete pole to its image (distinct poles; lightly damped pairs).
    d = np.abs(pd[:, None] - images[None, :])
    assert d.min(axis=1).max() < 1e-10
    assert d.min(axis=0).max() < 1e-10
    assert disc.dt == pytest.approx(T)
    assert np.all(disc.D == 0)
    # The filter poles are among them: 120 Hz real pole, 1300 Hz Butterworth pair.
    assert np.min(np.abs(pc + 2 * np.pi * 120)) < 1e-6
    wb = 2 * np.pi * 1300
    assert np.min(np.abs(pc - wb * np.exp(1j * 3 * np.pi / 4))) < 1e-6 * wb


def test_without_filters_the_acceleration_feedthrough_arrives_one_sample_late():
    m, F, sensors = frame_with_actuators()
    sensors = [Sensor(s.node, s.direction, "acceleration", s.sensitivity, s.name) for s in sensors]
    modes = solve_modes(m, n_modes=4)
    structure = modal_plant(modes, F, sensors)
    chain = LabChain(smoothing_order=0, smoothing_cutoff=1.0, lowpass_order=0, lowpass_cutoff=1.0,
                     amplifier_gain=1.0, sample_rate=20 * modes.frequencies_hz[3])
    cont, disc = lab_plant(structure, chain)
    assert np.any(cont.D != 0)
    assert np.all(disc.D == 0)
    # Impulse: the first sample is zero, the second carries D plus the ZOH response.
    u = np.zeros((F.shape[1], 5))
    u[0, 0] = 1.0
    y = control.forced_response(disc, U=u).outputs
    assert np.all(y[:, 0] == 0)
    assert np.allclose(y[:, 1] - cont.D[:, 0], (disc.C[:, :-2] @ disc.B[:-2, 0]), rtol=1e-12, atol=0)


def test_bad_inputs_name_the_offending_item():
    m, F, sensors = frame_with_actuators()
    modes = solve_modes(m, n_modes=4)
    with pytest.raises(ModelError, match="unknown node 999"):
        modal_plant(modes, F, [Sensor(999, (0, 0, 1), name="acc9")])
    with pytest.raises(ModelError, match="acc1: direction must be a non-zero"):
        Sensor(5, (0, 0, 0), name="acc1")
    with pytest.raises(ModelError, match="no elements given"):
        strain_actuator_loads(m, [], WAFER, 0.01)
    with pytest.raises(ModelError, match="element 777 is not a beam"):
        strain_actuator_loads(m, [777], WAFER, 0.01)
    structure = modal_plant(modes, F, sensors)
    with pytest.raises(ModelError, match="below twice the highest kept mode"):
        lab_plant(structure, LabChain.from_lab(LabSpec(), sample_rate=1.5 * modes.frequencies_hz[3]),
                  max_mode_hz=modes.frequencies_hz[3])
    with pytest.raises(ModelError, match="one per kept mode"):
        modal_plant(modes, F, sensors, damping=[0.01, 0.02])
