"""The testbed FE model: built where the layout says, with the solids' mass and the composite
adapter's stiffness, converged, calibrated to the thesis bands, symmetry broken, and the
wall-sweep fast path identical to a rebuild (issue 3, acceptance 3 and 5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from trussid.fem.assembly import assemble, beam_matrices, mass_blocks
from trussid.fem.constraints import rigid_body_modes
from trussid.fem.errors import ModelError
from trussid.testbed.labels import label_testbed_modes
from trussid.fem.modal import Modes
from trussid.testbed.model import build_testbed, tube_properties
from trussid.testbed.walls import design_at_walls, solve_testbed_modes, wall_basis, wall_matrices, wall_modes
from trussid.geometry.layout import testbed_layout
from trussid.geometry.solids import strut_solids, udf_rigid_body
from trussid.geometry.spec import Testbed


@pytest.fixture(scope="module")
def tb():
    return Testbed()


@pytest.fixture(scope="module")
def default(tb):
    tbm = build_testbed(tb)
    modes = solve_testbed_modes(tbm, 60)
    return tbm, modes, label_testbed_modes(tbm, modes)


# ------------------------------------------------------------------------------ map / mesh
def test_strut_nodes_lie_in_order_on_the_layouts_struts(tb, default):
    tbm = default[0]
    lay = testbed_layout(tb)
    xyz = tbm.model.xyz[tbm.model.index_of(tbm.map.strut_nodes)]  # (6, n, 3)
    expected = lay.strut_start[:, None, :] + tbm.map.strut_s[None, :, None] * lay.strut_axis[:, None, :]
    np.testing.assert_allclose(xyz, expected, atol=1e-12)
    assert (np.diff(tbm.map.strut_s) > 0).all()
    np.testing.assert_allclose(xyz[:, -1], lay.strut_end, atol=1e-12)


def test_adapter_and_wafer_grid_points_are_at_their_ends(tb, default):
    tbm = default[0]
    m, lay = tbm.map, testbed_layout(tb)
    xyz = lambda ids: tbm.model.xyz[tbm.model.index_of(ids)]  # noqa: E731
    np.testing.assert_allclose(xyz(m.adapter_nodes[:, 0]), lay.adapter_start, atol=1e-12)
    np.testing.assert_allclose(xyz(m.adapter_nodes[:, 1]), lay.adapter_end, atol=1e-12)
    wafer_len = np.linalg.norm(xyz(m.wafer_nodes[:, 1]) - xyz(m.wafer_nodes[:, 0]), axis=1)
    expected = tb.pzt.length if tb.adapter.length - tb.pzt.length > 0.01 * tb.adapter.length else tb.adapter.length
    np.testing.assert_allclose(wafer_len, expected, atol=1e-12)
    np.testing.assert_allclose(0.5 * (xyz(m.wafer_nodes[:, 0]) + xyz(m.wafer_nodes[:, 1])), lay.adapter_centre,
                               atol=1e-12)
    # adapter and wafer elements are strut elements of the right strut, joined end to end
    for i in range(6):
        assert set(m.wafer_elements[i]) <= set(m.adapter_elements[i]) <= set(m.strut_elements[i])
        assert (m.strut_of_element(m.adapter_elements[i]) == i).all()


def test_sensors_rigid_bodies_and_channels_are_mapped(tb, default):
    tbm = default[0]
    m, lay = tbm.map, testbed_layout(tb)
    np.testing.assert_allclose(tbm.model.xyz[tbm.model.index_of(m.accelerometer_nodes)], lay.accelerometer_points)
    np.testing.assert_allclose(m.accelerometer_directions, np.tile([0.0, 0.0, 1.0], (3, 1)))
    _, cg, _ = udf_rigid_body(tb)
    np.testing.assert_allclose(tbm.model.xyz[tbm.model.index_of([m.udf_master])][0], cg)
    bodies = {b.id: b for b in tbm.model.rigid_bodies}
    assert set(m.accelerometer_nodes) <= set(bodies[m.udf_body].slaves)
    assert m.base_master is not None and len(m.bungee_nodes) == tb.base.bungee_count
    assert m.channel_struts.tolist() == [[0, 1], [2, 3], [4, 5]]
    # point masses: the three accelerometers (plus zero-mass rotary inertias on the struts)
    pm = tbm.model.point_masses
    np.testing.assert_allclose(pm.mass[np.isin(pm.nodes, m.accelerometer_nodes)], tb.accelerometers.mass)


# ------------------------------------------------------------------------------ properties
def _solid_by_name(tb):
    return {s.name: s for s in strut_solids(tb)}


def test_each_struts_mass_and_inertia_equal_its_solids(tb, default):
    """Tube + adapter block + wafers from trimesh solids (independent of the section sums)."""
    tbm = default[0]
    model = tbm.model
    _, Mb, dofs = beam_matrices(model)
    R = rigid_body_modes(model.xyz, origin=np.zeros(3))  # (6 n, 6): rigid motions about the origin
    pm = model.point_masses
    pm_blocks, pm_dofs = mass_blocks(model)
    solids = _solid_by_name(tb)
    strut_of = tbm.map.strut_of_element(model.beams.ids)
    for i in range(6):
        sel = strut_of == i
        Re = R[dofs[sel]]  # (n_el, 12, 6)
        M_rb = np.einsum("eia,eij,ejb->ab", Re, Mb[sel], Re)
        on = np.flatnonzero(np.isin(pm.nodes, tbm.map.strut_nodes[i]))
        Rp = R[pm_dofs[0][on]]
        M_rb += np.einsum("eia,eij,ejb->ab", Rp, pm_blocks[0][on], Rp)
        parts = [solids[f"strut {i} tube"], solids[f"strut {i} adapter"]] + \
                [solids[f"strut {i} wafer {j}"] for j in range(tb.pzt.wafers_per_strut)]
        mass = 0.0
        inertia = np.zeros((3, 3))
        for part in parts:
            mp = part.mass_properties()
            c = mp.cg
            mass += mp.mass
            inertia += mp.inertia + mp.mass * (c @ c * np.eye(3) - np.outer(c, c))
        assert M_rb[0, 0] == pytest.approx(mass, rel=1e-3)
        np.testing.assert_allclose(M_rb[:3, :3], mass * np.eye(3), rtol=1e-3, atol=1e-12)
        assert abs(M_rb[3:, 3:] - inertia).max() <= 1e-3 * abs(inertia).max()


def _second_moments_per_length(solid, frame, centre, length):
    """(integral of density * y^2, of density * z^2) over a solid, per unit length, local axes."""
    mp = solid.mass_properties()
    J = frame @ mp.inertia @ frame.T  # about the cg, strut axes
    c = frame @ (mp.cg - centre)
    yy = 0.5 * (J[0, 0] + J[2, 2] - J[1, 1]) + mp.mass * c[1] ** 2
    zz = 0.5 * (J[0, 0] + J[1, 1] - J[2, 2]) + mp.mass * c[2] ** 2
    return yy / length, zz / length, mp.mass / length


def test_composite_adapter_stiffness_equals_the_solids_modulus_weighted_moments(tb, default):
    """E Iz = integral E y^2 dA and E Iy = integral E z^2 dA over tube, bored block and wafers,
    taken from the geometry package's meshes with 'density' = E (wafers on the +-y faces)."""
    tbm = default[0]
    lay = testbed_layout(tb)
    frames = lay.strut_frames()
    b = tbm.model.beams
    from dataclasses import replace as dc_replace

    i = 2
    solids = _solid_by_name(tb)
    block = dc_replace(solids[f"strut {i} adapter"], density=tb.adapter.youngs_modulus)
    wafers = [dc_replace(solids[f"strut {i} wafer {j}"], density=tb.pzt.youngs_modulus)
              for j in range(tb.pzt.wafers_per_strut)]
    By, Bz, BA = _second_moments_per_length(block, frames[i], lay.adapter_centre[i], tb.adapter.length)
    Wy = Wz = WA = 0.0
    for w in wafers:
        y, z, a = _second_moments_per_length(w, frames[i], lay.adapter_centre[i], tb.pzt.length)
        Wy, Wz, WA = Wy + y, Wz + z, WA + a
    E = tb.struts.youngs_modulus
    At, It = tube_properties(tb.struts.outer_radius, tb.struts.walls[i])
    row = np.flatnonzero(np.isin(b.ids, tbm.map.wafer_elements[i]))[0]
    # Iz: bending with deflection along y (about z) -> integral of y^2
    assert b.E[row] * b.Iz[row] == pytest.approx(E * It + By + Wy, rel=1e-3)
    assert b.E[row] * b.Iy[row] == pytest.approx(E * It + Bz + Wz, rel=1e-3)
    assert b.E[row] * b.A[row] == pytest.approx(E * At + BA + WA, rel=1e-3)
    # the wafers' parallel-axis term makes the section stiffer about z than about y
    assert b.Iz[row] > b.Iy[row]


