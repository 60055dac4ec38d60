"""NASTRAN modelling entries, each against an answer that does not use it.

Closed forms (spring-mass systems, a rod, a torsion pendulum), small models solved by hand
in numpy, or the same model built without the entry (GRDSET vs SPC1 on every grid, a CORD2C
grid vs the grid in basic, RBAR vs RBE2, CRIGD vs RBE2/RBAR, Guyan on massless DOFs vs the
full model). NASTRAN's element mass conventions are checked on one-element cases whose
frequency follows from the convention in one line.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sl

from trussid.fem import ModelError
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf

TWO_PI = 2.0 * math.pi


def deck(tmp_path: Path, bulk: str, name: str = "deck.bdf", case: str = "") -> Path:
    text = ("SOL 103\nCEND\n" + case + "BEGIN BULK\n" if case else "BEGIN BULK\n") + bulk.strip() + "\nENDDATA\n"
    p = tmp_path / name
    p.write_text(text)
    return p


def freqs(path: Path, n: int = 6) -> np.ndarray:
    model, info = read_bdf(path)
    return solve_modes(model, n_modes=n, autospc=info.autospc).frequencies_hz


def hz(k, m):
    return math.sqrt(k / m) / TWO_PI


# ------------------------------------------------------------------ GRDSET, coordinate systems
BEAM = """MAT1,1,70.+9,,0.3,2700.
PBAR,1,1,1.-4,2.-9,2.-9,4.-9
"""


def beam_grids(n, xyz_of, cp="", cd=""):
    return "".join(f"GRID,{i + 1},{cp},{','.join(repr(float(v)) for v in xyz_of(i))},{cd}\n" for i in range(n))


def test_grdset_ps_equals_spc1_on_every_grid(tmp_path):
    body = BEAM + beam_grids(6, lambda i: (0.2 * i, 0, 0)) + "".join(
        f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(5)) + "SPC1,1,123456,1\n"
    with_grdset = deck(tmp_path, body + "GRDSET,,,,,,,1345", "a.bdf")
    spelled = deck(tmp_path, body + "SPC1,1,1345,2,THRU,6", "b.bdf")
    np.testing.assert_array_equal(freqs(with_grdset), freqs(spelled))


@pytest.mark.parametrize("system,point,g0", [
    ("CORD2C,7,,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.", lambda i: (0.3 + 0.2 * i, 40.0, 0.0), (0.5, 40.0, 1.0)),
    ("CORD2S,7,,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.", lambda i: (0.3 + 0.2 * i, 60.0, 30.0), (0.5, 30.0, 30.0)),
    ("CORD2R,7,,0.1,0.2,0.,0.,0.3,1.,\n,1.,1.,0.", lambda i: (0.2 * i, 0.0, 0.0), (0.0, 0.0, 1.0)),
])
def test_grids_in_cp_and_cd_systems_equal_the_same_beam_in_basic(tmp_path, system, point, g0):
    """A radial line of a cylindrical/spherical system (the x axis of a rectangular one),
    grids with CP and CD in that system: component 1 is the beam axis, 2 and 3 are normal
    to it, so supports, a torsional CMASS (component 4) and a transverse spring-mass
    (component 2) act as components 1, 4 and 2 of the same beam along basic x (equal I1, I2:
    the orientation does not matter)."""
    n = 6
    elems = "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},99\n" for i in range(n - 1))
    extra = ("SPC1,1,123456,1,99\nSPC1,1,1,6\nCMASS2,50,3.-5,4,4\nCMASS2,51,1.,6,2\n"
             "CELAS2,52,1.+4,6,2\n")
    in_system = (system + "\n" + BEAM + elems + beam_grids(n, point, cp="7", cd="7")
                 + f"GRID,99,7,{g0[0]},{g0[1]},{g0[2]},7\n" + extra)
    basic = BEAM + elems + beam_grids(n, lambda i: (0.2 * i, 0, 0)) + "GRID,99,,0.,0.,1.\n" + extra
    f_sys = freqs(deck(tmp_path, in_system, "sys.bdf"), 8)
    f_basic = freqs(deck(tmp_path, basic, "basic.bdf"), 8)
    np.testing.assert_allclose(f_sys, f_basic, rtol=1e-9)


# ------------------------------------------------------------------ scalar masses and springs
def test_cmass_on_a_grid_component_is_a_spring_mass_oscillator(tmp_path):
    p = deck(tmp_path, """GRID,1,,0.,0.,0.
