"""Free bodies are rigid-body (0 Hz) modes; mechanisms stay errors (issue 33).

A zero-energy motion that moves every kinematic component of the model rigidly (a point
mass joined to nothing, a free part beside a supported one, a scalar point tied to a free
mass) is a free body: NASTRAN prints it at 0 Hz and so does trussid. A point that moves
alone inside a structure that does not resist it is a mechanism, refused naming the DOF.
Each case is checked against a closed form or against the same model without the free body.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from trussid.fem import ALUMINIUM, Model, ModelError, Section
from trussid.fem.assembly import assemble
from trussid.fem.free_bodies import component_rigid_fit, node_components
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf

TWO_PI = 2.0 * math.pi


def oscillator(free_mass: float | None = 2.0) -> Model:
    """Node 2 (1 kg) on a 1000 N/m spring to the clamped node 1, along x; node 3 carries
    ``free_mass`` and nothing joins it to anything (x free, the rest supported)."""
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    m.fix(1)
    m.fix([2, 3], "23456")
    m.add_springs([1], [[1, 2]], [1000.0, 0, 0, 0, 0, 0])
    m.add_point_masses([2], 1.0)
    if free_mass is not None:
        m.add_point_masses([3], free_mass)
    else:
        m.fix(3, "1")
    return m


def test_free_point_mass_beside_a_supported_oscillator_is_a_zero_hertz_mode():
    modes = solve_modes(oscillator(), n_modes=2)
    assert modes.frequencies_hz[0] == 0.0
    np.testing.assert_allclose(modes.frequencies_hz[1], math.sqrt(1000.0) / TWO_PI, rtol=1e-12)
    # the 0 Hz mode moves the free mass only
    shape = modes.shapes_full[:, 0].reshape(3, 6)
    assert abs(shape[2, 0]) > 0 and np.allclose(shape[:2], 0.0, atol=1e-12)


def test_elastic_modes_equal_those_of_the_model_without_the_free_body():
    with_free = solve_modes(oscillator(), n_modes=2).frequencies_hz
    without = solve_modes(oscillator(None), n_modes=1).frequencies_hz
    np.testing.assert_allclose(with_free[1:], without, rtol=1e-12)


def beam_model(n: int = 8, x0: float = 0.0, first_id: int = 1) -> Model:
    m = Model()
    ids = first_id + np.arange(n + 1)
    m.add_nodes(ids, np.c_[x0 + np.linspace(0, 1, n + 1), np.zeros((n + 1, 2))])
    m.add_beams(ids[:-1], np.c_[ids[:-1], ids[1:]], Section.tube(0.01, 0.001), ALUMINIUM, orient=[0, 0, 1])
    return m


def test_a_free_free_beam_beside_a_cantilever_adds_six_zeros_and_its_own_modes():
    """Two components: a cantilever (supported) and a free-free beam joined to nothing.
    The modes are the union of the two models' modes (each solved alone)."""
    both = beam_model()
    other = beam_model(x0=2.0, first_id=101)
    both.add_nodes(other.node_ids, other.xyz)
    b = other.beams
    both.add_beams(b.ids, b.nodes, Section.tube(0.01, 0.001), ALUMINIUM, orient=[0, 0, 1])
    both.fix(1)
    cantilever = beam_model()
    cantilever.fix(1)
    free = beam_model(x0=2.0, first_id=101)
    f_both = solve_modes(both, n_modes=16, method="dense").frequencies_hz
    union = np.sort(np.r_[solve_modes(cantilever, n_modes=10, method="dense").frequencies_hz,
                          solve_modes(free, n_modes=16, method="dense").frequencies_hz])[:16]
    assert (f_both[:6] == 0.0).all()
    np.testing.assert_allclose(f_both[6:], union[6:], rtol=1e-9)


def test_a_mass_moving_alone_inside_a_structure_is_still_a_mechanism():
    """A rod-only node carries a rotary inertia about an axis the rods do not resist: it
    rotates alone while its component stands still, a modelling error, named."""
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    m.add_beams([1, 2], [[1, 2], [2, 3]], Section.tube(0.01, 0.001), ALUMINIUM, orient=[0, 0, 1], rod=True)
    m.fix(1)
    m.fix([2, 3], "236")
    m.add_point_masses([2], 1.0, inertia=[0.0, 0.1, 0.0])
    with pytest.raises(ModelError, match=r"mechanism: node 2 ry has no stiffness"):
        solve_modes(m, n_modes=2, autospc=True)