# ------------------------------------------------------------------------------ numerics
def test_mesh_is_converged_below_400_hz(tb):
    """Doubling the elements per tube segment moves no mode below 400 Hz by 0.1 %.

    Measured on the calibrated defaults (36 modes up to 249 Hz): 4 -> 8 elements changes
    them by at most 3.9e-4, while 3 -> 6 would change them by 1.2e-3. (The third bending
    modes, 417-439 Hz, change by up to 1.1e-3 from 4 to 8.)
    """
    f4 = solve_testbed_modes(build_testbed(tb, 4), 60).frequencies_hz
    f8 = solve_testbed_modes(build_testbed(tb, 8), 60).frequencies_hz
    below = (f8 < 400.0) & (f8 > 0)
    assert below.sum() >= 30
    change = abs(f4[below] - f8[below]) / f8[below]
    assert change.max() < 1e-3, change.max()


def test_sweep_matrices_equal_a_rebuilt_model(tb):
    tbm = build_testbed(tb)
    basis = wall_basis(tbm)
    w = np.array(tb.struts.walls) * np.array([1.3, 0.7, 1.1, 0.9, 1.2, 0.8])
    K, M = wall_matrices(basis, w)
    ref = assemble(build_testbed(tb.with_walls(tuple(w))).model)
    assert abs(K - ref.K.toarray()).max() <= 1e-13 * abs(K).max()
    assert abs(M - ref.M.toarray()).max() <= 1e-13 * abs(M).max()
    f, X = wall_modes(basis, w, 30)
    np.testing.assert_allclose(X.T @ M @ X, np.eye(30), atol=1e-9)


