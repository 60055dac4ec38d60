"""NASTRAN bulk data in and out, through pyNastran.

:func:`read_bdf` maps a bulk-data deck onto a :class:`trussid.fem.Model` and reports, in a
:class:`BdfInfo`, every choice that changes the answer (mass formulation, WTMASS, beam
theory, SPC set, eigenvalue request, AUTOSPC). :func:`write_bdf` writes a model back as a
deck that NASTRAN can run and that :func:`read_bdf` re-reads to the same model.

The deck is parsed by pyNastran (``pyNastran.bdf.bdf.BDF``), so the card formats (small,
large and free field, continuations, INCLUDE) are pyNastran's. pyNastran's own element
matrices are not used: this module only translates cards into the model's arrays.

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
  :func:`_nastran_mass_conventions`; these were found on real NASTRAN output.
* Displacement systems (GRID CD, rectangular, cylindrical or spherical) become node frames
  of the model (:meth:`trussid.fem.Model.set_node_frames`): supports, scalar masses and
  springs, rigid elements, MPCs and OP2 results refer to them, as in NASTRAN.
* CONM2 inertia: the deck gives I11, I21, I22, I31, I32, I33 with the products of inertia as
  positive integrals (I21 = int x1 x2 dm); NASTRAN supplies the minus signs, so the tensor
  is ``[[I11, -I21, -I31], [-I21, I22, -I32], [-I31, -I32, I33]]`` (MSC/Autodesk QRG, CONM2
  remark on the form of the inertia matrix).
"""

from __future__ import annotations

import contextlib
import io
import math
import os
import re
import warnings
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from trussid.fem.errors import ModelError, UnitsWarning
from trussid.fem.materials import wave_speed_problem
from trussid.fem.model import Model
from trussid.fem.sections import Section
from trussid._util.files import atomic_path
from trussid.fem.assembly import _coo, beam_matrices, general_blocks, mass_blocks
from trussid.fem.constraints import rbe3_constraint, rigid_element, rigid_transform
from trussid.fem.elements import frame_matrices, local_axes, to_global

__all__ = ["SUPPORTED_CARDS", "RAW_CARDS", "IGNORED_CARDS", "THERMAL_CARDS", "HANDLED_PARAMS",
           "OUTPUT_PARAMS", "ROD_SHEAR_FACTOR", "SECTION_TYPES", "EigenRequest", "BdfInfo",
           "read_bdf", "coord_axes", "offset_spring_matrix", "write_bdf"]

#: Bulk-data cards :func:`read_bdf` translates.
SUPPORTED_CARDS = frozenset({
    "GRID", "GRDSET", "CORD1R", "CORD2R", "CORD1C", "CORD2C", "CORD1S", "CORD2S",
    "CBAR", "CBEAM", "CROD", "CONROD", "PBAR", "PBARL", "PBEAM", "PBEAML", "PROD", "PTUBE",
    "MAT1", "CONM2", "CMASS1", "CMASS2", "PMASS", "CELAS1", "CELAS2", "PELAS", "CBUSH", "PBUSH",
    "RBE2", "RBE3", "RBAR", "MPC", "MPCADD", "CRIGD1", "CRIGD2", "CRIGD3", "CRIGDR",
    "SPC", "SPC1", "SPCADD", "OMIT", "OMIT1", "ASET", "ASET1", "SUPORT", "SUPORT1", "SPOINT",
    "EIGRL", "EIGR", "PARAM", "ENDDATA",
})

#: NASTRAN-95 rigid elements that pyNastran does not parse: read from the raw card lines.
RAW_CARDS = frozenset({"CRIGD1", "CRIGD2", "CRIGD3", "CRIGDR"})

#: Entries that cannot change the real eigenvalues of the structure: accepted, not
#: translated, and listed with their counts in :attr:`BdfInfo.ignored`. Loads and enforced
#: motion (a SOL 103 run has no load; SPCD values are irrelevant to modes, their SPC set is
#: read), dynamic-load, frequency and random tables, damping (real modes are undamped),
#: aeroelastic model (its splines only read the structural modes), output and DMAP book-
#: keeping (USET, DTI, MDLPRM, PLOTEL), thermal materials (MAT4/MAT5: heat transfer only)
#: and the complex-eigenvalue method EIGC.
IGNORED_CARDS = frozenset({
    # static and dynamic loads, enforced motion
    "FORCE", "FORCE1", "FORCE2", "MOMENT", "MOMENT1", "MOMENT2", "LOAD", "GRAV", "ACCEL",
    "ACCEL1", "PLOAD", "PLOAD1", "PLOAD2", "PLOAD4", "RFORCE", "SPCD", "DLOAD", "RLOAD1",
    "RLOAD2", "TLOAD1", "TLOAD2", "DAREA", "DELAY", "DPHASE", "LSEQ", "ACSRCE",
    # tables, frequencies, random and transient set-up
    "TABLED1", "TABLED2", "TABLED3", "TABLED4", "TABDMP1", "TABRND1", "TABRNDG", "RANDPS",
    "RANDT1", "FREQ", "FREQ1", "FREQ2", "FREQ3", "FREQ4", "FREQ5", "TSTEP", "TSTEP1", "NLPARM",
    "EIGC", "EPOINT",
    # damping elements (real modes are undamped)
    "CDAMP1", "CDAMP2", "CDAMP3", "CDAMP4", "CVISC", "PDAMP", "PVISC",
    # aeroelastic model
    "AERO", "AEROS", "CAERO1", "CAERO2", "CAERO3", "CAERO4", "CAERO5", "PAERO1", "PAERO2",
    "PAERO3", "PAERO4", "PAERO5", "SPLINE1", "SPLINE2", "SPLINE3", "SPLINE4", "SPLINE5", "SET1",
    "SET2", "AEFACT", "AELIST", "AESTAT", "AESURF", "AESURFS", "AELINK", "AEPARM", "AECOMP",
    "AECOMPL", "MKAERO1", "MKAERO2", "FLFACT", "FLUTTER", "GUST", "TRIM", "DIVERG", "MONPNT1",
    "MONPNT2", "MONPNT3", "MONDSP1", "CSSCHD", "AEDW", "AEPRESS", "AEFORCE",
    # output, sets for DMAP, tables for post-processing, plotting
    "MDLPRM", "USET", "USET1", "DTI", "PLOTEL",
    # heat-transfer materials (structural SOL 103 does not use them)
    "MAT4", "MAT5",
})

#: Temperature-dependent material entries: ignored like the above unless the deck gives
#: temperatures (TEMP/TEMPD), when they would change the stiffness and are refused.
THERMAL_CARDS = frozenset({"MATT1", "TABLEM1", "TABLEM2", "TABLEM3", "TABLEM4", "TEMPD", "TEMP"})

#: PARAMs read. Every other PARAM is accepted and listed in :attr:`BdfInfo.ignored`
#: unless it is one of :data:`MODE_PARAMS`: NASTRAN has hundreds of PARAMs (and MYSTRAN,
#: NASTRAN-95 their own), and those that change a beam model's real modes are few.
HANDLED_PARAMS = frozenset({"WTMASS", "COUPMASS", "AUTOSPC"})

#: PARAMs that change the real modes and are not translated: the scale factors of direct
#: input matrices (K2GG, M2GG... through CK1-CK3, CM1-CM2, CP1-CP2, CB1-CB2). Refused unless
#: they keep their default 1.0.
MODE_PARAMS = frozenset({"CK1", "CK2", "CK3", "CM1", "CM2", "CP1", "CP2", "CB1", "CB2"})

#: PARAMs known to have no effect on the real modes of a beam model (output and solver
#: book-keeping, damping, aeroelastic and shell-only settings): listed like any other
#: accepted PARAM; kept as the documented list of those checked.
OUTPUT_PARAMS = frozenset({
    "POST", "PRTMAXIM", "GRDPNT", "OGEOM", "NOCOMPS", "PATVER", "SRCOMPS", "EST", "OUGCORD",
    "MAXRATIO", "BAILOUT", "NEWSEQ", "LMODES", "RESVEC", "PRGPST", "SEMAPPRT", "USETPRT",
    "AUTOMSET", "DDRMM", "POSTEXT", "PRINT", "NASPRT", "SOLADJC", "G", "W3", "W4", "K6ROT",
    "SNORM", "LAMLIM", "OIBULK", "OMACHPR", "RDRBE", "RSCON", "RSOPT", "UNITSYS", "KDAMP",
    "OPPHIPA", "GUSTAERO", "AUNITS", "Q", "USETSEL", "GRDEQ", "RPOSTS1", "SPARSEDR", "LGDISP",
    "MACH", "VREF", "OPGTKG", "PRTPCH", "DBALL", "SCRSAVE", "DBDICT", "DBUP", "OUNIT1", "OUNIT2",
    "SEP1XOVR", "AUTOQSET", "CHECKOUT", "OPTEXIT", "INREL", "FIXEDB", "MODACC", "NOELOF",
    "NOELOP", "NOGPF", "NOPRT", "PRTGPL", "PRTEQXIN", "PRTGPDT", "PRTCSTM", "PRTBGPDT",
    "PRTGPTT", "PRTMGG", "PRTPG", "ERROR", "DBCDIAG", "TINY", "XFLAG",
})

#: Build conventions :func:`read_bdf` can follow (``conventions=``), default first.
CONVENTIONS = ("nx", "msc")

#: Shear factor K1 = K2 of a PBARL/PBEAML ROD by build conventions (see :func:`_properties`):
#: 0.9 as NX/Simcenter and the newer MSC builds convert it, 6/7 as an MSC 2012 build did.
ROD_SHEAR_FACTOR = {"nx": 0.9, "msc": 6.0 / 7.0}

#: Shear factor of a PBARL/PBEAML BAR: 5/6, as NASTRAN converts it (MSC 2012.2 on a deep
#: CBEAM cantilever: bending modes 1e-4..7e-4 off with Cowper's 10(1+nu)/(12+11nu), 1e-6 with 5/6).
BAR_SHEAR_FACTOR = 5.0 / 6.0

#: PBARL/PBEAML shapes with a matching :class:`trussid.fem.sections.Section` constructor.
SECTION_TYPES = ("ROD", "TUBE", "BAR", "BOX")


@dataclass
class EigenRequest:
    """The deck's real-eigenvalue request (EIGRL or EIGR).

    Attributes
    ----------
    card : str
        "EIGRL" or "EIGR".
    sid : int
    n_modes : int or None
        ND: number of modes wanted.
    f_low, f_high : float or None
        Frequency range [Hz in the deck's time unit] (EIGRL V1, V2; EIGR F1, F2).
    """

    card: str
    sid: int
    n_modes: int | None
    f_low: float | None
    f_high: float | None


