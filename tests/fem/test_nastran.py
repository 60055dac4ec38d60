"""NASTRAN bulk data: cards map onto the model as NASTRAN defines them, and write -> read is
the identity.

Reference results are independent of the reader: Euler-Bernoulli closed forms, hand-computed
spring-mass frequencies, the QRG's CONM2 inertia form checked through a rotated spring, and
pyNastran's own PBARL section properties.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from trussid.fem import Model, ModelError, Section
from trussid.fem.materials import Material
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf, write_bdf

FRAME = Path(__file__).resolve().parents[2] / "examples" / "decks" / "frame.bdf"
BETA_L = (1.8751040687119611, 4.694091132974174)  # cantilever eigenvalues beta_n L


def real(x: float) -> str:
    """A free-field real that pyNastran reads back exactly."""
    s = repr(float(x))
    return s if ("." in s or "e" in s) else s + "."


def write(tmp_path: Path, text: str, name: str = "deck.bdf") -> Path:
    p = tmp_path / name
    p.write_text(text)
    return p


def freqs(model, info=None, n=10):
    return solve_modes(model, n_modes=n, autospc=True if info is None else info.autospc).frequencies_hz


def cantilever_deck(n_el=20, L=1.0, E=68.9e9, rho=2700.0, A=1e-4, I1=2e-9, I2=2e-9, J=4e-9,
                    coupmass="1", wtmass=None, extra="") -> str:
    """Cantilever along x, clamped at grid 1, PBAR (no shear flexibility), v = global z."""
    lines = ["BEGIN BULK"]
    if coupmass is not None:
        lines.append(f"PARAM,COUPMASS,{coupmass}")
    if wtmass is not None:
        lines.append(f"PARAM,WTMASS,{wtmass}")
    lines.append(f"MAT1,1,{real(E)},,0.33,{real(rho)}")
    lines.append(f"PBAR,1,1,{real(A)},{real(I1)},{real(I2)},{real(J)}")
    for i in range(n_el + 1):
        lines.append(f"GRID,{i + 1},,{real(L * i / n_el)},0.,0.")
    for i in range(n_el):
        lines.append(f"CBAR,{i + 1},1,{i + 1},{i + 2},0.,0.,1.")
    lines.append("SPC1,1,123456,1")
    lines.append(extra)
    lines.append("ENDDATA")
    return "\n".join(lines) + "\n"


def eb_cantilever(n, E, I, rho, A, L):
    return BETA_L[n] ** 2 / (2 * math.pi * L**2) * math.sqrt(E * I / (rho * A))


def tip_direction(modes, k):
    """"y" or "z": which transverse tip displacement dominates mode k."""
    u = modes.shapes_full[:, k].reshape(-1, 6)[-1]
    return "y" if abs(u[1]) > abs(u[2]) else "z"


# ----------------------------------------------------------------- independent references
def test_cantilever_tube_deck_matches_euler_bernoulli_closed_form(tmp_path):
    r, t = 0.00635, 0.001
    ri = r - t
    A = math.pi * (r**2 - ri**2)
    I = math.pi * (r**4 - ri**4) / 4
    model, info = read_bdf(write(tmp_path, cantilever_deck(A=A, I1=I, I2=I, J=2 * I)))
    assert info.mass == "consistent" and info.beam_theory == "euler-bernoulli"
    f = freqs(model, info, n=4)
    f1 = eb_cantilever(0, 68.9e9, I, 2700.0, A, 1.0)
    f2 = eb_cantilever(1, 68.9e9, I, 2700.0, A, 1.0)
    # Both bending planes. Cubic elements with consistent mass converge as h^4: with 20
    # elements that leaves ~1e-7 on mode 1 and ~2e-6 on mode 2 (beta h = 0.23).
    np.testing.assert_allclose(f[:2], [f1, f1], rtol=1e-6)
    np.testing.assert_allclose(f[2:], [f2, f2], rtol=1e-5)


def test_pbar_i1_is_bending_in_the_plane_of_the_orientation_vector(tmp_path):
    # v = global z: plane 1 (element x-y) is the global x-z plane, so I1 governs the
    # vertical (z) bending and I2 the horizontal (y) one.
    A, I1, I2 = 1e-4, 8e-9, 2e-9
    model, info = read_bdf(write(tmp_path, cantilever_deck(A=A, I1=I1, I2=I2, J=5e-9)))
    modes = solve_modes(model, n_modes=2)
    got = {tip_direction(modes, k): modes.frequencies_hz[k] for k in range(2)}
    assert got["z"] == pytest.approx(eb_cantilever(0, 68.9e9, I1, 2700.0, A, 1.0), rel=1e-6)
    assert got["y"] == pytest.approx(eb_cantilever(0, 68.9e9, I2, 2700.0, A, 1.0), rel=1e-6)


def test_conm2_on_celas2_gives_the_spring_mass_frequencies(tmp_path):
    m, k, Ixx, kt = 3.0, 1200.0, 0.2, 50.0
    deck = f"""BEGIN BULK
