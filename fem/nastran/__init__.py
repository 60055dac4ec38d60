"""NASTRAN bulk data in and out, by trussid's own parser and writer.

:func:`read_bdf` maps a bulk-data deck onto a :class:`trussid.fem.Model` and reports, in a
:class:`BdfInfo`, every choice that changes the answer (mass formulation, WTMASS, beam
theory, SPC set, eigenvalue request, AUTOSPC). :func:`write_bdf` writes a model back as a
deck that NASTRAN can run and that :func:`read_bdf` re-reads to the same model.

The deck is parsed by :mod:`~trussid.fem.nastran.cards` (small, large and free field,
continuations, comments, INCLUDE, executive and case control; NASTRAN's field rules) and the
entries trussid translates are typed by :mod:`~trussid.fem.nastran.bulk` (NASTRAN's defaults,
coordinate systems resolved); no third-party parser is involved (pyNastran's releases
declare ``numpy<2``). This package only translates cards into the model's arrays.

Modules: :mod:`~trussid.fem.nastran.entries` (what is read, accepted or refused),
:mod:`~trussid.fem.nastran.cards` (text to cards), :mod:`~trussid.fem.nastran.bulk` (cards
to typed entries), :mod:`~trussid.fem.nastran.records` (the typed entries),
:mod:`~trussid.fem.nastran.coords` (coordinate systems into basic),
:mod:`~trussid.fem.nastran.deck` (PARAMs, case control, checks),
:mod:`~trussid.fem.nastran.reader` (the translation: the model assembled from the modules
of each kind of entry, :mod:`~trussid.fem.nastran.grids`,
:mod:`~trussid.fem.nastran.line_properties`, :mod:`~trussid.fem.nastran.line_elements`,
:mod:`~trussid.fem.nastran.scalar_elements`, :mod:`~trussid.fem.nastran.rigid`,
:mod:`~trussid.fem.nastran.dof_sets`), :mod:`~trussid.fem.nastran.conventions`
(NASTRAN's element conventions and the build conventions, ``conventions="nx"|"msc"``),
:mod:`~trussid.fem.nastran.matrices` (DMIG through K2GG/M2GG),
:mod:`~trussid.fem.nastran.preload` (rigid format 13) and :mod:`~trussid.fem.nastran.writer`.

Conventions that matter
-----------------------
* Units are the deck's: numbers are used as given, except that every mass (densities,
  non-structural mass, CONM2 mass and inertia) is multiplied by ``PARAM,WTMASS``.
* Mass formulation: NASTRAN's default is lumped mass; ``PARAM,COUPMASS`` > 0 selects the
  coupled (consistent) mass.
* PBAR/PBEAM ``I1`` is the second moment for bending in plane 1 (the element x-y plane, which
  contains the orientation vector v), i.e. about the element z axis: ``Iz = I1``,
  ``Iy = I2``. Shear areas are ``K1 A`` (along y) and ``K2 A`` (along z).
* Shear flexibility follows NASTRAN: PBAR without K1/K2 has none (infinite shear area);
  PBEAM has K1 = K2 = 1.0 by default (0.0 means none); PBARL/PBEAML compute shear
  factors from the shape: ROD 0.9 as recent NASTRAN builds convert it, the other shapes the
  Cowper factors of :mod:`trussid.fem.sections` (whose torsion constants are used too). The
  model is Timoshenko when any CBAR/CBEAM has a finite shear area, else Euler-Bernoulli.
* Element mass follows NASTRAN where it differs from :mod:`trussid.fem.elements` (lumped
  CBEAM torsional inertia, coupled CROD, CBAR and shear-flexible CBEAM mass): see
  :func:`~trussid.fem.nastran.conventions.nastran_mass_conventions`; these were found on
  real NASTRAN output.
* Displacement systems (GRID CD, rectangular, cylindrical or spherical) become node frames
  of the model (:meth:`trussid.fem.Model.set_node_frames`): supports, scalar masses and
  springs, rigid elements, MPCs and OP2 results refer to them, as in NASTRAN.
* CONM2 inertia: the deck gives I11, I21, I22, I31, I32, I33 with the products of inertia as
  positive integrals (I21 = int x1 x2 dm); NASTRAN supplies the minus signs, so the tensor
  is ``[[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]]`` (MSC/Autodesk QRG, CONM2
  remark on the form of the inertia matrix).
"""

from trussid.fem.nastran.conventions import BAR_SHEAR_FACTOR, CONVENTIONS, ROD_SHEAR_FACTOR
from trussid.fem.nastran.deck import BdfInfo, EigenRequest
from trussid.fem.nastran.entries import (CASE_SELECTED_CARDS, HANDLED_PARAMS, IGNORED_CARDS, MODE_PARAMS,
                                         NOTED_CARDS, OUTPUT_PARAMS, RAW_CARDS, SECTION_TYPES, SUPPORTED_CARDS,
                                         THERMAL_CARDS)
from trussid.fem.nastran.reader import coord_axes, offset_spring_matrix, read_bdf
from trussid.fem.nastran.writer import write_bdf

__all__ = ["SUPPORTED_CARDS", "RAW_CARDS", "IGNORED_CARDS", "NOTED_CARDS", "CASE_SELECTED_CARDS", "THERMAL_CARDS",
           "HANDLED_PARAMS", "MODE_PARAMS", "OUTPUT_PARAMS", "CONVENTIONS", "ROD_SHEAR_FACTOR", "BAR_SHEAR_FACTOR", "SECTION_TYPES",
           "EigenRequest", "BdfInfo", "read_bdf", "coord_axes", "offset_spring_matrix", "write_bdf"]