SPC1,1,3456,1
CELAS2,1,400.,1,1
CELAS2,2,900.,1,2
CMASS1,3,7,1,1
PMASS,7,4.
CMASS2,4,9.,1,2
""")
    np.testing.assert_allclose(freqs(p, 2), sorted([hz(400, 4), hz(900, 9)]), rtol=1e-12)


def test_two_grid_cmass_couples_the_relative_motion(tmp_path):
    """M = diag(m0, m0) + m [1 -1; -1 1], K = diag(k, k): f = sqrt(k/m0), sqrt(k/(m0 + 2m))."""
    k, m0, m = 1000.0, 2.0, 0.5
    p = deck(tmp_path, f"""GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
SPC1,1,23456,1,2
CELAS2,1,{k},1,1
CELAS2,2,{k},2,1
CMASS2,3,{m0},1,1
CMASS2,4,{m0},2,1
CMASS2,5,{m},1,1,2,1
""")
    np.testing.assert_allclose(freqs(p, 2), [hz(k, m0 + 2 * m), hz(k, m0)], rtol=1e-12)


def test_celas_between_different_components(tmp_path):
    """CELAS2 on x of grid 1 and y of grid 2: the stiffness of u1x - u2y (hand 2x2)."""
    k, k0, m1, m2 = 500.0, 200.0, 1.0, 3.0
    p = deck(tmp_path, f"""GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