def test_a_free_part_without_mass_has_no_mode_and_is_refused():
    """A massless bar joined to nothing: its rigid motions have neither mass nor stiffness
    (no frequency at all), which AUTOSPC does not remove DOF by DOF (each DOF has stiffness)."""
    m = oscillator()
    m.add_nodes([4, 5], [[3, 0, 0], [4, 0, 0]])
    m.add_beams([9], [[4, 5]], Section.tube(0.01, 0.001), {"E": 70e9, "G": 26e9, "rho": 0.0}, orient=[0, 0, 1])
    with pytest.raises(ModelError, match=r"mechanism: node [45] \w\w has neither mass nor a stiffness"):
        solve_modes(m, n_modes=2, autospc=True)


def test_components_follow_stiffness_and_constraints_not_mass():
    m = Model()
    m.add_nodes([1, 2, 3, 4], np.eye(4, 3))
    m.add_springs([1], [[1, 2]], [1.0] * 6)
    m.add_rigid_body(2, 3, [4])
    m.add_matrices([5], [[2, 3]], M=np.eye(12))  # mass coupling joins nothing
    labels = assemble(m).components
    assert labels[0] == labels[1] and labels[2] == labels[3] and labels[0] != labels[2]
    # the same from the function itself: the spring's pair, the rigid body through T
    np.testing.assert_array_equal(node_components(4, [[0, 1]], assemble(m).T), labels)


def test_rigid_fit_accepts_rigid_motions_per_component_and_any_scalar_point_value():
    xyz = np.array([[0, 0, 0], [1, 0, 0], [5, 0, 0], [6, 0, 0], [0, 0, 0.0]])
    labels = np.array([0, 0, 1, 1, 1])
    free = np.zeros(30, bool)
    free[24:] = True  # node 5 is a scalar point
    Z = np.zeros((5, 6))
    Z[:2, 1] = [0.0, 0.3]              # component 0 rotates about z through node 1 ...
    Z[:2, 5] = 0.3
    Z[2:4, 0] = 1.0                    # ... component 1 translates along x
    Z[4, 0] = -7.0                     # the scalar point takes any value
    rigid, fitted = component_rigid_fit(xyz, labels, free, Z.reshape(-1, 1))
    assert rigid[0]
    np.testing.assert_allclose(fitted[:, 0], Z.ravel(), atol=1e-12)
    Z[3, 0] = 2.0                      # stretches component 1
    assert not component_rigid_fit(xyz, labels, free, Z.reshape(-1, 1))[0][0]


# ------------------------------------------------------------------ decks
FREE_DECK = """GRID,1,,0.,0.,0.,,123456
GRID,2,,1.,0.,0.,,23456
GRID,3,,2.,0.,0.,,23456
SPOINT,100
EPOINT,200
CELAS2,1,1000.,1,1,2,1
CONM2,2,2,,1.
CONM2,3,3,,2.
MPC,10,3,1,1.,100,0,-1.
TF,5,200,,1.,0.,0.
"""


@pytest.mark.parametrize("case", ["", "MPC = 10\n"], ids=["MPC not selected", "MPC to a scalar point"])
def test_deck_with_a_free_point_mass_gives_a_rigid_mode_then_the_elastic_one(tmp_path, case):
    """The field's case: a point mass with no stiffness, tied by an MPC to a scalar point,
    with TF/EPOINT in the deck (not selected for real modes)."""
    p = tmp_path / "free.bdf"
    p.write_text("SOL 103\nCEND\n" + case + "BEGIN BULK\n" + FREE_DECK + "ENDDATA\n")
    model, info = read_bdf(p)
    f = solve_modes(model, n_modes=5, autospc=info.autospc).frequencies_hz
    assert len(f) == 2 and f[0] == 0.0
    np.testing.assert_allclose(f[1], math.sqrt(1000.0) / TWO_PI, rtol=1e-12)


# ------------------------------------------------------------------ scalar points only
def string_deck(n: int, k: float, m: float, *, spoints: bool, form: int, ends: str) -> str:
    """A chain of ``n`` scalar masses joined by springs; ``ends`` "fixed" grounds both
    ends through springs, "free" leaves them free."""
    lines = [f"PELAS,1,{k!r}", f"PMASS,2,{m!r}"]
    if spoints:
        lines.append(f"SPOINT,1,THRU,{n}")
    spring = (lambda e, a, b: f"CELAS3,{e},1,{a},{b}") if form == 3 else (lambda e, a, b: f"CELAS4,{e},{k!r},{a},{b}")
    mass = (lambda e, a: f"CMASS3,{e},2,{a}") if form == 3 else (lambda e, a: f"CMASS4,{e},{m!r},{a}")
    for i in range(1, n + 1):
        lines.append(mass(i, i))
    for i in range(1, n):
        lines.append(spring(10000 + i, i, i + 1))
    if ends == "fixed":
        lines += [spring(20001, 1, ""), spring(20002, n, "")]
    return "\n".join(lines) + "\n"


