"""Entries and analyses that decks from the field use (issue 25), each against an answer that
does not use the entry: a closed form, a small model solved by hand in numpy, or the same
model written without the entry.

The decks are written here; none is copied from the corpus of published decks.
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


def deck(tmp_path: Path, bulk: str, name: str = "deck.bdf", case: str = "", executive: str = "SOL 103\n") -> Path:
    text = (executive + "CEND\n" + case + "BEGIN BULK\n" if case or executive != "SOL 103\n"
            else "BEGIN BULK\n") + bulk.strip() + "\nENDDATA\n"
    p = tmp_path / name
    p.write_text(text)
    return p


def freqs(path: Path, n: int = 6, **kw) -> np.ndarray:
    model, info = read_bdf(path, **kw)
    return solve_modes(model, n_modes=n, autospc=info.autospc).frequencies_hz


def hand(K, M) -> np.ndarray:
    return np.sqrt(np.abs(sl.eigh(K, M, eigvals_only=True))) / TWO_PI


# Three grids on x that move along x only.
LINE = """GRID,1,,0.,0.,0.,,23456
GRID,2,,1.,0.,0.,,23456
GRID,3,,2.,0.,0.,,23456
"""


# ------------------------------------------------------------------ GENEL
def test_genel_flexibility_with_rigid_body_matrix_is_a_spring_chain(tmp_path):
    """UI = x of grids 1, 2; UD = x of grid 3 (the reference). Z = flexibility of the chain
    3 -k1- 1 -k2- 2 with 3 held: [[1/k1, 1/k1], [1/k1, 1/k1 + 1/k2]], S = [1, 1]^T (a rigid
    translation). Free-free with three masses: the stiffness of the two springs (hand)."""
    k1, k2, m = 2000.0, 5000.0, (1.0, 2.0, 3.0)
    z = [1 / k1, 1 / k1, 1 / k1 + 1 / k2]  # Z11, Z21, Z22 (columns of the lower triangle)
    bulk = LINE + "".join(f"CONM2,{10 + i},{i + 1},,{mi}\n" for i, mi in enumerate(m)) + (
        f"GENEL,7,,1,1,2,1,,,\n,UD,,3,1,,,,,\n,Z,{z[0]!r},{z[1]!r},{z[2]!r},,,,\n,S,1.,1.\n")
    K = np.array([[k1 + k2, -k2, -k1], [-k2, k2, 0.0], [-k1, 0.0, k1]])
    want = hand(K, np.diag(m))
    np.testing.assert_allclose(freqs(deck(tmp_path, bulk), 3)[1:], want[1:], rtol=1e-9)
    assert abs(freqs(deck(tmp_path, bulk), 3)[0]) < 1e-6 * want[-1]


def test_genel_stiffness_form_equals_celas2_springs(tmp_path):
    """K given directly (no UD): the same as two CELAS2 springs, grid 1 grounded by k1."""
    k1, k2 = 3000.0, 1000.0
    masses = "CONM2,10,1,,1.\nCONM2,11,2,,2.\nSPC1,1,1,3\n"
    genel = f"GENEL,7,,1,1,2,1\n,K,{k1 + k2!r},{-k2!r},{k2!r}\n"
    springs = f"CELAS2,7,{k1},1,1\nCELAS2,8,{k2},1,1,2,1\n"
    np.testing.assert_allclose(freqs(deck(tmp_path, LINE + masses + genel, "g.bdf"), 2),
                               freqs(deck(tmp_path, LINE + masses + springs, "s.bdf"), 2), rtol=1e-12)


def test_genel_with_a_wrong_number_of_terms_is_named(tmp_path):
    with pytest.raises(ModelError, match=r"GENEL 7: Z needs 3 terms for 2 UI DOFs, got 2"):
        read_bdf(deck(tmp_path, LINE + "GENEL,7,,1,1,2,1\n,Z,1.,2.\n"))


# ------------------------------------------------------------------ CONM1, CMASS2 < 0
def test_conm1_full_mass_matrix_in_a_rotated_system(tmp_path):
    """A grid on six CELAS2 springs carrying a CONM1 6x6 mass given in a system turned 30
    degrees about z: M_basic = T^T M T (hand) with T the rotation of both triples."""
    a = math.radians(30.0)
    c, s = math.cos(a), math.sin(a)
    k = np.array([1e4, 2e4, 3e4, 40.0, 50.0, 60.0])
    M = np.diag([2.0, 2.0, 2.0, 0.01, 0.02, 0.03])
    M[4, 0] = M[0, 4] = 0.05  # a mass offset couples translation and rotation
    lower = [M[i, j] for i in range(6) for j in range(i + 1)]
    fields = ",".join(repr(float(v)) for v in lower)
    f = fields.split(",")
    # five terms on the first line, eight on each continuation (QRG CONM1)
    conm1 = (f"CONM1,1,1,5,{','.join(f[0:5])}\n,{','.join(f[5:13])}\n,{','.join(f[13:21])}\n")
    bulk = (f"CORD2R,5,,0.,0.,0.,0.,0.,1.,\n,{c!r},{s!r},0.\nGRID,1,,0.,0.,0.\n"
            + "".join(f"CELAS2,{i + 1},{float(k[i])!r},1,{i + 1}\n" for i in range(6)) + conm1)
    R = np.array([[c, s, 0], [-s, c, 0], [0, 0, 1.0]])  # rows: the system's axes in basic
    T = np.kron(np.eye(2), R)
    np.testing.assert_allclose(freqs(deck(tmp_path, bulk), 6), hand(np.diag(k), T.T @ M @ T), rtol=1e-10)


def test_negative_coupling_cmass2_is_read_as_nastran_does(tmp_path):
    """CMASS2 between two grids with a negative value: a coupling term of a lumped mass
    matrix (positive definite overall), m12 (u1 - u2)^2 added to the diagonal masses."""
    m1, m2, m12, k1, k2 = 5.0, 3.0, -0.7, 4000.0, 2500.0
    bulk = LINE + (f"CMASS2,1,{m1},1,1\nCMASS2,2,{m2},2,1\nCMASS2,3,{m12},1,1,2,1\n"
                   f"CELAS2,4,{k1},1,1\nCELAS2,5,{k2},1,1,2,1\nSPC1,1,1,3\n")
    M = np.array([[m1 + m12, -m12], [-m12, m2 + m12]])
    K = np.array([[k1 + k2, -k2], [-k2, k2]])
    np.testing.assert_allclose(freqs(deck(tmp_path, bulk), 2), hand(K, M), rtol=1e-12)


# ------------------------------------------------------------------ bars without A or G
def test_pbar_without_area_and_mat1_without_g_are_bending_springs(tmp_path):
    """PBAR A = 0 with I1 = I2 = I and a MAT1 with E alone: a massless bending cantilever,
    3 E I / L^3 under a tip mass in both planes; axial and torsion carry nothing (held)."""
    E, I, L, m = 1e6, 50.0, 100.0, 2.0
    bulk = (f"MAT1,1,{E}\nPBAR,1,1,0.,{I},{I}\nGRID,1,,0.,0.,0.\nGRID,2,,{L / 2},0.,0.\n"
            f"GRID,3,,{L},0.,0.\nCBAR,1,1,1,2,0.,0.,1.\nCBAR,2,1,2,3,0.,0.,1.\nSPC1,1,123456,1\n"
            f"SPC1,1,14,2,3\nCONM2,9,3,,{m}\n")
    want = math.sqrt(3 * E * I / L**3 / m) / TWO_PI
    np.testing.assert_allclose(freqs(deck(tmp_path, bulk), 2), [want, want], rtol=1e-10)


# ------------------------------------------------------------------ CBUSH without orientation
def test_axial_cbush_without_orientation_is_an_axial_spring(tmp_path):
    k, m = 1e5, 10.0
    bulk = (f"GRID,1,,0.,0.,0.,,123456\nGRID,2,,1.,0.,0.,,23456\nCBUSH,1,4,1,2\n"
            f"PBUSH,4,K,{k},0.,0.,0.,0.,0.\nCONM2,5,2,,{m}\n")
    np.testing.assert_allclose(freqs(deck(tmp_path, bulk), 1), [math.sqrt(k / m) / TWO_PI], rtol=1e-12)


def test_cbush_without_orientation_and_unequal_lateral_stiffness_is_refused(tmp_path):
    bulk = "GRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\nCBUSH,1,4,1,2\nPBUSH,4,K,1.,2.,3.,0.,0.,0.\n"
    with pytest.raises(ModelError, match=r"CBUSH 1: no orientation"):
        read_bdf(deck(tmp_path, bulk))


# ------------------------------------------------------------------ AUTOSPC, PARAMs, SPC set
CHAIN = ("GRID,1,,0.,0.,0.,,23\nGRID,2,,1.,0.,0.,,23\nCELAS2,1,1000.,1,1\nCELAS2,2,2000.,1,1,2,1\n"
         "CONM2,3,1,,1.\nCONM2,4,2,,2.\n")


def test_autospc_no_still_drops_dofs_without_stiffness_or_mass(tmp_path):
    """A CELAS2/CONM2 chain leaves the rotations with neither stiffness nor mass: NASTRAN
    runs it with AUTOSPC off; the modes are those of the two-mass chain (hand)."""
    p = deck(tmp_path, CHAIN + "PARAM,AUTOSPC,NO\n")
    model, info = read_bdf(p)
    assert "AUTOSPC,NO" in info.autospc_reason
    want = hand(np.array([[3000.0, -2000.0], [-2000.0, 2000.0]]), np.diag([1.0, 2.0]))
    np.testing.assert_allclose(freqs(p, 2), want, rtol=1e-12)


def test_params_without_effect_are_listed_and_matrix_scale_factors_refused(tmp_path):
    p = deck(tmp_path, CHAIN + "PARAM,SESDAMP,YES\nPARAM,EXTOUT,MATRIXPCH\nPARAM,EQCHECK,0,3,3,,,,-1.E10\n"
             "PARAM,MPTUNIT,4\nPARAM,AUTOSPC,YES\n")
    _model, info = read_bdf(p)
    for name in ("PARAM,SESDAMP", "PARAM,EXTOUT", "PARAM,EQCHECK", "PARAM,MPTUNIT"):
        assert name in info.ignored
    np.testing.assert_allclose(freqs(p, 2), freqs(deck(tmp_path, CHAIN, "plain.bdf"), 2), rtol=1e-14)
    with pytest.raises(ModelError, match=r"PARAM,CK2"):
        read_bdf(deck(tmp_path, CHAIN + "PARAM,CK2,2.0\n", "ck2.bdf"))


def test_undefined_spc_set_is_run_without_it_and_said_loudly(tmp_path):
    """NASTRAN warns and runs without the set: the same as the deck without the request."""
    p = deck(tmp_path, CHAIN + "SPC1,1,1,1\n", case="SPC = 7\n")
    model, info = read_bdf(p)
    assert any("WARNING" in n and "SPC = 7" in n for n in info.notes)
    np.testing.assert_allclose(freqs(p, 2), freqs(deck(tmp_path, CHAIN, "plain.bdf"), 2), rtol=1e-14)


# ------------------------------------------------------------------ executive control
def test_unknown_executive_statements_and_a_repeated_begin_bulk_are_read(tmp_path):
    plain = freqs(deck(tmp_path, CHAIN, "plain.bdf"), 2)
    text = "ID X,NASTRAN\nAPP AERO\nSOL 11,0\nTIME 5\nCEND\nTITLE = T\nBEGIN BULK\nBEGIN BULK\n" + CHAIN + "ENDDATA\n"
    (tmp_path / "aero.dat").write_text(text)
    model, info = read_bdf(tmp_path / "aero.dat")
    assert any("BEGIN BULK repeated" in n for n in info.notes)
    np.testing.assert_allclose(freqs(tmp_path / "aero.dat", 2), plain, rtol=1e-14)


def test_rigid_format_13_string_of_pretensioned_rods_is_the_taut_string(tmp_path):
    """Rigid format 13: massless CRODs pulled by an end FORCE1 T, masses m at the grids: the
    transverse modes are those of a taut string, (T / h) tridiag(-1, 2, -1) with m (hand), on
    soft grounded springs ks (without them the static preload solution is a mechanism, in
    NASTRAN too)."""
    n, h, T, m, ks = 6, 0.5, 800.0, 0.3, 50.0
    grids = "".join(f"GRID,{i + 1},,{h * i},0.,0.,,3456\n" for i in range(n + 1))
    bulk = (grids + "MAT1,1,70.+9,,0.3\nPROD,1,1,1.-4\n"
            + "".join(f"CROD,{i + 1},1,{i + 1},{i + 2}\n" for i in range(n))
            + "".join(f"CONM2,{100 + i},{i + 1},,{m}\nCELAS2,{200 + i},{ks},{i + 1},2\n" for i in range(1, n))
            + f"SPC1,1,12,1\nSPC1,1,2,{n + 1}\nFORCE1,5,{n + 1},{T},1,{n + 1}\nEIGR,9,INV,0.,1.+4,,{n - 1}\n")
    p = deck(tmp_path, bulk, executive="APP DISP\nSOL 13,0\n", case="SPC = 1\nSUBCASE 1\nLOAD = 5\nSUBCASE 2\nMETHOD = 9\n")
    model, info = read_bdf(p)
    assert any("SOL 13" in note for note in info.notes)
    K = T / h * (2 * np.eye(n - 1) - np.eye(n - 1, k=1) - np.eye(n - 1, k=-1)) + ks * np.eye(n - 1)
    want = hand(K, m * np.eye(n - 1))
    f = freqs(p, n - 1)
    np.testing.assert_allclose(f, want, rtol=1e-9)  # the axial modes (EA/h) are far above


def test_rigid_format_13_beam_at_half_its_euler_load(tmp_path):
    """A pinned beam under half its Euler load pi^2 E I / L^2: the first bending mode drops by
    sqrt(1/2) (the same sine shape with and without the preload), to 1e-6 with 20 elements."""
    E, I, A, rho, L, n = 70e9, 2e-9, 1e-4, 2700.0, 1.0, 20
    P = 0.5 * math.pi**2 * E * I / L**2
    grids = "".join(f"GRID,{i + 1},,{L * i / n},0.,0.,,345\n" for i in range(n + 1))
    bulk = (grids + f"MAT1,1,{E},,0.3,{rho}\nPBAR,1,1,{A},{I},{I},{2 * I}\nPARAM,COUPMASS,1\n"
            + "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0.\n" for i in range(n))
            + f"SPC1,1,12,1\nSPC1,1,2,{n + 1}\nFORCE1,5,{n + 1},{P!r},{n + 1},1\nEIGRL,9,,,1\n")
    free = deck(tmp_path, bulk, "free.bdf")
    pre = deck(tmp_path, bulk, "pre.dat", executive="APP DISP\nSOL 13,0\n", case="SPC = 1\nLOAD = 5\nMETHOD = 9\n")
    np.testing.assert_allclose(freqs(pre, 1) / freqs(free, 1), [math.sqrt(0.5)], rtol=1e-6)


def test_msc_statsub_preload_is_refused_naming_it(tmp_path):
    p = deck(tmp_path, CHAIN, case="SUBCASE 1\nLOAD = 5\nSUBCASE 2\nSTATSUB(PRELOAD) = 1\nMETHOD = 1\n")
    with pytest.raises(ModelError, match=r"STATSUB\(PRELOAD\) = 1 asks for the modes of a structure preloaded"):
        read_bdf(p)


def test_rigid_format_13_with_pressure_stiffness_is_refused_naming_it(tmp_path):
    p = deck(tmp_path, CHAIN + "CPSE2,17,2,1,2\n", executive="APP DISP\nSOL 13,0\n", case="LOAD = 1\n")
    with pytest.raises(ModelError, match=r"SOL 13 .*CPSE2 17 adds pressure stiffness"):
        read_bdf(p)


# ------------------------------------------------------------------ fixed-interface modes
FRAME = """MAT1,1,70.+9,,0.3,2700.
PBAR,1,1,1.-4,2.-9,2.-9,4.-9
GRID,1,,0.,0.,0.
GRID,2,,0.3,0.,0.
GRID,3,,0.6,0.,0.
GRID,4,,0.9,0.,0.
CBAR,1,1,1,2,0.,0.,1.
CBAR,2,1,2,3,0.,0.,1.
CBAR,3,1,3,4,0.,0.,1.
CONM2,9,4,,0.2
"""


def test_bset_of_a_component_reduction_holds_the_boundary(tmp_path):
    """BSET1 with QSET1 on scalar points and EXTSEOUT: NASTRAN prints the fixed-interface
    modes: the same frame with the boundary grid held by SPC1. An MPC term on a Q-set
    scalar point (held with the boundary) leaves its grid component held."""
    red = deck(tmp_path, FRAME + "SPOINT,101,THRU,104\nQSET1,0,101,THRU,104\nBSET1,123456,1\n"
               "MPC,5,4,4,1.0,101,0,1.0\n", "red.bdf", case="EXTSEOUT(ASMBULK,EXTID=100)\nMPC = 5\n")
    held = deck(tmp_path, FRAME + "SPC1,1,123456,1\nSPC1,1,4,4\n", "held.bdf")
    np.testing.assert_allclose(freqs(red, 6), freqs(held, 6), rtol=1e-12)


def test_bset_without_a_reduction_is_refused_naming_it(tmp_path):
    with pytest.raises(ModelError, match=r"BSET1 \(grid 1\): a boundary set without QSET or EXTSEOUT"):
        read_bdf(deck(tmp_path, FRAME + "BSET1,123456,1\n"))


def test_mystran_sol_31_holds_its_suport_boundary(tmp_path):
    """MYSTRAN SOL 31 (Craig-Bampton): SUPORT names the boundary, held in the printed modes."""
    cb = deck(tmp_path, FRAME + "SUPORT,1,123456\n", "cb.dat", executive="SOL 31\n", case="TITLE = CB\n")
    held = deck(tmp_path, FRAME + "SPC1,1,123456,1\n", "held.bdf")
    _model, info = read_bdf(cb)
    assert any("SOL 31" in n for n in info.notes)
    np.testing.assert_allclose(freqs(cb, 6), freqs(held, 6), rtol=1e-12)


# ------------------------------------------------------------------ build conventions
ROD = "".join(f"GRID,{i + 1},,{0.02 * i},0.,0.\n" for i in range(4)) + "".join(
    f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(3)) + "SPC1,1,123456,1\nMAT1,1,70.+9,,0.33,2700.\n"


@pytest.mark.parametrize("conventions,factor", [("nx", 0.9), ("msc", 6.0 / 7.0)])
def test_pbarl_rod_shear_factor_follows_the_conventions(tmp_path, conventions, factor):
    r = 0.01
    A, I, J = math.pi * r**2, math.pi * r**4 / 4, math.pi * r**4 / 2
    rod_deck = deck(tmp_path, ROD + f"PBARL,1,1,,ROD\n,{r}", "l.bdf")
    rod = freqs(rod_deck, 6, conventions=conventions)
    pbar = freqs(deck(tmp_path, ROD + f"PBAR,1,1,{A!r},{I!r},{I!r},{J!r}\n,,,,,,,,\n,{factor!r},{factor!r}",
                      "p.bdf"), 6)
    np.testing.assert_allclose(rod, pbar, rtol=1e-12)
    assert read_bdf(rod_deck, conventions=conventions)[1].conventions == conventions


def test_unknown_conventions_are_refused(tmp_path):
    with pytest.raises(ModelError, match="conventions must be one of nx, msc"):
        read_bdf(deck(tmp_path, ROD + "PBARL,1,1,,ROD\n,0.01"), conventions="abaqus")


def test_pbarl_bar_uses_shear_factor_five_sixths(tmp_path):
    """PBARL BAR DIM1 (along z) x DIM2 (along y) = PBAR with its A, I1, I2, the torsion
    constant of the rectangle and K1 = K2 = 5/6 (MSC 2012.2's conversion)."""
    from trussid.fem.sections import Section

    h, b = 0.01, 0.02
    s = Section.rectangle(b=b, h=h, nu=0.33)
    bar = freqs(deck(tmp_path, ROD + f"PBARL,1,1,,BAR\n,{h},{b}", "l.bdf"), 6)
    pbar = freqs(deck(tmp_path, ROD + f"PBAR,1,1,{s.A!r},{s.Iz!r},{s.Iy!r},{s.J!r}\n,,,,,,,,\n,{5 / 6!r},{5 / 6!r}",
                      "p.bdf"), 6)
    np.testing.assert_allclose(bar, pbar, rtol=1e-12)


def test_coupled_shear_flexible_cbar_mass_is_euler_bernoulli_cubic(tmp_path):
    """MSC: a shear-flexible CBAR's coupled mass is the Euler-Bernoulli cubic one without
    rotary inertia, on the Timoshenko stiffness: planar cantilever of 4 elements by hand."""
    E, G, A, I, rho, L, n, K1 = 2.9e7, 1.1e7, 0.1, 0.01, 7.357e-4, 1.0, 4, 0.8
    phi = 12 * E * I / (G * K1 * A * L * L)
    k = E * I / ((1 + phi) * L**3) * np.array([
        [12, 6 * L, -12, 6 * L], [6 * L, (4 + phi) * L * L, -6 * L, (2 - phi) * L * L],
        [-12, -6 * L, 12, -6 * L], [6 * L, (2 - phi) * L * L, -6 * L, (4 + phi) * L * L]])
    m = rho * A * L / 420 * np.array([
        [156, 22 * L, 54, -13 * L], [22 * L, 4 * L * L, 13 * L, -3 * L * L],
        [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L * L, -22 * L, 4 * L * L]])
    Kg, Mg = np.zeros((2 * n + 2,) * 2), np.zeros((2 * n + 2,) * 2)
    for e in range(n):
        Kg[2 * e:2 * e + 4, 2 * e:2 * e + 4] += k
        Mg[2 * e:2 * e + 4, 2 * e:2 * e + 4] += m
    want = hand(Kg[2:, 2:], Mg[2:, 2:])
    p = deck(tmp_path, f"PARAM,COUPMASS,1\nMAT1,1,{E},{G},,{rho}\nPBAR,1,1,{A},{I},{I},{2 * I}\n,,,,,,,,\n,{K1},{K1}\n"
             + "".join(f"GRID,{i + 1},,{L * i},0.,0.\n" for i in range(n + 1)) + "".join(
                 f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.\n" for i in range(n))
             + "SPC1,1,123456,1\nSPC1,1,1345,2,THRU,5\n")
    np.testing.assert_allclose(freqs(p, 2 * n), want, rtol=1e-10)


# ------------------------------------------------------------------ GRDSET CP / CD
def test_grdset_cp_and_cd_apply_to_blank_fields_only(tmp_path):
    """GRDSET CP = CD = 5: GRIDs with those fields blank are in system 5, a GRID with an
    explicit 0 stays in basic: the same as the deck with every field spelled out."""
    cord = "CORD2R,5,,0.1,0.2,0.,0.,0.,1.,\n,0.8,0.6,0.\n"
    tail = ("MAT1,1,70.+9,,0.3,2700.\nPBAR,1,1,1.-4,2.-9,3.-9,4.-9\nCBAR,1,1,1,2,0.,0.,1.\n"
            "CBAR,2,1,2,3,0.,0.,1.\nSPC1,1,123456,1\nCONM2,9,3,,0.5\n")
    grdset = (cord + "GRDSET,,5,,,,5\nGRID,1,,0.,0.,0.\nGRID,2,,0.3,0.,0.\nGRID,3,0,0.7,0.1,0.,0\n" + tail)
    spelled = (cord + "GRID,1,5,0.,0.,0.,5\nGRID,2,5,0.3,0.,0.,5\nGRID,3,0,0.7,0.1,0.,0\n" + tail)
    a, b = deck(tmp_path, grdset, "a.bdf"), deck(tmp_path, spelled, "b.bdf")
    np.testing.assert_allclose(read_bdf(a)[0].xyz, read_bdf(b)[0].xyz, rtol=1e-14)
    np.testing.assert_allclose(freqs(a, 6), freqs(b, 6), rtol=1e-12)
    basic = deck(tmp_path, spelled.replace("GRID,1,5,0.,0.,0.,5", "GRID,1,0,0.,0.,0.,0"), "c.bdf")
    assert not np.allclose(read_bdf(basic)[0].xyz, read_bdf(b)[0].xyz)


# ------------------------------------------------------------------ scalar points
def test_scalar_point_elements_are_a_spring_mass_chain(tmp_path):
    """CELAS3/CELAS4 and CMASS3/CMASS4 on SPOINTs (two elements on one CELAS4 entry, as
    NASTRAN allows), a CELAS2 and CMASS2 to a scalar point by component 0, an SPC1 on one:
    ground -k1- s1 -k2- s2 -k3- s3 (held), masses m1, m2 and a coupling mass (hand)."""
    k1, k2, k3, m1, m2, m12 = 1000.0, 2500.0, 400.0, 2.0, 3.0, 0.4
    bulk = (f"SPOINT,11,THRU,13\nPELAS,7,{k1}\nPMASS,8,{m1}\nCELAS3,1,7,11\n"
            f"CELAS4,2,{k2},11,12,3,{k3},12,13\nCMASS3,4,8,11\nCMASS4,5,{m2},12\n"
            f"CMASS2,6,{m12},11,0,12,0\nCELAS2,9,0.,11,0\nSPC1,1,0,13\n")
    K = np.array([[k1 + k2, -k2], [-k2, k2 + k3]])
    M = np.array([[m1 + m12, -m12], [-m12, m2 + m12]])
    np.testing.assert_allclose(freqs(deck(tmp_path, bulk), 2), hand(K, M), rtol=1e-12)


def test_mpc_on_a_scalar_point_ties_it_to_a_grid(tmp_path):
    """MPC u_s = 2 u_x(grid 1): a scalar spring ks on s acts on grid 1 as 4 ks (hand)."""
    k, ks, m = 1000.0, 300.0, 2.0
    bulk = (f"GRID,1,,0.,0.,0.,,23456\nSPOINT,20\nCELAS2,1,{k},1,1\nCONM2,2,1,,{m}\nCELAS4,3,{ks},20\n"
            f"MPC,7,20,0,1.,1,1,-2.\n")
    p = deck(tmp_path, bulk, case="MPC = 7\n")
    np.testing.assert_allclose(freqs(p, 1), [math.sqrt((k + 4 * ks) / m) / TWO_PI], rtol=1e-12)


def test_component_0_on_a_grid_is_named(tmp_path):
    with pytest.raises(ModelError, match=r"CELAS2 1: component 0 is a scalar point's, but 1 is no SPOINT"):
        read_bdf(deck(tmp_path, "GRID,1,,0.,0.,0.\nCELAS2,1,10.,1,0\n"))


# ------------------------------------------------------------------ DMIG through K2GG / M2GG
DMIG = """GRID,1,,0.,0.,0.,,3456
DMIG,KX,0,6,1
DMIG,KX,1,1,,1,1,100.,
,1,2,-5.
DMIG,KX,1,2,,1,2,80.
DMIG,MX,0,6,1
DMIG,MX,1,1,,1,1,2.
DMIG,MX,1,2,,1,2,3.
DMIG,UNUSED,0,6,1
DMIG,UNUSED,1,1,,1,1,1.+9
TF,3,1,1,1.
"""


def test_dmig_selected_by_k2gg_and_m2gg_is_the_hand_model(tmp_path):
    """K2GG (symmetric, lower triangle by columns) and M2GG scaled by the case control's
    factor; an unselected DMIG, a K2PP request and a TF change nothing (hand)."""
    p = deck(tmp_path, DMIG, case="K2GG = 2.0*KX\nM2GG = MX\nK2PP = PP\n")
    model, info = read_bdf(p)
    assert "TF (1)" in info.ignored
    assert any(n.startswith("DMIG UNUSED: not selected") for n in info.notes)
    K = 2.0 * np.array([[100.0, -5.0], [-5.0, 80.0]])
    np.testing.assert_allclose(freqs(p, 2), hand(K, np.diag([2.0, 3.0])), rtol=1e-12)


def test_dmig_not_selected_has_no_effect_and_a_missing_one_is_named(tmp_path):
    base = "GRID,1,,0.,0.,0.,,23456\nCELAS2,1,100.,1,1\nCONM2,2,1,,2.\n"
    np.testing.assert_allclose(freqs(deck(tmp_path, base + DMIG.split("\n", 1)[1], "a.bdf"), 1),
                               freqs(deck(tmp_path, base, "b.bdf"), 1), rtol=1e-14)
    with pytest.raises(ModelError, match="K2GG = NOPE: no DMIG NOPE is defined"):
        read_bdf(deck(tmp_path, base, "c.bdf", case="K2GG = NOPE\n"))


def test_square_dmig_must_be_symmetric(tmp_path):
    bulk = "GRID,1,,0.,0.,0.,,3456\nDMIG,KS,0,1,1\nDMIG,KS,1,1,,1,1,100.,\n,1,2,-5.\nDMIG,KS,1,2,,1,2,80.\n"
    with pytest.raises(ModelError, match="DMIG KS: a square .* must be symmetric"):
        read_bdf(deck(tmp_path, bulk, case="K2GG = KS\n"))


# ------------------------------------------------------------------ BAROR / BEAMOR
@pytest.mark.parametrize("where", ["before", "after"])
def test_baror_orientation_applies_wherever_it_stands(tmp_path, where):
    """BAROR X = (0, 1, 0) for CBARs without orientation, before or after them in the deck:
    the same beam as with the vector on every CBAR."""
    common = ("MAT1,1,70.+9,,0.3,2700.\nPBAR,1,1,1.-4,2.-9,5.-9,4.-9\nSPC1,1,123456,1\n"
              + "".join(f"GRID,{i + 1},,{0.2 * i},0.,0.\n" for i in range(5)))
    bare = "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2}\n" for i in range(4))
    spelled = "".join(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,1.,0.\n" for i in range(4))
    baror = "BAROR,,,,,0.,1.,0.\n"
    body = baror + bare if where == "before" else bare + baror
    a = deck(tmp_path, common + body, "a.bdf", case="TITLE = T\n")
    np.testing.assert_allclose(freqs(a, 6), freqs(deck(tmp_path, common + spelled, "b.bdf"), 6), rtol=1e-12)