SPC1,1,23456,1
SPC1,1,13456,2
CELAS2,1,{k},1,1,2,2
CELAS2,2,{k0},2,2
CMASS2,3,{m1},1,1
CMASS2,4,{m2},2,2
""")
    K = np.array([[k, -k], [-k, k + k0]])
    lam = sl.eigh(K, np.diag([m1, m2]), eigvals_only=True)
    np.testing.assert_allclose(freqs(p, 2), np.sqrt(lam) / TWO_PI, rtol=1e-12)


# ------------------------------------------------------------------ rigid elements and MPC
SPRING_SQUARE = """GRID,1,,-1.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,0.,-2.,0.
GRID,4,,0.,2.,0.
GRID,9,,0.,0.,0.
SPC1,1,12456,1,2,3,4
CELAS2,1,{k},1,3
CELAS2,2,{k},2,3
CELAS2,3,{k},3,3
CELAS2,4,{k},4,3
CONM2,10,9,,{m}
"""


def test_rbe3_reference_moves_with_nastrans_weighted_average(tmp_path):
    """Weights 1 on (+-1, 0) and 3 on (0, +-2): u_ref = sum c_i u_i with c = w / sum w. With
    the corner springs k the reference sees K = 1 / sum(c_i^2 / k) (Lagrange, by hand)."""
    k, m = 1000.0, 2.0
    p = deck(tmp_path, SPRING_SQUARE.format(k=k, m=m) + "RBE3,20,,9,3,1.,123,1,2,\n,3.,123,3,4\n"
             "SPC1,1,12456,9")
    c = np.array([1, 1, 3, 3]) / 8.0
    np.testing.assert_allclose(freqs(p, 1), [hz(k / np.sum(c**2), m)], rtol=1e-10)


def test_rbe3_rotation_uses_the_characteristic_length(tmp_path):
    """All six components of grids (0, +-2) weighted 1: a rigid motion is reproduced, and
    opposite z motions (no rotations) turn the reference about x by the weighted fit with
    rotations weighted Lc^2 = 4 (Lc: mean distance to the reference), by hand."""
    from trussid.fem.constraints import rbe3_constraint, rigid_transform

    xyz = np.array([[0.0, -2.0, 0.0], [0.0, 2.0, 0.0]])
    comps = np.ones((2, 6), bool)
    C = rbe3_constraint(np.zeros(3), None, xyz, None, comps, [1.0, 1.0], np.ones(6, bool), "RBE3")
    # a rigid motion of the independent grids is reproduced exactly at the reference point
    q = np.array([0.1, -0.2, 0.3, 0.01, 0.02, -0.03])
    u = np.concatenate([rigid_transform(x) @ q for x in xyz])
    np.testing.assert_allclose(C @ u, q, rtol=1e-12, atol=1e-15)
    # opposite z at the two grids (no rotation given): the reference rotates about x by the
    # weighted fit: minimise sum w (u_zi - y_i th)^2 + w Lc^2 (th - 0)^2 -> th = sum y u / (sum y^2 + 2 Lc^2)
    u = np.zeros(12)
    u[2], u[8] = -1.0, 1.0
    th = (2.0 * 1 + 2.0 * 1) / (4.0 + 4.0 + 2 * 4.0)
    assert abs((C @ u)[3] - th) < 1e-12


def test_rbar_any_independent_set_equals_rbe2(tmp_path):
    """An RBAR making GB depend on GA, and one with mixed independent components, define the
    same rigid link as RBE2 GA 123456 GB."""
    body = BEAM + beam_grids(4, lambda i: (0.3 * i, 0, 0)) + "GRID,10,,0.9,0.2,0.1\nCONM2,5,10,,2.,,,,,\n,0.01,,0.02,,,0.03\n" \
        + "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(3)) + "SPC1,1,123456,1\n"
    f_rbe2 = freqs(deck(tmp_path, body + "RBE2,20,4,123456,10", "rbe2.bdf"))
    f_rbar = freqs(deck(tmp_path, body + "RBAR,20,4,10,123456", "rbar.bdf"))
    f_mixed = freqs(deck(tmp_path, body + "RBAR,20,4,10,123,456,456,123", "mixed.bdf"))
    np.testing.assert_allclose(f_rbar, f_rbe2, rtol=1e-10)
    np.testing.assert_allclose(f_mixed, f_rbe2, rtol=1e-10)


def test_nastran95_rigid_elements_equal_rbe2_and_rbar(tmp_path):
    body = BEAM + beam_grids(4, lambda i: (0.3 * i, 0, 0)) + "GRID,10,,0.9,0.2,0.1\nCONM2,5,10,,2.,,,,,\n,0.01,,0.02,,,0.03\n" \
        + "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(3)) + "SPC1,1,123456,1\n"
    f_rbe2 = freqs(deck(tmp_path, body + "RBE2,20,4,123456,10", "rbe2.bdf"))
    f_c1 = freqs(deck(tmp_path, body + "CRIGD1  20      4       10", "c1.bdf"))
    f_c2 = freqs(deck(tmp_path, body + "CRIGD2  20      4       10      123456", "c2.bdf"))
    f_c3 = freqs(deck(tmp_path, body + "CRIGD3  20      4       123     10      456             +C\n"
                                      "+C      MSET    4       456     10      123", "c3.bdf"))
    for f in (f_c1, f_c2, f_c3):
        np.testing.assert_allclose(f, f_rbe2, rtol=1e-10)


def test_crigdr_keeps_the_rod_length(tmp_path):
    """CRIGDR: the mass at grid 2 cannot move along the line 1-2 (45 deg); across it, a
    spring k: f = sqrt(k / m) for motion normal to the rod, none along it."""
    k, m = 800.0, 2.0
    p = deck(tmp_path, f"""GRID,1,,0.,0.,0.
GRID,2,,1.,1.,0.
SPC1,1,123456,1
SPC1,1,3456,2
CELAS2,3,{k},2,1
CELAS2,4,{k},2,2
CONM2,5,2,,{m}
CRIGDR  6       1       2       1
""")
    # u1 (x) of grid 2 follows -u2: the free motion is along (-1, 1)/sqrt(2), spring k in x and y
    np.testing.assert_allclose(freqs(p, 1), [hz(k, m)], rtol=1e-12)


def test_mpc_ties_dofs_with_its_coefficients(tmp_path):
    """MPC 2 u2 - u1 = 0 (u2 = u1 / 2): K = k1 + k2 / 4, M = m1 + m2 / 4."""
    k1, k2, m1, m2 = 300.0, 800.0, 1.0, 2.0
    body = f"""GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
