"""Mode labels: energy partitions are complete, bending orders follow the shapes, and the
rules (suspension / UDF rigid-body / strut bending / axial / torsion / mixed) apply."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from trussid.fem.assembly import assemble
from trussid.testbed.labels import DOMINANT, bending_order, element_energies, label_testbed_modes
from trussid.testbed.model import build_testbed
from trussid.testbed.walls import solve_testbed_modes


@pytest.fixture(scope="module")
def default():
    tbm = build_testbed()
    system = assemble(tbm.model)
    modes = solve_testbed_modes(tbm, 30, system=system)
    return tbm, system, modes, label_testbed_modes(tbm, modes)


def _clamped_clamped_shapes(x, n_modes):
    """Closed-form clamped-clamped beam modes on [0, 1] (roots of cos b cosh b = 1)."""
    shapes = []
    for n in range(1, n_modes + 1):
        guess = (n + 0.5) * np.pi
        b = brentq(lambda z: np.cos(z) * np.cosh(z) - 1.0, guess - 0.3, guess + 0.3)
        s = (np.cosh(b) - np.cos(b)) / (np.sinh(b) - np.sin(b))
        shapes.append(np.cosh(b * x) - np.cos(b * x) - s * (np.sinh(b * x) - np.sin(b * x)))
    return np.array(shapes).T


def test_bending_order_counts_the_half_waves_of_clamped_beam_modes():
    x = np.linspace(0.0, 1.0, 23)
    assert bending_order(_clamped_clamped_shapes(x, 4), x).tolist() == [1, 2, 3, 4]


def test_bending_order_ignores_rigid_motion_of_the_ends():
    x = np.linspace(0.0, 1.0, 23)
    shapes = _clamped_clamped_shapes(x, 3) + (0.7 + 2.0 * x)[:, None]  # plus a rigid translation/rotation
    assert bending_order(shapes, x).tolist() == [1, 2, 3]


def test_energy_parts_sum_to_the_assembled_quadratic_forms(default):
    tbm, system, modes, _ = default
    e = element_energies(tbm.model, modes.shapes_full)
    kinetic = e.beam_kinetic.sum(0) + e.mass_kinetic.sum(0) + e.body_kinetic.sum(0)
    strain = e.beam_strain.sum(0) + e.spring_strain.sum(0)
    X = modes.shapes
    np.testing.assert_allclose(kinetic, np.einsum("ij,ij->j", X, system.M @ X), rtol=1e-10)
    # Strain energy is a small difference of large stiff-axial terms: compare at the
    # round-off scale |phi|^T |K| |phi| of the quadratic form, not relative to its value.
    scale = np.einsum("ij,ij->j", abs(X), abs(system.K) @ abs(X))
    assert (abs(strain - np.einsum("ij,ij->j", X, system.K @ X)) <= 1e-12 * scale).all()
    # The axial/torsion/bending split of each beam is exhaustive (no coupling in E-B).
    # (element energies of nearly unstrained elements are round-off: compare with the mode's
    # total at the same round-off scale)
    err = abs(e.beam_strain_parts.sum(1) - e.beam_strain).max(axis=0)
    assert (err <= 1e-12 * scale).all(), (err / scale).max()


def test_fractions_are_partitions(default):
    *_, lab = default
    np.testing.assert_allclose(lab.kinetic.sum(1), 1.0, rtol=1e-12)
    flexible = lab.strain.sum(1) > 0
    np.testing.assert_allclose(lab.strain[flexible].sum(1), 1.0, rtol=1e-12)


def test_default_labels_have_the_documented_forms(default):
    *_, lab = default
    pattern = re.compile(r"suspension|UDF rigid-body|strut [0-5] (bending [1-9] \(plane [yz]\)|axial|torsion)"
                         r"|mixed \(.+ \d\.\d\d, .+ \d\.\d\d\)")
    assert all(pattern.fullmatch(s) for s in lab.labels), lab.labels


def test_suspension_modes_keep_their_strain_energy_in_the_bungees(default):
    _, _, modes, lab = default
    susp = np.array([k == "suspension" for k in lab.kind])
    assert susp.sum() == 6
    assert (lab.strain[susp, -1] >= DOMINANT).all()
    assert (modes.frequencies_hz[susp] < 5.0).all()


def test_each_strut_has_one_first_bending_mode_per_plane(default):
    *_, lab = default
    first = [(int(s), p) for s, o, p in zip(lab.strut, lab.order, lab.plane) if o == 1]
    assert sorted(first) == [(k, p) for k in range(6) for p in ("y", "z")]


def _fake_modes(modes, X, freq=50.0):
    return replace(modes, shapes_full=X, frequencies_hz=np.full(X.shape[1], freq))


def test_three_equal_strut_modes_superposed_are_mixed_and_name_the_top_two(default):
    tbm, _, modes, lab = default
    picks = [int(np.flatnonzero((lab.strut == k) & (lab.order == 1))[0]) for k in (0, 1, 2)]
    X = modes.shapes_full[:, picks].sum(axis=1, keepdims=True)
    out = label_testbed_modes(tbm, _fake_modes(modes, X))
    assert out.kind == ["mixed"]
    assert re.fullmatch(r"mixed \(strut [012] 0\.3\d, strut [012] 0\.3\d\)", out.labels[0]), out.labels[0]


def _strut_field(tbm, strut, components):
    """A displacement field living on one strut's interior nodes: components(s) -> (n, 6) local."""
    m = tbm.map
    X = np.zeros((tbm.model.n_dof, 1))
    idx = tbm.model.index_of(m.strut_nodes[strut])
    R = m.strut_frames[strut]
    local = components(m.strut_s / m.strut_s[-1])
    local[[0, -1]] = 0.0  # ends held
    X[(6 * idx)[:, None] + np.arange(3), 0] = local[:, :3] @ R
    X[(6 * idx)[:, None] + np.arange(3, 6), 0] = local[:, 3:] @ R
    return X


@pytest.mark.parametrize("n, plane", [(1, "y"), (2, "z"), (3, "y")])
def test_a_sine_deflection_is_named_by_its_plane_and_half_waves(default, n, plane):
    tbm, _, modes, _ = default
    col = 1 if plane == "y" else 2

    def field(xi):
        out = np.zeros((len(xi), 6))
        out[:, col] = np.sin(n * np.pi * xi)
        # slope of the deflection: rz = dv/dx for deflection along y, ry = -dw/dx along z
        slope = n * np.pi * np.cos(n * np.pi * xi) / tbm.testbed.struts.length
        out[:, 5 if plane == "y" else 4] = slope if plane == "y" else -slope
        return out

    out = label_testbed_modes(tbm, _fake_modes(modes, _strut_field(tbm, 4, field)))
    assert out.labels == [f"strut 4 bending {n} (plane {plane})"]


@pytest.mark.parametrize("col, word", [(0, "axial"), (3, "torsion")])
def test_axial_and_torsional_fields_are_named_so(default, col, word):
    tbm, _, modes, _ = default

    def field(xi):
        out = np.zeros((len(xi), 6))
        out[:, col] = np.sin(np.pi * xi)
        return out

    out = label_testbed_modes(tbm, _fake_modes(modes, _strut_field(tbm, 2, field)))
    assert out.labels == [f"strut 2 {word}"]
