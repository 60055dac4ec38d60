"""NASTRAN coordinate systems resolved into the basic system: CORD1R/C/S (defined by three
grids) and CORD2R/C/S (by three points in another system), each possibly defined in another,
and the grids' positions (given in their CP systems) into basic coordinates.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.nastran.cards import Card, integer, integer_or_blank, real_or_blank
from trussid.fem.nastran.records import BASIC, Coord

__all__ = ["resolve_coordinates"]


def _coord_points(card: Card, base: int) -> np.ndarray:
    return np.array([real_or_blank(card, base + m, "coordinate", 0.0) for m in range(9)]).reshape(3, 3)


def _from_points(cid: int, kind: str, a: np.ndarray, b: np.ndarray, c: np.ndarray, card: Card) -> Coord:
    """A system from its origin A, a point B on z and a point C in the x-z plane (basic)."""
    k = b - a
    nk = np.linalg.norm(k)
    if not nk > 0:
        raise card.error(None, f"system {cid}: points A and B coincide")
    k = k / nk
    j = np.cross(k, c - a)
    nj = np.linalg.norm(j)
    if not nj > 1e-12 * max(nk, np.linalg.norm(c - a)):
        raise card.error(None, f"system {cid}: point C is on the z axis (A-B)")
    j = j / nj
    return Coord(cid, kind, a, np.cross(j, k), j, k)


def resolve_coordinates(cards: list, nodes: dict, xyz_local: np.ndarray) -> tuple:
    """Coordinate systems in basic and the grids' basic positions (systems may be defined in
    other systems, CORD1x by grids whose positions are in yet other systems: resolved until
    nothing changes; a cycle or an undefined system is an error naming the entry)."""
    coords = {0: BASIC}
    pending = []  # (cid, kind, card, how)
    for card in cards:
        kind = card.name[-1]
        if card.name.startswith("CORD2"):
            cid = integer(card, 1, "CID")
            pending.append((cid, kind, card, ("2", integer_or_blank(card, 2, "RID", 0), _coord_points(card, 3))))
        else:
            for base in (1, 5):
                if card.get(base):
                    cid = integer(card, base, "CID")
                    g = [integer(card, base + m, "G") for m in (1, 2, 3)]
                    pending.append((cid, kind, card, ("1", g)))
    ids = np.fromiter(nodes.keys(), dtype=np.int64, count=len(nodes))
    cp = np.fromiter((g.cp for g in nodes.values()), dtype=np.int64, count=len(nodes))
    xyz = np.array(xyz_local, float).reshape(-1, 3)
    done = cp == 0
    pos = {int(n): i for i, n in enumerate(ids)} if pending or not done.all() else {}
    seen = set()
    for cid, _k, card, _h in pending:
        if cid in seen or cid == 0:
            raise card.error(1, f"coordinate system {cid} is defined twice" if cid else "CID 0 is the basic system")
        seen.add(cid)
    while True:
        progress = False
        for c in list(np.unique(cp[~done])):
            if int(c) in coords:
                sel = (~done) & (cp == c)
                xyz[sel] = coords[int(c)].to_basic(xyz[sel])
                done |= sel
                progress = True
        rest = []
        for item in pending:
            cid, kind, card, how = item
            if how[0] == "2":
                rid = how[1]
                if rid in coords:
                    p = coords[rid].to_basic(how[2])
                    coords[cid] = _from_points(cid, kind, p[0], p[1], p[2], card)
                    progress = True
                    continue
            else:
                idx = []
                for g in how[1]:
                    if g not in pos:
                        raise card.error(None, f"system {cid}: grid {g} is not defined")
                    idx.append(pos[g])
                if all(done[i] for i in idx):
                    coords[cid] = _from_points(cid, kind, xyz[idx[0]], xyz[idx[1]], xyz[idx[2]], card)
                    progress = True
                    continue
            rest.append(item)
        pending = rest
        if not progress:
            break
    if pending:
        cid, _k, card, how = pending[0]
        if how[0] == "2" and how[1] not in {p[0] for p in pending}:
            raise card.error(2, f"system {cid}: reference system RID={how[1]} is not defined")
        raise card.error(None, f"cannot resolve coordinate system {cid} (its definition refers to itself "
                               f"through other systems or grids)")
    if not done.all():
        i = int(np.flatnonzero(~done)[0])
        raise ModelError(f"GRID {ids[i]}: coordinate system CP={cp[i]} is not defined")
    return coords, xyz