SPC1,1,23456,1,2
CELAS2,1,{k1},1,1
CELAS2,2,{k2},2,1
CONM2,3,1,,{m1}
CONM2,4,2,,{m2}
MPC,5,2,1,2.,1,1,-1.
"""
    p = deck(tmp_path, body, case="SPC = 1\nMPC = 5\n")
    np.testing.assert_allclose(freqs(p, 1), [hz(k1 + k2 / 4, m1 + m2 / 4)], rtol=1e-12)
    unselected = deck(tmp_path, body, "plain.bdf", case="SPC = 1\n")
    np.testing.assert_allclose(freqs(unselected, 2), sorted([hz(k1, m1), hz(k2, m2)]), rtol=1e-12)


# ------------------------------------------------------------------ CBUSH offset, SUPORT, OMIT
def test_cbush_between_non_coincident_grids_acts_at_s(tmp_path):
    """Spring ky at the midpoint of a 1 m bar, grid 1 fixed, grid 2 with mass m and inertia
    J about z, plus krz: K = [[ky, -ky L/2], [-ky L/2, ky L^2/4 + krz]] on (v, rz) (hand)."""
    ky, krz, m, J, L = 1000.0, 50.0, 2.0, 0.1, 1.0
    p = deck(tmp_path, f"""GRID,1,,0.,0.,0.
GRID,2,,{L},0.,0.
SPC1,1,123456,1
SPC1,1,1345,2
CBUSH,7,8,1,2,0.,1.,0.
PBUSH,8,K,0.,{ky},0.,0.,0.,{krz}
CONM2,9,2,,{m},,,,,\n,0.,,0.,,,{J}
""")
    K = np.array([[ky, -ky * L / 2], [-ky * L / 2, ky * L * L / 4 + krz]])
    lam = sl.eigh(K, np.diag([m, J]), eigvals_only=True)
    np.testing.assert_allclose(freqs(p, 2), np.sqrt(lam) / TWO_PI, rtol=1e-10)


def test_suport_is_accepted_with_a_note_and_changes_nothing(tmp_path):
    body = """GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
CBUSH,7,8,1,2,,,,1
PBUSH,8,K,1000.,2000.,3000.,40.,50.,60.
CORD2R,1,,0.,0.,0.,0.,0.,1.,\n,1.,0.,0.
CONM2,9,1,,2.,,,,,\n,0.1,,0.1,,,0.1
CONM2,10,2,,3.,,,,,\n,0.2,,0.2,,,0.2
"""
    _, info = read_bdf(deck(tmp_path, body + "SUPORT,1,123456", "s.bdf"))
    assert any(n.startswith("SUPORT accepted") for n in info.notes)
    np.testing.assert_array_equal(freqs(tmp_path / "s.bdf", 12), freqs(deck(tmp_path, body, "n.bdf"), 12))


def test_omit_of_massless_rotations_is_exact_and_aset_is_its_complement(tmp_path):
    body = BEAM + beam_grids(7, lambda i: (0.2 * i, 0.05 * i, 0)) + "".join(
        f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(6)) + "SPC1,1,123456,1\nCONM2,20,7,,0.05\n"
    full = freqs(deck(tmp_path, body, "full.bdf"), 8)
    omit = freqs(deck(tmp_path, body + "OMIT1,456,2,THRU,7", "omit.bdf"), 8)
    aset = freqs(deck(tmp_path, body + "ASET1,123,2,THRU,7", "aset.bdf"), 8)
    np.testing.assert_allclose(omit, full, rtol=1e-9)
    np.testing.assert_allclose(aset, full, rtol=1e-9)


def test_omit_with_mass_is_guyans_approximation(tmp_path):
    """Chain ground-k1-m1-k2-m2, omit m2: T = [1; 1], K = k1, M = m1 + m2 (by hand)."""
    k1, k2, m1, m2 = 1000.0, 3000.0, 2.0, 0.5
    p = deck(tmp_path, f"""GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