GRID,1,,0.,0.,0.
CONM2,10,1,,{real(m)},,,,
,{real(Ixx)},,1.,,,1.
CELAS2,20,{real(k)},1,1
CELAS2,21,{real(kt)},1,4
SPC1,1,2356,1
ENDDATA
"""
    model, info = read_bdf(write(tmp_path, deck))
    f = freqs(model, info, n=2)
    np.testing.assert_allclose(f, np.sort([math.sqrt(k / m), math.sqrt(kt / Ixx)]) / (2 * np.pi),
                               rtol=1e-12)


def test_celas1_between_two_grids_couples_equal_components(tmp_path):
    m1, m2, k0, k12 = 2.0, 5.0, 300.0, 700.0
    deck = f"""BEGIN BULK
GRID,1,,0.,0.,0.,,23456
GRID,2,,1.,0.,0.,,23456
CONM2,1,1,,{real(m1)}
CONM2,2,2,,{real(m2)}
PELAS,7,{real(k12)}
CELAS1,3,7,1,1,2,1
CELAS2,4,{real(k0)},1,1
ENDDATA
"""
    model, info = read_bdf(write(tmp_path, deck))
    K = np.array([[k0 + k12, -k12], [-k12, k12]])
    M = np.diag([m1, m2])
    ref = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, K)).real)) / (2 * np.pi)
    np.testing.assert_allclose(freqs(model, info, n=2), ref, rtol=1e-12)


def test_conm2_products_of_inertia_take_nastrans_minus_sign(tmp_path):
    # The QRG: tensor = [[I11, -I21, ...], ...]. A body with I21 > 0 has its smallest inertia
    # about the (1, 1, 0) diagonal: I - p. A grounded CBUSH whose CID is rotated 45 deg
    # about z puts stiffness ka about that diagonal and kb about (-1, 1, 0).
    I, p, I33, ka, kb, kc = 2.0, 0.5, 3.0, 100.0, 400.0, 900.0
    s = math.sqrt(0.5)
    deck = f"""BEGIN BULK
GRID,1,,0.,0.,0.,,123
CORD2R,5,,0.,0.,0.,0.,0.,1.,
,{real(s)},{real(s)},0.
CONM2,10,1,,1.,,,,
,{real(I)},{real(p)},{real(I)},0.,0.,{real(I33)}
PBUSH,2,K,0.,0.,0.,{real(ka)},{real(kb)},{real(kc)}
CBUSH,3,2,1,,,,,5
ENDDATA
"""
    model, info = read_bdf(write(tmp_path, deck))
    np.testing.assert_allclose(model.point_masses.inertia[0][0, 1], -p)
    ref = np.sqrt(sorted([ka / (I - p), kb / (I + p), kc / I33])) / (2 * np.pi)
    np.testing.assert_allclose(freqs(model, info, n=3), ref, rtol=1e-10)


def test_rbe2_slave_mass_moves_with_the_master(tmp_path):
    m, k = 4.0, 1000.0
    deck = f"""BEGIN BULK
GRID,1,,0.,0.,0.,,23456
GRID,2,,0.,1.,0.
RBE2,5,1,123456,2
CONM2,6,2,,{real(m)}
CELAS2,7,{real(k)},1,1
ENDDATA
"""
    model, info = read_bdf(write(tmp_path, deck))
    rb = model.rigid_bodies[0]
    assert (rb.master, rb.slaves.tolist(), rb.dofs.all(), rb.mass) == (1, [2], True, 0.0)
    np.testing.assert_allclose(freqs(model, info, n=1), [math.sqrt(k / m) / (2 * np.pi)], rtol=1e-12)


def test_pbarl_sections_match_pyNastrans_own_section_properties(tmp_path):
    # pyNastran is an independent oracle here only; 1.4 fails at import on numpy >= 2.4
    try:
        from pyNastran.bdf.bdf import BDF
    except Exception as exc:  # ImportError, or AttributeError (np.in1d) on numpy >= 2.4
        pytest.skip(f"pyNastran is not importable here ({type(exc).__name__})")

    deck = """BEGIN BULK
MAT1,1,70.+9,,0.3,2700.
PBARL,1,1,,ROD
,0.01
PBARL,2,1,,TUBE
,0.01,0.008
PBARL,3,1,,BAR
,0.03,0.01
PBARL,4,1,,BOX
,0.04,0.02,0.002,0.002
PBEAML,5,1,,BAR
,0.03,0.01
""" + "".join(f"GRID,{2 * i + 1},,0.,0.,{real(i)}\nGRID,{2 * i + 2},,1.,0.,{real(i)}\n"
               f"{'CBEAM' if i == 4 else 'CBAR'},{i + 1},{i + 1},{2 * i + 1},{2 * i + 2},0.,1.,0.\n"
               for i in range(5)) + "ENDDATA\n"
    path = write(tmp_path, deck)
    model, _ = read_bdf(path)
    ref = BDF(debug=None)
    ref.read_bdf(str(write(tmp_path, deck.replace("BEGIN BULK\n", ""), "punch.bdf")), punch=True)
    b = model.beams
    for i, pid in enumerate(range(1, 6)):
        prop = ref.properties[pid]
        assert b.A[i] == pytest.approx(prop.Area(), rel=1e-12)
        i1, i2 = (prop.I11(), prop.I22()) if prop.type == "PBEAML" else (prop.I1(), prop.I2())
        assert b.Iz[i] == pytest.approx(i1, rel=1e-12)  # I1: plane 1, about element z
        assert b.Iy[i] == pytest.approx(i2, rel=1e-12)


def test_grid_in_a_cylindrical_system_is_placed_in_basic_coordinates(tmp_path):
    deck = """BEGIN BULK
