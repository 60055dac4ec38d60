"""Modes of a preloaded structure: NASTRAN-95 rigid format 13 (normal modes with differential
stiffness).

The deck's static subcase (its LOAD set) is solved on the model; each frame element's axial
force N then gives its differential (geometric) stiffness, which is added to the model, so
that the modes are those of ``K + K_D``. Only frame and rod elements carry it here (the
elements trussid reads); pressure-stiffness elements (CPSE2/3/4) are refused, naming them.

The differential stiffness of a frame element under an axial force N (tension positive) is
the consistent one of cubic bending shape functions (Przemieniecki, Theory of Matrix
Structural Analysis, sec. 15.2; NASTRAN-95 Theoretical Manual 5.8 for the BAR): in each
bending plane ``N / (30 L) [[36, 3L, -36, 3L], [3L, 4L^2, -3L, -L^2], ...]``; a rod's is
``N / L`` on its transverse translations. NASTRAN-95 computes it in two steps (subcase 1:
static, subcase 2: the "second-order" static solution with the same load); for a linear
preload these coincide with the one-step form used here.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.elements import local_axes, to_global
from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.nastran.deck import BdfInfo, case_int
from trussid.fem.static import solve_static

__all__ = ["frame_differential_stiffness"]


def frame_differential_stiffness(L: np.ndarray, N: np.ndarray, rod: np.ndarray) -> np.ndarray:
    """(n, 12, 12) differential stiffness in element axes of frames (or rods) of length ``L``
    under axial force ``N`` (tension positive) [N/m]; DOFs (ux, uy, uz, rx, ry, rz) per end."""
    L, N, rod = (np.asarray(a) for a in (L, N, rod))
    n = len(L)
    K = np.zeros((n, 12, 12))
    c = (N / (30.0 * L))[:, None, None]
    LL = L[:, None, None]
    one = np.ones((n, 1, 1))
    # (v1, rz1, v2, rz2) and (w1, ry1, w2, ry2): the second plane has the rotation sign flipped.
    for (t1, r1, t2, r2), s in (((1, 5, 7, 11), 1.0), ((2, 4, 8, 10), -1.0)):
        blk = np.concatenate([
            np.concatenate([36 * one, s * 3 * LL, -36 * one, s * 3 * LL], axis=2),
            np.concatenate([s * 3 * LL, 4 * LL**2, -s * 3 * LL, -LL**2], axis=2),
            np.concatenate([-36 * one, -s * 3 * LL, 36 * one, -s * 3 * LL], axis=2),
            np.concatenate([s * 3 * LL, -LL**2, -s * 3 * LL, 4 * LL**2], axis=2)], axis=1) * c
        idx = np.array([t1, r1, t2, r2])
        K[:, idx[:, None], idx[None, :]] = blk
    if rod.any():
        k = (N[rod] / L[rod])[:, None, None] * np.array([[1.0, -1.0], [-1.0, 1.0]])
        K[rod] = 0.0
        for t1, t2 in ((1, 7), (2, 8)):
            K[np.ix_(np.flatnonzero(rod), [t1, t2], [t1, t2])] = k
    return K


def _load_vector(bdf, model: Model, nodes, sid: int, rect_frame) -> np.ndarray:
    """Full (6 n_nodes) load vector of FORCE/FORCE1/MOMENT/MOMENT1 set ``sid`` (basic axes)."""
    f = np.zeros(6 * len(model.node_ids))
    pos = {int(n): i for i, n in enumerate(model.node_ids)}
    loads = bdf.loads.get(sid, [])
    if not loads:
        raise ModelError(f"case control LOAD = {sid}: no FORCE, FORCE1, MOMENT or MOMENT1 has set {sid}")
    for ld in loads:
        card = f"{ld.type} {sid}"
        if ld.type not in ("FORCE", "FORCE1", "MOMENT", "MOMENT1"):
            raise ModelError(f"{card}: a preload given by {ld.type} is not supported (FORCE, FORCE1, MOMENT, "
                             f"MOMENT1 are)")
        g = int(ld.node)
        if g not in pos:
            raise ModelError(f"{card}: grid {g} is not defined")
        if ld.type in ("FORCE1", "MOMENT1"):
            a, b = nodes.coords([ld.g1, ld.g2], ld.type, [sid, sid])
            d = b - a
            if not np.linalg.norm(d) > 0:
                raise ModelError(f"{card}: grids {ld.g1} and {ld.g2} coincide: no direction")
            vec = ld.mag * d / np.linalg.norm(d)
        else:
            cid = int(ld.cid or 0)
            xyz = np.asarray(ld.xyz, float)
            if cid:
                xyz = rect_frame(bdf, cid, card).T @ xyz
            vec = ld.mag * xyz
        off = 0 if ld.type.startswith("FORCE") else 3
        f[6 * pos[g] + off:6 * pos[g] + off + 3] += vec
    return f


def add_preload_stiffness(bdf, model: Model, nodes, info: BdfInfo, rect_frame) -> None:
    """Solve the static subcase and add the frames' differential stiffness to ``model``.

    ``nodes`` is the reader's node table and ``rect_frame(bdf, cid, card)`` its rectangular
    system lookup (the reader imports this module, so they are passed in).
    """
    chosen = case_int(bdf, "LOAD")
    if not chosen:
        raise ModelError("SOL 13 (normal modes with differential stiffness): no LOAD in the case control "
                         "for the static preload")
    sid = int(chosen[0])
    b = model.beams
    if len(b) == 0:
        raise ModelError("SOL 13: no frame or rod elements to carry a differential stiffness")
    f = _load_vector(bdf, model, nodes, sid, rect_frame)
    u = solve_static(model, f, autospc=info.autospc).reshape(-1, 6)
    pos = {int(n): i for i, n in enumerate(model.node_ids)}
    ia = np.array([pos[int(n)] for n in b.nodes[:, 0]])
    ib = np.array([pos[int(n)] for n in b.nodes[:, 1]])
    xa, xb = model.xyz[ia], model.xyz[ib]
    L, R = local_axes(xa, xb, b.orient, b.ids)
    e = R[:, 0, :]
    N = b.E * b.A / L * np.einsum("ij,ij->i", e, u[ib, :3] - u[ia, :3])
    KD = to_global(frame_differential_stiffness(L, N, np.asarray(b.rod, bool)), R)
    model.add_matrices(b.ids, b.nodes, K=0.5 * (KD + KD.transpose(0, 2, 1)), label="differential stiffness")
    info.notes.append(f"SOL 13: modes of the structure preloaded by LOAD = {sid} (static solution, then the "
                      f"differential stiffness of {len(b)} frame/rod elements from their axial forces, "
                      f"{N.min():.6g} .. {N.max():.6g}), as NASTRAN-95 rigid format 13")
