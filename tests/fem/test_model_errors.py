"""Bad input gives a clear ModelError naming the offending item (issue 2, acceptance 8).

(The CLI side and unsupported NASTRAN cards are tested with the CLI and the reader.)
"""

import numpy as np
import pytest

from trussid.fem import ALUMINIUM, Material, Model, ModelError, Section
from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes
from trussid.fem.static import solve_static
from trussid._util.errors import UserError

TUBE = Section.tube(0.01, 0.001, name="strut tube")
GOOD_SECTION = {"A": 1e-4, "Iy": 1e-9, "Iz": 2e-9, "J": 3e-9, "Asy": 5e-5, "Asz": 5e-5}
GOOD_MATERIAL = {"E": 70e9, "G": 26e9, "rho": 2700.0}


def two_beams(**beam_kw):
    """Nodes 1-2-3 along x, elements 11 and 12; element 12 gets ``beam_kw`` overrides."""
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0]])
    m.add_beams([11], [[1, 2]], TUBE, ALUMINIUM, orient=[0, 1, 0])
    kw = dict(ids=[12], nodes=[[2, 3]], section=TUBE, material=ALUMINIUM, orient=[0, 1, 0])
    kw.update(beam_kw)
    m.add_beams(**kw)
    m.fix(1)
    return m


def test_model_errors_are_user_errors():
    assert issubclass(ModelError, UserError) and issubclass(ModelError, ValueError)


def test_zero_length_element_is_named():
    m = two_beams()
    m.add_nodes([4], [[1.0, 0, 0]])  # coincides with node 3
    m.add_beams([13], [[3, 4]], TUBE, ALUMINIUM, orient=[0, 1, 0])
    with pytest.raises(ModelError, match=r"element 13: zero length"):
        assemble(m)


def test_element_with_the_same_node_at_both_ends_is_named():
    with pytest.raises(ModelError, match=r"element 12: zero length .*node 2"):
        assemble(two_beams(nodes=[[2, 2]]))


@pytest.mark.parametrize("key", ["E", "G", "rho"])
@pytest.mark.parametrize("value", [0.0, -1.0])
def test_non_positive_material_constant_is_named(key, value):
    kw = {"E": 70e9, "G": 26e9, "rho": 2700.0, "name": "bad alloy"}
    kw[key] = value
    with pytest.raises(ModelError, match=rf"material 'bad alloy': {key} must be positive"):
        Material(**kw)


@pytest.mark.parametrize("key", ["E", "G"])
def test_non_positive_material_array_is_named_at_assembly_by_element(key):
    mat = dict(GOOD_MATERIAL)
    mat[key] = 0.0
    with pytest.raises(ModelError, match=rf"element 12 \(.*\): {key} must be positive"):
        assemble(two_beams(material=mat))


def test_negative_density_array_is_named_at_assembly_by_element():
    with pytest.raises(ModelError, match=r"element 12 \(.*\): rho must be >= 0 and finite, "
                                         r"got -1\.0$"):
        assemble(two_beams(material=dict(GOOD_MATERIAL, rho=-1.0)))


@pytest.mark.parametrize("key, value, shown", [("E", -2.0, "-2.0"), ("J", -1e-9, "-1e-09"),
                                               ("A", float("nan"), "nan")])
def test_the_offending_value_is_printed_as_a_number(key, value, shown):
    """numpy 2 prints a numpy scalar's repr as np.float64(-2.0): the message shows the
    number as the user wrote it."""
    kw = ({"material": dict(GOOD_MATERIAL, **{key: value})} if key == "E"
          else {"section": dict(GOOD_SECTION, **{key: value})})
    with pytest.raises(ModelError, match=rf"element 12 \(.*\): {key} must be .*, got {shown}$"):
        assemble(two_beams(**kw))


@pytest.mark.parametrize("key", ["A", "Iy", "Iz", "J"])
def test_non_positive_section_property_is_named(key):
    kw = {"A": 1e-4, "Iy": 1e-9, "Iz": 1e-9, "J": 2e-9, "name": "flat bar"}
    kw[key] = -1e-9
    with pytest.raises(ModelError, match=rf"section 'flat bar': {key} must be positive"):
        Section.general(**kw)
    sec = dict(GOOD_SECTION)
    sec[key] = -1e-9 if key != "A" else 0.0
    with pytest.raises(ModelError, match=rf"element 12 \(.*\): {key} must be (positive|>= 0)"):
        assemble(two_beams(section=sec))


