"""Tapered beams (PBEAM stations, PBEAML dimensions at both ends; issue 33): integrated along
the element, checked against the uniform element, closed-form tapered-cantilever
flexibilities, and fine decks of uniform sections (the same beam without the taper entry),
whose own discretisation error is bounded by Richardson extrapolation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from trussid.fem.elements import frame_matrices
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf
from trussid.fem.properties import SectionArrays
from trussid.fem.tapered import tapered_frame_matrices

E, G, RHO = 70e9, 26e9, 2700.0


@pytest.mark.parametrize("theory", ["euler-bernoulli", "timoshenko"])
@pytest.mark.parametrize("mass", ["consistent", "lumped"])
def test_a_uniform_section_gives_the_textbook_element(theory, mass):
    L = np.array([0.7, 1.3])
    A, Iy, Iz, J = 2e-4, 3e-9, 5e-9, 4e-9
    K, M = tapered_frame_matrices(L, [0.0, 0.4, 1.0], lambda xi: SectionArrays(A=A, Iy=Iy, Iz=Iz, J=J, Asy=0.8 * A,
                                                                               Asz=0.7 * A),
                                  E, G, RHO, nsm_at=lambda xi: np.full(len(xi), 0.3), theory=theory, mass=mass,
                                  torsion_lumped=False)
    full = lambda v: np.full(2, v)
    K0, M0 = frame_matrices(L, full(A), full(Iy), full(Iz), full(J), full(E), full(G), full(RHO), nsm=0.3,
                            Asy=0.8 * A, Asz=0.7 * A, theory=theory, mass=mass)
    np.testing.assert_allclose(K, K0, rtol=0, atol=1e-12 * np.abs(K0).max())
    if theory == "euler-bernoulli" or mass == "lumped":  # the Timoshenko element adds rotary inertia
        np.testing.assert_allclose(M, M0, rtol=0, atol=1e-12 * np.abs(M0).max())
    if mass == "lumped":  # NASTRAN's lumped CBEAM: torsional inertia rho (I1 + I2) L / 2 per end
        Mt = tapered_frame_matrices(L, [0.0, 1.0], lambda xi: SectionArrays(A=A, Iy=Iy, Iz=Iz, J=J),
                                   E, G, RHO, mass="lumped")[1]
        np.testing.assert_allclose(Mt[:, 3, 3], RHO * (Iy + Iz) * L / 2, rtol=1e-13)
        np.testing.assert_allclose(Mt[:, 9, 9], RHO * (Iy + Iz) * L / 2, rtol=1e-13)


def test_one_element_has_the_closed_form_flexibility_of_a_tapered_cantilever():
    """A and I linear from end A to ratio r at end B, clamped at A, loaded at B:
    axial L ln r / (E A_a (r - 1)); tip deflection under a tip force
    P L^3 / (E I_a a^3) (r^2 ln r - 2 r a + (r^2 - 1) / 2), a = r - 1 (integral of
    (L - x)^2 / E I(x)); tip rotation under a tip moment L ln r / (E I_a a)."""
    L, r, Aa, Ia = 1.5, 3.0, 1e-4, 2e-9
    at = lambda xi: SectionArrays(A=Aa * (1 + (r - 1) * xi), Iy=Ia * (1 + (r - 1) * xi),
                                  Iz=Ia * (1 + (r - 1) * xi), J=Ia * (1 + (r - 1) * xi))
    K, _ = tapered_frame_matrices(np.array([L]), [0.0, 1.0], at, E, G, RHO)
    flex = np.linalg.inv(K[0][6:, 6:])   # end A clamped
    a = r - 1
    np.testing.assert_allclose(flex[0, 0], L * math.log(r) / (E * Aa * a), rtol=1e-12)
    np.testing.assert_allclose(flex[1, 1], L**3 / (E * Ia * a**3) * (r**2 * math.log(r) - 2 * r * a + (r**2 - 1) / 2),
                               rtol=1e-12)
    np.testing.assert_allclose(flex[5, 5], L * math.log(r) / (E * Ia * a), rtol=1e-12)
    np.testing.assert_allclose(flex[3, 3], L * math.log(r) / (G * Ia * a), rtol=1e-12)


# ------------------------------------------------------------------ decks
HEAD = "BEGIN BULK\nPARAM,COUPMASS,1\nMAT1,1,70.+9,26.+9,,2700.\nSPC1,1,123456,1\n"
LENGTH, N_ELEM = 1.0, 10


def num(v) -> str:
    return repr(float(v))


def cantilever(n: int, prop_of) -> str:
    """``n`` CBEAMs along x from the clamped grid 1, each with its own property line(s)."""
    x = np.linspace(0.0, LENGTH, n + 1)
    out = [f"GRID,{i + 1},,{num(xi)},0.,0.\n" for i, xi in enumerate(x)]
    for e in range(n):
        out.append(prop_of(e, x[e] / LENGTH, x[e + 1] / LENGTH))
        out.append(f"CBEAM,{e + 1},{e + 1},{e + 1},{e + 2},0.,0.,1.\n")
    return "".join(out)


def pbeam_props(xi):
    """A, I1, I2, J, NSM of the beam at x / L = xi: linear to an intermediate station at
    x / L = 0.5 (not on a grid), and on to end B with another slope."""
    A = np.interp(xi, [0, 0.5, 1], [2e-4, 1.4e-4, 1e-4])
    I1 = np.interp(xi, [0, 0.5, 1], [8e-9, 4e-9, 2.5e-9])
    I2 = np.interp(xi, [0, 0.5, 1], [6e-9, 4e-9, 3e-9])
    J = np.interp(xi, [0, 0.5, 1], [9e-9, 6e-9, 4e-9])
    nsm = np.interp(xi, [0, 0.5, 1], [0.2, 0.1, 0.05])
    return A, I1, I2, J, nsm


def tapered_pbeam(e, a, b):
    """One PBEAM per element with its end values (and the x/L = 0.5 kink as a station)."""
    xs = [0.0, 1.0] if not a < 0.5 < b else [0.0, (0.5 - a) / (b - a), 1.0]
    vals = [pbeam_props(a + s * (b - a)) for s in xs]
    first = vals[0]
    lines = [f"PBEAM,{e + 1},1,{num(first[0])},{num(first[1])},{num(first[2])},,{num(first[3])},{num(first[4])}\n"]
    for s, v in zip(xs[1:], vals[1:]):
        lines.append(f",{'YES' if s == 1.0 else 'NO'},{num(s)},{num(v[0])},{num(v[1])},{num(v[2])},,{num(v[3])},{num(v[4])}\n")
    return "".join(lines)


def uniform_pbeam(e, a, b):
    v = pbeam_props(0.5 * (a + b))  # the section at the element's middle
    return f"PBEAM,{e + 1},1,{num(v[0])},{num(v[1])},{num(v[2])},,{num(v[3])},{num(v[4])}\n"


def tapered_pbeaml(e, a, b):
    """BAR 10 x (10 -> 20) mm, height linear along the beam, NSM too."""
    d = lambda s: (0.01 + 0.01 * s, 0.01, 0.1 * (1 + s))
    da, db = d(a), d(b)
    return (f"PBEAML,{e + 1},1,,BAR\n,{num(da[0])},{num(da[1])},{num(da[2])},YES,1.,{num(db[0])},{num(db[1])},{num(db[2])}\n")


def uniform_pbeaml(e, a, b):
    s = 0.5 * (a + b)
    return f"PBEAML,{e + 1},1,,BAR\n,{num(0.01 + 0.01 * s)},0.01,{num(0.1 * (1 + s))}\n"


def frequencies(tmp_path, bulk: str, name: str, n: int = 6) -> np.ndarray:
    p = tmp_path / name
    p.write_text(HEAD + bulk + "ENDDATA\n")
    model, info = read_bdf(p)
    return solve_modes(model, n_modes=n, autospc=info.autospc).frequencies_hz


@pytest.mark.parametrize("theory", ["euler-bernoulli", "timoshenko"])
def test_element_stiffness_is_the_limit_of_finely_subdivided_uniform_sections(theory):
    """The tapered element's 12 x 12 stiffness against a chain of S uniform sub-elements
    (section at each one's middle) with its inner nodes condensed statically: the chain
    converges as 1 / S^2 (midpoint rule), Richardson's limit of S = 200 and 400 bounds its
    error, and the integrated element lies within that bound (1e-9)."""
    L = 0.8
    kink = [0.0, 0.4, 1.0]
    at = lambda xi: SectionArrays(A=np.interp(xi, kink, [2e-4, 1.2e-4, 1e-4]),
                                  Iy=np.interp(xi, kink, [6e-9, 3e-9, 2e-9]),
                                  Iz=np.interp(xi, kink, [9e-9, 5e-9, 2e-9]), J=np.interp(xi, kink, [9e-9, 6e-9, 3e-9]),
                                  Asy=0.8 * np.interp(xi, kink, [2e-4, 1.2e-4, 1e-4]),
                                  Asz=0.7 * np.interp(xi, kink, [2e-4, 1.2e-4, 1e-4]))
    K = tapered_frame_matrices(np.array([L]), kink, at, E, G, RHO, theory=theory)[0][0]

    def chain(S: int) -> np.ndarray:
        mid = (np.arange(S) + 0.5) / S
        p = at(mid)
        Ke = frame_matrices(np.full(S, L / S), p.A, p.Iy, p.Iz, p.J, np.full(S, E), np.full(S, G),
                            np.full(S, RHO), Asy=p.Asy, Asz=p.Asz, theory=theory)[0]
        Kc = np.zeros((6 * (S + 1), 6 * (S + 1)))
        for e in range(S):
            Kc[6 * e:6 * e + 12, 6 * e:6 * e + 12] += Ke[e]
        ends = np.r_[0:6, 6 * S:6 * S + 6]
        inner = np.arange(6, 6 * S)
        return Kc[np.ix_(ends, ends)] - Kc[np.ix_(ends, inner)] @ np.linalg.solve(
            Kc[np.ix_(inner, inner)], Kc[np.ix_(inner, ends)])

    k200, k400 = chain(200), chain(400)
    limit = k400 + (k400 - k200) / 3.0
    scale = np.abs(limit).max()
    assert np.abs(k400 - k200).max() / 3.0 < 1e-5 * scale      # the chain's own error at S = 400
    np.testing.assert_allclose(K, limit, rtol=0, atol=1e-9 * scale)


@pytest.mark.parametrize("tapered,uniform", [(tapered_pbeam, uniform_pbeam), (tapered_pbeaml, uniform_pbeaml)],
                         ids=["PBEAM with a station", "PBEAML BAR"])
def test_tapered_decks_converge_to_the_limit_of_fine_uniform_section_decks(tmp_path, tapered, uniform):
    """Modes of a tapered cantilever: fine decks of uniform sections (160 and 320 elements,
    the section at each element's middle, error O(1 / h^2)) extrapolate to the continuous
    beam, their estimated error below 1e-5 of it. Forty tapered CBEAMs agree with that limit
    to 1e-5 in the first six modes; at ten elements the mesh (cubic shape functions, not the
    section) limits them to 5e-4, ten times closer than ten uniform sections."""
    m = 160
    f_m = frequencies(tmp_path, cantilever(m, uniform), "fine.bdf")
    f_2m = frequencies(tmp_path, cantilever(2 * m, uniform), "finer.bdf")
    limit = f_2m + (f_2m - f_m) / 3.0                  # Richardson, O(h^2)
    assert (np.abs(f_2m - f_m) / 3.0 / limit < 1e-5).all()
    np.testing.assert_allclose(frequencies(tmp_path, cantilever(40, tapered), "taper40.bdf"), limit, rtol=1e-5)
    f10 = frequencies(tmp_path, cantilever(N_ELEM, tapered), "taper10.bdf")
    np.testing.assert_allclose(f10, limit, rtol=5e-4)
    coarse = frequencies(tmp_path, cantilever(N_ELEM, uniform), "coarse.bdf")
    assert np.max(np.abs(coarse / limit - 1)) > 10 * np.max(np.abs(f10 / limit - 1))