def test_the_design_at_other_walls_is_the_rebuilt_model_and_its_modes(tb):
    """design_at_walls moves the strut sections of the built model (no rebuild); the model it
    returns is a real fem.Model that assembles to the rebuilt testbed's K and M, and its
    modes are mass-normalised Modes whose labels are the rebuilt model's."""
    tbm = build_testbed(tb)
    basis = wall_basis(tbm)
    w = np.array(tb.struts.walls) * np.array([1.3, 0.7, 1.1, 0.9, 1.2, 0.8])
    design, modes = design_at_walls(tbm, basis, w, 30)
    rebuilt = build_testbed(tb.with_walls(tuple(w)))
    assert design.testbed == rebuilt.testbed
    for key in ("A", "Iy", "Iz", "J"):
        np.testing.assert_allclose(getattr(design.model.beams, key), getattr(rebuilt.model.beams, key),
                                   rtol=1e-14)
    ours, ref = assemble(design.model), assemble(rebuilt.model)
    assert abs(ours.K - ref.K).max() <= 1e-13 * abs(ref.K).max()
    assert abs(ours.M - ref.M).max() <= 1e-13 * abs(ref.M).max()
    assert isinstance(modes, Modes) and len(modes) == 30
    K, M = ref.K.toarray(), ref.M.toarray()
    np.testing.assert_allclose(modes.shapes.T @ M @ modes.shapes, np.eye(30), atol=1e-9)
    lam = (2 * np.pi * modes.frequencies_hz) ** 2
    np.testing.assert_allclose(K @ modes.shapes, M @ modes.shapes * lam, atol=1e-6 * lam.max() ** 0.5)
    assert label_testbed_modes(design, modes).labels == \
        label_testbed_modes(rebuilt, solve_testbed_modes(rebuilt, 30)).labels
    # the reference model is not changed by making a design from it
    np.testing.assert_array_equal(tbm.model.beams.A, build_testbed(tb).model.beams.A)


def test_sweep_needs_euler_bernoulli_and_valid_walls(tb):
    with pytest.raises(ModelError, match="Euler-Bernoulli"):
        wall_basis(build_testbed(tb, beam_theory="timoshenko"))
    with pytest.raises(ModelError, match="consistent mass"):
        wall_basis(build_testbed(tb, mass="lumped"))
    basis = wall_basis(build_testbed(tb))
    bad = list(tb.struts.walls)
    bad[4] = tb.struts.outer_radius
    with pytest.raises(ModelError, match="strut 4 wall"):
        wall_modes(basis, bad)