SPC1,1,23456,1,2
CELAS2,1,{k1},1,1
CELAS2,2,{k2},1,1,2,1
CONM2,3,1,,{m1}
CONM2,4,2,,{m2}
OMIT,2,1
""")
    np.testing.assert_allclose(freqs(p, 1), [hz(k1, m1 + m2)], rtol=1e-12)


def test_omitted_mechanism_is_named(tmp_path):
    """Grids 2 and 3 omitted, joined to each other but to nothing else: K_oo is singular."""
    p = deck(tmp_path, """GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,2.,0.,0.
SPC1,1,23456,1,2,3
CELAS2,1,100.,1,1
CELAS2,2,100.,2,1,3,1
CONM2,3,1,,1.
CONM2,4,2,,1.
CONM2,5,3,,1.
OMIT1,1,2,3
""")
    with pytest.raises(ModelError, match="omitted DOFs are a mechanism"):
        freqs(p, 1)


# ------------------------------------------------------------------ massless bars, J = 0
def test_massless_bar_without_rho_and_j_carries_a_tip_mass(tmp_path):
    """MAT1 without RHO, PBAR without J: cantilever spring 3 E I / L^3 with the tip mass."""
    E, I, L, m = 70e9, 2e-9, 1.0, 3.0
    p = deck(tmp_path, f"""MAT1,1,{E},,0.3