def test_massless_beam_and_zero_torsion_constant_are_legal_like_nastran():
    """rho = 0 (all mass in point masses) and J = 0 are NASTRAN defaults: a cantilever of
    massless beams with a tip mass is the spring-mass k = 3 E I / L^3 (closed form)."""
    E, I, L, mass = 70e9, 1e-9, 1.0, 2.0
    m = Model(mass="lumped")
    m.add_nodes([1, 2, 3], [[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0]])
    sec = dict(GOOD_SECTION, Iy=I, Iz=I, J=0.0)
    m.add_beams([11, 12], [[1, 2], [2, 3]], sec, dict(GOOD_MATERIAL, E=E, rho=0.0), orient=[0, 1, 0])
    m.add_point_masses([3], [mass])
    m.fix(1)
    m.fix([2, 3], "14")  # axial and torsion: no mass (axial) and no stiffness (J = 0)
    f = solve_modes(m, n_modes=1, autospc=True).frequencies_hz[0]
    assert abs(f / (np.sqrt(3 * E * I / L**3 / mass) / (2 * np.pi)) - 1) < 1e-10


def test_non_positive_shear_area_is_named_for_timoshenko():
    m = Model(beam_theory="timoshenko")
    m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    m.add_beams([7], [[1, 2]], dict(GOOD_SECTION, Asz=0.0), GOOD_MATERIAL, orient=[0, 1, 0], label="PBAR 3")
    m.fix(1)
    with pytest.raises(ModelError, match=r"element 7 \(PBAR 3\): Asz must be positive"):
        assemble(m)


@pytest.mark.parametrize("t", [0.01, 0.012])
def test_wall_thickness_not_below_outer_radius_is_named(t):
    with pytest.raises(ModelError, match=r"section 'thick tube': wall thickness .* must be less than the outer radius"):
        Section.tube(0.01, t, name="thick tube")


def test_orientation_vector_parallel_to_element_is_named():
    with pytest.raises(ModelError, match=r"element 12: orientation vector \[2.0, 0.0, 0.0\] is parallel"):
        assemble(two_beams(orient=[2.0, 0.0, 0.0]))


def test_zero_orientation_vector_is_named():
    with pytest.raises(ModelError, match=r"element 12: orientation vector .* is zero"):
        assemble(two_beams(orient=[0.0, 0.0, 0.0]))


def test_undefined_node_is_named_with_its_element():
    with pytest.raises(ModelError, match=r"undefined node 99 \(referenced by element 12\)"):
        assemble(two_beams(nodes=[[2, 99]]))


def test_undefined_nodes_of_springs_masses_bodies_and_supports_are_named():
    m = two_beams()
    m.add_springs([5], [[3, 42]], np.ones(6))
    with pytest.raises(ModelError, match=r"undefined node 42 \(referenced by spring 5\)"):
        assemble(m)
    m = two_beams()
    m.add_point_masses([43], 1.0)
    with pytest.raises(ModelError, match=r"undefined node 43 \(referenced by point mass"):
        assemble(m)
    m = two_beams()
    m.add_rigid_body(8, 3, [44])
    with pytest.raises(ModelError, match=r"undefined node 44 \(referenced by rigid body 8"):
        assemble(m)
    m = two_beams()
    m.fix(45)
    with pytest.raises(ModelError, match=r"undefined node 45 \(referenced by a support\)"):
        assemble(m)


def test_free_dof_without_stiffness_is_a_mechanism_naming_node_and_component():
    """A point mass hung on a rod along x: its node has mass but no stiffness in y."""
    m = two_beams()
    m.add_nodes([7], [[1.0, 0.0, 0.4]])
    m.add_beams([20], [[3, 7]], TUBE, ALUMINIUM, orient=[0, 1, 0], rod=True)
    m.add_point_masses([7], 0.5)
    m.add_springs([1], [7], [0, 0, 0, 1.0, 1.0, 1.0])  # rotations held, translations not
    with pytest.raises(ModelError, match=r"mechanism: node 7 (ux|uy) has no stiffness"):
        assemble(m)