# ------------------------------------------------------------------------------ ends, base
def test_very_stiff_flexures_reproduce_clamped_ends(tb):
    clamped = tb.replace(struts__base_rotational_stiffness=math.inf, struts__top_rotational_stiffness=math.inf)
    stiff = tb.replace(struts__base_rotational_stiffness=1e9, struts__top_rotational_stiffness=1e9)
    fc = solve_testbed_modes(build_testbed(clamped), 30).frequencies_hz[6:]
    fs = solve_testbed_modes(build_testbed(stiff), 30).frequencies_hz[6:]
    np.testing.assert_allclose(fs, fc, rtol=1e-4)
    tbm = build_testbed(stiff)
    assert (tbm.map.flexure_springs >= 0).all()
    assert (build_testbed(clamped).map.flexure_springs == -1).all()


def test_softer_flexures_lower_the_first_bending_modes(tb):
    def first_bending(k):
        t = tb.replace(struts__base_rotational_stiffness=k, struts__top_rotational_stiffness=k)
        tbm = build_testbed(t)
        m = solve_testbed_modes(tbm, 30)
        lab = label_testbed_modes(tbm, m)
        return np.sort(m.frequencies_hz[lab.order == 1])

    stiff, soft = first_bending(1e5), first_bending(1e2)
    assert len(stiff) == len(soft) == 12
    assert (soft < stiff).all()


def test_lumped_mass_and_timoshenko_variants_stay_close_to_the_default(tb, default):
    """Other element options give the same bands: lumped mass within 2 %, shear within 1 %."""
    f0 = default[1].frequencies_hz[6:30]
    for kw, tol in ((dict(mass="lumped"), 0.02), (dict(beam_theory="timoshenko"), 0.01)):
        f = solve_testbed_modes(build_testbed(tb, **kw), 30).frequencies_hz[6:30]
        assert (abs(f - f0) / f0).max() < tol, kw


def test_clamped_base_has_no_suspension(tb):
    t = tb.replace(base__support="clamped")
    tbm = build_testbed(t)
    m = solve_testbed_modes(tbm, 20)
    lab = label_testbed_modes(tbm, m)
    assert tbm.map.base_master is None and len(tbm.map.bungee_nodes) == 0
    assert "suspension" not in lab.kind
    assert m.frequencies_hz[0] > 5.0


# ------------------------------------------------------------------------------ acceptance 3
def _band(default, kind, order=None):
    _, modes, lab = default
    sel = np.array([k == kind for k in lab.kind])
    if order is not None:
        sel &= lab.order == order
    return np.sort(modes.frequencies_hz[sel])


def test_twelve_first_bending_modes_within_50_to_70_hz(default):
    f = _band(default, "bending", 1)
    assert len(f) == 12 and f.min() >= 50.0 and f.max() <= 70.0, f


def test_twelve_second_bending_modes_within_200_to_250_hz(default):
    f = _band(default, "bending", 2)
    assert len(f) == 12 and f.min() >= 200.0 and f.max() <= 250.0, f


def test_udf_and_third_bending_bands_are_recorded_and_do_not_regress(default, record_property):
    """The two thesis bands this geometry cannot meet (README, Testbed calibration; accepted
    as the thesis geometry's physics): the figures are recorded, and only a step back fails,
    so that a better calibration passes. Today: 4 of the 6 UDF rigid-body modes in
    130-250 Hz (the lowest two at 79 and 118 Hz) and third bending at 417-439 Hz."""
    udf = _band(default, "udf")
    third = _band(default, "bending", 3)
    in_band = int(((udf >= 130.0) & (udf <= 250.0)).sum())
    record_property("udf_modes_hz", np.round(udf, 1).tolist())
    record_property("udf_modes_in_130_250_hz", in_band)
    record_property("third_bending_hz", [round(float(third.min()), 1), round(float(third.max()), 1)])
    assert len(udf) == 6 and len(third) == 12
    assert in_band >= 4, udf
    # no worse than today's 16-22 % above the 300-360 Hz band
    assert third.max() <= 1.25 * 360.0 and third.min() >= 300.0, third


def test_third_bending_modes_are_the_next_twelve_strut_modes(default):
    f = _band(default, "bending", 3)
    assert len(f) == 12 and f.min() > _band(default, "bending", 2).max()