CORD2C,7,,1.,2.,3.,1.,2.,4.,
,2.,2.,3.
GRID,5,7,2.,30.,0.5
GRID,6,,1.,1.,1.
ENDDATA
"""
    model, _ = read_bdf(write(tmp_path, deck))
    xyz = dict(zip(model.node_ids.tolist(), model.xyz))
    th = math.radians(30)
    np.testing.assert_allclose(xyz[5], [1 + 2 * math.cos(th), 2 + 2 * math.sin(th), 3.5], atol=1e-12)
    np.testing.assert_allclose(xyz[6], [1, 1, 1])


def test_conm2_offsets_in_basic_absolute_and_rotated_systems(tmp_path):
    deck = """BEGIN BULK
GRID,1,,1.,1.,1.
CORD2R,3,,0.,0.,0.,0.,0.,1.,
,0.,1.,0.
CONM2,1,1,,2.,0.1,0.2,0.3
CONM2,2,1,-1,2.,1.5,1.,1.
CONM2,3,1,3,2.,1.,0.,0.,
,1.,,2.,,,3.
ENDDATA
"""
    model, _ = read_bdf(write(tmp_path, deck))
    pm = model.point_masses
    np.testing.assert_allclose(pm.offset[0], [0.1, 0.2, 0.3])
    np.testing.assert_allclose(pm.offset[1], [0.5, 0.0, 0.0])
    # CID 3: x3 along basic y, z along basic z -> its x axis along basic y.
    np.testing.assert_allclose(pm.offset[2], [0.0, 1.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(np.diag(pm.inertia[2]), [2.0, 1.0, 3.0], atol=1e-15)


def test_mat1_blank_field_follows_nastrans_rule(tmp_path):
    deck = """BEGIN BULK
MAT1,1,200.+9,,0.25,7800.
MAT1,2,,80.+9,0.25,7800.
MAT1,3,200.+9,70.+9,,7800.
PBAR,1,1,1.-4,1.-9,1.-9,2.-9
PBAR,2,2,1.-4,1.-9,1.-9,2.-9
PBAR,3,3,1.-4,1.-9,1.-9,2.-9
GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
CBAR,1,1,1,2,0.,0.,1.
CBAR,2,2,1,2,0.,0.,1.
CBAR,3,3,1,2,0.,0.,1.
ENDDATA
"""
    model, _ = read_bdf(write(tmp_path, deck))
    b = model.beams
    np.testing.assert_allclose(b.E, [200e9, 2 * 1.25 * 80e9, 200e9])
    np.testing.assert_allclose(b.G, [200e9 / 2.5, 80e9, 70e9])


def test_spc_set_selected_by_case_control_else_all_sets(tmp_path):
    body = """GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