@pytest.mark.parametrize("method", ["dense", "sparse"])
def test_zero_energy_direction_off_the_axes_is_a_mechanism(method):
    """A rod along a skew direction: the two transverse directions at its free node have
    non-zero diagonal stiffness in global axes but no stiffness at all: found by the
    factorisation's pivots."""
    m = two_beams()
    m.add_nodes([7], [[1.3, 0.2, 0.4]])
    m.add_beams([20], [[3, 7]], TUBE, ALUMINIUM, orient=[0, 1, 0], rod=True)
    m.add_point_masses([7], 0.5)
    m.add_springs([1], [7], [0, 0, 0, 1.0, 1.0, 1.0])
    with pytest.raises(ModelError, match=r"mechanism: node 7 u[xyz] has no stiffness"):
        solve_modes(m, 4, method=method)
    with pytest.raises(ModelError, match=r"singular at node 7 u[xyz]"):
        solve_static(m, np.zeros(m.n_dof))


def rod_triangle(J):
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [1, 0, 0], [0, 1, 0]])
    sec = dict(A=TUBE.A, Iy=TUBE.Iy, Iz=TUBE.Iz, J=J, Asy=np.inf, Asz=np.inf)
    m.add_beams([1, 2, 3], [[1, 2], [2, 3], [3, 1]], sec, ALUMINIUM, orient=[0, 0, 1], rod=True)
    m.fix([1, 3], "123")
    m.fix(2, "3")
    return m


def test_dof_with_neither_mass_nor_stiffness_is_an_error_unless_autospc():
    """Nodes joined only by rods without torsion (J = 0): rotations have no stiffness and
    no mass. AUTOSPC removes them; node 2 then vibrates in x and y on two rods."""
    m = rod_triangle(J=0.0)
    with pytest.raises(ModelError, match=r"mechanism: node 1 rx has no stiffness .*AUTOSPC"):
        assemble(m)
    s = assemble(m, autospc=True)
    assert s.autospc == [(n, c) for n in (1, 2, 3) for c in ("rx", "ry", "rz")]
    assert s.n_dof == 2
    # Hand-derived: rod 1-2 along x (k = EA/L), rod 2-3 at 135 deg (k = EA/(L sqrt 2));
    # consistent rod mass of the two rods at node 2 (each rho A L / 3 on the free node).
    EA, L2 = ALUMINIUM.E * TUBE.A, np.sqrt(2.0)
    e = np.array([-1.0, 1.0]) / L2
    K = EA / 1.0 * np.diag([1.0, 0.0]) + EA / L2 * np.outer(e, e)
    mass = ALUMINIUM.rho * TUBE.A * (1.0 + L2) / 3.0
    expected = np.sqrt(np.linalg.eigvalsh(K) / mass) / (2 * np.pi)
    assert np.allclose(solve_modes(s, 2).frequencies_hz, expected, rtol=1e-12)


def test_floating_massless_rotations_of_a_rod_truss_are_named():
    """With J > 0 in-plane rods' torsion ties node rotations to each other but not to
    the ground: rz is removed by AUTOSPC, the rx-ry set still floats without mass."""
    s = assemble(rod_triangle(J=TUBE.J), autospc=True)
    assert s.autospc == [(1, "rz"), (2, "rz"), (3, "rz")]
    with pytest.raises(ModelError, match=r"mechanism: node \d r[xy] has neither mass nor a stiffness"):
        solve_modes(s, 2)


def test_slave_that_is_also_supported_is_named():
    m = two_beams()
    m.add_nodes([5], [[1.0, 0.3, 0.0]])
    m.add_rigid_body(4, 3, [5])
    m.fix(5, "2")
    with pytest.raises(ModelError, match=r"node 5 is a slave of rigid body 4 and also supported in uy"):
        assemble(m)


def test_slave_of_two_rigid_bodies_is_named():
    m = two_beams()
    m.add_nodes([5], [[1.0, 0.3, 0.0]])
    m.add_rigid_body(4, 3, [5])
    m.add_rigid_body(6, 2, [5])
    with pytest.raises(ModelError, match=r"node 5 is a slave of two rigid bodies \(4 and 6\)"):
        assemble(m)


def test_rigid_body_cycle_is_named():
    m = two_beams()
    m.add_nodes([5, 6], [[1.0, 0.3, 0.0], [1.0, 0.6, 0.0]])
    m.add_rigid_body(4, 5, [6])
    m.add_rigid_body(6, 6, [5])
    with pytest.raises(ModelError, match=r"rigid bodies form a cycle through node [56]"):
        assemble(m)


