"""Craig-Bampton component modes on scalar points (NASTRAN ASET/OMIT + QSET; issue 33).

The reduced model keeps the boundary (a-set) DOFs and one generalized coordinate per Q-set
scalar point; its modes, as many as the a-set and Q-set hold, are checked against a
Craig-Bampton reduction computed here with numpy/scipy from the unreduced matrices.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as la

from trussid.fem import ALUMINIUM, Model, ModelError, Section
from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf

TWO_PI = 2.0 * math.pi


def hand_craig_bampton(K: np.ndarray, M: np.ndarray, boundary: np.ndarray, n_q: int) -> np.ndarray:
    """Frequencies [Hz] of the Craig-Bampton model: static shapes plus the lowest ``n_q``
    fixed-interface modes, eigenvalues of ``G^T K G``, ``G^T M G`` (dense, textbook)."""
    b, o = np.flatnonzero(boundary), np.flatnonzero(~boundary)
    psi = -la.solve(K[np.ix_(o, o)], K[np.ix_(o, b)], assume_a="pos")
    _, phi = la.eigh(K[np.ix_(o, o)], M[np.ix_(o, o)], subset_by_index=[0, n_q - 1])
    G = np.zeros((len(K), len(b) + n_q))
    G[b, np.arange(len(b))] = 1.0
    G[np.ix_(o, np.arange(len(b)))] = psi
    G[np.ix_(o, len(b) + np.arange(n_q))] = phi
    lam = la.eigh(G.T @ K @ G, G.T @ M @ G, eigvals_only=True)
    return np.sqrt(np.abs(lam)) / TWO_PI


def frame(n_q: int | None) -> Model:
    """A cantilevered tube of 12 elements, consistent mass; the tip node is the a-set, every
    other free DOF omitted, ``n_q`` component modes on scalar points 101...."""
    m = Model(mass="consistent")
    ids = np.arange(1, 14)
    m.add_nodes(ids, np.c_[np.linspace(0, 1.2, 13), 0.1 * np.sin(np.linspace(0, 3, 13)), np.zeros(13)])
    m.add_beams(ids[:-1], np.c_[ids[:-1], ids[1:]], Section.tube(0.01, 0.001), ALUMINIUM, orient=[0, 0, 1])
    m.fix(1)
    if n_q is not None:
        m.omit(ids[1:-1])
        q = 101 + np.arange(n_q)
        m.add_scalar_points(q)
        m.add_generalized_coordinates(q)
    return m


@pytest.mark.parametrize("n_q", [1, 3, 8])
def test_reduced_modes_equal_a_craig_bampton_reduction_done_by_hand(n_q):
    full = assemble(frame(None))
    K, M = full.K.toarray(), full.M.toarray()
    tip = (full.dofs // 6) == 12                      # the a-set: the tip node's six DOFs
    expected = hand_craig_bampton(K, M, tip, n_q)
    reduced = assemble(frame(n_q))
    assert reduced.n_dof == 6 + n_q
    modes = solve_modes(reduced, n_modes=50)
    assert len(modes) == 6 + n_q                      # as many modes as the a- and q-sets hold
    np.testing.assert_allclose(modes.frequencies_hz, expected, rtol=1e-9)


def test_with_every_component_mode_the_reduction_is_the_unreduced_model():
    """66 omitted DOFs, 66 component modes (and 4 points more, left out): exact."""
    exact = solve_modes(frame(None), n_modes=12).frequencies_hz
    system = assemble(frame(70))
    assert system.n_dof == 6 + 66 and [a for a, _ in system.autospc] == [167, 168, 169, 170]
    np.testing.assert_allclose(solve_modes(system, n_modes=12).frequencies_hz, exact, rtol=1e-10)


def test_the_generalized_coordinates_carry_the_modal_amplitudes():
    """Each scalar point's DOF in the expanded shape is the amplitude of its component mode."""
    modes = solve_modes(frame(3), n_modes=9)
    system = assemble(frame(3))
    q_cols = np.arange(6, 9)
    np.testing.assert_allclose(modes.shapes_full[system.dofs[q_cols]], modes.shapes[q_cols], atol=1e-14)


def test_a_scalar_point_with_an_element_cannot_hold_component_modes():
    m = frame(2)
    m.add_springs([99], [101], [1.0, 0, 0, 0, 0, 0])
    with pytest.raises(ModelError, match="generalized coordinate node 101 ux: an element acts on it"):
        assemble(m)


BAR = """MAT1,1,70.+9,,0.3,2700.
PBAR,1,1,1.-4,2.-9,3.-9,4.-9
""" + "".join(f"GRID,{i},,{0.25 * (i - 1)!r},{0.05 * (i - 1) ** 2!r},0.\n" for i in range(1, 6)) + "".join(
    f"CBAR,{e},1,{e},{e + 1},0.,0.,1.\n" for e in range(1, 5)) + "SPC1,1,123456,1\nPARAM,COUPMASS,1\n"


@pytest.mark.parametrize("aset_q", ["", "ASET1,0,101,THRU,103\n"], ids=["QSET only", "Q points also in ASET1"])
def test_deck_with_aset_and_qset_on_three_scalar_points_has_nine_modes(tmp_path, aset_q):
    """The field's case: a BAR model with ASET plus QSET on three SPOINTs. Against the same
    deck without ASET/QSET, reduced by hand."""
    plain = tmp_path / "plain.bdf"
    plain.write_text("BEGIN BULK\n" + BAR + "ENDDATA\n")
    model, info = read_bdf(plain)
    full = assemble(model, autospc=info.autospc)
    expected = hand_craig_bampton(full.K.toarray(), full.M.toarray(), (full.dofs // 6) == 4, 3)

    red = tmp_path / "cb.bdf"
    red.write_text("SOL 103\nCEND\nBEGIN BULK\n" + BAR + "ASET1,123456,5\n" + aset_q + "SPOINT,101,THRU,103\n"
                   "QSET1,0,101,THRU,103\nEIGRL,1,,,20\nENDDATA\n")
    model, info = read_bdf(red)
    modes = solve_modes(model, n_modes=20, autospc=info.autospc)
    assert len(modes) == 9
    np.testing.assert_allclose(modes.frequencies_hz, expected, rtol=1e-9)
    assert any("Craig-Bampton" in note for note in info.notes)
