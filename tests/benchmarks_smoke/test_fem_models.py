"""The FE benchmark's structures are the intended ones, and OpenSeesPy agrees with trussid on them.

The benchmark (benchmarks/bench_fem_vs_opensees.py) times trussid against OpenSeesPy; these
checks make sure it times the right thing: the generators give the DOF counts the issue
asks for, every boom member is split in two, and both tools solve the same structure. The
last check is also an independent verification of trussid's frame element: OpenSees'
``elasticBeamColumn`` with ``-cMass`` is a separately written element of the same theory
(Euler-Bernoulli, consistent mass without rotary inertia, torsional inertia rho*J).
"""

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes

ROOT = Path(__file__).resolve().parents[2]


def _load_fem_models():
    # benchmarks/ is not an installed package: load the module from its file.
    spec = importlib.util.spec_from_file_location("fem_models", ROOT / "benchmarks" / "fem_models.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["fem_models"] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


fm = _load_fem_models()


@pytest.mark.parametrize("n_bays", [1, 4, 208, 2083])
def test_boom_has_72_dof_per_bay_and_every_member_split_in_two(n_bays):
    spec = fm.truss_boom(n_bays)
    members = 3 * n_bays + 3 * (n_bays + 1) + 3 * n_bays  # longerons, battens, diagonals
    assert spec.n_elements == 2 * members
    assert len(spec.node_ids) == 3 * (n_bays + 1) + members
    assert spec.n_free_dof == 72 * n_bays + 18
    # Each mid-member node joins exactly two elements, at the midpoint of their outer ends.
    mids = spec.node_ids[3 * (n_bays + 1):]
    counts = np.bincount(spec.elem_nodes.ravel(), minlength=spec.node_ids.max() + 1)
    assert (counts[mids] == 2).all()
    xyz = dict(zip(spec.node_ids.tolist(), spec.xyz))
    first, second = spec.elem_nodes[0::2], spec.elem_nodes[1::2]
    assert (first[:, 1] == second[:, 0]).all()
    for a, m, b in zip(first[:50, 0], first[:50, 1], second[:50, 1]):
        np.testing.assert_allclose(xyz[m], 0.5 * (xyz[a] + xyz[b]), atol=1e-15)


def test_boom_section_is_an_equilateral_triangle_clamped_at_station_0():
    spec = fm.truss_boom(3, side=0.4, bay=0.5)
    st0 = spec.xyz[:3]
    sides = [np.linalg.norm(st0[i] - st0[(i + 1) % 3]) for i in range(3)]
    np.testing.assert_allclose(sides, 0.4, rtol=1e-14)
    np.testing.assert_allclose(spec.xyz[3:6, 0], 0.5)
    assert sorted(spec.clamped.tolist()) == spec.node_ids[:3].tolist()


@pytest.mark.parametrize("n", [2, 3, 8, 17])
def test_lattice_has_n_cubed_nodes_and_a_clamped_base(n):
    spec = fm.cubic_lattice(n)
    assert len(spec.node_ids) == n**3
    assert spec.n_elements == 3 * n * n * (n - 1)
    assert len(spec.clamped) == n * n
    assert np.all(spec.xyz[spec.clamped - 1, 2] == 0.0)
    assert spec.n_free_dof == 6 * n * n * (n - 1)


def test_benchmark_sizes_are_the_ones_the_issue_names():
    nominal = {"boom-1.5e4": 1.5e4, "boom-1.5e5": 1.5e5, "lattice-3e3": 3e3, "lattice-3e4": 3e4}
    for case, target in nominal.items():
        dof = fm.spec_from_name(case).n_free_dof
        # "about": within 11 % (the lattice grows in steps of whole layers: n = 8 and 17).
        assert abs(dof / target - 1) < 0.11, (case, dof)


@pytest.mark.parametrize("case", ["boom:4", "lattice:3"])
def test_trussid_model_has_the_spec_dof_count(case):
    spec = fm.spec_from_name(case)
    assert assemble(fm.to_trussid(spec)).n_dof == spec.n_free_dof


def test_long_boom_bends_like_the_equivalent_beam():
    # A slender lattice boom is a cantilever with EI = E A_longeron side^2 / 2 (three
    # longerons on a circle of radius side/sqrt(3)) and the lacing's mass smeared along it.
    # Shear flexibility of the lacing makes the truss slightly softer; at 50 bays
    # (length/side = 50) that is under 1 %. Both bending planes are equal by symmetry.
    n_bays, side, bay = 50, 0.4, 0.4
    spec = fm.truss_boom(n_bays, side=side, bay=bay)
    f = solve_modes(fm.to_trussid(spec), n_modes=2).frequencies_hz
    A_l, A_c = spec.sections[0].A, spec.sections[1].A
    mat = spec.material
    EI = mat.E * A_l * side**2 / 2
    m = mat.rho * (3 * A_l + A_c * (3 * side + 3 * math.hypot(side, bay)) / bay)
    L = n_bays * bay
    f_beam = 1.875104068711961**2 / (2 * math.pi) * math.sqrt(EI / (m * L**4))
    assert -0.01 < f[0] / f_beam - 1 < 0
    assert f[1] == pytest.approx(f[0], rel=1e-6)


@pytest.mark.parametrize("case", ["boom:4", "lattice:3"])
def test_opensees_gives_the_same_lowest_frequencies(case):
    pytest.importorskip("openseespy")
    spec = fm.spec_from_name(case)
    f_trussid = solve_modes(fm.to_trussid(spec), n_modes=12).frequencies_hz
    f_opensees = fm.opensees_frequencies(case, n_modes=12, timeout=120)
    # Same element theory and the same consistent mass (round tubes: J = Iy + Iz, so
    # OpenSees' torsional inertia rho*A*J/A equals rho*Ip); only round-off differs.
    np.testing.assert_allclose(f_trussid, f_opensees, rtol=1e-6)
