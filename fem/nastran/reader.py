"""Translation of a parsed deck into a :class:`trussid.fem.Model` (:func:`read_bdf`).

This module assembles the model from the deck; each kind of entry is translated by the
module of its job: grids and coordinate frames (:mod:`~trussid.fem.nastran.grids`),
materials and line properties (:mod:`~trussid.fem.nastran.line_properties`), bars, beams
and rods (:mod:`~trussid.fem.nastran.line_elements`), springs, masses and general elements
(:mod:`~trussid.fem.nastran.scalar_elements`), rigid elements and MPCs
(:mod:`~trussid.fem.nastran.rigid`), supports and DOF sets
(:mod:`~trussid.fem.nastran.dof_sets`), direct matrices
(:mod:`~trussid.fem.nastran.matrices`), preload (:mod:`~trussid.fem.nastran.preload`) and
NASTRAN's element conventions (:mod:`~trussid.fem.nastran.conventions`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.model import Model
from trussid.fem.nastran.conventions import CONVENTIONS, nastran_mass_conventions
from trussid.fem.nastran.deck import (is_preload_run, BdfInfo, check_cards, parse_bdf, read_params,
                                      select_eigen)
from trussid.fem.nastran.dof_sets import add_dof_sets, add_spcs, scalar_points
from trussid.fem.nastran.grids import NodeTable, coord_axes, dof_matrix, grid_nodes, rect_frame
from trussid.fem.nastran.line_elements import add_bars, add_rods
from trussid.fem.nastran.line_properties import check_units, deck_materials, line_properties
from trussid.fem.nastran.matrices import add_direct_matrices
from trussid.fem.nastran.preload import add_preload_stiffness
from trussid.fem.nastran.rigid import add_mpcs, add_raw_rigid, add_rigid
from trussid.fem.nastran.scalar_elements import (add_conm1, add_conm2, add_genel, add_scalar_masses,
                                                 add_scalar_point_elements, add_springs, offset_spring_matrix)

# coord_axes and offset_spring_matrix are re-exported: code imports them from here.
__all__ = ['read_bdf', 'coord_axes', 'offset_spring_matrix']


# ======================================================================= reading
def read_bdf(path: str | os.PathLike, beam_theory: str | None = None,
             conventions: str = "nx") -> tuple[Model, BdfInfo]:
    """Read a NASTRAN bulk-data deck into a :class:`trussid.fem.Model`.

    Parameters
    ----------
    path : path-like
        A deck (.bdf/.dat/.nas...), with or without executive and case control.
    beam_theory : {"euler-bernoulli", "timoshenko"}, optional
        Override the theory chosen from the shear factors (see the module notes).
    conventions : {"nx", "msc"}
        Whose element conventions to follow where NASTRAN builds differ: the PBARL/PBEAML
        ROD shear factor is 0.9 with "nx" (NX/Simcenter, and the newer MSC builds: the
        default) and 6/7 with "msc" (an MSC 2012 build). Recorded in ``info.conventions``.

    Returns
    -------
    model : fem.Model
        Nodes in the deck's basic coordinates, everything in the deck's units, masses
        multiplied by WTMASS.
    info : BdfInfo

    Raises
    ------
    ModelError
        A missing or unreadable file, any card this reader does not translate (all such
        cards are listed with their counts; element entries such as shells and solids
        first), or a card it cannot translate faithfully (offsets, pin flags, tapered beams,
        scalar points...), naming the card.

    Notes
    -----
    Entries without effect on real modes (loads, tables, damping, aero model, output
    requests: :data:`IGNORED_CARDS`) are accepted and listed with their counts in
    ``info.ignored``. NASTRAN's own element conventions are reproduced where they differ
    from the textbook elements of :mod:`trussid.fem.elements` (see
    :func:`~trussid.fem.nastran.conventions.nastran_mass_conventions` and the PBARL/PBEAML
    ROD shear factor).

    Examples
    --------
    A deck of a 1 m steel cantilever (CBAR, 20 x 10 mm section), written here and read back;
    its first bending frequencies against Euler-Bernoulli (8.154 and 16.308 Hz):

    >>> import numpy as np
    >>> from pathlib import Path
    >>> from trussid.fem import read_bdf, solve_modes
    >>> grids = "".join(f"GRID,{i},,{0.25 * (i - 1)},0.,0.\\n" for i in range(1, 6))
    >>> bars = "".join(f"CBAR,{e},1,{e},{e + 1},0.,0.,1.\\n" for e in range(1, 5))
    >>> _ = Path("cantilever.bdf").write_text(
    ...     "SOL 103\\nCEND\\nBEGIN BULK\\nPARAM,COUPMASS,1\\nMAT1,1,200.+9,,0.3,7850.\\n"
    ...     "PBAR,1,1,2.-4,1.6667-9,6.6667-9,4.5776-9\\n" + grids + bars + "SPC1,1,123456,1\\nENDDATA\\n")
    >>> model, info = read_bdf("cantilever.bdf")
    >>> model.n_nodes, len(model.beams), info.mass, info.beam_theory
    (5, 4, 'consistent', 'euler-bernoulli')
    >>> print(np.round(solve_modes(model, n_modes=2).frequencies_hz, 3))
    [ 8.154 16.308]
    """
    path = Path(path)
    if conventions not in CONVENTIONS:
        raise ModelError(f"conventions must be one of {', '.join(CONVENTIONS)}, got {conventions!r}")
    bdf = parse_bdf(path)
    info = BdfInfo(path=str(path), cards=dict(sorted(bdf.card_count.items())), conventions=conventions)
    info.notes.extend(bdf.parsed.notes)
    check_cards(bdf, path, info)
    read_params(bdf, info)

    node_ids, xyz, frames = grid_nodes(bdf)
    scalar = scalar_points(bdf, set(node_ids.tolist()), info)
    if not len(node_ids) and not scalar:
        raise ModelError("the deck has no GRID cards (and no scalar points)")
    if scalar:
        # Scalar points become nodes of their own with only component 1 free (position and
        # frame are irrelevant: only scalar elements and MPCs join them).
        node_ids = np.concatenate([node_ids, np.array(scalar, dtype=np.int64)])
        xyz = np.concatenate([xyz, np.zeros((len(scalar), 3))])
        if frames is not None:
            frames = np.concatenate([frames, np.broadcast_to(np.eye(3), (len(scalar), 3, 3))])
    nodes = NodeTable(node_ids, xyz, frames)
    nodes.spoints = set(scalar)
    mats = deck_materials(bdf, info.wtmass)
    check_units(bdf, mats, info.wtmass)
    props = line_properties(bdf, mats, info.wtmass, conventions)

    if beam_theory is None:
        used = {e.pid for e in bdf.elements.values() if e.type in ("CBAR", "CBEAM")}
        shear = sorted({props[pid].label for pid in used if pid in props and props[pid].shear})
        if shear:
            info.beam_theory = "timoshenko"
            info.beam_theory_reason = (f"shear flexibility given by {', '.join(shear[:5])}"
                                       f"{' ...' if len(shear) > 5 else ''} (NASTRAN includes it)")
        else:
            info.beam_theory = "euler-bernoulli"
            info.beam_theory_reason = "no property gives shear flexibility"
    elif beam_theory in ("euler-bernoulli", "timoshenko"):
        info.beam_theory = beam_theory
        info.beam_theory_reason = "requested by the caller"
    else:
        raise ModelError(f"beam_theory must be 'euler-bernoulli' or 'timoshenko', got {beam_theory!r}")

    model = Model(beam_theory=info.beam_theory, mass=info.mass, name=path.stem)
    n_grid = len(node_ids) - len(scalar)
    if n_grid:
        model.add_nodes(node_ids[:n_grid], xyz[:n_grid])
    if scalar:
        model.add_scalar_points(scalar)
    if nodes.frames is not None:
        model.set_node_frames(node_ids, nodes.frames)
    add_bars(bdf, model, nodes, props)
    add_rods(bdf, model, nodes, props, mats, info.wtmass)
    nastran_mass_conventions(bdf, model, nodes, props, info)
    add_conm2(bdf, model, nodes, info.wtmass)
    add_scalar_masses(bdf, model, nodes, info.wtmass)
    add_scalar_point_elements(bdf, model, nodes, info.wtmass)
    add_conm1(bdf, model, nodes, info.wtmass)
    add_genel(bdf, model, nodes)
    add_direct_matrices(bdf, model, info, lambda dofs, card, eid: dof_matrix(nodes, dofs, card, eid))
    add_springs(bdf, model, nodes)
    add_rigid(bdf, model, nodes)
    add_raw_rigid(bdf, model, nodes)
    add_mpcs(bdf, model, nodes, info)
    add_spcs(bdf, model, nodes, info)
    add_dof_sets(bdf, model, nodes, info)
    select_eigen(bdf, info)
    if is_preload_run(*bdf.solution):
        add_preload_stiffness(bdf, model, nodes, info, rect_frame)
    return model, info