@dataclass
class BdfInfo:
    """What :func:`read_bdf` found and decided, for reports.

    Attributes
    ----------
    path : str
    wtmass : float
        PARAM,WTMASS (1.0 when absent): the factor applied to every mass.
    mass : {"consistent", "lumped"}
        Mass formulation used.
    mass_reason : str
        Why (the PARAM,COUPMASS value, or NASTRAN's lumped default).
    beam_theory : {"euler-bernoulli", "timoshenko"}
    beam_theory_reason : str
    eigen : EigenRequest or None
        The eigenvalue request selected by the case control (METHOD), or the only one.
    spc_sets : list of int or None
        SPC set ids applied (after SPCADD expansion); ``None`` when the deck has none.
    spc_reason : str
    autospc : bool
        Whether DOFs with neither stiffness nor mass should be removed (NASTRAN's AUTOSPC,
        on by default in SOL 103; ``PARAM,AUTOSPC,NO`` turns it off).
    autospc_reason : str
    conventions : {"nx", "msc"}
        The NASTRAN build conventions followed (see :func:`read_bdf`).
    cards : dict of str to int
        Bulk-data cards read, with counts.
    ignored : list of str
        Accepted entries without effect on the modes, with counts (e.g. ``"FORCE (3)"``,
        ``"PARAM,POST"``).
    notes : list of str
        Other things a user should know (multiple subcases, enforced displacements...).
    """

    path: str
    wtmass: float = 1.0
    mass: str = "lumped"
    mass_reason: str = ""
    beam_theory: str = "euler-bernoulli"
    beam_theory_reason: str = ""
    eigen: EigenRequest | None = None
    spc_sets: list | None = None
    spc_reason: str = ""
    autospc: bool = True
    autospc_reason: str = ""
    conventions: str = "nx"
    cards: dict = field(default_factory=dict)
    ignored: list = field(default_factory=list)
    notes: list = field(default_factory=list)


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
    :func:`_nastran_mass_conventions` and the PBARL/PBEAML ROD shear factor).

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
    bdf = _parse(path)
    info = BdfInfo(path=str(path), cards=dict(sorted(bdf.card_count.items())), conventions=conventions)
    _check_cards(bdf, path, info)
    _read_params(bdf, info)

    node_ids, xyz, frames = _nodes(bdf)
    nodes = _NodeTable(node_ids, xyz, frames)
    mats = _materials(bdf, info.wtmass)
    _check_units(bdf, mats, info.wtmass)
    props = _properties(bdf, mats, info.wtmass, conventions)

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
    model.add_nodes(node_ids, xyz)
    if nodes.frames is not None:
        model.set_node_frames(node_ids, nodes.frames)
    _check_scalar_points(bdf, info)
    _add_bars(bdf, model, nodes, props)
    _add_rods(bdf, model, nodes, props, mats, info.wtmass)
    _nastran_mass_conventions(bdf, model, nodes, props, info)
    _add_masses(bdf, model, nodes, info.wtmass)
    _add_scalar_masses(bdf, model, nodes, info.wtmass)
    _add_springs(bdf, model, nodes)
    _add_rigid(bdf, model, nodes)
    _add_raw_rigid(bdf, model, nodes)
    _add_mpcs(bdf, model, nodes, info)
    _add_spcs(bdf, model, nodes, info)
    _add_dof_sets(bdf, model, nodes, info)
    _select_eigen(bdf, info)
    return model, info


@dataclass
class _RawParam:
    """A PARAM entry from its raw fields (pyNastran validates PARAM values against its own
    lists and refuses legal ones, e.g. ``PARAM,EXTOUT,MATRIXPCH`` or MYSTRAN's EQCHECK)."""

    name: str
    values: list


def _nastran_value(text: str):
    """A field as NASTRAN reads it: int, real (also ``1.5-3`` = 1.5e-3), or the string."""
    t = text.strip()
    for conv in (int, float):
        try:
            return conv(t)
        except ValueError:
            pass
    m = re.fullmatch(r"([+-]?(?:\d+\.?\d*|\.\d+))([+-]\d+)", t)
    if m:
        return float(f"{m.group(1)}e{m.group(2)}")
    return t.upper()


def _executive(text: str, path: Path) -> tuple[str, str, list[str]]:
    """(executive control, rest, notes): the executive control is dropped before pyNastran.

    trussid needs nothing from it but the solution (read here), and pyNastran refuses
    statements it does not know (NASTRAN-95's ``APP AERO``, ``APP DISP``, DMAP ALTERs).
    """
    m = re.search(r"^\s*CEND\b.*$", text, re.IGNORECASE | re.MULTILINE)
    if m is None:
        return "", text, []
    return text[:m.start()], text[m.end() + 1:], []


def _solution(executive: str) -> tuple[str | None, str | None]:
    """(SOL value, APP value) of an executive control, upper case, or None."""
    sol = re.search(r"^\s*SOL\s+([^\s$]+)", executive, re.IGNORECASE | re.MULTILINE)
    app = re.search(r"^\s*APP\s+([^\s$]+)", executive, re.IGNORECASE | re.MULTILINE)
    return (sol.group(1).upper() if sol else None), (app.group(1).upper() if app else None)


def _check_solution(path: Path, sol: str | None, app: str | None) -> None:
    """Refuse solutions whose printed modes are not the structure's real modes, naming them."""
    if sol is None:
        return
    number = sol.split(",")[0]
    if app in (None, "DISP", "DISPLACEMENT", "AERO") and number == "13":
        raise ModelError(f"{path}: SOL 13 (NASTRAN-95 rigid format 13, normal modes with differential "
                         f"stiffness): its modes are those of the structure preloaded by the static subcase, "
                         f"which trussid does not compute (differential stiffness is not supported)")


def _parse(path: Path):
    """pyNastran's BDF of ``path``, quietly; any failure becomes a one-line ModelError."""
    from cpylog import SimpleLogger  # deferred: ~1.5 s to load, decks only
    from pyNastran.bdf.bdf import BDF  # deferred: ~1.5 s to load, decks only

    if not path.exists():
        raise ModelError(f"{path}: no such file")
    if path.is_dir():
        raise ModelError(f"{path}: is a directory, not a bulk-data file")
    try:
        text = path.read_text(errors="replace")
    except OSError as exc:
        raise ModelError(f"{path}: cannot read ({exc.strerror})") from None
    flags = re.IGNORECASE | re.MULTILINE
    # INCLUDE files are relative to the deck. Checked here so that a missing one is named
    # (pyNastran would also leave a crash file in the working directory).
    includes = re.findall(r"^\s*INCLUDE\s+'([^']+)'", text, flags)
    for inc in includes:
        if not (path.parent / inc).is_file():
            raise ModelError(f"{path}: INCLUDE '{inc}': no such file (looked in {path.parent})")
    notes = []
    executive, rest, _ = _executive(text, path)
    sol, app = _solution(executive)
    _check_solution(path, sol, app)
    punch = re.search(r"^\s*BEGIN\s+(BULK|SUPER)", text, flags) is None
    if not punch:
        # The deck goes to pyNastran from memory, with an empty executive control (see
        # _executive) and INCLUDEs made absolute (pyNastran resolves them from the working
        # directory when reading from memory).
        text = re.sub(r"^(\s*INCLUDE\s+')([^']+)(')",
                      lambda m: m.group(1) + str((path.parent / m.group(2)).resolve()) + m.group(3),
                      rest, flags=flags)
        # A repeated BEGIN BULK (MSC's HA144D) is accepted by NASTRAN; pyNastran reads the
        # second as a superelement header.
        heads = list(re.finditer(r"^\s*BEGIN\s+BULK\b.*$\n?", text, flags))
        if len(heads) > 1:
            for h in reversed(heads[1:]):
                text = text[:h.start()] + text[h.end():]
            notes.append(f"BEGIN BULK repeated {len(heads)} times: read once, as NASTRAN")
        source: str | io.StringIO = io.StringIO("CEND\n" + text)
    else:
        source = str(path)
    bdf = BDF(log=SimpleLogger(level="critical"), debug=None)
    # Cards this reader does not translate are only counted, never parsed, so that a
    # malformed one is reported as unsupported rather than failing the parse; those read
    # from their raw fields (RAW_CARDS, PARAM) too.
    bdf.disable_cards(sorted((set(bdf.cards_to_read) - SUPPORTED_CARDS) | RAW_CARDS | {"PARAM"}))
    try:
        # pyNastran also print()s some complaints; keep them off the user's terminal (the
        # exception carries the message).
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            bdf.read_bdf(source, xref=False, validate=False, punch=punch)
    except Exception as exc:  # pyNastran raises many types for malformed decks
        raise ModelError(f"{path}: not a readable bulk-data deck ({_parser_message(exc)})") from None
    if not bdf.card_count:
        raise ModelError(f"{path}: no bulk-data cards found")
    bdf.params = _raw_params(bdf)
    bdf.trussid_notes = notes
    bdf.trussid_solution = (sol, app)
    return bdf


def _parser_message(exc: Exception) -> str:
    """pyNastran's message in user terms: the entry and its id, without its internals.

    pyNastran words its complaints as ``field 'x' (field #3) on card must be ...
    card=['CBAR', '1', ...]``: the list is the raw card; the entry name and id (its first
    two fields) are what a user can find in the deck.
    """
    msg = " ".join(str(exc).split())
    card = re.search(r"card=\[\s*'([A-Z0-9*]+)'\s*,\s*'?([^',\]]*)'?", msg)
    msg = re.sub(r"\s*card=\[.*$", "", msg)
    msg = re.sub(r"\s*\b(uline|allowed_methods|allowed|len\(\w+ card\))\s*=.*$", "", msg)
    msg = msg.strip(" ;,.") or type(exc).__name__
    if card:
        name, ident = card.group(1), card.group(2).strip()
        msg = f"{name} {ident}: {msg}" if ident else f"{name}: {msg}"
    return msg[:300]


def _card_lines(lines: list[str]) -> list[str]:
    """A rejected card's lines without the comment lines pyNastran keeps in front."""
    return [ln for ln in lines if ln.strip() and not ln.lstrip().startswith("$")]


def _raw_params(bdf) -> dict:
    """PARAM name -> :class:`_RawParam` from the raw lines (the last entry of a name wins)."""
    params = {}
    for lines in getattr(bdf, "reject_lines", []):
        body = _card_lines(lines)
        if not body or not re.match(r"\s*PARAM\b", body[0], re.IGNORECASE):
            continue
        f = _raw_fields(body, "PARAM")
        if len(f) < 2 or not f[1]:
            raise ModelError(f"PARAM: no name ({body[0].strip()!r})")
        params[f[1]] = _RawParam(f[1], [_nastran_value(v) for v in f[2:] if v.strip()])
    return params


def _check_cards(bdf, path: Path, info: BdfInfo) -> None:
    """Every card must be translated or known to be harmless: list all the others.

    Unsupported element entries (shells, solids...) come first in the message: they are
    the reason a beam code cannot read the deck, the rest would follow from them.
    """
    counts = bdf.card_count
    thermal_on = any(counts.get(c) for c in ("TEMPD", "TEMP")) or _case_values(bdf, "TEMPERATURE") \
        or _case_values(bdf, "TEMP")
    bad, ignored = {}, {}
    for name, n in counts.items():
        if name in SUPPORTED_CARDS:
            continue
        if name in IGNORED_CARDS or (name in THERMAL_CARDS and not thermal_on):
            ignored[name] = n
        else:
            bad[name] = n
    for name in sorted(bdf.params):
        if name in HANDLED_PARAMS:
            continue
        if name in MODE_PARAMS and bdf.params[name].values not in ([], [1], [1.0]):
            bad[f"PARAM,{name}"] = 1
        else:
            ignored[f"PARAM,{name}"] = 1
    info.ignored = [f"{k} ({v})" if not k.startswith("PARAM,") else k for k, v in sorted(ignored.items())]
    if not bad:
        return
    elements = {k: v for k, v in bad.items() if _is_element_entry(k)}
    if elements:
        listing = ", ".join(f"{k} ({v})" for k, v in sorted(elements.items()))
        rest = {k: v for k, v in bad.items() if k not in elements}
        also = f"; also unsupported: {', '.join(f'{k} ({v})' for k, v in sorted(rest.items()))}" if rest else ""
        raise ModelError(f"{path}: unsupported element entries: {listing} (trussid reads beam, rod, "
                         f"spring, mass and rigid elements: CBAR, CBEAM, CROD, CONROD, CELAS1/2, "
                         f"CBUSH, CONM2, CMASS1/2, RBE2, RBE3, RBAR, CRIGD1/2/3/R){also}")
    listing = ", ".join(f"{k} ({v})" for k, v in sorted(bad.items()))
    raise ModelError(f"{path}: unsupported bulk-data entries: {listing}; "
                     f"supported cards are {', '.join(sorted(SUPPORTED_CARDS))}")


def _is_element_entry(name: str) -> bool:
    """Element connection entries (CQUAD4, CHEXA, CTUBE, GENEL...), not coordinate systems."""
    return (name.startswith("C") and not name.startswith("CORD") and name not in ("CONM1", "CMASS3", "CMASS4")
            ) or name in ("GENEL", "PLOTEL")