SPC1,1,123,1
SPC,2,2,456,0.
SPCADD,3,2
ENDDATA
"""
    model, info = read_bdf(write(tmp_path, "SOL 103\nCEND\nSUBCASE 1\n  SPC = 3\nBEGIN BULK\n" + body))
    assert info.spc_sets == [2, 3]
    np.testing.assert_array_equal(model.fixed_mask(), [[0] * 6, [0, 0, 0, 1, 1, 1]])
    model, info = read_bdf(write(tmp_path, "BEGIN BULK\n" + body, "all.bdf"))
    np.testing.assert_array_equal(model.fixed_mask(), [[1, 1, 1, 0, 0, 0], [0, 0, 0, 1, 1, 1]])


def test_eigrl_request_is_reported(tmp_path):
    model, info = read_bdf(FRAME)
    assert (info.eigen.card, info.eigen.n_modes) == ("EIGRL", 10)


# ----------------------------------------------------------------- WTMASS and COUPMASS
def test_wtmass_scales_frequencies_by_inverse_square_root(tmp_path):
    # The example frame has densities and a CONM2 with inertia: all must be scaled.
    text = FRAME.read_text()
    scaled = text.replace("PARAM,COUPMASS,1", "PARAM,COUPMASS,1\nPARAM,WTMASS,0.00259")
    m0, i0 = read_bdf(FRAME)
    m1, i1 = read_bdf(write(tmp_path, scaled))
    assert (i0.wtmass, i1.wtmass) == (1.0, 0.00259)
    f0, f1 = freqs(m0, i0), freqs(m1, i1)
    np.testing.assert_allclose(f1, f0 / math.sqrt(0.00259), rtol=1e-10)


def test_coupmass_selects_consistent_mass_and_lumped_is_the_default(tmp_path):
    r = {}
    for key, value in (("absent", None), ("on", "1"), ("off", "-1")):
        model, info = read_bdf(write(tmp_path, cantilever_deck(coupmass=value), f"{key}.bdf"))
        assert model.mass_formulation == info.mass
        r[key] = (info, freqs(model, info, n=1)[0])
    assert r["absent"][0].mass == "lumped" and "default" in r["absent"][0].mass_reason
    assert r["on"][0].mass == "consistent" and "COUPMASS,1" in r["on"][0].mass_reason
    assert r["off"][0].mass == "lumped" and "COUPMASS,-1" in r["off"][0].mass_reason
    exact = eb_cantilever(0, 68.9e9, 2e-9, 2700.0, 1e-4, 1.0)
    # Consistent mass converges as h^4, lumped (no rotary inertia) only as h^2.
    err_c = abs(r["on"][1] / exact - 1)
    err_l = abs(r["off"][1] / exact - 1)
    assert err_c < 1e-6 < err_l < 1e-2
    assert r["absent"][1] == r["off"][1]


# ----------------------------------------------------------------- write -> read
def _frame_model(theory="euler-bernoulli", mass="consistent", nastran_bars=False) -> Model:
    """A 3-D frame with every kind of item the writer handles.

    ``nastran_bars``: the bars as NASTRAN's coupled CBAR mass has them, without torsional
    or rotary inertia: their structural mass given as non-structural mass per length.
    """
    m = Model(beam_theory=theory, mass=mass, name="roundtrip")
    al = Material.isotropic(68.9e9, 0.33, 2700.0, "al")
    st = Material.isotropic(200e9, 0.29, 7850.0, "steel")
    pts = {1: (0, 0, 0), 2: (0.4, 0, 0), 3: (0.4, 0.3, 0), 4: (0, 0.3, 0),
           5: (0, 0, 0.5), 6: (0.4, 0, 0.5), 7: (0.4, 0.3, 0.5), 8: (0, 0.3, 0.5),
           9: (0.2, 0.15, 0.6), 10: (0.2, 0.15, 0.6)}
    m.add_nodes(list(pts), list(pts.values()))
    tube = Section.tube(0.01, 0.0015, name="tube")
    rect = Section.rectangle(0.02, 0.008, name="rect")
    def bar_mass(sec, mat, nsm=0.0):
        if not nastran_bars:
            return mat, nsm
        return {"E": mat.E, "G": mat.G, "rho": 0.0}, nsm + mat.rho * sec.A

    m.add_beams([1, 2, 3, 4], [[1, 5], [2, 6], [3, 7], [4, 8]], tube, bar_mass(tube, al)[0],
                orient=[1, 0.2, 0], nsm=bar_mass(tube, al)[1])
    m.add_beams([5, 6, 7, 8], [[5, 6], [6, 7], [7, 8], [8, 5]], rect, bar_mass(rect, st)[0],
                orient=[0.1, 0.3, 1], nsm=bar_mass(rect, st, 0.05)[1])
    m.add_beams([9], [[5, 7]], Section.general(2e-5, 1, 1, 1e-10), al, orient=[0, 0, 1], rod=True)
    # inclined bars: their torsion axis is no single DOF (NASTRAN's coupled CBAR has none)
    m.add_beams([11, 12], [[6, 8], [2, 7]], tube, bar_mass(tube, al)[0], orient=[0, 0, 1],
                nsm=bar_mass(tube, al)[1])
    m.add_point_masses([6, 9], [0.3, 1.5],
                       inertia=[np.diag([1e-4, 2e-4, 3e-4]),
                                [[0.02, 0.003, -0.001], [0.003, 0.03, 0.002], [-0.001, 0.002, 0.04]]],
                       offset=[[0, 0, 0.01], [0.01, -0.02, 0.03]])
    m.add_rigid_body(50, 9, [7, 8], mass=0.8, cg=[0.15, 0.2, 0.62],
                     inertia=[[0.01, -0.001, 0], [-0.001, 0.012, 0.0005], [0, 0.0005, 0.015]])
    c, s = math.cos(0.3), math.sin(0.3)
    m.add_springs([60], [[10, 9]], [1e5, 2e5, 3e5, 50, 60, 70],
                  frame=[[c, s, 0], [-s, c, 0], [0, 0, 1]])
    m.add_springs([61, 62], [[10, -1], [5, 6]], [[1e4, 1e4, 2e4, 0, 0, 0], [0, 3e3, 0, 0, 0, 0]])
    m.add_point_masses([10], [0.2])
    m.fix([1, 2, 3, 4], "123456")
    m.fix([10], "456")
    return m


def _add_nastran_rod_mass(model: Model) -> None:
    """Add (NASTRAN's coupled CROD mass - the textbook rod mass) to ``model``'s rods: NASTRAN
    axial m [5/12 1/12; 1/12 5/12] and lumped transverse m/2, against linear interpolation
    m/6 [2 1; 1 2] in every direction."""
    b = model.beams
    xyz = dict(zip(model.node_ids.tolist(), model.xyz))
    for i in np.flatnonzero(b.rod):
        d = xyz[int(b.nodes[i, 1])] - xyz[int(b.nodes[i, 0])]
        L = np.linalg.norm(d)
        ee = np.outer(d, d) / L**2
        m = (b.rho[i] * b.A[i] + b.nsm[i]) * L
        nastran = np.kron(m * np.array([[5 / 12, 1 / 12], [1 / 12, 5 / 12]]), ee) + np.kron(m / 2 * np.eye(2), np.eye(3) - ee)
        textbook = np.kron(m / 6 * np.array([[2.0, 1.0], [1.0, 2.0]]), np.eye(3))
        M = np.zeros((12, 12))
        t = [0, 1, 2, 6, 7, 8]
        M[np.ix_(t, t)] = nastran - textbook
        model.add_matrices([1000 + i], [b.nodes[i]], M=[M])


def _add_nastran_shear_bar_mass(model: Model) -> None:
    """Add (Euler-Bernoulli cubic mass - Timoshenko-consistent mass) to ``model``'s bars: a
    shear-flexible CBAR's coupled mass in NASTRAN is the cubic one (no shear terms)."""
    from trussid.fem.elements import frame_matrices, local_axes

    b = model.beams
    bar = ~np.asarray(b.rod, bool)
    xyz = dict(zip(model.node_ids.tolist(), model.xyz))
    xa = np.array([xyz[int(n)] for n in b.nodes[bar, 0]])
    xb = np.array([xyz[int(n)] for n in b.nodes[bar, 1]])
    L, R = local_axes(xa, xb, b.orient[bar], b.ids[bar])
    args = (L, b.A[bar], b.Iy[bar], b.Iz[bar], b.J[bar], b.E[bar], b.G[bar], b.rho[bar])
    kw = dict(nsm=b.nsm[bar], Asy=b.Asy[bar], Asz=b.Asz[bar], R=R, mass="consistent")
    dM = (frame_matrices(*args, **kw, theory="euler-bernoulli")[1]
          - frame_matrices(*args, **kw, theory="timoshenko")[1])
    model.add_matrices(2000 + np.flatnonzero(bar), b.nodes[bar], M=0.5 * (dM + dM.transpose(0, 2, 1)))


def test_pin_flags_equal_a_hinge_built_from_a_duplicate_grid(tmp_path):
    """CBAR PA=456 (rotations released at end A) is the same beam starting at its own grid
    that follows grid 4 in translation only (RBE2 123): the model without the entry. The
    beam is clamped at both ends so that the hinge is not a mechanism."""
    base = cantilever_deck(n_el=6, coupmass="-1", extra="SPC1,1,123456,7")
    pinned = base.replace("CBAR,4,1,4,5,0.,0.,1.", "CBAR,4,1,4,5,0.,0.,1.,,\n,456")
    hinge = base.replace("CBAR,4,1,4,5,0.,0.,1.", "GRID,44,,0.5,0.,0.\nCBAR,4,1,44,5,0.,0.,1.\nRBE2,90,4,123,44")
    f_pin = freqs(*read_bdf(write(tmp_path, pinned, "pin.bdf")), n=8)
    f_hinge = freqs(*read_bdf(write(tmp_path, hinge, "hinge.bdf")), n=8)
    assert 0 < f_pin[0] < 0.99 * freqs(*read_bdf(write(tmp_path, base, "base.bdf")), n=1)[0]
    np.testing.assert_allclose(f_pin, f_hinge, rtol=1e-9)


THEORY_MASS = [("euler-bernoulli", "consistent"), ("euler-bernoulli", "lumped"),
               ("timoshenko", "consistent"), ("timoshenko", "lumped")]


@pytest.mark.parametrize("theory,mass", THEORY_MASS)
def test_written_deck_reads_back_to_the_same_frequencies(tmp_path, theory, mass):
    """Inclined bars, rods, a rigid body, springs, point masses: the deck NASTRAN would
    solve is the model itself, every mode that carries mass (issue 24: 6.4e-4 before)."""
    model = _frame_model(theory, mass)
    path = tmp_path / "rt.bdf"
    write_bdf(model, path, n_modes=12)
    back, info = read_bdf(path)
    assert (info.mass, back.beam_theory, info.eigen.n_modes) == (mass, theory, 12)
    f0 = solve_modes(model, n_modes=200).frequencies_hz
    f1 = solve_modes(back, n_modes=200, autospc=info.autospc).frequencies_hz
    assert len(f1) == len(f0) > 12
    np.testing.assert_allclose(f1, f0, rtol=1e-10)


@pytest.mark.parametrize("theory", ["euler-bernoulli", "timoshenko"])
def test_the_written_mass_corrections_are_nastrans_coupled_mass_conventions(tmp_path, theory):
    """Without its CMASS2 cards the consistent-mass deck is the model with NASTRAN's coupled
    CBAR (no torsional, and with shear flexibility no rotary, inertia) and CROD mass, built
    here independently of the writer: the cards hold exactly that difference."""
    write_bdf(_frame_model(theory, "consistent"), tmp_path / "rt.bdf", n_modes=12)
    text = (tmp_path / "rt.bdf").read_text()
    assert "CMASS2" in text
    lines, keep = text.splitlines(), []
    skip = False
    for line in lines:  # a large-field CMASS2 is two lines: "CMASS2*" and its "*" continuation
        if line.startswith("CMASS2"):
            skip = True
            continue
        if skip and line.startswith("*"):
            continue
        skip = False
        keep.append(line)
    bare = "\n".join(keep) + "\n"
    (tmp_path / "bare.bdf").write_text(bare)
    back, info = read_bdf(tmp_path / "bare.bdf")
    nastran = _frame_model(theory, "consistent", nastran_bars=True)
    _add_nastran_rod_mass(nastran)
    if theory == "timoshenko":
        _add_nastran_shear_bar_mass(nastran)
    f0 = solve_modes(nastran, n_modes=12).frequencies_hz
    f1 = solve_modes(back, n_modes=12, autospc=info.autospc).frequencies_hz
    np.testing.assert_allclose(f1, f0, rtol=1e-10)
    f_model = solve_modes(_frame_model(theory, "consistent"), n_modes=12).frequencies_hz
    assert np.max(np.abs(f1 / f_model - 1)) > 1e-6  # the conventions do change the modes


def test_written_deck_reads_back_to_the_same_model_arrays(tmp_path):
    # lumped: a coupled CBAR's mass is read back as non-structural mass (NASTRAN's coupled
    # CBAR has no torsional inertia), which the frequency round trip above covers
    model = _frame_model("timoshenko", "lumped")
    write_bdf(model, tmp_path / "rt.bdf")
    back, _ = read_bdf(tmp_path / "rt.bdf")
    np.testing.assert_array_equal(back.node_ids, model.node_ids)
    # 16-character fields hold 12 to 14 significant digits (fewer with a 2-digit exponent).
    np.testing.assert_allclose(back.xyz, model.xyz, rtol=1e-12)
    b0, b1 = model.beams, back.beams
    o0, o1 = np.argsort(b0.ids), np.argsort(b1.ids)
    for key in ("nodes", "A", "E", "G", "rho", "nsm", "rod"):
        np.testing.assert_allclose(getattr(b1, key)[o1], getattr(b0, key)[o0], rtol=1e-12, err_msg=key)
    frame = ~b0.rod[o0]  # a rod has no orientation or bending properties
    for key in ("orient", "Iy", "Iz", "J", "Asy", "Asz"):
        np.testing.assert_allclose(getattr(b1, key)[o1][frame], getattr(b0, key)[o0][frame], rtol=1e-12)
    np.testing.assert_array_equal(back.fixed_mask(), model.fixed_mask())
    # The rigid body's mass comes back as a CONM2 at its master: same node, mass, cg, inertia.
    pm = back.point_masses
    rb = model.rigid_bodies[0]
    at_master = np.flatnonzero((pm.nodes == rb.master) & np.isclose(pm.mass, rb.mass))
    assert len(at_master) == 1
    xyz = dict(zip(model.node_ids.tolist(), model.xyz))
    np.testing.assert_allclose(pm.offset[at_master[0]], rb.cg - xyz[rb.master], rtol=1e-12)
    np.testing.assert_allclose(pm.inertia[at_master[0]], rb.inertia, rtol=1e-12)


def test_written_deck_is_a_runnable_sol103_deck(tmp_path):
    write_bdf(_frame_model(mass="lumped"), tmp_path / "rt.bdf", n_modes=8)
    text = (tmp_path / "rt.bdf").read_text()
    for token in ("SOL 103", "CEND", "METHOD = 1", "SPC = 1", "BEGIN BULK", "COUPMASS", "EIGRL",
                  "ENDDATA"):
        assert token in text


def test_writer_refuses_a_spring_nastran_cannot_express_and_leaves_no_file(tmp_path):
    m = Model()
    m.add_nodes([1, 2], [[0, 0, 0], [1, 0, 0]])
    c, s = math.cos(0.3), math.sin(0.3)
    m.add_springs([1], [[1, 2]], [1, 1, 1, 0, 0, 0], frame=[[c, s, 0], [-s, c, 0], [0, 0, 1]])
    with pytest.raises(ModelError, match="spring 1"):
        write_bdf(m, tmp_path / "out.bdf")
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------- bad input
def test_unsupported_cards_are_all_listed_with_counts(tmp_path):
    # NSM adds non-structural mass (it would change the modes; not translated)
    deck = cantilever_deck(n_el=2, extra="CTUBE,5,1,1,2\nNSM,90,PBAR,1,0.5\nPARAM,CK1,2.0")
    with pytest.raises(ModelError) as exc:
        read_bdf(write(tmp_path, deck))
    msg = str(exc.value)
    for item in ("CTUBE (1)", "NSM (1)", "PARAM,CK1"):
        assert item in msg
    assert "\n" not in msg


def test_shell_and_solid_elements_are_named_first_in_one_line(tmp_path):
    deck = cantilever_deck(n_el=2, extra="CQUAD4,100,1,1,2,3,1\nCQUAD4,101,1,1,2,3,1\n"
                                         "CTRIA3,102,1,1,2,3\nPSHELL,1,1,0.1\nPARAM,CM1,2.0")
    with pytest.raises(ModelError) as exc:
        read_bdf(write(tmp_path, deck))
    msg = str(exc.value)
    assert "unsupported element entries: CQUAD4 (2), CTRIA3 (1)" in msg
    assert "also unsupported: PARAM,CM1 (1), PSHELL (1)" in msg
    assert "\n" not in msg


def test_entries_without_effect_on_modes_are_ignored_and_listed_once(tmp_path):
    """Loads, tables, damping, aero and output entries leave the modes unchanged."""
    extra = ("FORCE,1,21,0,1.,0.,100.,0.\nFORCE,1,20,0,1.,0.,100.,0.\nMDLPRM,HDF5,0\n"
             "TABDMP1,1,CRIT\n,0.,0.02,1000.,0.02,ENDT\nPARAM,OIBULK,YES\nMAT4,501,200.")
    plain, _ = read_bdf(write(tmp_path, cantilever_deck(n_el=20)))
    model, info = read_bdf(write(tmp_path, cantilever_deck(n_el=20, extra=extra), "loaded.bdf"))
    assert info.ignored == ["FORCE (2)", "MAT4 (1)", "MDLPRM (1)", "PARAM,OIBULK", "TABDMP1 (1)"]
    np.testing.assert_array_equal(freqs(model, info), freqs(plain))


@pytest.mark.parametrize("extra,replace,match", [
    ("", ("CBAR,2,1,2,3,0.,0.,1.", "CBAR,2,1,2,99,0.,0.,1."), "CBAR 2: grid 99 is not defined"),
    ("", ("CBAR,1,1,1,2,0.,0.,1.", "CBAR,1,1,1,2,0.,0.,1.\n,,,,0.,0.,0.1"), "CBAR 1: offsets"),
    ("", ("CBAR,1,1,1,2,0.,0.,1.", "CBAR,1,1,1,2,0.,0.,1.,,\n,7"), "CBAR 1: pin flags"),
    ("CELAS2,50,10.,2,0,3,2", ("", ""), "CELAS2 50: component 0 is a scalar point.s, but 2 is no SPOINT"),
    ("", ("GRID,3,,", "GRID,3,,0.,0.,0.,5\nGRID,33,,"), "GRID 3: coordinate system CD=5 is not defined"),
    ("", ("PBAR,1,1,", "PBAR,1,77,"), "PBAR 1: material 77 is not defined"),
    ("CBUSH,60,61,2,3,0.,1.,0.,,\n,,7,0.1,0.,0.\nPBUSH,61,K,1.,1.,1.", ("", ""), "CBUSH 60: spring offset OCID"),
])
def test_bad_deck_errors_name_the_card(tmp_path, extra, replace, match):
    deck = cantilever_deck(n_el=4, extra=extra).replace(*replace)
    with pytest.raises(ModelError, match=match):
        read_bdf(write(tmp_path, deck))


def test_tapered_and_unsupported_sections_are_refused(tmp_path):
    base = "BEGIN BULK\nMAT1,1,70.+9,,0.3,2700.\nGRID,1,,0.,0.,0.\nGRID,2,,1.,0.,0.\n"
    with pytest.raises(ModelError, match="CBEAM 1: pin flags on a tapered beam"):
        read_bdf(write(tmp_path, base + "PBEAM,4,1,1.-4,1.-9,1.-9,,2.-9\n,YES,1.,2.-4,1.-9,1.-9,,2.-9\n"
                                        "CBEAM,1,4,1,2,0.,0.,1.\n,4\nENDDATA\n"))
    with pytest.raises(ModelError, match="PBARL 4: section type I "):
        read_bdf(write(tmp_path, base + "PBARL,4,1,,I\n,0.1,0.1,0.1,0.01,0.01,0.01\n"
                                        "CBAR,1,4,1,2,0.,0.,1.\nENDDATA\n", "i.bdf"))


def test_missing_and_unreadable_files_are_user_errors(tmp_path):
    with pytest.raises(ModelError, match="no such file"):
        read_bdf(tmp_path / "nope.bdf")
    # NASTRAN's reals have a decimal point: an integer there is refused, naming file, line,
    # entry and field
    with pytest.raises(ModelError, match=r"deck.bdf, line 2: GRID 1: field 4: X1 must be a real number"):
        read_bdf(write(tmp_path, "BEGIN BULK\nGRID,1,,0,0,0\nENDDATA\n"))


# ----------------------------------------------------------------- more card semantics
def test_g0_orientation_equals_the_vector_to_the_third_grid(tmp_path):
    deck = cantilever_deck(n_el=2, extra="GRID,99,,0.3,0.4,5.\nCBAR,10,1,1,2,99")
    model, _ = read_bdf(write(tmp_path, deck))
    b = model.beams
    np.testing.assert_allclose(b.orient[b.ids == 10][0], [0.3, 0.4, 5.0])


def test_rod_cards_give_the_axial_closed_form_and_agree_with_each_other(tmp_path):
    # Fixed-free bar, 40 linear rod elements, consistent mass: f_n = (2n - 1) c / (4 L).
    E, rho, L, n_el = 70e9, 2700.0, 2.0, 40
    od, t = 0.02, 0.002
    A = math.pi / 4 * (od**2 - (od - 2 * t) ** 2)
    c = math.sqrt(E / rho)
    ref = np.array([(2 * k - 1) * c / (4 * L) for k in (1, 2)])
    grids = "".join(f"GRID,{i + 1},,{real(L * i / n_el)},0.,0.,,23\n" for i in range(n_el + 1))
    # MAT1 with E alone (G = NU = 0 by NASTRAN's rule) is fine for rods without torsion.
    head = f"BEGIN BULK\nPARAM,COUPMASS,1\nMAT1,1,{real(E)},,,{real(rho)}\n" + grids
    tail = "SPC1,1,1,1\nENDDATA\n"
    decks = {
        "PROD": f"PROD,5,1,{real(A)}\n" + "".join(f"CROD,{i + 1},5,{i + 1},{i + 2}\n" for i in range(n_el)),
        "PTUBE": f"PTUBE,5,1,{real(od)},{real(t)}\n"
                 + "".join(f"CROD,{i + 1},5,{i + 1},{i + 2}\n" for i in range(n_el)),
        "CONROD": "".join(f"CONROD,{i + 1},{i + 1},{i + 2},1,{real(A)}\n" for i in range(n_el)),
    }
    got = {}
    for name, body in decks.items():
        model, info = read_bdf(write(tmp_path, head + body + tail, f"{name}.bdf"))
        assert model.beams.rod.all()
        got[name] = freqs(model, info, n=2)
    # Linear elements converge as h^2: (pi/2 / 40)^2 / 24 ~ 6e-5 on mode 1.
    np.testing.assert_allclose(got["PROD"], ref, rtol=1e-3)
    np.testing.assert_allclose(got["PTUBE"], got["PROD"], rtol=1e-12)
    np.testing.assert_allclose(got["CONROD"], got["PROD"], rtol=1e-12)


def test_pbeam_shear_flexibility_follows_nastrans_k_defaults(tmp_path):
    # PBEAM K1 = K2 = 1.0 by default (shear area = A): Timoshenko, lower frequencies.
    # K1 = K2 = 0.0 means no shear flexibility: the same beam as a PBAR.
    bar = cantilever_deck(n_el=10, A=4e-4, I1=1.3e-8, I2=1.3e-8, J=2.6e-8)
    beam_default = bar.replace("PBAR,1,1,0.0004,1.3e-08,1.3e-08,2.6e-08",
                               "PBEAM,1,1,0.0004,1.3e-08,1.3e-08,,2.6e-08").replace("CBAR", "CBEAM")
    beam_rigid = beam_default.replace(",2.6e-08\n", ",2.6e-08\n,,,,,,,,\n,0.,0.\n", 1)
    assert beam_default != bar and beam_rigid != beam_default
    f = {}
    for name, text in (("bar", bar), ("default", beam_default), ("rigid", beam_rigid)):
        model, info = read_bdf(write(tmp_path, text, f"{name}.bdf"))
        f[name] = (info.beam_theory, freqs(model, info, n=1)[0])
    assert f["bar"][0] == f["rigid"][0] == "euler-bernoulli" and f["default"][0] == "timoshenko"
    assert f["rigid"][1] == pytest.approx(f["bar"][1], rel=1e-12)
    assert f["default"][1] < f["bar"][1]


def test_inch_pound_example_deck_with_wtmass_matches_the_closed_form_in_its_units():
    # examples/decks/cantilever_inch.bdf: E in psi, RHO a weight density in lbf/in^3, and
    # WTMASS = 0.00259 s^2/in turning it into mass; frequencies come out in Hz.
    model, info = read_bdf(FRAME.parent / "cantilever_inch.bdf")
    assert info.wtmass == 0.00259 and info.eigen.n_modes == 6
    ro, ri, L = 0.25, 0.215, 40.0
    A = math.pi * (ro**2 - ri**2)
    I = math.pi * (ro**4 - ri**4) / 4
    ref = [eb_cantilever(k, 1.0e7, I, 0.0975 * 0.00259, A, L) for k in (0, 1)]
    f = freqs(model, info, n=4)
    np.testing.assert_allclose(f[:2], [ref[0]] * 2, rtol=1e-6)  # h^4 convergence, as above
    np.testing.assert_allclose(f[2:], [ref[1]] * 2, rtol=1e-5)
