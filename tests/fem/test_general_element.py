"""GENEL in its documented forms (issue 33): UI and UD lists over continuations, stiffness K
or flexibility Z with the rigid-body matrix S, on grid components and scalar points.

The independent answer is a hand-assembled model: a GENEL written from the textbook
flexibility of a cantilever (root = UD, tip = UI, S the rigid transfer root -> tip) is the
beam element itself, so a chain of such GENELs with point masses has the modes of the same
chain of massless CBARs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from trussid.fem import ModelError
from trussid.fem.general_element import general_element_stiffness, lower_by_columns
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf

# Chosen so that every flexibility term and S term is exact in 8 characters (9.-3, 4.5-3...).
E, G, A, I1, I2, J, L = 1e6, 1e6, 3e-3, 1e-3, 2e-3, 3e-3, 3.0


def cantilever_flexibility() -> np.ndarray:
    """Tip flexibility of a uniform Euler-Bernoulli cantilever along x, tip DOFs ux..rz;
    I1 bends in the x-y plane (about z), I2 in x-z (about y), as PBAR's I1, I2."""
    Z = np.zeros((6, 6))
    Z[0, 0] = L / (E * A)
    Z[3, 3] = L / (G * J)
    Z[1, 1], Z[1, 5], Z[5, 5] = L**3 / (3 * E * I1), L**2 / (2 * E * I1), L / (E * I1)
    Z[2, 2], Z[2, 4], Z[4, 4] = L**3 / (3 * E * I2), -(L**2) / (2 * E * I2), L / (E * I2)
    return Z + np.triu(Z, 1).T


def rigid_transfer() -> np.ndarray:
    """S: tip DOFs of a rigid motion per unit root DOF (u_tip = u_root + theta x L e_x)."""
    S = np.eye(6)
    S[1, 5] = L
    S[2, 4] = -L
    return S


def lower_terms(A: np.ndarray) -> list[float]:
    return [A[i, j] for j in range(len(A)) for i in range(j, len(A))]


def fixed_field(name: str, fields: list[str]) -> str:
    """An entry in 8-character fields: 8 data fields on the first line, then continuations."""
    out, line = [], name.ljust(8)
    for k, v in enumerate(fields):
        if k and k % 8 == 0:
            out.append(line.rstrip())
            line = " " * 8
        line += str(v)[:8].ljust(8)
    out.append(line.rstrip())
    return "\n".join(out) + "\n"


def num(x: float, layout: str) -> str:
    """A real as written: full precision in free field, 8 characters (NASTRAN's 1.5-3 form,
    exact for this deck's flexibility terms) in fixed fields."""
    if layout == "free":
        return repr(float(x))
    m, e = f"{x:.3e}".split("e")
    m = m.rstrip("0")
    return f"{m}{int(e):+d}" if x else "0."


def genel_fields(eid: int, root: int, tip: int, kind: str, layout: str) -> str:
    """GENEL with UI = the tip's six components, UD = the root's, K or Z and S, in the QRG's
    layout: ``layout`` "fixed" (8-character fields) or "free" (commas, the same positions)."""
    M = cantilever_flexibility() if kind == "Z" else np.linalg.inv(cantilever_flexibility())
    fields = [str(eid), ""] + sum(([str(tip), str(c)] for c in range(1, 7)), [])
    fields += [""] * (-(len(fields) - 8) % 8)              # UD starts a continuation
    fields += ["UD", ""] + sum(([str(root), str(c)] for c in range(1, 7)), [])
    fields += [""] * (-(len(fields) - 8) % 8)
    fields += [kind] + [num(x, layout) for x in lower_terms(M)]
    fields += [""] * (-(len(fields) - 8) % 8)
    fields += ["S"] + [num(x, layout) for x in rigid_transfer().ravel()]
    if layout == "fixed":
        return fixed_field("GENEL", fields)
    lines, k = ["GENEL," + ",".join(fields[:8])], 8
    while k < len(fields):
        lines.append("," + ",".join(fields[k:k + 8]))
        k += 8
    return "\n".join(lines) + "\n"


GRIDS = "".join(f"GRID,{i},,{L * (i - 1)!r},0.,0.\n" for i in range(1, 6)) + "SPC1,1,123456,1\n" + "".join(
    f"CONM2,{100 + i},{i},,{0.3 + 0.1 * i!r},,,,\n,{1e-4 * i!r},,{2e-4!r},,,{3e-4!r}\n" for i in range(2, 6))


