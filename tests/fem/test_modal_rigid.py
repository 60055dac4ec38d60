"""Rigid-body modes are exactly those the model admits with no strain energy.

A model of short, stiff elements hung on soft springs has real sub-hertz modes whose
shapes are nearly rigid and whose eigenvalues sit far below ``1e-12 max(K_ii / M_ii)``;
they must keep their frequencies. A free model must still show exactly its rigid-body
zeros.
"""

import numpy as np
import pytest

from trussid.fem import ALUMINIUM, Model, Section
from trussid.fem.assembly import assemble
from trussid.fem.modal import eigenvalue_scale, rigid_null_dimension, solve_modes


def stiff_beam(n=20, length=0.2, springs=None):
    """A 1 in square aluminium bar of short elements with a 5 kg mass at mid-length."""
    m = Model()
    m.add_nodes(np.arange(n + 1), np.c_[np.linspace(0, length, n + 1), np.zeros(n + 1), np.zeros(n + 1)])
    m.add_beams(np.arange(1, n + 1), np.c_[np.arange(n), np.arange(1, n + 1)], Section.rectangle(0.0254, 0.0254),
                ALUMINIUM, orient=(0, 0, 1))
    m.add_point_masses([n // 2], 5.0, inertia=np.diag([0.01, 0.01, 0.01]))
    if springs is not None:
        m.add_springs([n + 1, n + 2], [0, n], springs)  # element ids are unique across kinds
    return m


def test_soft_suspension_modes_keep_their_frequencies():
    k = 10.0
    model = stiff_beam(springs=[k, k, k, 0.1, 0.1, 0.1])
    system = assemble(model)
    # The hard case: every suspension eigenvalue lies far below the old zero threshold.
    assert 20.0 < 1e-12 * eigenvalue_scale(system)
    assert rigid_null_dimension(system) == 0
    modes = solve_modes(system, n_modes=8, method="dense")
    assert np.all(modes.frequencies_hz[:6] > 0)
    # The three translations are the (practically rigid) bar on two isotropic springs:
    # omega^2 = 2 k / m_total. These eigenvalues are 1e-13 of the largest; both solvers
    # reach them to 0.6-3e-6 (round-off), where a plain dense eigh(K, M) is off by 3e-3.
    m_total = 5.0 + ALUMINIUM.rho * 0.0254**2 * 0.2
    for method in ("dense", "sparse"):
        omega2 = solve_modes(system, n_modes=8, method=method).omega[:3] ** 2
        assert np.allclose(omega2, 2 * k / m_total, rtol=1e-5), method


@pytest.mark.parametrize("method", ["dense", "sparse"])
def test_free_model_has_exactly_its_rigid_body_zeros(method):
    system = assemble(stiff_beam(n=40))
    assert rigid_null_dimension(system) == 6
    modes = solve_modes(system, n_modes=10, method=method)
    assert np.all(modes.frequencies_hz[:6] == 0)
    assert modes.frequencies_hz[6] > 100.0


def test_partly_supported_model_counts_only_the_free_motions():
    model = stiff_beam()
    # Vertical supports at both ends, both on the bar's axis: translation along x and y,
    # rotation about z, and rotation about the bar's own axis (x) stay free.
    model.fix([0, 20], "3")
    system = assemble(model)
    assert rigid_null_dimension(system) == 4
    modes = solve_modes(system, n_modes=6, method="dense")
    assert np.count_nonzero(modes.frequencies_hz == 0) == 4