def test_suspension_modes_are_below_5_hz(default):
    f = _band(default, "suspension")
    assert len(f) == 6 and f.max() < 5.0 and f.min() > 0.0


# ------------------------------------------------------------------------------ acceptance 5
def test_first_bending_modes_are_twelve_distinct_frequencies(default):
    _, modes, lab = default
    f = np.sort(modes.frequencies_hz[lab.order == 1])
    assert len(f) == 12
    assert (np.diff(f) / f[1:]).min() > 1e-4


@pytest.mark.parametrize("strut", range(6))
def test_changing_one_wall_moves_that_struts_modes(tb, default, strut):
    _, modes, lab = default
    w = list(tb.struts.walls)
    w[strut] *= 1.05
    tbm2 = build_testbed(tb.with_walls(tuple(w)))
    m2 = solve_testbed_modes(tbm2, 30)
    lab2 = label_testbed_modes(tbm2, m2)
    own = np.sort(modes.frequencies_hz[(lab.strut == strut) & (lab.order == 1)])
    own2 = np.sort(m2.frequencies_hz[(lab2.strut == strut) & (lab2.order == 1)])
    assert len(own) == len(own2) == 2
    assert (abs(own2 - own) / own > 1e-3).all()


# ------------------------------------------------------------------------------ study script
def test_wall_thickness_study_writes_a_plot_and_prints_sensitivities(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    import matplotlib.image as mpimg

    root = Path(__file__).resolve().parents[2]
    out = tmp_path / "study.png"  # an existing folder: nothing creates one uninvited
    res = subprocess.run([sys.executable, str(root / "examples" / "wall_thickness_study.py"), "--points", "2",
                          "--modes", "20", "--out", str(out)], capture_output=True, text=True, cwd=tmp_path)
    assert res.returncode == 0, res.stderr
    assert out.is_file() and out.stat().st_size > 20_000
    img = mpimg.imread(out)
    assert img.shape[0] > 400 and img.shape[1] > 600 and img[..., :3].std() > 0.05  # not blank
    assert not list(out.parent.glob(".study.*"))  # no temporary file left behind
    assert "sensitivities df/dt" in res.stdout and "strut 0 bending 1" in res.stdout


def test_wall_thickness_study_rejects_a_bad_sweep_without_writing(tmp_path):
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    out = tmp_path / "study.png"
    res = subprocess.run([sys.executable, str(root / "examples" / "wall_thickness_study.py"), "--points", "1",
                          "--out", str(out)], capture_output=True, text=True)
    assert res.returncode == 2 and "--points" in res.stderr and "Traceback" not in res.stderr
    assert not out.exists()


def test_fine_meshes_take_the_sparse_path_and_match_a_dense_solution():
    """Above DENSE_MAX_DOF the testbed's modes come from sparse shift-invert (no n x n
    matrix): same frequencies as LAPACK's dense eigh of the same K, M, every mode below a
    frequency found by count-doubling, and the wall sweep's sparse path agrees too."""
    import scipy.linalg as la

    from trussid.fem.modal import DENSE_MAX_DOF
    from trussid.testbed.walls import solve_testbed_modes, wall_basis, wall_modes

    tbm = build_testbed(elements_per_segment=10)
    system = assemble(tbm.model)
    assert system.n_dof > DENSE_MAX_DOF
    lam = la.eigh(system.K.toarray(), system.M.toarray(), eigvals_only=True, subset_by_index=[0, 59])
    f_ref = np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)
    modes = solve_testbed_modes(tbm, 12, system=system)
    assert modes.method == "shift-invert"
    assert np.max(np.abs(modes.frequencies_hz[6:] / f_ref[6:12] - 1)) < 1e-8
    f_max = 0.5 * (f_ref[40] + f_ref[41])                 # 41 modes lie below it
    below = solve_testbed_modes(tbm, 12, system=system, max_frequency_hz=f_max)
    assert len(below) == 41 and below.frequencies_hz[-1] < f_max
    basis = wall_basis(tbm, system)
    f_sweep, X = wall_modes(basis, basis.walls_ref, 12)
    assert np.max(np.abs(f_sweep[6:] / f_ref[6:12] - 1)) < 1e-8
    assert np.allclose(X.T @ (system.M @ X), np.eye(12), atol=1e-9)
