"""Massless directions that are no single DOF (issue 24, acceptance 4).

A CBAR's coupled mass has no torsional inertia: on an inclined bar the rotation about the
bar's axis carries no mass, and that direction mixes three rotation DOFs. Every mode that
carries mass can be asked for; each is checked against the eigen-equation itself
(``K x = lambda M x``) and against the solver's other algorithm (the inverted problem,
which never condenses anything) where the two overlap.
"""

import numpy as np
import pytest

from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf


def inclined_truss_deck() -> str:
    """A cantilevered two-bay space truss of inclined CBARs (face and body diagonals) with
    NASTRAN's coupled mass, two tip masses; 30 free grids = 180 DOFs."""
    pts = {}
    for f in range(3):
        for c, (y, z) in enumerate([(0.0, 0.0), (0.3, 0.0), (0.3, 0.3), (0.0, 0.3)]):
            pts[10 * f + c + 1] = (0.5 * f, y, z)
    bars = []
    for f in range(2):
        for c in range(4):
            a, b = 10 * f + c + 1, 10 * (f + 1) + c + 1
            bars += [(a, b), (a, 10 * (f + 1) + (c + 1) % 4 + 1)]  # longeron and face diagonal
        bars.append((10 * f + 1, 10 * (f + 1) + 3))                  # body diagonal
    for c in range(4):
        bars.append((20 + c + 1, 20 + (c + 1) % 4 + 1))                # tip frame
    lines = ["SOL 103", "CEND", "SUBCASE 1", "  SPC = 1", "BEGIN BULK", "PARAM,COUPMASS,1",
             "MAT1,1,7.e10,,0.33,2700.", "PBAR,1,1,1.2e-4,1.5e-8,1.5e-8,3.e-8"]
    lines += [f"GRID,{n},,{x:.4f},{y:.4f},{z:.4f}" for n, (x, y, z) in pts.items()]
    for e, (a, b) in enumerate(bars, start=1):
        # each bar in two elements: the mid grid has one bar axis, and the rotation about it
        # carries no mass (at a corner the other bars' rotary inertia gives it some)
        d = np.subtract(pts[b], pts[a])
        v = np.cross(d, [0.3, 0.4, 1.0])
        mid = 100 + e
        x, y, z = (np.add(pts[a], pts[b]) / 2).tolist()
        lines.append(f"GRID,{mid},,{x:.4f},{y:.4f},{z:.4f}")
        for k, (p, q) in enumerate([(a, mid), (mid, b)]):
            lines.append(f"CBAR,{2 * e + k},1,{p},{q},{v[0]:.4f},{v[1]:.4f},{v[2]:.4f}")
    lines += ["CONM2,901,21,,0.5", "CONM2,902,23,,0.8", "SPC1,1,123456,1,2,3,4", "ENDDATA"]
    return "\n".join(lines) + "\n"


@pytest.fixture(scope="module")
def truss(tmp_path_factory):
    path = tmp_path_factory.mktemp("deck") / "inclined.bdf"
    path.write_text(inclined_truss_deck())
    model, info = read_bdf(path)
    return path, model, info


def test_every_mode_with_mass_can_be_asked_for(truss):
    _, model, info = truss
    system = assemble(model, autospc=info.autospc)
    M = system.M.toarray()
    K = system.K.toarray()
    # the number of directions with mass: the rank of M scaled to a unit diagonal
    has = np.diag(M) > 0
    d = 1 / np.sqrt(np.diag(M)[has])
    Mm = M[np.ix_(has, has)] * d[:, None] * d[None, :]
    rank = int(np.sum(np.linalg.eigvalsh(Mm) > 1e-10))
    assert rank < int(has.sum())  # massless directions that are not whole DOFs exist
    ref = solve_modes(system, n_modes=system.n_dof // 3).frequencies_hz  # inverted problem
    for n in range(1, rank + 1):
        modes = solve_modes(system, n_modes=n)
        assert len(modes) == n
        np.testing.assert_allclose(modes.frequencies_hz[:len(ref)], ref[:n], rtol=1e-9)
    # beyond: the rank, and each mode satisfies K x = lambda M x, M-orthonormal
    modes = solve_modes(system, n_modes=system.n_dof)
    assert len(modes) == rank
    X, lam = modes.shapes, modes.omega**2
    res = np.linalg.norm(K @ X - (M @ X) * lam, axis=0) / np.linalg.norm(K @ X, axis=0)
    assert res.max() < 1e-8
    np.testing.assert_allclose(X.T @ M @ X, np.eye(rank), atol=1e-9)


def test_modes_cli_gives_all_the_modes_and_says_how_many_exist(truss, capsys):
    from trussid.cli import main

    path, model, info = truss
    assert main(["modes", str(path), "--n", "180"]) == 0
    out = capsys.readouterr().out
    rank = len(solve_modes(model, n_modes=180, autospc=info.autospc))
    assert rank < 180
    assert f"only {rank} modes exist (asked for 180)" in out
