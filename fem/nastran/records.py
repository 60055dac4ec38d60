"""The typed entries of a NASTRAN deck: one small frozen dataclass (or named tuple) per kind
of entry :func:`trussid.fem.nastran.read_bdf` translates, whose attributes are the QRG's field
names with NASTRAN's defaults applied, and the :class:`Bulk` that gathers them by kind.

:mod:`trussid.fem.nastran.bulk` builds them from the cards; :mod:`trussid.fem.nastran.coords`
resolves the coordinate systems (:class:`Coord`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from trussid.fem.nastran.cards import ParsedDeck

__all__ = ["Grid", "Coord", "BASIC", "Bar", "BarDefaults", "Rod", "Scalar", "Bush", "Conm2", "Prop", "Mat1", "Rigid",
           "Spc", "Mpc", "SetAdd", "DofSet", "Eigrl", "Load", "GrdSet", "Bulk"]


class Grid(NamedTuple):
    nid: int
    cp: int
    xyz: tuple
    cd: int
    ps: str
    seid: int


@dataclass(frozen=True, slots=True)
class Coord:
    """A coordinate system resolved in basic: origin and axes (rows i, j, k)."""

    cid: int
    Type: str  # "R", "C" or "S"
    origin: np.ndarray
    i: np.ndarray
    j: np.ndarray
    k: np.ndarray

    @property
    def R(self) -> np.ndarray:
        return np.vstack([self.i, self.j, self.k])

    def to_basic(self, p: np.ndarray) -> np.ndarray:
        """Basic coordinates of points ``p`` (n, 3) given in this system (angles in degrees)."""
        p = np.asarray(p, float).reshape(-1, 3)
        if self.Type == "C":
            t = np.radians(p[:, 1])
            p = np.column_stack([p[:, 0] * np.cos(t), p[:, 0] * np.sin(t), p[:, 2]])
        elif self.Type == "S":
            t, f = np.radians(p[:, 1]), np.radians(p[:, 2])
            p = np.column_stack([p[:, 0] * np.sin(t) * np.cos(f), p[:, 0] * np.sin(t) * np.sin(f),
                                 p[:, 0] * np.cos(t)])
        return self.origin + p @ self.R


BASIC = Coord(0, "R", np.zeros(3), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, 1.0]))


class Bar(NamedTuple):
    """CBAR or CBEAM (BAROR/BEAMOR defaults applied). Grid, Bar and Scalar, the entries a
    large deck has by the hundred thousand, are named tuples: immutable, and three times
    faster to build than frozen dataclasses."""

    type: str
    eid: int
    pid: int
    ga: int
    gb: int
    x: tuple | None
    g0: int | None
    offt: str
    pa: int
    pb: int
    wa: tuple
    wb: tuple
    sa: int
    sb: int
    bit: float | None

    @property
    def nodes(self):
        return [self.ga, self.gb]


class BarDefaults(NamedTuple):
    """BAROR/BEAMOR: defaults of the CBAR/CBEAM entries that leave a field blank."""

    pid: int         # 0: none (the element's own id, NASTRAN's default)
    x: tuple | None  # orientation vector X1-X3, or None
    g0: int | None   # orientation grid G0, or None
    offt: str | None


@dataclass(frozen=True, slots=True)
class Rod:
    """CROD (``mid``/``A``... unused) or CONROD (``pid`` 0)."""

    type: str
    eid: int
    pid: int
    nodes: tuple
    mid: int = 0
    A: float = 0.0
    j: float = 0.0
    nsm: float = 0.0


class Scalar(NamedTuple):
    """CELAS1/2 and CMASS1/2: ``value`` is K or M (1: from the property ``pid``)."""

    type: str
    eid: int
    pid: int
    value: float | None
    nodes: tuple
    c1: int
    c2: int

    @property
    def k(self):
        return self.value

    @property
    def mass(self):
        return self.value


@dataclass(frozen=True, slots=True)
class Bush:
    type: str
    eid: int
    pid: int
    nodes: tuple
    x: tuple | None
    g0: int | None
    cid: int | None
    s: float | None
    ocid: int | None
    si: tuple


@dataclass(frozen=True, slots=True)
class Conm2:
    type: str
    eid: int
    nid: int
    cid: int
    mass: float
    X: tuple
    I: tuple


@dataclass(frozen=True, slots=True)
class Prop:
    """PBAR, PBEAM (per-station arrays A, i1...), PBARL/PBEAML, PROD, PTUBE, PELAS, PBUSH, PMASS."""

    type: str
    pid: int
    mid: int | None = None
    A: object = 0.0
    i1: object = 0.0
    i2: object = 0.0
    i12: object = 0.0
    j: object = 0.0
    nsm: object = 0.0
    k1: float | None = None
    k2: float | None = None
    k: float = 0.0  # PELAS K
    mass: float = 0.0  # PMASS M
    Ki: tuple = ()  # PBUSH K1-K6
    vars: tuple = ()  # PBUSH keywords given
    beam_type: str = ""  # PBARL/PBEAML section type
    dim: object = None  # PBARL dimensions; PBEAML (stations, dimensions)
    xxb: tuple = (0.0,)  # PBEAM/PBEAML station positions X/XB, end A (0.0) first
    OD1: float = 0.0  # PTUBE outer diameters and wall thickness (None: solid)
    OD2: float | None = None
    t: float | None = None
    # PBEAM non-structural inertia, warping, centre-of-mass and neutral-axis offsets
    nsia: float = 0.0
    nsib: float = 0.0
    cwa: float = 0.0
    cwb: float = 0.0
    m1a: float = 0.0
    m2a: float = 0.0
    m1b: float = 0.0
    m2b: float = 0.0
    n1a: float = 0.0
    n2a: float = 0.0
    n1b: float = 0.0
    n2b: float = 0.0


@dataclass(frozen=True, slots=True)
class Mat1:
    mid: int
    e: float
    g: float
    nu: float
    rho: float


@dataclass(frozen=True, slots=True)
class Rigid:
    """RBE2 (gn, cm, Gmi), RBAR (ga, gb, cna, cnb, cma, cmb), RBE3 (refgrid, refc, weights,
    comps, Gijs, Gmi = UM grids)."""

    type: str
    eid: int
    gn: int = 0
    cm: str = ""
    Gmi: tuple = ()
    ga: int = 0
    gb: int = 0
    cna: str = ""
    cnb: str = ""
    cma: str = ""
    cmb: str = ""
    refgrid: int = 0
    refc: str = ""
    weights: tuple = ()
    comps: tuple = ()
    Gijs: tuple = ()


@dataclass(frozen=True, slots=True)
class Spc:
    """SPC (nodes, components, enforced) or SPC1 (nodes, one component string)."""

    type: str
    sid: int
    nodes: tuple
    components: object
    enforced: tuple = ()


@dataclass(frozen=True, slots=True)
class Mpc:
    sid: int
    nodes: tuple
    components: tuple
    coefficients: tuple


@dataclass(frozen=True, slots=True)
class SetAdd:
    sid: int
    sets: tuple


@dataclass(frozen=True, slots=True)
class DofSet:
    """OMIT/ASET/BSET/QSET/SUPORT (pairs) and their ``1`` forms: grid ids and components."""

    type: str
    ids: tuple
    components: object

    @property
    def nodes(self):
        return self.ids


@dataclass(frozen=True, slots=True)
class Eigrl:
    type: str
    sid: int
    v1: float | None
    v2: float | None
    nd: int | None


@dataclass(frozen=True, slots=True)
class Load:
    """FORCE/MOMENT (node, cid, mag, xyz) and FORCE1/MOMENT1 (node, mag, g1, g2)."""

    type: str
    sid: int
    node: int
    mag: float
    cid: int = 0
    xyz: tuple = (0.0, 0.0, 0.0)
    g1: int = 0
    g2: int = 0


@dataclass(frozen=True, slots=True)
class GrdSet:
    cp: int
    cd: int
    ps: str
    seid: int


@dataclass(frozen=True)
class Bulk:
    """A deck's entries by kind (ids -> typed entries), as :func:`read_bdf` translates them."""

    parsed: ParsedDeck
    nodes: dict
    coords: dict
    elements: dict
    masses: dict
    properties: dict
    properties_mass: dict
    materials: dict
    rigid_elements: dict
    spcs: dict
    spcadds: dict
    mpcs: dict
    mpcadds: dict
    omits: list
    asets: list
    bsets: list
    qsets: list
    suport: list
    suport1: dict
    spoints: set
    methods: dict
    loads: dict
    grdset: GrdSet | None
    raw: dict  # name -> list of Card, every entry not typed above
    card_count: dict
    xyz_basic: np.ndarray | None = None  # grid positions in basic, in ``nodes`` order

    @property
    def case(self):
        return self.parsed.case

    @property
    def solution(self) -> tuple:
        return self.parsed.sol, self.parsed.app