def _param(bdf, name):
    p = bdf.params.get(name)
    if p is None:
        return None
    return p.values[0]


def _read_params(bdf, info: BdfInfo) -> None:
    wt = _param(bdf, "WTMASS")
    if wt is not None:
        if not (isinstance(wt, (int, float)) and math.isfinite(wt) and wt > 0):
            raise ModelError(f"PARAM,WTMASS must be a positive number, got {wt!r}")
        info.wtmass = float(wt)
    cm = _param(bdf, "COUPMASS")
    if cm is None:
        info.mass = "lumped"
        info.mass_reason = "PARAM,COUPMASS absent: NASTRAN's default lumped mass"
    else:
        if not isinstance(cm, (int, float)):
            raise ModelError(f"PARAM,COUPMASS must be a number, got {cm!r}")
        info.mass = "consistent" if cm > 0 else "lumped"
        info.mass_reason = f"PARAM,COUPMASS,{cm}: {'> 0, coupled' if cm > 0 else '<= 0, lumped'} mass"
    auto = _param(bdf, "AUTOSPC")
    if auto is None:
        info.autospc, info.autospc_reason = True, "NASTRAN's default (AUTOSPC=YES in SOL 103)"
    else:
        value = str(auto).strip().upper()
        if value not in ("YES", "NO"):
            raise ModelError(f"PARAM,AUTOSPC must be YES or NO, got {auto!r}")
        info.autospc, info.autospc_reason = value == "YES", f"PARAM,AUTOSPC,{value}"


class _NodeTable:
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


def _nodes(bdf):
    """GRID ids, basic coordinates and displacement frames; GRDSET defaults applied.

    CP systems are resolved by pyNastran. A displacement system CD gives the grid's DOFs
    along that system's axes at the grid (for cylindrical and spherical systems these
    depend on the position): returned as frames whose rows are the axes in basic.
    """
    if not bdf.nodes:
        raise ModelError("the deck has no GRID cards")
    grdset = getattr(bdf, "grdset", None)
    if grdset is not None:
        if grdset.cp or grdset.cd:
            raise ModelError(f"GRDSET: default CP={grdset.cp} / CD={grdset.cd} is not supported "
                             f"(pyNastran cannot tell a GRID's blank CP/CD from 0); give them on the GRIDs")
        if grdset.seid:
            raise ModelError("GRDSET: superelements (SEID) are not supported")
        if grdset.ps:
            for g in bdf.nodes.values():
                if not g.ps:
                    g.ps = grdset.ps
    ids = np.fromiter(bdf.nodes.keys(), dtype=np.int64, count=len(bdf.nodes))
    cd = np.fromiter((g.cd for g in bdf.nodes.values()), dtype=np.int64, count=len(ids))
    seid = [g.nid for g in bdf.nodes.values() if getattr(g, "seid", 0)]
    if seid:
        raise ModelError(f"GRID {seid[0]}: superelements (SEID) are not supported")
    cp = np.fromiter((g.cp for g in bdf.nodes.values()), dtype=np.int64, count=len(ids))
    for what, arr in (("CP", cp), ("CD", cd)):
        for nid, c in zip(ids[arr > 0], arr[arr > 0]):
            if c not in bdf.coords:
                raise ModelError(f"GRID {nid}: coordinate system {what}={c} is not defined")
    try:
        if len(bdf.coords) > 1:  # resolve coordinate systems defined relative to others
            bdf.cross_reference(xref=True, xref_nodes=True, xref_elements=False, xref_properties=False,
                                xref_masses=False, xref_materials=False, xref_loads=False,
                                xref_constraints=False, xref_aero=False, xref_sets=False,
                                xref_optimization=False)
    except Exception as exc:  # pyNastran raises many types for a malformed system
        raise ModelError(f"cannot resolve coordinate systems: {' '.join(str(exc).split())[:200]}") from None
    if not (cp != 0).any():
        xyz = np.array([g.xyz for g in bdf.nodes.values()], dtype=float).reshape(-1, 3)
    else:
        try:
            _icd, icp, xyz_cp, nid_cp_cd = bdf.get_displacement_index_xyz_cp_cd()
            xyz_b = bdf.transform_xyzcp_to_xyz_cid(xyz_cp, nid_cp_cd[:, 0], icp, cid=0)
        except Exception as exc:  # pyNastran raises many types for a malformed system
            msg = " ".join(str(exc).split())[:200]
            raise ModelError(f"cannot resolve grid coordinate systems: {msg}") from None
        order = {int(n): i for i, n in enumerate(nid_cp_cd[:, 0])}
        xyz = np.asarray(xyz_b, float)[[order[int(n)] for n in ids]]
    frames = None
    if (cd > 0).any():
        frames = np.broadcast_to(np.eye(3), (len(ids), 3, 3)).copy()
        for c in np.unique(cd[cd > 0]):
            sel = cd == c
            frames[sel] = coord_axes(bdf.coords[int(c)], xyz[sel], f"GRID {ids[sel][0]} (CD={c})")
    return ids, xyz, frames