def test_master_that_is_its_own_slave_is_named():
    m = two_beams()
    m.add_rigid_body(4, 3, [3, 2])
    with pytest.raises(ModelError, match=r"rigid body 4: node 3 is both master and slave"):
        assemble(m)


def test_spring_joining_a_node_to_itself_is_named():
    m = two_beams()
    m.add_springs([9], [[3, 3]], np.ones(6))
    with pytest.raises(ModelError, match=r"spring 9: both ends are node 3"):
        assemble(m)


def test_duplicate_node_id_is_named():
    m = two_beams()
    m.add_nodes([2], [[5.0, 0, 0]])
    with pytest.raises(ModelError, match=r"node 2 is defined more than once"):
        assemble(m)


def test_duplicate_element_ids_are_refused_at_assembly():
    """Audit A07: add_beams([1, 1], ...) used to solve; NASTRAN refuses repeated EIDs."""
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [0.5, 0, 0], [1.0, 0, 0]])
    m.add_beams([1, 1], [[1, 2], [2, 3]], TUBE, ALUMINIUM, orient=[0, 1, 0])
    m.fix(1)
    with pytest.raises(ModelError, match=r"element 1 is defined more than once \(beam and beam\)"):
        assemble(m)


def test_a_spring_may_not_reuse_a_beam_id():
    m = two_beams()
    m.add_springs([12], [[3, -1]], k=[1e3] * 6)
    with pytest.raises(ModelError, match=r"element 12 is defined more than once \(beam and "
                                         r"spring\)"):
        assemble(m)


# ------------------------------------------------ newcomer audit 2 (issue 24): API input
@pytest.mark.parametrize("ids", [[4.5], [np.nan], ["x"]])
def test_a_node_id_that_is_not_a_whole_number_is_refused(ids):
    """P02: node 4.5 was stored as node 4, and a beam to node 4 then worked."""
    m = Model()
    with pytest.raises(ModelError, match="add_nodes: node ids must be whole numbers"):
        m.add_nodes(ids, [[0.0, 0.0, 0.0]])
    m.add_nodes([4.0], [[0.0, 0.0, 0.0]])  # a whole number written as a float is fine
    assert m.node_ids.tolist() == [4]


def test_element_nodes_that_are_not_whole_numbers_are_refused():
    m = Model()
    m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    with pytest.raises(ModelError, match="add_beams: nodes must be whole numbers, got 1.5"):
        m.add_beams([1], [[1.5, 2]], TUBE, ALUMINIUM, orient=[0, 0, 1])


@pytest.mark.parametrize("inertia, match", [
    ([-1.0, 1.0, 1.0], "negative principal moment"),                    # P08
    ([[1, 0.5, 0], [0, 1, 0], [0, 0, 1]], "not symmetric"),
    ([[1, 2, 0], [2, 1, 0], [0, 0, 1]], "negative principal moment"),  # symmetric, indefinite
    ([1.0, 2.0], "inertia must be 3 principal moments"),                # P07
])
def test_an_inertia_no_body_can_have_is_refused(inertia, match):
    m = Model()
    m.add_nodes([1], [[0, 0, 0]])
    with pytest.raises(ModelError, match=match):
        m.add_point_masses([1], 1.0, inertia=inertia)


def test_three_inertia_numbers_are_the_principal_moments():
    """They used to be broadcast to a (3, 3) matrix of equal rows: a rank-one 'tensor'."""
    m = Model()
    m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    m.add_point_masses([1, 2], 1.0, inertia=[1e-3, 2e-3, 3e-3])
    np.testing.assert_array_equal(m.point_masses.inertia[1], np.diag([1e-3, 2e-3, 3e-3]))


@pytest.mark.parametrize("kw, match", [
    ({"nodes": [[2, 3, 1]]}, r"nodes must be 1 pairs of node ids"),      # P04
    ({"orient": [0, 1]}, r"orient must be a 3-vector or \(1, 3\)"),      # P05
])
def test_wrong_shapes_of_beam_arguments_are_named(kw, match):
    with pytest.raises(ModelError, match=match):
        two_beams(**kw)


def test_a_negative_point_mass_is_printed_as_a_number():
    m = Model()
    m.add_nodes([1], [[0.0, 0.0, 0.0]])
    with pytest.raises(ModelError, match=r"point mass at node 1: mass must be >= 0, got -2\.0$"):
        m.add_point_masses([1], np.array([-2.0]))
