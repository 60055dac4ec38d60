"""Frame-element frequencies against classical beam theory (issue 2, acceptance 1-3).

Every reference frequency here is computed in the test from the governing equations
(characteristic equations solved numerically with brentq, or closed forms), never copied
from the code under test.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from trussid.fem import ALUMINIUM, Model, Section
from trussid.fem.modal import solve_modes

L_BEAM = 2.5  # m; slender: length / radius of gyration ~ 180
TUBE = Section.tube(0.02, 0.001, name="thin tube")  # t / r = 0.05
# The same tube with a stiffer x-y plane (Iz = 1.7 Iy) so the two bending planes separate.
TUBE_2 = Section.general(TUBE.A, TUBE.Iy, 1.7 * TUBE.Iz, TUBE.J, name="tube, Iz = 1.7 Iy")
SKEW_AXIS = np.array([1.0, 2.0, -0.7]) / np.linalg.norm([1.0, 2.0, -0.7])
SKEW_ORIENT = np.array([0.3, -0.2, 1.0])


def straight_beam(n_el, section, axis=(1.0, 0.0, 0.0), orient=(0.0, 1.0, 0.0), length=L_BEAM,
                  origin=(0.0, 0.0, 0.0), **model_kw):
    """Beam of ``n_el`` equal elements from ``origin`` along unit vector ``axis``; nodes 0..n_el.

    With the defaults, local axes coincide with the global ones (local y = global y).
    """
    m = Model(**model_kw)
    s = np.linspace(0.0, length, n_el + 1)
    m.add_nodes(np.arange(n_el + 1), np.asarray(origin) + s[:, None] * np.asarray(axis))
    m.add_beams(np.arange(1, n_el + 1), np.c_[np.arange(n_el), np.arange(1, n_el + 1)], section,
                ALUMINIUM, orient=orient)
    return m


def roots(f, n, start=0.5, step=0.05):
    """First ``n`` positive roots of ``f`` by scanning for sign changes then brentq."""
    out, x = [], start
    while len(out) < n:
        if np.sign(f(x)) != np.sign(f(x + step)):
            out.append(brentq(f, x, x + step, xtol=1e-15, rtol=4 * np.finfo(float).eps))
        x += step
    return np.array(out)


#: Eigenvalue parameters beta*L of the Euler-Bernoulli beam, from the characteristic equations.
BETA_L = {
    "cantilever": roots(lambda b: np.cos(b) * np.cosh(b) + 1.0, 4),
    "pinned-pinned": np.pi * np.arange(1, 5),
    "clamped-clamped": roots(lambda b: np.cos(b) * np.cosh(b) - 1.0, 4, start=1.0),
    "free-free": roots(lambda b: np.cos(b) * np.cosh(b) - 1.0, 4, start=1.0),
}


def apply_supports(m, case, n_el, axis=(1.0, 0.0, 0.0)):
    """Supports of the four classical cases on a beam of nodes 0..n_el along ``axis``."""
    if case == "cantilever":
        m.fix(0)
    elif case == "pinned-pinned":
        m.fix([0, n_el], "123")
        # Torsion about the beam's own axis needs restraint (else it is a mechanism); a
        # global rx support would also restrain bending rotation on a skew beam, so use
        # stiff torsion springs in the beam's frame, which do not touch bending.
        frame = np.linalg.qr(np.c_[axis, np.eye(3)])[0][:, :3].T
        frame[0] = axis  # QR may flip the sign of the first column
        m.add_springs([n_el + 1, n_el + 2], [0, n_el], [0, 0, 0, 1e3 * ALUMINIUM.G * TUBE.J / L_BEAM, 0, 0],
                      frame=frame)
    elif case == "clamped-clamped":
        m.fix([0, n_el])
    elif case != "free-free":
        raise ValueError(case)


def eb_frequencies(case, I, length=L_BEAM, section=TUBE, material=ALUMINIUM):
    """Euler-Bernoulli frequencies [Hz]: omega = (beta L)^2 sqrt(E I / (rho A L^4))."""
    return BETA_L[case] ** 2 * math.sqrt(material.E * I / (material.rho * section.A * length**4)) / (2 * math.pi)


def bending_modes(modes, case):
    """Frequencies of the flexible modes (free-free: skip the 6 rigid-body modes)."""
    f = modes.frequencies_hz
    return f[6:] if case == "free-free" else f


def plane_of_modes(modes, axis, orient):
    """+1 for bending along local y (x-y plane, Iz), -1 along local z (Iy), 0 for axial or
    torsional modes."""
    axis = np.asarray(axis, float)
    ey = np.asarray(orient) - np.dot(orient, axis) * axis
    ey /= np.linalg.norm(ey)
    ez = np.cross(axis, ey)
    u = modes.shapes_full.reshape(-1, 6, modes.shapes_full.shape[1])
    dy, dz, dx = (np.linalg.norm(np.einsum("i,nim->nm", e, u[:, :3, :]), axis=0) for e in (ey, ez, axis))
    twist = np.linalg.norm(np.einsum("i,nim->nm", axis, u[:, 3:, :]), axis=0) * L_BEAM
    return np.where(np.maximum(dy, dz) > np.maximum(dx, twist), np.sign(dy - dz), 0.0)


CASES = ["cantilever", "pinned-pinned", "clamped-clamped", "free-free"]

#: Modes within 1e-4 with 20 elements. Issue 2 asks for all four; the 4th mode of the
#: pinned, clamped and free beams is off by 1.07e-4, 1.71e-4 and 1.71e-4: the
#: discretisation error of the consistent-mass cubic element, which grows like
#: (beta h)^4 (beta h = 0.63 and 0.71 there). NOT MET at 20 elements for those three;
#: 24 elements meet it for every case (test below).
WITHIN_1E4_AT_20 = {"cantilever": 4, "pinned-pinned": 3, "clamped-clamped": 3, "free-free": 3}


def check_both_planes(case, n_el, n_check):
    """Tube along x (degenerate planes) and Iy != Iz skew beam, against the closed form."""
    m = straight_beam(n_el, TUBE)
    apply_supports(m, case, n_el)
    f = bending_modes(solve_modes(m, 14), case)[:2 * n_check]
    expected = np.repeat(eb_frequencies(case, TUBE.Iy)[:n_check], 2)  # Iy = Iz: pairs
    errors = [np.abs(f / expected - 1.0)]

    m = straight_beam(n_el, TUBE_2, axis=SKEW_AXIS, orient=SKEW_ORIENT, origin=(0.3, -1.0, 2.0))
    apply_supports(m, case, n_el, SKEW_AXIS)
    modes = solve_modes(m, 16)
    first = 6 if case == "free-free" else 0
    f = modes.frequencies_hz[first:]
    plane = plane_of_modes(modes, SKEW_AXIS, SKEW_ORIENT)[first:]
    assert (plane > 0).sum() >= 4 and (plane < 0).sum() >= 4  # four modes in each plane
    f_xy = f[plane > 0][:n_check]  # displacement along local y: stiffness E Iz
    f_xz = f[plane < 0][:n_check]
    errors.append(np.abs(f_xy / eb_frequencies(case, TUBE_2.Iz)[:n_check] - 1.0))
    errors.append(np.abs(f_xz / eb_frequencies(case, TUBE_2.Iy)[:n_check] - 1.0))
    return max(e.max() for e in errors)


@pytest.mark.parametrize("case", CASES)
def test_bending_frequencies_of_both_planes_within_1e4_with_20_elements(case):
    assert check_both_planes(case, 20, WITHIN_1E4_AT_20[case]) < 1e-4


@pytest.mark.parametrize("case", CASES)
def test_first_four_bending_frequencies_of_both_planes_within_1e4_with_24_elements(case):
    assert check_both_planes(case, 24, 4) < 1e-4


def first_frequency_errors(case, counts=(2, 4, 8, 16)):
    exact = eb_frequencies(case, TUBE_2.Iy)[0]  # lowest: the x-z plane (Iy < Iz)
    errors = []
    for n_el in counts:
        m = straight_beam(n_el, TUBE_2, axis=SKEW_AXIS, orient=SKEW_ORIENT)
        apply_supports(m, case, n_el, SKEW_AXIS)
        errors.append(abs(bending_modes(solve_modes(m, 8), case)[0] / exact - 1.0))
    return np.array(errors)


@pytest.mark.parametrize("case", CASES)
def test_first_frequency_converges_at_order_at_least_3p5(case):
    """Observed order log2(e_n / e_2n) over 2, 4, 8, 16 elements.

    The free-free beam's 2 -> 4 step is pre-asymptotic (beta h = 2.4 with 2 elements) and
    shows order 1.0: NOT MET for that one pair; its 4 -> 8 and 8 -> 16 orders are >= 3.5
    like every other case's.
    """
    e = first_frequency_errors(case)
    order = np.log2(e[:-1] / e[1:])
    checked = order[1:] if case == "free-free" else order
    assert checked.min() >= 3.5, (e, order)
    assert np.all(np.diff(e) < 0)


def fixed_free_axial_torsion_model(n_el):
    """Fixed-free bar with bending suppressed, so only axial (ux) and torsion (rx) remain."""
    m = straight_beam(n_el, TUBE)
    m.fix(0)
    m.fix(np.arange(1, n_el + 1), "2356")
    return m


def test_axial_and_torsional_fixed_free_frequencies_within_1e3_with_40_elements():
    modes = solve_modes(fixed_free_axial_torsion_model(40), 6)
    u = modes.shapes_full.reshape(-1, 6, len(modes))
    axial = np.linalg.norm(u[:, 0, :], axis=0) > np.linalg.norm(u[:, 3, :], axis=0) * L_BEAM
    f_axial = modes.frequencies_hz[axial][:2]
    f_torsion = modes.frequencies_hz[~axial][:2]
    n = np.array([1, 2])
    c_axial = math.sqrt(ALUMINIUM.E / ALUMINIUM.rho)
    # Torsion: G J / (rho I_p), with I_p the polar moment of area.
    c_torsion = math.sqrt(ALUMINIUM.G * TUBE.J / (ALUMINIUM.rho * (TUBE.Iy + TUBE.Iz)))
    assert np.max(np.abs(f_axial / ((2 * n - 1) * c_axial / (4 * L_BEAM)) - 1)) < 1e-3
    assert np.max(np.abs(f_torsion / ((2 * n - 1) * c_torsion / (4 * L_BEAM)) - 1)) < 1e-3


# ---------------------------------------------------------------------------- Timoshenko
def timoshenko_simply_supported(n, length, section, material, I, As):
    """Exact Timoshenko frequency [Hz] of the n-th simply-supported bending mode.

    With w = sin(k x) e^{i omega t}, k = n pi / L, the Timoshenko equations give
    rho^2 I / (G As / A) omega^4 - (rho A + rho I k^2 (1 + E A / (G As))) omega^2 + E I k^4 = 0
    (all divided through consistently); the lower root is the bending branch.
    """
    E, G, rho, A = material.E, material.G, material.rho, section.A
    k = n * math.pi / length
    a = rho**2 * I / (G * As / A) / A  # coefficient of omega^4, per unit A
    b = rho + rho * I / A * k**2 * (1.0 + E * A / (G * As))
    c = E * I / A * k**4
    w2 = (b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    return math.sqrt(w2) / (2 * math.pi)


@pytest.mark.parametrize("plane", ["x-z", "x-y"])
def test_stubby_timoshenko_beam_matches_frequency_equation_within_half_percent(plane):
    # Rectangle b x h, given unequal shear areas so that a mix-up of the planes' I and As
    # would show: each plane must use its own pair.
    rect = Section.rectangle(0.04, 0.06, nu=ALUMINIUM.nu)
    sec = Section.general(rect.A, rect.Iy, rect.Iz, rect.J, Asy=0.55 * rect.A, Asz=0.8 * rect.A, name="stubby bar")
    I, As = (sec.Iy, sec.Asz) if plane == "x-z" else (sec.Iz, sec.Asy)
    r_g = math.sqrt(I / sec.A)
    length = 10.0 * r_g  # length / radius of gyration = 10
    # The shear-flexible cubic element has piecewise-constant shear strain, so in this
    # shear-dominated regime frequencies converge like h^2 (measured: mode 3 is 0.61 % /
    # 0.70 % high in the two planes with 20 elements, 0.15 % / 0.18 % with 40); 40 elements
    # keep three modes within 0.5 %.
    n_el = 40
    m = straight_beam(n_el, sec, length=length, beam_theory="timoshenko")
    # Keep only the plane under test: x-z bending is (uz, ry), x-y bending is (uy, rz).
    m.fix(np.arange(n_el + 1), "1246" if plane == "x-z" else "1345")
    m.fix([0, n_el], "3" if plane == "x-z" else "2")
    f = solve_modes(m, 3).frequencies_hz
    exact = np.array([timoshenko_simply_supported(n, length, sec, ALUMINIUM, I, As) for n in (1, 2, 3)])
    eb = np.array([(n * math.pi / length) ** 2 * math.sqrt(ALUMINIUM.E * I / (ALUMINIUM.rho * sec.A))
                   / (2 * math.pi) for n in (1, 2, 3)])
    assert np.all(exact < 0.9 * eb)  # the beam is stubby enough for shear to matter
    assert np.max(np.abs(f / exact - 1.0)) < 5e-3


def test_slender_timoshenko_and_euler_bernoulli_agree_to_1e4():
    # Shear and rotary inertia change mode n by ~ (beta_n r_g / L)^2: "slender" for four
    # modes within 1e-4 needs L / r_g ~ 3000 (the 2.5 m tube, L / r_g = 180, differs by 2e-3).
    sec = Section.tube(0.005, 0.0005, nu=ALUMINIUM.nu, name="slender tube")
    f = {}
    for theory in ("euler-bernoulli", "timoshenko"):
        m = straight_beam(20, sec, axis=SKEW_AXIS, orient=SKEW_ORIENT, length=10.0, beam_theory=theory)
        m.fix(0)
        f[theory] = solve_modes(m, 8).frequencies_hz
    assert 10.0 / math.sqrt(sec.Iy / sec.A) > 2500
    rel = f["timoshenko"] / f["euler-bernoulli"] - 1.0
    assert np.max(np.abs(rel)) < 1e-4
    # ... and the difference is real: shear and rotary inertia lower every frequency.
    assert np.all(rel < 0)