def coord_axes(coord, xyz: np.ndarray, label: str) -> np.ndarray:
    """Local axes (rows, in basic) of a NASTRAN coordinate system at basic points ``xyz``.

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


def _check_units(bdf, mats: dict, wtmass: float) -> None:
    """Warn (:class:`UnitsWarning`, once per deck) when a material used by an element has an
    E and a density that no consistent unit system gives a solid (:func:`wave_speed_problem`):
    NASTRAN would run such a deck too, with frequencies off by orders of magnitude."""
    used = set()
    for p in bdf.properties.values():
        mid = getattr(p, "mid", None)
        if mid is not None:
            used.add(int(mid))
    for mid in sorted(used & set(mats)):
        m = mats[mid]
        why = wave_speed_problem(m["E"], m["rho"], wtmass)
        if why:
            warnings.warn(f"MAT1 {mid}: {why}", UnitsWarning, stacklevel=3)
            return


def _materials(bdf, wtmass: float) -> dict:
    """MAT1 id -> dict(E, G, nu, rho); NASTRAN's rule for a blank E, G or NU is pyNastran's."""
    mats = {}
    for mid, mat in bdf.materials.items():
        # pyNastran applies the MAT1 rule when it reads the card: one blank of E, G, NU is
        # computed from E = 2 (1 + NU) G; E (or G) alone gives the others 0.0.
        mats[mid] = {"E": float(mat.e or 0.0), "G": float(mat.g or 0.0), "nu": float(mat.nu or 0.0),
                     "rho": float(mat.rho or 0.0) * wtmass, "label": f"MAT1 {mid}"}
    return mats


@dataclass
class _Prop:
    """A line property resolved to section arrays, material and mass per length."""

    label: str
    kind: str  # "bar" (bending) or "rod"
    section: dict
    mat: dict
    nsm: float
    shear: bool


def _material(mats: dict, mid: int, label: str) -> dict:
    if mid not in mats:
        raise ModelError(f"{label}: material {mid} is not defined (MAT1 expected)")
    return mats[mid]


def _section_from_shape(shape: str, dims, nu: float, label: str) -> Section:
    """A :class:`Section` for a PBARL/PBEAML shape.

    NASTRAN's element axes for these shapes (QRG PBARL figure, and pyNastran's I1/I2): DIM1
    runs along element z, DIM2 along element y, so for BAR ``I1 = Izz = DIM1 DIM2^3 / 12``.
    """
    d = [float(x) for x in dims]
    need = {"ROD": 1, "TUBE": 2, "BAR": 2, "BOX": 4}[shape]
    if len(d) < need:
        raise ModelError(f"{label}: {shape} needs {need} dimensions, got {len(d)}")
    if shape == "ROD":
        return Section.circle(d[0], nu=nu, name=label)
    if shape == "TUBE":
        if not d[1] < d[0]:
            raise ModelError(f"{label}: TUBE inner radius DIM2={d[1]:g} must be less than the outer "
                             f"radius DIM1={d[0]:g}")
        return Section.tube(d[0], d[0] - d[1], nu=nu, name=label)
    if shape == "BAR":
        return Section.rectangle(b=d[1], h=d[0], nu=nu, name=label)
    if d[2] != d[3]:
        raise ModelError(f"{label}: BOX with unequal wall thicknesses (DIM3={d[2]:g}, DIM4={d[3]:g}) "
                         f"is not supported")
    return Section.box(b=d[1], h=d[0], t=d[2], nu=nu, name=label)


def _sec(A, Iy, Iz, J, Asy=math.inf, Asz=math.inf) -> dict:
    return {"A": float(A), "Iy": float(Iy), "Iz": float(Iz), "J": float(J),
            "Asy": float(Asy), "Asz": float(Asz)}


def _properties(bdf, mats: dict, wtmass: float, conventions: str = "nx") -> dict:
    props = {}
    for pid, p in bdf.properties.items():
        label = f"{p.type} {pid}"
        if p.type in ("PELAS", "PBUSH"):
            continue
        full = _material(mats, p.mid, label)
        mat = {k: full[k] for k in ("E", "G", "rho")}
        if p.type == "PBAR":
            if p.i12:
                raise ModelError(f"{label}: I12 = {p.i12:g} (non-principal axes) is not supported")
            # NASTRAN: K1/K2 blank means no shear flexibility; pyNastran stores blank as 1e8.
            k1 = math.inf if p.k1 is None or p.k1 >= 1e8 or p.k1 == 0 else p.k1
            k2 = math.inf if p.k2 is None or p.k2 >= 1e8 or p.k2 == 0 else p.k2
            sec = _sec(p.A, p.i2, p.i1, p.j, k1 * p.A, k2 * p.A)
            props[pid] = _Prop(label, "bar", sec, mat, float(p.nsm) * wtmass,
                               math.isfinite(k1) or math.isfinite(k2))
        elif p.type == "PBEAM":
            for key in ("A", "i1", "i2", "j", "nsm"):
                v = np.asarray(getattr(p, key), float)
                if (v != v[0]).any():
                    raise ModelError(f"{label}: tapered beam ({key} varies along the element) is not "
                                     f"supported; give a constant section")
            if np.any(np.asarray(p.i12, float) != 0):
                raise ModelError(f"{label}: I12 (non-principal axes) is not supported")
            for key in ("m1a", "m2a", "m1b", "m2b", "n1a", "n2a", "n1b", "n2b", "nsia", "nsib",
                        "cwa", "cwb"):
                if getattr(p, key, 0.0) not in (None, 0.0):
                    raise ModelError(f"{label}: {key.upper()} = {getattr(p, key):g} is not supported "
                                     f"(offsets, non-structural inertia and warping must be 0)")
            # PBEAM: K default 1.0; K = 0.0 means no shear flexibility.
            k1 = math.inf if not p.k1 else p.k1
            k2 = math.inf if not p.k2 else p.k2
            A = float(p.A[0])
            sec = _sec(A, p.i2[0], p.i1[0], p.j[0], k1 * A, k2 * A)
            props[pid] = _Prop(label, "bar", sec, mat, float(p.nsm[0]) * wtmass,
                               math.isfinite(k1) or math.isfinite(k2))
        elif p.type in ("PBARL", "PBEAML"):
            shape = str(p.beam_type).strip().upper()
            if shape not in SECTION_TYPES:
                raise ModelError(f"{label}: section type {shape} is not supported "
                                 f"(supported: {', '.join(SECTION_TYPES)})")
            if p.type == "PBEAML":
                dims = np.atleast_2d(np.asarray(p.dim, float))
                nsm = np.atleast_1d(np.asarray(p.nsm, float))
                if (dims != dims[0]).any() or (nsm != nsm[0]).any():
                    raise ModelError(f"{label}: tapered beam (dimensions vary along the element) is "
                                     f"not supported; give a constant section")
                dims, nsm = dims[0], float(nsm[0])
            else:
                dims, nsm = p.dim, float(p.nsm or 0.0)
            s = _section_from_shape(shape, dims, _nu_for_shear(full), label)
            asy, asz = s.Asy, s.Asz
            if shape == "ROD":
                # NASTRAN converts PBARL/PBEAML ROD to PBAR/PBEAM with K1 = K2 = 0.9 in the
                # newest builds (Simcenter 2019.2, NX 2022 ~0.898, MSC 2012-13 OP2s); one
                # MSC 2012 build used 6/7. Cowper's 6(1+nu)/(7+6nu) (0.886 at nu = 0.33)
                # sits between them; 0.9 is what the recent decks of the corpus were run with.
                asy = asz = ROD_SHEAR_FACTOR[conventions] * s.A
            elif shape == "BAR":
                asy = asz = BAR_SHEAR_FACTOR * s.A
            props[pid] = _Prop(label, "bar", _sec(s.A, s.Iy, s.Iz, s.J, asy, asz), mat,
                               nsm * wtmass, True)
        elif p.type == "PROD":
            props[pid] = _Prop(label, "rod", _rod_sec(p.A, p.j), mat, float(p.nsm) * wtmass, False)
        elif p.type == "PTUBE":
            if p.OD2 is not None and p.OD2 != p.OD1:
                raise ModelError(f"{label}: tapered tube (OD2 != OD1) is not supported")
            r = p.OD1 / 2.0
            t = p.t if p.t else r
            s = Section.circle(r, name=label) if t >= r else Section.tube(r, t, name=label)
            props[pid] = _Prop(label, "rod", _rod_sec(s.A, s.J), mat, float(p.nsm) * wtmass, False)
    return props


def _nu_for_shear(mat: dict) -> float:
    # Cowper's shear factors need Poisson's ratio; MAT1 with E alone has NU = 0.
    nu = mat["nu"]
    return nu if -1.0 < nu < 0.5 else 0.3


def _rod_sec(A, J) -> dict:
    # Rods have no bending: Iy, Iz are placeholders the element ignores for rods.
    return _sec(A, 1.0, 1.0, J or 0.0)


def _rod_torsion(section: dict, mat: dict) -> tuple[dict, dict]:
    """Rods whose G is 0 (a MAT1 with E alone): no torsional stiffness, as in NASTRAN.

    The element checks G > 0 for every element, so such a rod gets J = 0 and a placeholder
    G = E / 2: its torsional stiffness G J is 0 either way, and nothing else uses G.
    """
    G = np.asarray(mat["G"], float)
    zero = G == 0
    if not zero.any():
        return section, mat
    J = np.where(zero, 0.0, np.asarray(section["J"], float))
    return {**section, "J": J}, {**mat, "G": np.where(zero, np.asarray(mat["E"], float) / 2.0, G)}


def _group(items, key):
    groups = defaultdict(list)
    for item in items:
        groups[key(item)].append(item)
    return groups


def _add_bars(bdf, model: Model, nodes: _NodeTable, props: dict) -> None:
    """CBAR and CBEAM: one add_beams call per property."""
    elems = [e for e in bdf.elements.values() if e.type in ("CBAR", "CBEAM")]
    for e in elems:
        card = f"{e.type} {e.eid}"
        for flag in (e.pa, e.pb):
            if flag and any(ch not in "123456" for ch in str(flag)):
                raise ModelError(f"{card}: pin flags PA={e.pa or ''} PB={e.pb or ''} must be digits 1-6")
        if np.any(np.asarray(e.wa, float) != 0) or np.any(np.asarray(e.wb, float) != 0):
            raise ModelError(f"{card}: offsets WA={list(e.wa)} WB={list(e.wb)} are not supported "
                             f"(give the grids at the neutral axis)")
        if e.type == "CBEAM" and (getattr(e, "sa", 0) or getattr(e, "sb", 0)):
            raise ModelError(f"{card}: warping scalar points SA/SB are not supported")
        if getattr(e, "bit", None) is not None:
            raise ModelError(f"{card}: BIT (beam-in-time orientation) is not supported")
        if e.pid not in props:
            raise ModelError(f"{card}: property {e.pid} is not defined")
        if props[e.pid].kind != "bar":
            raise ModelError(f"{card}: property {e.pid} is a {props[e.pid].label.split()[0]}, "
                             f"not a bar/beam property")
    for (_card, pid), group in _group(elems, lambda e: (e.type, e.pid)).items():
        prop = props[pid]
        eids = np.array([e.eid for e in group], dtype=np.int64)
        ends = np.array([[e.ga, e.gb] if e.type == "CBAR" else e.nodes for e in group], dtype=np.int64)
        card = group[0].type
        xyz = nodes.coords(ends, card, eids)
        g0 = np.array([e.g0 if e.g0 not in (None, 0) else -1 for e in group], dtype=np.int64)
        orient = np.array([[np.nan] * 3 if e.x is None or e.x[0] is None else e.x for e in group],
                          dtype=float)
        use_g0 = g0 >= 0
        if use_g0.any():
            orient[use_g0] = nodes.coords(g0[use_g0], card, eids[use_g0]) - xyz[use_g0, 0]
        bad = ~np.isfinite(orient).all(axis=1)
        if bad.any():
            raise ModelError(f"{card} {eids[bad][0]}: no orientation (give X1-X3 or G0)")
        mat, nsm = prop.mat, prop.nsm
        if card == "CBAR" and model.mass_formulation == "consistent":
            # NASTRAN's coupled CBAR mass has no torsional (nor rotary) inertia: the structural
            # mass goes in as non-structural mass per length, which the element gives
            # translational inertia only (the same translational mass, exactly; MSC 2020 on
            # the pt145 deck: torsion modes 2.6e-4 high with it, 3e-7 without).
            mat, nsm = {**prop.mat, "rho": 0.0}, prop.nsm + prop.mat["rho"] * prop.section["A"]
        model.add_beams(eids, ends, prop.section, mat, orient, nsm=nsm, rod=False, label=prop.label)
        pinned = np.array([bool(e.pa or e.pb) for e in group])
        if pinned.any():
            _add_pin_flags(model, [e for e, p in zip(group, pinned) if p], xyz[pinned], orient[pinned], prop)


def _add_pin_flags(model: Model, elems: list, xyz: np.ndarray, orient: np.ndarray, prop: _Prop) -> None:
    """CBAR/CBEAM pin flags PA/PB: the released end DOFs (element axes) carry no force.

    The element's stiffness is condensed statically on the released DOFs, one at a time
    (a DOF already free after earlier releases is skipped), and the difference from the
    unpinned element is added as an element matrix, so the beam itself stays a plain beam.
    The mass is unchanged (NASTRAN's pin flags act on the stiffness).
    """
    eids = np.array([e.eid for e in elems], dtype=np.int64)
    L, R = local_axes(xyz[:, 0], xyz[:, 1], orient, eids)
    sec, mat = prop.section, prop.mat
    K = frame_matrices(L, sec["A"], sec["Iy"], sec["Iz"], sec["J"], mat["E"], mat["G"], mat["rho"],
                       Asy=sec["Asy"], Asz=sec["Asz"], theory=model.beam_theory)[0]
    dK = np.zeros_like(K)
    for i, e in enumerate(elems):
        k = K[i].copy()
        released = [int(c) - 1 for c in str(e.pa or "")] + [6 + int(c) - 1 for c in str(e.pb or "")]
        for d in released:
            if k[d, d] <= 1e-12 * np.abs(k).max():
                continue
            k = k - np.outer(k[:, d], k[d, :]) / k[d, d]
            k[d, :] = k[:, d] = 0.0
        dK[i] = 0.5 * (k + k.T) - K[i]
    model.add_matrices(eids, np.array([[e.ga, e.gb] if e.type == "CBAR" else e.nodes for e in elems]),
                       K=to_global(dK, R), label=f"{elems[0].type} pin flags")


def _add_rods(bdf, model: Model, nodes: _NodeTable, props: dict, mats: dict, wtmass: float) -> None:
    """CROD (one call per property) and CONROD (one call with per-element arrays)."""
    crods = [e for e in bdf.elements.values() if e.type == "CROD"]
    for e in crods:
        if e.pid not in props:
            raise ModelError(f"CROD {e.eid}: property {e.pid} is not defined")
        if props[e.pid].kind != "rod":
            raise ModelError(f"CROD {e.eid}: property {e.pid} is not a PROD or PTUBE")
    for pid, group in _group(crods, lambda e: e.pid).items():
        prop = props[pid]
        eids = np.array([e.eid for e in group], dtype=np.int64)
        ends = np.array([e.nodes for e in group], dtype=np.int64)
        section, mat = _rod_torsion(prop.section, prop.mat)
        model.add_beams(eids, ends, section, mat, _rod_orient(nodes, ends, "CROD", eids),
                        nsm=prop.nsm, rod=True, label=prop.label)
    conrods = [e for e in bdf.elements.values() if e.type == "CONROD"]
    if conrods:
        eids = np.array([e.eid for e in conrods], dtype=np.int64)
        ends = np.array([e.nodes for e in conrods], dtype=np.int64)
        m = [_material(mats, e.mid, f"CONROD {e.eid}") for e in conrods]
        sec = {"A": [e.A for e in conrods], "Iy": 1.0, "Iz": 1.0, "J": [e.j or 0.0 for e in conrods],
               "Asy": math.inf, "Asz": math.inf}
        sec = {k: np.broadcast_to(np.asarray(v, float), (len(eids),)) for k, v in sec.items()}
        sec, mat = _rod_torsion(sec, {k: np.array([mi[k] for mi in m]) for k in ("E", "G", "rho")})
        nsm = np.array([e.nsm or 0.0 for e in conrods]) * wtmass
        model.add_beams(eids, ends, sec, mat, _rod_orient(nodes, ends, "CONROD", eids), nsm=nsm,
                        rod=True, label="CONROD")


def _rod_orient(nodes: _NodeTable, ends: np.ndarray, card: str, eids: np.ndarray) -> np.ndarray:
    """Some vector not parallel to each rod (rods have no bending; the element wants axes)."""
    xyz = nodes.coords(ends, card, eids)
    d = np.abs(xyz[:, 1] - xyz[:, 0])
    return np.eye(3)[np.argmin(d, axis=1)]


def _rect_frame(bdf, cid: int, card: str) -> np.ndarray:
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


def _add_masses(bdf, model: Model, nodes: _NodeTable, wtmass: float) -> None:
    """CONM2: mass, cg offset and inertia tensor (minus signs on I21, I31, I32), times WTMASS."""
    conm2 = [m for m in bdf.masses.values() if m.type == "CONM2"]
    if not conm2:
        return
    eids = np.array([m.eid for m in conm2], dtype=np.int64)
    nids = np.array([m.nid for m in conm2], dtype=np.int64)
    xyz = nodes.coords(nids, "CONM2", eids)
    mass = np.array([m.mass for m in conm2], dtype=float)
    X = np.array([m.X for m in conm2], dtype=float)
    I = np.array([m.I for m in conm2], dtype=float)  # I11, I21, I22, I31, I32, I33
    tensor = np.empty((len(conm2), 3, 3))
    tensor[:, 0, 0], tensor[:, 1, 1], tensor[:, 2, 2] = I[:, 0], I[:, 2], I[:, 5]
    tensor[:, 0, 1] = tensor[:, 1, 0] = -I[:, 1]
    tensor[:, 0, 2] = tensor[:, 2, 0] = -I[:, 3]
    tensor[:, 1, 2] = tensor[:, 2, 1] = -I[:, 4]
    cid = np.array([m.cid for m in conm2], dtype=np.int64)
    offset = X.copy()
    absolute = cid == -1  # X is the cg in basic coordinates
    offset[absolute] = X[absolute] - xyz[absolute]
    for i in np.flatnonzero(cid > 0):
        R = _rect_frame(bdf, int(cid[i]), f"CONM2 {eids[i]}")
        offset[i] = R.T @ X[i]
        tensor[i] = R.T @ tensor[i] @ R
    bad = mass < 0
    if bad.any():
        raise ModelError(f"CONM2 {eids[bad][0]}: mass must be >= 0, got {mass[bad][0]:g}")
    model.add_point_masses(nids, mass * wtmass, inertia=tensor * wtmass, offset=offset)


def _scalar_ends(e, card: str, nodes: _NodeTable):
    """(g1, c1, g2, c2) of a CELAS1/2 or CMASS1/2, grounded end last (g2 = 0)."""
    g1, g2 = (n or 0 for n in (list(e.nodes) + [None, None])[:2])
    c1, c2 = e.c1 or 0, e.c2 or 0
    if g1 == 0 and g2 == 0:
        raise ModelError(f"{card}: no grid given")
    if g1 == 0:  # grounded at its first end: swap
        g1, g2, c1, c2 = g2, g1, c2, c1
    spoints = getattr(nodes, "spoints", set())
    if c1 == 0 or (g2 != 0 and c2 == 0) or g1 in spoints or g2 in spoints:
        raise ModelError(f"{card}: scalar points (SPOINT, component 0) are not supported")
    if not (1 <= c1 <= 6) or (g2 and not 1 <= c2 <= 6):
        raise ModelError(f"{card}: component must be 1-6, got {c1} / {c2}")
    if g2 == g1 and c1 == c2:
        raise ModelError(f"{card}: both ends are component {c1} of grid {g1}")
    return g1, c1, g2, c2


def _add_scalar_elements(model: Model, nodes: _NodeTable, ends: list, values: np.ndarray, eids: np.ndarray,
                         card: str, kind: str) -> None:
    """Scalar springs (``kind`` "K") or masses ("M") between grid components, any frames.

    The element acts on ``u1 - u2`` with ``u`` the component along the grid's displacement
    frame, so its matrix is ``value * a a^T`` with ``a`` the two DOF directions (the second
    negated): a 12x12 block on the two grids, or 6x6 when grounded or on one grid.
    """
    if not ends:
        return
    g1, c1, g2, c2 = (np.array(col, dtype=np.int64) for col in zip(*ends))
    a = nodes.dof_vectors(g1, c1, card, eids)
    one = (g2 == 0) | (g2 == g1)
    two = ~one
    if one.any():
        v = a[one].copy()
        same = (g2[one] == g1[one])
        if same.any():
            v[same] -= nodes.dof_vectors(g1[one][same], c2[one][same], card, eids[one][same])
        blocks = values[one][:, None, None] * v[:, :, None] * v[:, None, :]
        model.add_matrices(eids[one], g1[one][:, None], **{kind: blocks}, label=card)
    if two.any():
        v = np.concatenate([a[two], -nodes.dof_vectors(g2[two], c2[two], card, eids[two])], axis=1)
        blocks = values[two][:, None, None] * v[:, :, None] * v[:, None, :]
        model.add_matrices(eids[two], np.column_stack([g1[two], g2[two]]), **{kind: blocks}, label=card)


def _add_springs(bdf, model: Model, nodes: _NodeTable) -> None:
    """CELAS1/CELAS2 and CBUSH/PBUSH.

    A CELAS on equal components of grids in the basic system is a model spring; any other
    (different components, displacement frames) a scalar element matrix.
    """
    ids, pairs, ks = [], [], []
    gen_ends, gen_k, gen_ids = [], [], []
    for e in bdf.elements.values():
        if e.type not in ("CELAS1", "CELAS2"):
            continue
        card = f"{e.type} {e.eid}"
        if e.type == "CELAS1":
            p = bdf.properties.get(e.pid)
            if p is None or p.type != "PELAS":
                raise ModelError(f"{card}: property {e.pid} is not a defined PELAS")
            k = float(p.k)
        else:
            k = float(e.k)
        if not (math.isfinite(k) and k >= 0):
            raise ModelError(f"{card}: stiffness must be finite and >= 0, got {k:g}")
        g1, c1, g2, c2 = _scalar_ends(e, card, nodes)
        framed = nodes.frames is not None and (
            np.any(nodes.frame([g1], card, [e.eid]) != np.eye(3))
            or (g2 and np.any(nodes.frame([g2], card, [e.eid]) != np.eye(3))))
        if (g2 and c1 != c2) or g2 == g1 or framed:
            gen_ends.append((g1, c1, g2, c2))
            gen_k.append(k)
            gen_ids.append(e.eid)
            continue
        kv = np.zeros(6)
        kv[c1 - 1] = k
        ids.append(e.eid)
        pairs.append([g1, g2 if g2 else -1])
        ks.append(kv)
    if ids:
        ids_a = np.array(ids, dtype=np.int64)
        pairs_a = np.array(pairs, dtype=np.int64)
        nodes.index(pairs_a[:, 0], "spring", ids_a)
        two = pairs_a[:, 1] >= 0
        nodes.index(pairs_a[two, 1], "spring", ids_a[two])
        model.add_springs(ids_a, pairs_a, np.array(ks))
    _add_scalar_elements(model, nodes, gen_ends, np.array(gen_k, float), np.array(gen_ids, dtype=np.int64),
                         "CELAS", "K")
    _add_bushes(bdf, model, nodes)


def _add_scalar_masses(bdf, model: Model, nodes: _NodeTable, wtmass: float) -> None:
    """CMASS1 (mass from PMASS) and CMASS2: scalar masses on grid components, times WTMASS."""
    ends, values, eids = [], [], []
    for m in bdf.masses.values():
        if m.type not in ("CMASS1", "CMASS2"):
            continue
        card = f"{m.type} {m.eid}"
        if m.type == "CMASS1":
            p = bdf.properties_mass.get(m.pid)
            if p is None or p.type != "PMASS":
                raise ModelError(f"{card}: property {m.pid} is not a defined PMASS")
            value = float(p.mass)
        else:
            value = float(m.mass)
        # NASTRAN takes a negative scalar mass (write_bdf's mass corrections use them); the
        # assembled mass is checked as a whole by the eigensolver
        if not math.isfinite(value):
            raise ModelError(f"{card}: mass must be finite, got {value:g}")
        ends.append(_scalar_ends(m, card, nodes))
        values.append(value * wtmass)
        eids.append(m.eid)
    _add_scalar_elements(model, nodes, ends, np.array(values, float), np.array(eids, dtype=np.int64),
                         "CMASS", "M")


def offset_spring_matrix(xa, xb, p, frame, k) -> np.ndarray:
    """12x12 global stiffness of a 6-DOF spring at point ``p`` joined rigidly to grids A and B.

    The spring sees the relative motion at ``p``: ``d = F6 (S_B u_B - S_A u_A)`` with
    ``S_X`` the rigid map from grid X to ``p`` and ``F6 = diag(F, F)`` (rows of ``frame``
    are the spring axes), so ``K = B^T F6^T diag(k) F6 B`` with ``B = [-S_A, S_B]``.
    """
    B = np.concatenate([-rigid_transform(np.asarray(p) - xa), rigid_transform(np.asarray(p) - xb)], axis=1)
    F6 = np.zeros((6, 6))
    F6[:3, :3] = F6[3:, 3:] = frame
    A = F6 @ B
    return A.T @ (np.asarray(k, float)[:, None] * A)


def _add_bushes(bdf, model: Model, nodes: _NodeTable) -> None:
    bushes = [e for e in bdf.elements.values() if e.type == "CBUSH"]
    if not bushes:
        return
    ids, pairs, ks, frames = [], [], [], []
    offset_ids, offset_pairs, offset_K = [], [], []
    for e in bushes:
        card = f"CBUSH {e.eid}"
        p = bdf.properties.get(e.pid)
        if p is None or p.type != "PBUSH":
            raise ModelError(f"{card}: property {e.pid} is not a defined PBUSH")
        if "K" not in p.vars:
            raise ModelError(f"PBUSH {p.pid}: no K stiffness line")
        k = np.array([0.0 if v is None else float(v) for v in (list(p.Ki) + [None] * 6)[:6]])
        ga, gb = e.nodes[0], e.nodes[1] if len(e.nodes) > 1 else None
        xa = nodes.coords([ga], "CBUSH", [e.eid])[0]
        xb = nodes.coords([gb], "CBUSH", [e.eid])[0] if gb else xa
        d = xb - xa
        L = float(np.linalg.norm(d))
        coincident = L <= 1e-9 * max(1.0, float(np.abs(nodes.xyz).max()))
        if e.ocid not in (None, -1) and any(v not in (None, 0.0) for v in (e.si or [])):
            raise ModelError(f"{card}: spring offset OCID/S1-S3 is not supported (it adds a lever arm)")
        if e.cid is not None and e.cid >= 0:
            frame = _rect_frame(bdf, int(e.cid), card)
        elif coincident:
            raise ModelError(f"{card}: element axes undefined (grounded or coincident grids need CID)")
        else:
            if e.g0 not in (None, 0):
                v = nodes.coords([e.g0], "CBUSH", [e.eid])[0] - xa
            elif e.x is not None and e.x[0] is not None:
                v = np.asarray(e.x, float)
            else:
                raise ModelError(f"{card}: no orientation (give X1-X3, G0 or CID)")
            x = d / L
            z = np.cross(x, v)
            if np.linalg.norm(z) <= 1e-9 * np.linalg.norm(v):
                raise ModelError(f"{card}: orientation vector is parallel to GA-GB")
            z /= np.linalg.norm(z)
            frame = np.vstack([x, np.cross(z, x), z])
        if not coincident:
            # NASTRAN puts the spring at the point S of GA-GB (S = 0.5 by default), joined
            # rigidly to both grids, so a translational stiffness across that line also
            # transmits a moment (lever arm): an element matrix of its own.
            across = np.linalg.norm(np.cross(frame, d / L), axis=1) > 1e-9
            if (across & (k[:3] != 0)).any():
                S = 0.5 if getattr(e, "s", None) is None else float(e.s)
                offset_ids.append(e.eid)
                offset_pairs.append([ga, gb])
                offset_K.append(offset_spring_matrix(xa, xb, xa + S * d, frame, k))
                continue
        ids.append(e.eid)
        pairs.append([ga, gb if gb else -1])
        ks.append(k)
        frames.append(frame)
    if ids:
        model.add_springs(np.array(ids, dtype=np.int64), np.array(pairs, dtype=np.int64), np.array(ks),
                          frame=np.array(frames))
    if offset_ids:
        model.add_matrices(np.array(offset_ids, dtype=np.int64), np.array(offset_pairs, dtype=np.int64),
                           K=np.array(offset_K), label="CBUSH")


def _comps(text, card: str) -> list[int]:
    """0-based components of a NASTRAN component string such as "123456"."""
    text = "" if text is None else str(text).strip()
    if any(ch not in "123456" for ch in text):
        raise ModelError(f"{card}: components {text!r} must be digits 1-6")
    return sorted({int(ch) - 1 for ch in text})


def _add_rigid_element(model: Model, nodes: _NodeTable, eid: int, grids, independent, dependent,
                       label: str) -> None:
    """A rigid element given by (grid, component) lists: a linear constraint of the model."""
    grids = list(dict.fromkeys(grids))
    pos = {g: i for i, g in enumerate(grids)}
    xyz = nodes.coords(grids, label.split()[0], [eid] * len(grids))
    frames = None if nodes.frames is None else nodes.frame(grids, label.split()[0], [eid] * len(grids))
    C = rigid_element(xyz, frames, [(pos[g], c) for g, c in independent],
                      [(pos[g], c) for g, c in dependent], label)
    dep = np.array(dependent, dtype=np.int64).reshape(-1, 2)
    ind = np.array(independent, dtype=np.int64).reshape(-1, 2)
    model.add_constraint(eid, (dep[:, 0], dep[:, 1]), (ind[:, 0], ind[:, 1]), C, label=label)


def _add_rigid(bdf, model: Model, nodes: _NodeTable) -> None:
    """RBE2 (rigid body), RBAR (rigid bar, any independent set) and RBE3 (interpolation)."""
    for eid, e in sorted(bdf.rigid_elements.items()):
        card = f"{e.type} {eid}"
        if e.type == "RBE2":
            nodes.index([e.gn], "RBE2", [eid])
            nodes.index(np.asarray(e.Gmi, dtype=np.int64), "RBE2", [eid] * len(e.Gmi))
            model.add_rigid_body(eid, e.gn, e.Gmi, dofs=str(e.cm), mass=0.0, label=card)
        elif e.type == "RBAR":
            ind = [(e.ga, c) for c in _comps(e.cna, card)] + [(e.gb, c) for c in _comps(e.cnb, card)]
            cma, cmb = _comps(e.cma, card), _comps(e.cmb, card)
            if not cma and not cmb:  # NASTRAN: blank CMA and CMB = every DOF not independent
                cma = [c for c in range(6) if (e.ga, c) not in ind]
                cmb = [c for c in range(6) if (e.gb, c) not in ind]
            dep = [(e.ga, c) for c in cma] + [(e.gb, c) for c in cmb]
            if set(dep) & set(ind):
                raise ModelError(f"{card}: a component is both independent and dependent")
            _add_rigid_element(model, nodes, eid, [e.ga, e.gb], ind, dep, card)
        elif e.type == "RBE3":
            if e.Gmi:
                raise ModelError(f"{card}: UM (alternative dependent DOFs) is not supported")
            rows, comps, weights = [], [], []
            for w, c, grids in zip(e.weights, e.comps, e.Gijs):
                mask = np.zeros(6, bool)
                mask[_comps(c, card)] = True
                for g in grids:
                    rows.append(int(g))
                    comps.append(mask)
                    weights.append(float(w))
            rows_a = np.array(rows, dtype=np.int64)
            comps_a = np.array(comps, dtype=bool).reshape(-1, 6)
            refc = np.zeros(6, bool)
            refc[_comps(e.refc, card)] = True
            ref_xyz = nodes.coords([e.refgrid], "RBE3", [eid])[0]
            xyz = nodes.coords(rows_a, "RBE3", [eid] * len(rows_a))
            frames = None if nodes.frames is None else nodes.frame(rows_a, "RBE3", [eid] * len(rows_a))
            ref_frame = None if nodes.frames is None else nodes.frame([e.refgrid], "RBE3", [eid])[0]
            C = rbe3_constraint(ref_xyz, ref_frame, xyz, frames, comps_a, weights, refc, card)
            ind_nodes = np.repeat(rows_a, comps_a.sum(axis=1))
            ind_comps = np.nonzero(comps_a)[1]
            dep_comps = np.flatnonzero(refc)
            model.add_constraint(eid, (np.full(len(dep_comps), e.refgrid), dep_comps), (ind_nodes, ind_comps),
                                 C, label=card)
        else:
            raise ModelError(f"{card}: not supported")


def _raw_fields(lines: list[str], name: str) -> list[str]:
    from pyNastran.bdf.bdf_interface.utils import to_fields  # deferred: ~1.5 s to load, decks only

    return [f.strip().upper() for f in to_fields(lines, name)]


def _ints(fields: list[str], card: str) -> list[int]:
    """Grid ids of a field list, with ``A THRU B`` expanded and blanks dropped."""
    out, i = [], 0
    fields = [f for f in fields if f]
    while i < len(fields):
        if i + 2 < len(fields) and fields[i + 1] == "THRU":
            out.extend(range(int(fields[i]), int(fields[i + 2]) + 1))
            i += 3
            continue
        try:
            out.append(int(fields[i]))
        except ValueError:
            raise ModelError(f"{card}: field {fields[i]!r} is not a grid id") from None
        i += 1
    return out


def _add_raw_rigid(bdf, model: Model, nodes: _NodeTable) -> None:
    """NASTRAN-95's rigid elements CRIGD1, CRIGD2, CRIGD3 and CRIGDR (unparsed by pyNastran).

    CRIGD1 EID GI GM...: every component of each GM follows GI rigidly. CRIGD2 EID GI
    (GM CM)...: the listed components. CRIGD3 EID (GI CI)... MSET (GM CM)...: six
    independent components anywhere on the element determine the rigid motion. CRIGDR EID
    GI GM CM: a rigid pin-ended rod, component CM of GM keeps the distance GI-GM.
    """
    for lines in getattr(bdf, "reject_lines", []):
        body = _card_lines(lines)
        name = body[0][:8].strip().rstrip("*").upper() if body else ""
        if "," in name:
            name = name.split(",")[0]
        if name not in RAW_CARDS:
            continue
        f = _raw_fields(body, name)
        try:
            eid = int(f[1])
        except (IndexError, ValueError):
            raise ModelError(f"{name}: no element id") from None
        card = f"{name} {eid}"
        try:
            if name == "CRIGD1":
                gi, gms = int(f[2]), _ints(f[3:], card)
                nodes.index([gi] + gms, name, [eid] * (1 + len(gms)))
                model.add_rigid_body(eid, gi, gms, dofs="123456", label=card)
            elif name == "CRIGD2":
                gi = int(f[2])
                vals = [x for x in f[3:] if x]
                pairs = list(zip(vals[0::2], vals[1::2]))
                grids = [gi] + [int(g) for g, _ in pairs]
                ind = [(gi, c) for c in range(6)]
                dep = [(int(g), c) for g, cm in pairs for c in _comps(cm, card)]
                _add_rigid_element(model, nodes, eid, grids, ind, dep, card)
            elif name == "CRIGD3":
                vals = [x for x in f[2:] if x]
                if "MSET" not in vals:
                    raise ModelError(f"{card}: no MSET (dependent components) given")
                k = vals.index("MSET")
                ind = [(int(g), c) for g, cm in zip(vals[:k:2], vals[1:k:2]) for c in _comps(cm, card)]
                dep = [(int(g), c) for g, cm in zip(vals[k + 1::2], vals[k + 2::2]) for c in _comps(cm, card)]
                grids = [g for g, _ in ind + dep]
                _add_rigid_element(model, nodes, eid, grids, ind, dep, card)
            else:  # CRIGDR
                gi, gm, cm = int(f[2]), int(f[3]), int(f[4])
                _add_rigid_rod(model, nodes, eid, gi, gm, cm, card)
        except (IndexError, ValueError):
            raise ModelError(f"{card}: malformed entry") from None


def _add_rigid_rod(model: Model, nodes: _NodeTable, eid: int, gi: int, gm: int, cm: int, card: str) -> None:
    """CRIGDR: ``e . (u_M - u_I) = 0`` solved for translation ``cm`` of GM (frames honoured)."""
    if cm not in (1, 2, 3):
        raise ModelError(f"{card}: dependent component must be a translation 1-3, got {cm}")
    x = nodes.coords([gi, gm], "CRIGDR", [eid, eid])
    d = x[1] - x[0]
    if not np.linalg.norm(d) > 0:
        raise ModelError(f"{card}: grids {gi} and {gm} coincide")
    e = d / np.linalg.norm(d)
    F = nodes.frame([gi, gm], "CRIGDR", [eid, eid])
    a, b = F[1] @ e, F[0] @ e  # the rod direction in each grid's displacement frame
    c = cm - 1
    if abs(a[c]) <= 1e-6:
        raise ModelError(f"{card}: component {cm} of grid {gm} is normal to the rod; it cannot be dependent")
    others = [k for k in range(3) if k != c]
    ind_nodes = [gi, gi, gi] + [gm, gm]
    ind_comps = [0, 1, 2] + others
    C = np.concatenate([b, -a[others]])[None, :] / a[c]
    model.add_constraint(eid, ([gm], [c]), (ind_nodes, ind_comps), C, label=card)


def _add_mpcs(bdf, model: Model, nodes: _NodeTable, info: BdfInfo) -> None:
    """MPC (through MPCADD) of the case control's MPC set: the first term is dependent."""
    chosen = _case_values(bdf, "MPC")
    if not chosen:
        if bdf.mpcs or bdf.mpcadds:
            info.notes.append(f"MPC sets {sorted(set(bdf.mpcs) | set(bdf.mpcadds))} present but not "
                              f"selected by the case control: not applied (as NASTRAN)")
        return
    top = int(chosen[0])
    if len(chosen) > 1:
        info.notes.append(f"subcases select different MPC sets {chosen}; using the first, {top}")
    sets, stack = [], [top]
    while stack:
        sid = stack.pop()
        if sid in sets:
            continue
        if sid not in bdf.mpcs and sid not in bdf.mpcadds:
            raise ModelError(f"case control MPC = {top}: MPC set {sid} is not defined")
        sets.append(sid)
        for add in bdf.mpcadds.get(sid, []):
            stack.extend(add.sets)
    for sid in sets:
        for k, c in enumerate(bdf.mpcs.get(sid, [])):
            card = f"MPC {sid}"
            g = np.asarray(c.nodes, dtype=np.int64)
            comp = [_comps(x, card) for x in c.components]
            if any(len(x) != 1 for x in comp):
                raise ModelError(f"{card}: each term needs exactly one component (scalar points are "
                                 f"not supported)")
            comp = np.array([x[0] for x in comp])
            a = np.asarray(c.coefficients, float)
            if a[0] == 0:
                raise ModelError(f"{card}: the dependent term's coefficient is 0")
            nodes.index(g, "MPC", [sid] * len(g))
            model.add_constraint(sid, ([g[0]], [comp[0]]), (g[1:], comp[1:]), -a[1:][None, :] / a[0],
                                 label=card)


def _add_dof_sets(bdf, model: Model, nodes: _NodeTable, info: BdfInfo) -> None:
    """OMIT/OMIT1 and ASET/ASET1 (Guyan reduction); SUPORT/SUPORT1 (accepted, noted)."""
    n = len(nodes.ids)
    def mask_of(cards, what):
        mask = np.zeros((n, 6), bool)
        for c in cards:
            ids = np.asarray(c.ids if hasattr(c, "ids") else c.node_ids, dtype=np.int64)
            comps = c.components if isinstance(c.components, list) else [c.components] * len(ids)
            idx = nodes.index(ids, what, np.zeros(len(ids), dtype=np.int64))
            for i, cm in zip(np.atleast_1d(idx), comps):
                mask[i, _comps(cm, what)] = True
        return mask

    omits = getattr(bdf, "omits", [])
    asets = getattr(bdf, "asets", [])
    if omits or asets:
        omitted = mask_of(omits, "OMIT")
        if asets:
            omitted |= ~mask_of(asets, "ASET")
        for c in range(6):
            sel = omitted[:, c]
            if sel.any():
                model.omit(nodes.ids[sel], str(c + 1))
        info.notes.append(f"OMIT/ASET: {int(omitted.sum())} DOFs condensed by Guyan reduction, as "
                          f"NASTRAN does (exact for DOFs without mass)")
    suport = getattr(bdf, "suport", []) + list(getattr(bdf, "suport1", {}).values())
    if suport:
        info.notes.append("SUPORT accepted: it selects reference DOFs for NASTRAN's rigid-body modes, "
                          "which trussid computes anyway (they come first, at about 0 Hz)")


def _check_scalar_points(bdf, info: BdfInfo) -> None:
    """SPOINTs are accepted only when nothing connects them (then they are inert)."""
    spoints = set(getattr(bdf, "spoints", {}) or {})
    if not spoints:
        return
    used = set()
    for e in list(bdf.elements.values()) + list(bdf.masses.values()):
        used |= {n for n in (getattr(e, "nodes", None) or []) if n in spoints}
    if used:
        g = sorted(used)[0]
        raise ModelError(f"SPOINT {g}: scalar points joined by elements are not supported")
    info.notes.append(f"SPOINT {', '.join(map(str, sorted(spoints)[:5]))}: unconnected scalar "
                      f"point(s), no effect on the modes: ignored")


def _nastran_mass_conventions(bdf, model: Model, nodes: _NodeTable, props: dict, info: BdfInfo) -> None:
    """NASTRAN's element mass where it differs from the textbook elements of fem.elements.

    Each was found on real NASTRAN output (the nastran-corpus diagnosis) and is added as a
    correction, so that :mod:`trussid.fem.elements` stays the textbook formulation:

    * lumped CBEAM: the section's torsional inertia ``rho (I1 + I2) L / 2`` about the axis
      at each end (a CBAR's lumped mass has none);
    * coupled CBAR: no torsional inertia (the textbook element has ``rho (I1 + I2)``): done
      in :func:`_add_bars`, exactly, by reading its structural mass as non-structural mass;
    * coupled CROD/CONROD: axial ``m [[5/12, 1/12], [1/12, 5/12]]``, transverse lumped
      ``m / 2`` (the textbook rod interpolates all three translations linearly);
    * coupled shear-flexible CBEAM (NX) and CBAR (MSC 2013 and the MSC NAS102 workshop run):
      the Euler-Bernoulli cubic translational mass without rotary inertia, on the
      shear-flexible stiffness (CBAR frames 1.7e-4 and 4.1e-4 off with the Timoshenko
      mass, 4e-7 and 7e-6 with this).
    """
    b = model.beams
    if len(b) == 0:
        return
    idx = nodes.index(b.nodes, "element", b.ids)
    xa, xb = nodes.xyz[idx[:, 0]], nodes.xyz[idx[:, 1]]
    d = xb - xa
    L = np.linalg.norm(d, axis=1)
    if not (L > 0).all():
        return  # zero-length elements are reported by the assembly, naming them
    e = d / L[:, None]
    cbeam = np.array([str(lbl).split()[0] in ("PBEAM", "PBEAML") for lbl in b.labels]) & ~b.rod
    if model.mass_formulation == "lumped":
        sel = cbeam & (b.rho * (b.Iy + b.Iz) > 0)
        if sel.any():
            polar = b.rho[sel] * (b.Iy[sel] + b.Iz[sel]) * L[sel] / 2.0
            tensor = polar[:, None, None] * e[sel][:, :, None] * e[sel][:, None, :]
            model.add_point_masses(np.concatenate([b.nodes[sel, 0], b.nodes[sel, 1]]), 0.0,
                                   inertia=np.concatenate([tensor, tensor]))
            info.notes.append(f"CBEAM lumped mass: torsional inertia rho (I1 + I2) L / 2 at each end "
                              f"({int(sel.sum())} elements), as NASTRAN")
        return
    cbar = np.array([str(lbl).split()[0] in ("PBAR", "PBARL") for lbl in b.labels]) & ~b.rod
    if cbar.any():
        info.notes.append(f"CBAR coupled mass: no torsional inertia ({int(cbar.sum())} elements: structural "
                          f"mass read as non-structural mass per length), as NASTRAN")
    rod = np.asarray(b.rod, bool)
    if rod.any():
        m = (b.rho[rod] * b.A[rod] + b.nsm[rod]) * L[rod]
        ee = e[rod][:, :, None] * e[rod][:, None, :]
        # NASTRAN minus textbook: axial 5/12 - 1/3 = 1/12, transverse 1/2 - 1/3 = 1/6 on the
        # diagonal, the opposite off the diagonal (total mass unchanged).
        B3 = m[:, None, None] * (ee / 12.0 + (np.eye(3) - ee) / 6.0)
        dM = np.zeros((int(rod.sum()), 12, 12))
        dM[:, :3, :3] = dM[:, 6:9, 6:9] = B3
        dM[:, :3, 6:9] = dM[:, 6:9, :3] = -B3
        model.add_matrices(b.ids[rod], b.nodes[rod], M=dM, label="CROD coupled mass (NASTRAN)")
        info.notes.append(f"CROD coupled mass: axial 5/12, 1/12 and lumped transverse mass "
                          f"({int(rod.sum())} rods), as NASTRAN")
    shear = (cbeam | cbar) & (np.isfinite(b.Asy) | np.isfinite(b.Asz))
    if model.beam_theory == "timoshenko" and shear.any():
        s = shear
        Ls, R = local_axes(xa[s], xb[s], b.orient[s], b.ids[s])
        args = (Ls, b.A[s], b.Iy[s], b.Iz[s], b.J[s], b.E[s], b.G[s], b.rho[s])
        kw = dict(nsm=b.nsm[s], Asy=b.Asy[s], Asz=b.Asz[s], R=R, mass="consistent")
        M_eb = frame_matrices(*args, **kw, theory="euler-bernoulli")[1]
        M_t = frame_matrices(*args, **kw, theory="timoshenko")[1]
        dM = M_eb - M_t
        dM = 0.5 * (dM + dM.transpose(0, 2, 1))
        model.add_matrices(b.ids[s], b.nodes[s], M=dM, label="CBAR/CBEAM coupled mass (NASTRAN)")
        info.notes.append(f"CBAR/CBEAM coupled mass with shear flexibility: Euler-Bernoulli cubic mass "
                          f"without rotary inertia ({int(s.sum())} elements), as NASTRAN")


def _case_values(bdf, key: str) -> list:
    """Values of case-control ``key`` (e.g. "SPC", "METHOD") over the subcases, in order."""
    deck = getattr(bdf, "case_control_deck", None)
    if deck is None:
        return []
    values = []
    for sid in sorted(deck.subcases):
        sub = deck.subcases[sid]
        if sub.has_parameter(key)[0]:
            value = sub.get_parameter(key)[0]
            if value not in values:
                values.append(value)
    return values


def _add_spcs(bdf, model: Model, nodes: _NodeTable, info: BdfInfo) -> None:
    """SPC/SPC1 (through SPCADD) of the case control's SPC set, else of all sets; GRID PS."""
    all_sets = set(bdf.spcs) | set(bdf.spcadds)
    chosen = _case_values(bdf, "SPC")
    if chosen:
        if len(chosen) > 1:
            info.notes.append(f"subcases select different SPC sets {chosen}; using the first, {chosen[0]}")
        top = int(chosen[0])
        if top not in all_sets:
            raise ModelError(f"case control SPC = {top}, but no SPC, SPC1 or SPCADD has set {top}")
        info.spc_reason = f"SPC = {top} in the case control"
        roots = [top]
    elif all_sets:
        roots = sorted(all_sets)
        info.spc_reason = "no SPC request in the case control: all SPC sets applied"
    else:
        roots = []
        info.spc_reason = "no SPC cards"
    used = []
    stack = list(roots)
    while stack:
        sid = stack.pop()
        if sid in used:
            continue
        used.append(sid)
        for add in bdf.spcadds.get(sid, []):
            for s in add.sets:
                if s not in all_sets:
                    raise ModelError(f"SPCADD {sid}: SPC set {s} is not defined")
                stack.append(s)
    info.spc_sets = sorted(used) if used else None
    by_comp = defaultdict(list)
    for sid in used:
        for c in bdf.spcs.get(sid, []):
            if c.type == "SPC1":
                ids = np.asarray(c.nodes, dtype=np.int64)
                nodes.index(ids, "SPC1", np.full(len(ids), sid))
                by_comp[str(c.components)].append(ids)
            elif c.type == "SPC":
                for nid, comp, d in zip(c.nodes, c.components, c.enforced):
                    if d:
                        info.notes.append(f"SPC {sid}: enforced displacement {d:g} at grid {nid} "
                                          f"(irrelevant to modes) treated as a support")
                    nodes.index([nid], "SPC", [sid])
                    by_comp[str(comp)].append(np.array([nid], dtype=np.int64))
            else:
                raise ModelError(f"{c.type} {sid}: not supported")
    for g in bdf.nodes.values():
        if g.ps:
            by_comp[str(g.ps)].append(np.array([g.nid], dtype=np.int64))
    for comp, chunks in sorted(by_comp.items()):
        comp = comp.replace("0", "")  # component 0 is a scalar point's: nothing to fix
        if comp:
            model.fix(np.unique(np.concatenate(chunks)), comp)


def _select_eigen(bdf, info: BdfInfo) -> None:
    methods = {sid: m for sid, m in bdf.methods.items() if m.type in ("EIGRL", "EIGR")}
    chosen = _case_values(bdf, "METHOD")
    if chosen:
        sid = int(chosen[0])
        if sid not in methods:
            raise ModelError(f"case control METHOD = {sid}, but no EIGRL or EIGR has SID {sid}")
        if len(chosen) > 1:
            info.notes.append(f"subcases select different METHODs {chosen}; using the first, {sid}")
    elif methods:
        sid = min(methods)
        if len(methods) > 1:
            info.notes.append(f"several eigenvalue requests and no METHOD in the case control; using {sid}")
    else:
        return
    m = methods[sid]
    if m.type == "EIGRL":
        info.eigen = EigenRequest("EIGRL", sid, m.nd, m.v1, m.v2)
    else:
        info.eigen = EigenRequest("EIGR", sid, m.nd or m.ne, m.f1, m.f2)


# ======================================================================= writing
def write_bdf(model: Model, path: str | os.PathLike, n_modes: int | None = 20,
              title: str | None = None) -> None:
    """Write ``model`` as a runnable SOL 103 NASTRAN deck.

    Parameters
    ----------
    model : fem.Model
    path : path-like
        Output deck; written atomically (no partial file on error).
    n_modes : int or None
        ND of the EIGRL written (with METHOD in the case control); None writes no EIGRL.
    title : str, optional
        Case-control TITLE (default: the model's name).

    Notes
    -----
    Cards written: GRID; CBAR + PBAR (``I1 = Iz``, ``I2 = Iy``, K1/K2 = shear areas / A only
    for a Timoshenko model, blank otherwise) or CROD + PROD for rods; MAT1 (E, G, RHO; NU
    left blank so NASTRAN derives it); CONM2 (mass, offset and inertia about the cg, products
    of inertia with NASTRAN's sign); CELAS2 per nonzero component of springs in global axes,
    CBUSH + PBUSH with a CORD2R for springs in other axes (grounded or between coincident
    grids only: elsewhere NASTRAN adds a lever arm the model's spring does not have); RBE2
    (a rigid body's mass as a CONM2 at its master, CID = 0, offset to its cg); SPC1 (set 1);
    PARAM,COUPMASS (1 consistent, -1 lumped); EIGRL. NASTRAN's coupled CROD and CBAR mass differ
    from the model's textbook consistent mass (see :func:`_nastran_mass_conventions`), so a
    consistent-mass model with rods or torsional inertia reads back with NASTRAN's mass, as
    NASTRAN would run it. Element ids that clash across kinds are
    renumbered above the largest id. Values are written in 16-character fields so that a
    re-read model matches to about 1e-12 (16-character fields).

    Examples
    --------
    A model built in Python, written as a deck and read back: the same modes.

    >>> import numpy as np
    >>> from trussid.fem import ALUMINIUM, Model, Section, read_bdf, solve_modes, write_bdf
    >>> m = Model(mass="lumped")
    >>> m.add_nodes([1, 2, 3], [[0, 0, 0], [0, 0, 0.5], [0, 0, 1.0]])
    >>> m.add_beams([1, 2], [[1, 2], [2, 3]], Section.tube(0.0125, 0.002), ALUMINIUM, orient=[1, 0, 0])
    >>> m.fix(1)
    >>> write_bdf(m, "mast.bdf", n_modes=4)
    >>> again, info = read_bdf("mast.bdf")
    >>> f0, f1 = solve_modes(m, 4).frequencies_hz, solve_modes(again, 4).frequencies_hz
    >>> print(np.round(f0, 2), np.allclose(f0, f1, rtol=1e-6), info.eigen.n_modes)
    [ 20.71  20.71 106.69 106.69] True 4
    """
    from cpylog import SimpleLogger  # deferred: ~1.5 s to load, decks only
    from pyNastran.bdf.bdf import BDF  # deferred: ~1.5 s to load, decks only
    from pyNastran.bdf.case_control_deck import CaseControlDeck  # deferred: ~1.5 s to load, decks only

    bdf = BDF(log=SimpleLogger(level="critical"), debug=None)
    ids, xyz = model.node_ids, model.xyz
    if len(ids) == 0:
        raise ModelError("write_bdf: the model has no nodes")
    unwritable = [what for what, present in (
        ("element matrices (add_matrices)", bool(getattr(model, "general", None))),
        ("linear constraints (add_constraint)", bool(getattr(model, "constraints", None))),
        ("node displacement frames", model.node_frames() is not None if hasattr(model, "node_frames") else False),
        ("omitted DOFs", bool(model.omitted_mask().any()) if hasattr(model, "omitted_mask") else False),
    ) if present]
    if unwritable:
        raise ModelError(f"write_bdf: the model has {', '.join(unwritable)}, which this writer does not "
                         f"translate back into NASTRAN entries")
    for nid, x in zip(ids.tolist(), xyz):
        bdf.add_grid(nid, x.tolist())

    used_eids: set[int] = set()
    next_id = [0]
    beams = model.beams
    all_ids = [beams.ids, model.springs.ids, np.array([b.id for b in model.rigid_bodies], dtype=np.int64)]
    next_id[0] = int(max([a.max() for a in all_ids if len(a)] + [0])) + 1

    def eid_for(wanted: int) -> int:
        if wanted > 0 and wanted not in used_eids:
            used_eids.add(wanted)
            return wanted
        new = next_id[0]
        next_id[0] += 1
        used_eids.add(new)
        return new

    _write_beams(bdf, model, eid_for)
    _write_masses(bdf, model, eid_for)
    _write_springs(bdf, model, eid_for)
    _write_rigid(bdf, model, eid_for)

    fixed = model.fixed_mask() if model.has_supports else np.zeros((len(ids), 6), bool)
    has_spc = bool(fixed.any())
    if has_spc:
        codes = np.array(["".join(str(k + 1) for k in np.flatnonzero(row)) for row in fixed])
        for comp in sorted(set(codes) - {""}):
            bdf.add_spc1(1, comp, ids[codes == comp].tolist())
    bdf.add_param("COUPMASS", [1 if model.mass_formulation == "consistent" else -1])
    if n_modes:
        bdf.add_eigrl(1, nd=int(n_modes))

    bdf.sol = 103
    bdf.executive_control_lines = ["SOL 103", "CEND"]
    lines = [f"TITLE = {title or model.name}", "ECHO = NONE", "SUBCASE 1"]
    if n_modes:
        lines.append("  METHOD = 1")
    if has_spc:
        lines.append("  SPC = 1")
    lines += ["  DISPLACEMENT = ALL", "BEGIN BULK"]
    bdf.case_control_deck = CaseControlDeck(lines, log=bdf.log)
    with atomic_path(path) as tmp:
        bdf.write_bdf(str(tmp), size=16, is_double=False, enddata=True)
        n_scalar = _write_mass_corrections(bdf, model, tmp, eid_for)
        if n_scalar:
            bdf.write_bdf(str(tmp), size=16, is_double=False, enddata=True)


def _global_mass(model: Model):
    """The model's unconstrained mass matrix (6 DOFs per node, in node-id order) [kg, kg m^2]."""
    _, Mb, db = beam_matrices(model)
    ms, dm = mass_blocks(model)
    _, mg, dg = general_blocks(model)
    return _coo([Mb] + ms + mg, [db] + dm + dg, model.n_dof)


#: Mass entries of the written deck's difference from the model below this fraction of
#: ``sqrt(M_ii M_jj)`` are the round-off of 16-character fields, not a convention: no card.
MASS_CORRECTION_FLOOR = 1e-11


def _write_mass_corrections(bdf, model: Model, deck, eid_for) -> int:
    """CMASS2 elements that make NASTRAN's mass of the written ``deck`` the model's own.

    NASTRAN's coupled CBAR mass has no torsional inertia, its coupled CROD mass is not the
    textbook rod's and its shear-flexible coupled mass drops the rotary inertia
    (:func:`_nastran_mass_conventions`). The deck is read back as NASTRAN would run it and
    the difference ``dM`` from the model's mass is added as scalar masses: ``-dM_ij``
    between components ``i`` and ``j`` (a CMASS2 adds its value to both diagonals and
    subtracts it off the diagonal), and on each diagonal the rest, grounded. NASTRAN takes
    negative scalar masses; the sum is the model's positive semi-definite mass. Returns the
    number of cards added.
    """
    back, _ = read_bdf(deck)
    M0 = _global_mass(model).tocsr()
    # the read-back model's DOFs in the model's node order
    pos = {int(n): i for i, n in enumerate(back.node_ids)}
    perm = np.array([pos[int(n)] for n in model.node_ids])
    dof = (6 * perm[:, None] + np.arange(6)).ravel()
    M1 = _global_mass(back).tocsr()[dof][:, dof]
    dM = (M0 - M1).tocoo()
    d0 = np.abs(M0.diagonal())
    scale = np.sqrt(np.maximum(d0[dM.row] * d0[dM.col], 1e-300))
    big = np.abs(dM.data) > MASS_CORRECTION_FLOOR * scale
    if not big.any():
        return 0
    rows, cols, vals = dM.row[big], dM.col[big], dM.data[big]
    ids = model.node_ids
    diag = np.zeros(model.n_dof)
    n = 0
    for i, j, v in zip(rows.tolist(), cols.tolist(), vals.tolist()):
        if i < j:
            gi, gj = int(ids[i // 6]), int(ids[j // 6])
            bdf.add_cmass2(eid_for(0), -v, [gi, gj], i % 6 + 1, j % 6 + 1,
                           comment="" if n else "model mass minus NASTRAN's coupled element "
                           "mass (trussid write_bdf)")
            diag[i] += v
            diag[j] += v
            n += 1
        elif i == j:
            diag[i] += v
    for i in np.flatnonzero(np.abs(diag) > MASS_CORRECTION_FLOOR * np.maximum(d0, 1e-300)):
        bdf.add_cmass2(eid_for(0), float(diag[i]), [int(ids[i // 6]), None], int(i % 6 + 1), None)
        n += 1
    return n


def _unique_rows(arr: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rows, inverse = np.unique(arr, axis=0, return_inverse=True)
    return rows, inverse.ravel()


def _write_beams(bdf, model: Model, eid_for) -> None:
    b = model.beams
    if len(b) == 0:
        return
    mats, mat_of = _unique_rows(np.column_stack([b.E, b.G, b.rho]))
    for mid, (E, G, rho) in enumerate(mats, start=1):
        bdf.add_mat1(mid, float(E), float(G), None, rho=float(rho))
    timo = model.beam_theory == "timoshenko"
    Asy = np.where(np.isfinite(b.Asy), b.Asy, 0.0)
    Asz = np.where(np.isfinite(b.Asz), b.Asz, 0.0)
    keys = np.column_stack([b.rod, b.A, b.Iy, b.Iz, b.J, Asy, Asz, b.nsm, mat_of])
    props, prop_of = _unique_rows(keys)
    for pid, (rod, A, Iy, Iz, J, asy, asz, nsm, mi) in enumerate(props, start=1):
        mid = int(mi) + 1
        label = str(b.labels[np.flatnonzero(prop_of == pid - 1)[0]])
        if rod:
            bdf.add_prod(pid, mid, float(A), j=float(J), nsm=float(nsm), comment=label)
        else:
            # Euler-Bernoulli: K1/K2 blank (no shear flexibility). pyNastran writes blank
            # for its 1e8 sentinel.
            k1 = float(asy / A) if timo and asy > 0 else 1e8
            k2 = float(asz / A) if timo and asz > 0 else 1e8
            bdf.add_pbar(pid, mid, A=float(A), i1=float(Iz), i2=float(Iy), j=float(J), nsm=float(nsm),
                         k1=k1, k2=k2, comment=label)
    for i in range(len(b)):
        eid = eid_for(int(b.ids[i]))
        pid = int(prop_of[i]) + 1
        ga, gb = (int(n) for n in b.nodes[i])
        if b.rod[i]:
            bdf.add_crod(eid, pid, [ga, gb])
        else:
            bdf.add_cbar(eid, pid, [ga, gb], b.orient[i].tolist(), None)


def _tensor_to_conm2(I: np.ndarray) -> list[float]:
    """Tensor about the cg -> CONM2 I11, I21, I22, I31, I32, I33 (NASTRAN adds the minus)."""
    return [float(I[0, 0]), float(-I[1, 0]), float(I[1, 1]), float(-I[2, 0]), float(-I[2, 1]),
            float(I[2, 2])]


def _write_masses(bdf, model: Model, eid_for) -> None:
    pm = model.point_masses
    for i in range(len(pm)):
        bdf.add_conm2(eid_for(0), int(pm.nodes[i]), float(pm.mass[i]), cid=0,
                      X=pm.offset[i].tolist(), I=_tensor_to_conm2(pm.inertia[i]))


def _write_springs(bdf, model: Model, eid_for) -> None:
    s = model.springs
    if len(s) == 0:
        return
    ids, xyz = model.node_ids, model.xyz
    pos = {int(n): i for i, n in enumerate(ids)}
    next_cid = [max(bdf.coords) + 1]
    next_pid = [max(bdf.properties, default=0) + 1]
    for i in range(len(s)):
        ga, gb = int(s.nodes[i, 0]), int(s.nodes[i, 1])
        frame = s.frame[i]
        if np.array_equal(frame, np.eye(3)):
            for c in np.flatnonzero(s.k[i]):
                nodes = [ga, gb] if gb >= 0 else [ga, None]
                comps = [int(c) + 1, int(c) + 1] if gb >= 0 else [int(c) + 1, 0]
                bdf.add_celas2(eid_for(int(s.ids[i])), float(s.k[i, c]), nodes, c1=comps[0], c2=comps[1])
            continue
        if gb >= 0 and np.linalg.norm(xyz[pos[ga]] - xyz[pos[gb]]) > 0:
            raise ModelError(f"spring {s.ids[i]}: a spring in rotated axes between non-coincident nodes "
                             f"{ga} and {gb} has no exact NASTRAN equivalent (CBUSH adds a lever arm)")
        cid = next_cid[0]
        next_cid[0] += 1
        # CORD2R by origin, a point on z and a point in the x-z plane (basic coordinates).
        bdf.add_cord2r(cid, [0.0, 0.0, 0.0], frame[2].tolist(), frame[0].tolist())
        pid = next_pid[0]
        next_pid[0] += 1
        bdf.add_pbush(pid, s.k[i].tolist(), [0.0] * 6, [0.0] * 6)
        bdf.add_cbush(eid_for(int(s.ids[i])), pid, [ga, gb if gb >= 0 else None], None, None, cid=cid)


def _write_rigid(bdf, model: Model, eid_for) -> None:
    xyz_of = dict(zip(model.node_ids.tolist(), model.xyz))
    for rb in model.rigid_bodies:
        comps = "".join(str(k + 1) for k in np.flatnonzero(rb.dofs))
        bdf.add_rbe2(eid_for(rb.id), rb.master, comps, rb.slaves.tolist(), comment=rb.label)
        if rb.mass > 0 or np.any(rb.inertia):
            if rb.master not in xyz_of:
                raise ModelError(f"{rb.label}: master node {rb.master} is not defined")
            offset = np.zeros(3) if rb.cg is None else np.asarray(rb.cg, float) - xyz_of[rb.master]
            bdf.add_conm2(eid_for(0), rb.master, float(rb.mass), cid=0, X=offset.tolist(),
                          I=_tensor_to_conm2(rb.inertia), comment=f"mass of {rb.label}")
