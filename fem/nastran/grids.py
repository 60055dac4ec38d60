"""Grids of a deck as the reader sees them: node ids, basic coordinates and displacement
frames (GRID CD, resolved through the deck's coordinate systems), looked up with messages
that name the referring entry; and the coordinate-system helpers the translation uses.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.errors import ModelError

__all__ = ["NodeTable", "grid_nodes", "coord_axes", "rect_frame", "dof_matrix"]


class NodeTable:
    """Node id -> index and coordinates, with lookups that name the referring card.

    ``frames`` holds each grid's displacement frame (rows = axes in basic), or None when
    every grid uses the basic system.
    """

    def __init__(self, ids: np.ndarray, xyz: np.ndarray, frames: np.ndarray | None = None):
        self.ids, self.xyz, self.frames = ids, xyz, frames
        self.order = np.argsort(ids, kind="stable")
        self.sorted = ids[self.order]

    def index(self, ids, card: str, eids) -> np.ndarray:
        ids = np.asarray(ids, dtype=np.int64)
        pos = np.searchsorted(self.sorted, ids.ravel())
        pos_c = np.minimum(pos, len(self.sorted) - 1)
        ok = self.sorted[pos_c] == ids.ravel()
        if not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            eid = np.broadcast_to(np.asarray(eids)[:, None] if ids.ndim == 2 else np.asarray(eids),
                                  ids.shape).ravel()[i]
            raise ModelError(f"{card} {eid}: grid {ids.ravel()[i]} is not defined")
        return self.order[pos_c].reshape(ids.shape)

    def coords(self, ids, card: str, eids) -> np.ndarray:
        return self.xyz[self.index(ids, card, eids)]

    def frame(self, ids, card: str, eids) -> np.ndarray:
        """(..., 3, 3) displacement frames of grids ``ids`` (identity for basic)."""
        idx = self.index(ids, card, eids)
        if self.frames is None:
            return np.broadcast_to(np.eye(3), idx.shape + (3, 3)).copy()
        return self.frames[idx]

    def dof_vectors(self, ids, comps, card: str, eids) -> np.ndarray:
        """(n, 6) global DOF direction of component ``comps`` (1-6) of each grid.

        A scalar element on component c of a grid with displacement frame F acts along
        row c of F (translation or rotation axis) in basic coordinates.
        """
        comps = np.asarray(comps, dtype=np.int64)
        F = self.frame(ids, card, eids)
        out = np.zeros((len(comps), 6))
        rows = F[np.arange(len(comps)), (comps - 1) % 3]
        rot = comps > 3
        out[~rot, :3] = rows[~rot]
        out[rot, 3:] = rows[rot]
        return out


def grid_nodes(bdf):
    """GRID ids, basic coordinates and displacement frames (GRDSET defaults applied and
    coordinate systems resolved by :func:`trussid.fem.nastran.bulk.build_bulk`).

    A displacement system CD gives the grid's DOFs along that system's axes at the grid (for
    cylindrical and spherical systems these depend on the position): returned as frames
    whose rows are the axes in basic.
    """
    if not bdf.nodes:  # scalar points only (checked by the caller)
        return np.zeros(0, dtype=np.int64), np.zeros((0, 3)), None
    if bdf.grdset is not None and bdf.grdset.seid:
        raise ModelError("GRDSET: superelements (SEID) are not supported")
    ids = np.fromiter(bdf.nodes.keys(), dtype=np.int64, count=len(bdf.nodes))
    cd = np.fromiter((g.cd for g in bdf.nodes.values()), dtype=np.int64, count=len(ids))
    seid = [g.nid for g in bdf.nodes.values() if g.seid]
    if seid:
        raise ModelError(f"GRID {seid[0]}: superelements (SEID) are not supported")
    for nid, c in zip(ids[cd > 0], cd[cd > 0]):
        if c not in bdf.coords:
            raise ModelError(f"GRID {nid}: coordinate system CD={c} is not defined")
    xyz = bdf.xyz_basic
    frames = None
    if (cd > 0).any():
        frames = np.broadcast_to(np.eye(3), (len(ids), 3, 3)).copy()
        for c in np.unique(cd[cd > 0]):
            sel = cd == c
            frames[sel] = coord_axes(bdf.coords[int(c)], xyz[sel], f"GRID {ids[sel][0]} (CD={c})")
    return ids, xyz, frames


def coord_axes(coord, xyz: np.ndarray, label: str) -> np.ndarray:
    """Local axes (rows, in basic) of a NASTRAN coordinate system at basic points ``xyz``.

    ``coord`` has ``cid``, ``Type`` ("R", "C", "S"), ``origin`` and axes ``i``, ``j``, ``k``
    in basic (:class:`trussid.fem.nastran.bulk.Coord`).

    Rectangular: the system's axes. Cylindrical (r, theta, z) and spherical (r, theta,
    phi): the unit vectors of the coordinate directions at the point, which NASTRAN uses as
    the displacement directions of a grid with that CD. On the axis (cylindrical) or at the
    origin (spherical) those directions are undefined and the grid is refused.
    """
    R = np.vstack([coord.i, coord.j, coord.k]).astype(float)  # rows: system axes in basic
    n = len(xyz)
    if coord.Type == "R":
        return np.broadcast_to(R, (n, 3, 3)).copy()
    p = (np.asarray(xyz, float) - np.asarray(coord.origin, float)) @ R.T  # local rectangular
    rho = np.hypot(p[:, 0], p[:, 1])
    scale = max(float(np.abs(p).max(initial=0.0)), 1.0)
    if coord.Type == "C":
        if (rho <= 1e-12 * scale).any():
            raise ModelError(f"{label}: grid on the axis of cylindrical system {coord.cid}: radial "
                             f"and tangential directions are undefined")
        c, s = p[:, 0] / rho, p[:, 1] / rho
        loc = np.stack([np.stack([c, s, 0 * c], 1), np.stack([-s, c, 0 * c], 1),
                        np.broadcast_to([0.0, 0.0, 1.0], (n, 3))], axis=1)
    else:
        r = np.linalg.norm(p, axis=1)
        if (rho <= 1e-12 * scale).any():
            raise ModelError(f"{label}: grid on the polar axis of spherical system {coord.cid}: "
                             f"its directions are undefined")
        ct, st = p[:, 2] / r, rho / r
        cp_, sp_ = p[:, 0] / rho, p[:, 1] / rho
        loc = np.stack([np.stack([st * cp_, st * sp_, ct], 1), np.stack([ct * cp_, ct * sp_, -st], 1),
                        np.stack([-sp_, cp_, 0 * cp_], 1)], axis=1)
    return loc @ R


def rect_frame(bdf, cid: int, card: str) -> np.ndarray:
    """Rows = axes of rectangular coordinate system ``cid`` in basic coordinates."""
    if cid == 0:
        return np.eye(3)
    if cid not in bdf.coords:
        raise ModelError(f"{card}: coordinate system {cid} is not defined")
    coord = bdf.coords[cid]
    if coord.Type != "R":
        raise ModelError(f"{card}: coordinate system {cid} is not rectangular (only CORD1R/CORD2R "
                         f"are supported here)")
    return np.vstack([coord.i, coord.j, coord.k]).astype(float)


def dof_matrix(nodes: NodeTable, dofs: list, card: str, eid: int) -> tuple[list, np.ndarray]:
    """(grids, A): A maps the grids' 6-DOF vectors (basic) to the listed (grid, component) DOFs."""
    grids = list(dict.fromkeys(g for g, _ in dofs))
    pos = {g: i for i, g in enumerate(grids)}
    spoints = getattr(nodes, "spoints", set())
    dofs = [(g, 1 if g in spoints and c == 0 else c) for g, c in dofs]  # a scalar point's DOF
    for g, c in dofs:
        if g in spoints and c != 1:
            raise ModelError(f"{card}: scalar point {g} has component 0 only, got {c}")
        if not 1 <= c <= 6:
            raise ModelError(f"{card}: component {c} of grid {g} must be 1-6 (0 or blank only on a scalar point)")
    vec = nodes.dof_vectors([g for g, _ in dofs], [c for _, c in dofs], card.split()[0], [eid] * len(dofs))
    A = np.zeros((len(dofs), 6 * len(grids)))
    for k, (g, _c) in enumerate(dofs):
        A[k, 6 * pos[g]:6 * pos[g] + 6] = vec[k]
    return grids, A