def frequencies(tmp_path, bulk: str, name: str, n: int = 12) -> np.ndarray:
    p = tmp_path / name
    p.write_text("BEGIN BULK\n" + bulk + "ENDDATA\n")
    model, info = read_bdf(p)
    return solve_modes(model, n_modes=n, autospc=info.autospc).frequencies_hz


@pytest.mark.parametrize("kind,layout", [("Z", "fixed"), ("Z", "free"), ("K", "free")])
def test_genel_chain_equals_the_chain_of_massless_bars(tmp_path, kind, layout):
    bars = (f"MAT1,1,{E!r},{G!r},,0.\nPBAR,1,1,{A!r},{I1!r},{I2!r},{J!r}\n"
            + "".join(f"CBAR,{e},1,{e},{e + 1},0.,1.,0.\n" for e in range(1, 5)))
    genels = "".join(genel_fields(e, e, e + 1, kind, layout) for e in range(1, 5))
    expected = frequencies(tmp_path, GRIDS + bars, "bars.bdf")
    np.testing.assert_allclose(frequencies(tmp_path, GRIDS + genels, "genel.bdf"), expected, rtol=1e-9)


def test_genel_stiffness_is_the_beam_element_exactly():
    """At full precision the element matrix equals the Euler-Bernoulli beam's (hand)."""
    K = general_element_stiffness(cantilever_flexibility(), "Z", rigid_transfer(), "GENEL 1")
    k = E * I1 / L**3
    # bending in x-y on (uy, rz) of tip then root: the textbook 4x4
    idx = [1, 5, 7, 11]
    beam = k * np.array([[12, -6 * L, -12, -6 * L], [-6 * L, 4 * L**2, 6 * L, 2 * L**2],
                         [-12, 6 * L, 12, 6 * L], [-6 * L, 2 * L**2, 6 * L, 4 * L**2]])
    np.testing.assert_allclose(K[np.ix_(idx, idx)], beam, rtol=1e-10, atol=1e-6 * k)
    np.testing.assert_allclose(K[0, [0, 6]], [E * A / L, -E * A / L], rtol=1e-12)
    # and a rigid motion strains nothing
    np.testing.assert_allclose(K @ np.r_[rigid_transfer() @ np.arange(1.0, 7.0), np.arange(1.0, 7.0)], 0.0,
                               atol=1e-9 * np.abs(K).max())


def test_lower_triangle_by_columns():
    np.testing.assert_array_equal(lower_by_columns([1, 2, 3, 4, 5, 6], 3, "G"),
                                  [[1, 2, 3], [2, 4, 5], [3, 5, 6]])


def test_genel_on_scalar_points_equals_a_scalar_spring(tmp_path):
    """UI = scalar point 11 (blank component), UD = scalar point 12, K = [k], S = [1]: the
    spring k between them, as a CELAS4; grounded mass and spring elsewhere."""
    k, m1, m2, kg = 400.0, 2.0, 3.0, 1000.0
    rest = f"SPOINT,11,12\nCMASS4,1,{m1},11\nCMASS4,2,{m2},12\nCELAS4,3,{kg},12\n"
    genel = f"GENEL,7,,11,,,,,\n,UD,,12,0,,,,\n,K,{k!r},,,,,,\n,S,1.\n"
    np.testing.assert_allclose(frequencies(tmp_path, rest + genel, "g.bdf", 2),
                               frequencies(tmp_path, rest + f"CELAS4,4,{k!r},11,12\n", "c.bdf", 2), rtol=1e-12)


@pytest.mark.parametrize("bulk,message", [
    ("GENEL,7,,1,1,2,1\n,K,1.,,3.\n", "GENEL 7: a blank field inside the K terms"),
    ("GENEL,7,,1,1,2,1\n,Z,1.,2.\n", "GENEL 7: Z needs 3 terms for 2 UI DOFs, got 2"),
    ("GENEL,7,,1,1,2,1\n,UD,,3,1\n,K,1.,0.,1.\n", "GENEL 7: UD DOFs given without the S matrix"),
    ("GENEL,7,,1,1,2,1\n,Z,1.,1.,1.\n", "GENEL 7: the flexibility matrix Z is singular"),
    ("GENEL,7,,1,1,2,1\n", "GENEL 7: no K or Z matrix"),
    ("GENEL,7,,1,1,2,x\n,K,1.,0.,1.\n", "GENEL 7: malformed entry"),
])
def test_bad_genel_is_named(tmp_path, bulk, message):
    p = tmp_path / "bad.bdf"
    p.write_text("BEGIN BULK\n" + "".join(f"GRID,{i},,{i}.,0.,0.\n" for i in (1, 2, 3)) + bulk + "ENDDATA\n")
    with pytest.raises(ModelError, match=message):
        read_bdf(p)