@pytest.mark.parametrize("spoints", [True, False], ids=["SPOINT cards", "points defined by the elements"])
@pytest.mark.parametrize("form", [3, 4], ids=["CELAS3/CMASS3", "CELAS4/CMASS4"])
def test_a_500_cell_string_of_scalar_points_has_the_chains_closed_form_frequencies(tmp_path, spoints, form):
    """No GRID: n masses m between n + 1 springs k (both ends held by springs),
    omega_j = 2 sqrt(k / m) sin(j pi / (2 (n + 1)))."""
    n, k, m = 500, 1000.0, 0.5
    p = tmp_path / "string.bdf"
    p.write_text("SOL 103\nCEND\nBEGIN BULK\n" + string_deck(n, k, m, spoints=spoints, form=form, ends="fixed")
                 + "ENDDATA\n")
    model, info = read_bdf(p)
    assert model.n_nodes == n
    f = solve_modes(model, n_modes=10, autospc=info.autospc).frequencies_hz
    j = np.arange(1, 11)
    np.testing.assert_allclose(f, 2 * math.sqrt(k / m) * np.sin(j * math.pi / (2 * (n + 1))) / TWO_PI, rtol=1e-9)


def test_a_free_free_scalar_string_has_one_zero_then_the_closed_form(tmp_path):
    """n masses, n - 1 springs, nothing grounded: omega_j = 2 sqrt(k / m) sin(j pi / (2 n)),
    j = 0 the free body."""
    n, k, m = 200, 50.0, 2.0
    p = tmp_path / "free_string.bdf"
    p.write_text("BEGIN BULK\n" + string_deck(n, k, m, spoints=False, form=4, ends="free") + "ENDDATA\n")
    model, info = read_bdf(p)
    f = solve_modes(model, n_modes=8, autospc=info.autospc).frequencies_hz
    j = np.arange(8)
    assert f[0] == 0.0
    np.testing.assert_allclose(f[1:], (2 * math.sqrt(k / m) * np.sin(j * math.pi / (2 * n)) / TWO_PI)[1:], rtol=1e-9)


def test_a_deck_without_grids_or_scalar_points_is_refused(tmp_path):
    p = tmp_path / "empty.bdf"
    p.write_text("BEGIN BULK\nMAT1,1,70.+9,,0.3,2700.\nENDDATA\n")
    with pytest.raises(ModelError, match="no GRID cards"):
        read_bdf(p)


def test_a_softly_suspended_part_beside_a_supported_one_keeps_its_low_frequencies():
    """Its suspension modes are nearly rigid shapes far below the zero threshold: their
    component is rigid, but the nearest rigid motion strains the springs, so they keep their
    frequencies (2 k / m for the translations), not 0 Hz."""
    k, n = 10.0, 20
    m = Model()
    m.add_nodes(np.arange(n + 1), np.c_[np.linspace(0, 0.2, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    m.add_beams(np.arange(1, n + 1), np.c_[np.arange(n), np.arange(1, n + 1)], Section.rectangle(0.0254, 0.0254),
                ALUMINIUM, orient=(0, 0, 1))
    m.add_point_masses([n // 2], 5.0, inertia=np.diag([0.01, 0.01, 0.01]))
    m.add_springs([n + 1, n + 2], [0, n], [k, k, k, 0.1, 0.1, 0.1])
    m.add_nodes([100, 101], [[1, 0, 0], [2, 0, 0]])           # a supported oscillator beside it
    m.fix(100)
    m.fix(101, "23456")
    m.add_springs([200], [[100, 101]], [1000.0, 0, 0, 0, 0, 0])
    m.add_point_masses([101], 1.0)
    f = solve_modes(m, n_modes=8, method="dense").frequencies_hz
    assert (f > 0).all()
    m_total = 5.0 + ALUMINIUM.rho * 0.0254**2 * 0.2
    np.testing.assert_allclose(f[:3], np.sqrt(2 * k / m_total) / TWO_PI, rtol=1e-5)
