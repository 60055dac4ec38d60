"""Guyan reduction (Model.omit / fem.reduction.guyan) and the generic constraint API.

Exact where the omitted DOFs carry no mass (a lumped-mass beam's rotations: the full model's
frequencies), Guyan's static shape otherwise (a two-mass chain solved by hand).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from trussid.fem import ALUMINIUM, Model, ModelError, Section
from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes


def _cantilever(mass="lumped"):
    m = Model(mass=mass)
    n = 9
    m.add_nodes(np.arange(1, n + 1), np.column_stack([np.linspace(0, 1, n), np.zeros(n), np.zeros(n)]))
    m.add_beams(np.arange(1, n), np.column_stack([np.arange(1, n), np.arange(2, n + 1)]),
                Section.tube(0.01, 0.001), ALUMINIUM, orient=[0, 0, 1])
    m.fix(1)
    return m


def test_omitting_massless_rotations_keeps_the_frequencies():
    full = solve_modes(_cantilever(), n_modes=8).frequencies_hz
    m = _cantilever()
    m.omit(np.arange(2, 10), "456")
    system = assemble(m)
    assert system.n_dof == 8 * 3
    np.testing.assert_allclose(solve_modes(system, n_modes=8).frequencies_hz, full, rtol=1e-9)


def test_omitting_massive_dofs_is_guyans_static_shape():
    """Ground-k1-m1-k2-m2, omit m2: T = [1; 1], K = k1, M = m1 + m2."""
    k1, k2, m1, m2 = 1000.0, 3000.0, 2.0, 0.5
    m = Model()
    m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    m.add_springs([1, 2], [[1, -1], [2, 1]], [[k1, 0, 0, 0, 0, 0], [k2, 0, 0, 0, 0, 0]])
    m.add_point_masses([1, 2], [m1, m2])
    m.fix([1, 2], "23456")
    m.omit([2], "1")
    f = solve_modes(m, n_modes=1).frequencies_hz
    assert abs(f[0] / (math.sqrt(k1 / (m1 + m2)) / (2 * math.pi)) - 1) < 1e-12


def test_linear_constraint_and_general_matrices_by_hand():
    """u2 = 0.5 u1 through add_constraint; springs and masses through add_matrices:
    K = k1 + k2 / 4, M = m1 + m2 / 4."""
    k1, k2, m1, m2 = 300.0, 800.0, 1.0, 2.0
    m = Model()
    m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    e = np.zeros((2, 6, 6))
    e[0, 0, 0], e[1, 0, 0] = k1, k2
    mm = np.zeros((2, 6, 6))
    mm[0, 0, 0], mm[1, 0, 0] = m1, m2
    m.add_matrices([1, 2], [[1], [2]], K=e, M=mm)
    m.add_constraint(5, ([2], [0]), ([1], [0]), [[0.5]])
    m.fix([1, 2], "23456")
    f = solve_modes(m, n_modes=1).frequencies_hz
    assert abs(f[0] / (math.sqrt((k1 + k2 / 4) / (m1 + m2 / 4)) / (2 * math.pi)) - 1) < 1e-12


def test_node_frames_turn_supports_with_the_node():
    """A node whose frame is turned 90 deg about z: fixing its component 1 fixes global y."""
    m = Model()
    m.add_nodes([1], [[0, 0, 0]])
    m.add_springs([1], [1], [100.0, 400.0, 0, 0, 0, 0])
    m.add_point_masses([1], [1.0])
    m.set_node_frames([1], [[0, 1, 0], [-1, 0, 0], [0, 0, 1]])
    m.fix([1], "13456")  # frame x = global y fixed: only global x moves, on k = 100
    f = solve_modes(m, n_modes=1).frequencies_hz
    assert abs(f[0] - math.sqrt(100.0) / (2 * math.pi)) < 1e-12


def test_dependent_dof_of_two_constraints_is_named():
    m = Model()
    m.add_nodes([1, 2, 3], [[0, 0, 0], [1, 0, 0], [2, 0, 0]])
    m.add_constraint(1, ([2], [0]), ([1], [0]), [[1.0]], label="MPC 1")
    m.add_constraint(2, ([2], [0]), ([3], [0]), [[1.0]], label="MPC 2")
    with pytest.raises(ModelError, match=r"node 2 ux is dependent in two .*\(MPC 1 and MPC 2\)"):
        assemble(m, autospc=True)