PBAR,1,1,1.-4,{I},{I}
""" + beam_grids(5, lambda i: (L * i / 4, 0, 0)) + "".join(
        f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(4)) + f"SPC1,1,123456,1\nCONM2,9,5,,{m}\n")
    f = freqs(p, 2)
    np.testing.assert_allclose(f, [hz(3 * E * I / L**3, m)] * 2, rtol=1e-10)


# ------------------------------------------------------------------ NASTRAN's element mass
ONE = "GRID,1,,0.,0.,0.\nGRID,2,,{L},0.,0.\nSPC1,1,123456,1\n"


def test_lumped_cbeam_has_torsional_inertia_rho_i1_i2_l_over_2(tmp_path):
    E, G, rho, A, I1, I2, J, L = 70e9, 26e9, 2700.0, 1e-4, 2e-9, 3e-9, 4e-9, 0.5
    p = deck(tmp_path, ONE.format(L=L) + f"SPC1,1,12356,2\nMAT1,1,{E},{G},,{rho}\n"
             f"PBEAM,1,1,{A},{I1},{I2},,{J}\nCBEAM,1,1,1,2,0.,0.,1.\n")
    np.testing.assert_allclose(freqs(p, 1), [hz(G * J / L, rho * (I1 + I2) * L / 2)], rtol=1e-12)


def test_coupled_cbar_has_no_torsional_inertia(tmp_path):
    E, G, rho, J, L, J0 = 70e9, 26e9, 2700.0, 4e-9, 0.5, 1e-4
    p = deck(tmp_path, ONE.format(L=L) + f"SPC1,1,12356,2\nMAT1,1,{E},{G},,{rho}\nPARAM,COUPMASS,1\n"
             f"PBAR,1,1,1.-4,2.-9,3.-9,{J}\nCBAR,1,1,1,2,0.,0.,1.\nCONM2,5,2,,0.,,,,,\n,{J0},,0.,,,0.\n")
    np.testing.assert_allclose(freqs(p, 1), [hz(G * J / L, J0)], rtol=1e-12)


def test_coupled_crod_mass_is_five_twelfths_axially_and_lumped_across(tmp_path):
    E, rho, A, L, k = 70e9, 2700.0, 1e-4, 0.5, 1e4
    m = rho * A * L
    p = deck(tmp_path, ONE.format(L=L) + f"SPC1,1,3456,2\nMAT1,1,{E},,0.3,{rho}\nPARAM,COUPMASS,1\n"
             f"PROD,1,1,{A}\nCROD,1,1,1,2\nCELAS2,5,{k},2,2\n")
    np.testing.assert_allclose(freqs(p, 2), sorted([hz(k, m / 2), hz(E * A / L, 5 * m / 12)]), rtol=1e-12)


def test_pbarl_rod_uses_shear_factor_0_9(tmp_path):
    r = 0.01
    A, I, J = math.pi * r**2, math.pi * r**4 / 4, math.pi * r**4 / 2
    common = beam_grids(4, lambda i: (0.02 * i, 0, 0)) + "".join(
        f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(3)) + "SPC1,1,123456,1\nMAT1,1,70.+9,,0.33,2700.\n"
    rod = freqs(deck(tmp_path, common + f"PBARL,1,1,,ROD\n,{r}", "l.bdf"), 6)
    pbar = freqs(deck(tmp_path, common + f"PBAR,1,1,{A!r},{I!r},{I!r},{J!r}\n,,,,,,,,\n,0.9,0.9", "p.bdf"), 6)
    np.testing.assert_allclose(rod, pbar, rtol=1e-12)


def test_coupled_shear_flexible_cbeam_mass_is_euler_bernoulli_cubic(tmp_path):
    """NX: Timoshenko stiffness (Przemieniecki) with the Euler-Bernoulli cubic mass and no
    rotary inertia, planar cantilever of 4 elements solved by hand in numpy."""
    E, G, A, I, rho, L, n = 2.9e7, 1.1e7, 0.1, 0.01, 7.357e-4, 1.0, 4
    phi = 12 * E * I / (G * A * L * L)
    k = E * I / ((1 + phi) * L**3) * np.array([
        [12, 6 * L, -12, 6 * L], [6 * L, (4 + phi) * L * L, -6 * L, (2 - phi) * L * L],
        [-12, -6 * L, 12, -6 * L], [6 * L, (2 - phi) * L * L, -6 * L, (4 + phi) * L * L]])
    m = rho * A * L / 420 * np.array([
        [156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
        [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    K, M = np.zeros((2 * n + 2,) * 2), np.zeros((2 * n + 2,) * 2)
    for e in range(n):
        K[2 * e:2 * e + 4, 2 * e:2 * e + 4] += k
        M[2 * e:2 * e + 4, 2 * e:2 * e + 4] += m
    want = np.sqrt(sl.eigh(K[2:, 2:], M[2:, 2:], eigvals_only=True)) / TWO_PI
    p = deck(tmp_path, f"PARAM,COUPMASS,1\nMAT1,1,{E},{G},,{rho}\nPBEAM,1,1,{A},{I},{I},,{2 * I}\n"
             + beam_grids(n + 1, lambda i: (L * i, 0, 0)) + "".join(
                 f"CBEAM,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(n))
             + "SPC1,1,123456,1\nSPC1,1,1345,2,THRU,5\n")
    np.testing.assert_allclose(freqs(p, 2 * n), want, rtol=1e-10)


def test_rbe2_dependent_components_are_in_the_dependent_grids_cd_system(tmp_path):
    """RBE2 2 -> 3 on component 1 of grid 3, whose CD is turned 30 deg about z: u3' = c u2x
    + s u2y carries the scalar mass m3, so M = m I + m3 [c s]^T [c s] on (u2x, u2y) (hand)."""
    kx, ky, m, m3, a = 1000.0, 3000.0, 2.0, 1.5, math.radians(30.0)
    c, s = math.cos(a), math.sin(a)
    p = deck(tmp_path, f"""CORD2R,5,,0.,0.,0.,0.,0.,1.,
,{c!r},{s!r},0.
GRID,2,,0.,0.,0.
GRID,3,,0.,0.,0.,5
SPC1,1,3456,2
SPC1,1,23456,3
CELAS2,1,{kx},2,1
CELAS2,2,{ky},2,2
CONM2,3,2,,{m}
CMASS2,4,{m3},3,1
RBE2,9,2,1,3
""")
    v = np.array([c, s])
    lam = sl.eigh(np.diag([kx, ky]), m * np.eye(2) + m3 * np.outer(v, v), eigvals_only=True)
    np.testing.assert_allclose(freqs(p, 2), np.sqrt(lam) / TWO_PI, rtol=1e-12)
