"""Bulk-data cards (:mod:`~trussid.fem.nastran.cards`) to typed entries: what
:func:`trussid.fem.nastran.read_bdf` translates, with NASTRAN's defaults applied.

Each entry is a small frozen dataclass whose attributes are the QRG's field names
(:mod:`trussid.fem.nastran.records`); the :class:`Bulk` gathers them by kind (grids,
elements, properties...). Entries this module does not type stay available as
:class:`~trussid.fem.nastran.cards.Card` s (``Bulk.raw``). Coordinate systems (CORD1R/C/S,
CORD2R/C/S, each possibly defined in another) are resolved into origins and axes in the
basic system, and the grids' positions into basic, by :mod:`trussid.fem.nastran.coords`.
"""

from __future__ import annotations

import numpy as np

from trussid.fem.nastran.cards import (Card, ParsedDeck, integer, integer_or_blank, real, real_or_blank,
                                       to_int, to_real)
from trussid.fem.nastran.coords import resolve_coordinates
from trussid.fem.nastran.records import (Bar, BarDefaults, Bulk, Bush, Conm2, Coord, DofSet, Eigrl, GrdSet, Grid, Load, Mat1,
                                         Mpc, Prop, Rigid, Rod, Scalar, SetAdd, Spc)

# The entry types are re-exported: code imports them from here (nastran.bulk).
__all__ = ["Bulk", "build_bulk", "Coord"]

_SO = ("YES", "YESA", "NO")


# ================================================================== card -> entry
def _ints_thru(card: Card, start: int, what: str, stop: int | None = None) -> list:
    """Integers of fields ``start:stop`` with ``A THRU B`` expanded, blanks skipped."""
    out = []
    f = card.fields[start:stop]
    k = 0
    while k < len(f):
        t = f[k]
        if not t:
            k += 1
            continue
        if t == "THRU":
            if not out or k + 1 >= len(f):
                raise card.error(start + k, f"{what}: THRU without both ends")
            hi = to_int(f[k + 1])
            if hi is None:
                raise card.error(start + k + 1, f"{what} must be an integer, got {f[k + 1]!r}")
            out.extend(range(out[-1] + 1, hi + 1))
            k += 2
            continue
        v = to_int(t)
        if v is None:
            raise card.error(start + k, f"{what} must be an integer, got {t!r}")
        out.append(v)
        k += 1
    return out


_COMP_CHARS = frozenset("0123456 ")


def _comp(card: Card, i: int, default: str = "") -> str:
    """A component field: digits 0-6 (checked by the reader, which names the entry).

    Written with embedded blanks (``12 4 6``, as MYSTRAN writes them) it is the digits
    together (``1246``), as MYSTRAN and NASTRAN read it.
    """
    t = card.get(i)
    if " " in t and _COMP_CHARS.issuperset(t):
        t = t.replace(" ", "")
    return t if t else default


def _orientation(card: Card, i: int, default):
    """(x, g0) of fields i..i+2: G0 when field i is an integer, else X1-X3 (or the default)."""
    t = card.get(i)
    if not t:
        if card.get(i + 1) or card.get(i + 2):
            return (real_or_blank(card, i, "X1", 0.0), real_or_blank(card, i + 1, "X2", 0.0),
                    real_or_blank(card, i + 2, "X3", 0.0)), None
        return default
    g0 = to_int(t)
    if g0 is not None:
        return None, g0
    return (real(card, i, "X1"), real_or_blank(card, i + 1, "X2", 0.0), real_or_blank(card, i + 2, "X3", 0.0)), None


_ZERO3 = (0.0, 0.0, 0.0)


def _bar(card: Card, orient: dict[str, BarDefaults]) -> Bar:
    f = card.fields
    if len(f) == 9 and not f[8] and card.name not in orient:
        # fast path: one line, no pin flags or offsets (the bulk of a large deck); anything
        # unusual (implicit exponents, G0 forms...) falls through to the general path
        try:
            eid, ga, gb = int(f[1]), int(f[3]), int(f[4])
            pid = int(f[2]) if f[2] else eid
            x1, x2, x3 = f[5], f[6], f[7]
            x = (to_real(x1) if x1 else None, to_real(x2) if x2 else 0.0, to_real(x3) if x3 else 0.0)
            if None not in x:
                return Bar(card.name, eid, pid, ga, gb, x, None, "GGG", "", "", _ZERO3, _ZERO3, 0, 0, None)
        except ValueError:
            pass
    eid = integer(card, 1, "EID")
    d = orient.get(card.name)
    pid = integer_or_blank(card, 2, "PID", d.pid if d and d.pid else eid)
    default = (d.x, d.g0) if d else (None, None)
    x, g0 = _orientation(card, 5, default)
    f8 = card.get(8)
    bit = None
    offt = "GGG"
    if f8:
        if card.name == "CBEAM" and to_real(f8) is not None:
            bit = to_real(f8)
        else:
            offt = f8
    elif d and d.offt:
        offt = d.offt
    wa = tuple(real_or_blank(card, k, "offset", 0.0) for k in (11, 12, 13))
    wb = tuple(real_or_blank(card, k, "offset", 0.0) for k in (14, 15, 16))
    sa = integer_or_blank(card, 17, "SA", 0) if card.name == "CBEAM" else 0
    sb = integer_or_blank(card, 18, "SB", 0) if card.name == "CBEAM" else 0
    pa, pb = _comp(card, 9), _comp(card, 10)
    return Bar(card.name, eid, pid, integer(card, 3, "GA"), integer(card, 4, "GB"), x, g0, offt,
               pa, pb, wa, wb, sa, sb, bit)


def _baror(card: Card) -> BarDefaults:
    x, g0 = _orientation(card, 5, (None, None))
    return BarDefaults(integer_or_blank(card, 2, "PID", 0), x, g0, card.get(8))


def _mat1(card: Card) -> Mat1:
    mid = integer(card, 1, "MID")
    E = real_or_blank(card, 2, "E")
    G = real_or_blank(card, 3, "G")
    nu = real_or_blank(card, 4, "NU")
    rho = real_or_blank(card, 5, "RHO", 0.0)
    # NASTRAN's MAT1 rule: one blank of E, G, NU follows from E = 2 (1 + NU) G; E or G alone
    # gives the other and NU 0.0 (QRG MAT1 remarks).
    if E is None and G is None:
        raise card.error(2, "E and G cannot both be blank")
    if E is not None and G is not None and nu is not None:
        pass
    elif E is not None and nu is not None:
        G = E / 2.0 / (1.0 + nu)
    elif G is not None and nu is not None:
        E = 2.0 * (1.0 + nu) * G
    elif G is not None and E is not None:
        nu = E / (2.0 * G) - 1.0
    elif G is None:
        G, nu = 0.0, 0.0
    else:
        E, nu = 0.0, 0.0
    return Mat1(mid, E, G, nu, rho)


#: Dimensions of each PBARL/PBEAML section type (QRG PBARL table).
_NDIM = {"ROD": 1, "TUBE": 2, "TUBE2": 2, "BAR": 2, "BOX": 4, "I": 6, "CHAN": 4, "T": 4, "L": 4,
         "H": 4, "Z": 4, "CROSS": 4, "HAT": 4, "I1": 4, "CHAN1": 4, "CHAN2": 4, "T1": 4, "T2": 4,
         "BOX1": 6, "HEXA": 3, "HAT1": 5, "DBOX": 10}


def _reals(card: Card, start: int, stop: int, what: str, default=0.0) -> list:
    return [real_or_blank(card, k, what, default) for k in range(start, stop)]


def _pbeam(card: Card) -> Prop:
    pid = integer(card, 1, "PID")
    mid = integer(card, 2, "MID")
    a = [real(card, 3, "A")] + _reals(card, 4, 9, "section property")  # A I1 I2 I12 J NSM
    stations, xxb = [a], [0.0]
    n = len(card.fields)
    k = 9  # second line: stress recovery points at A, unless a station starts there
    if k < n and card.get(k) not in _SO:
        k += 8
    while k < n and card.get(k) in _SO:
        so = card.get(k)
        xxb.append(real(card, k + 1, "X/XB"))
        vals = [real_or_blank(card, k + 2 + m, "section property") for m in range(6)]
        stations.append([a[m] if v is None else v for m, v in enumerate(vals)])
        k += 8
        if so == "YES":
            k += 8  # its stress recovery points
    tail = [real_or_blank(card, k + m, "PBEAM field") for m in range(16)]
    k1 = 1.0 if tail[0] is None else tail[0]
    k2 = 1.0 if tail[1] is None else tail[1]
    z = [0.0 if v is None else v for v in tail]
    m1a, m2a = z[8], z[9]
    m1b = m1a if tail[10] is None else tail[10]
    m2b = m2a if tail[11] is None else tail[11]
    n1a, n2a = z[12], z[13]
    n1b = n1a if tail[14] is None else tail[14]
    n2b = n2a if tail[15] is None else tail[15]
    nsia = z[4]
    nsib = nsia if tail[5] is None else tail[5]
    cwa = z[6]
    cwb = cwa if tail[7] is None else tail[7]
    S = np.array(stations, float)
    return Prop("PBEAM", pid, mid, A=S[:, 0], i1=S[:, 1], i2=S[:, 2], i12=S[:, 3], j=S[:, 4], nsm=S[:, 5],
                k1=k1, k2=k2, m1a=m1a, m2a=m2a, m1b=m1b, m2b=m2b, n1a=n1a, n2a=n2a, n1b=n1b, n2b=n2b,
                nsia=nsia, nsib=nsib, cwa=cwa, cwb=cwb, xxb=tuple(xxb))


def _pbarl(card: Card) -> Prop:
    pid = integer(card, 1, "PID")
    mid = integer(card, 2, "MID")
    shape = card.get(4)
    if not shape:
        raise card.error(4, "TYPE (section shape) is blank")
    ndim = _NDIM.get(shape)
    n = len(card.fields)
    if card.name == "PBARL":
        if ndim is None:
            ndim = max(n - 10, 0)
        dims = _reals(card, 9, 9 + ndim, "DIM", None)
        if any(d is None for d in dims):
            raise card.error(9 + dims.index(None), f"DIM{dims.index(None) + 1} of {shape} is blank")
        nsm = real_or_blank(card, 9 + ndim, "NSM", 0.0)
        return Prop("PBARL", pid, mid, nsm=nsm, beam_type=shape, dim=dims)
    if ndim is None:
        ndim = max(n - 10, 0)
    dims = _reals(card, 9, 9 + ndim, "DIM", None)
    if any(d is None for d in dims):
        raise card.error(9 + dims.index(None), f"DIM{dims.index(None) + 1}(A) of {shape} is blank")
    rows, nsms, xxb = [dims], [real_or_blank(card, 9 + ndim, "NSM", 0.0)], [0.0]
    k = 10 + ndim
    while k < n and card.get(k) in _SO:
        xxb.append(real(card, k + 1, "X/XB"))
        d = _reals(card, k + 2, k + 2 + ndim, "DIM", None)
        rows.append([dims[m] if v is None else v for m, v in enumerate(d)])
        nsms.append(real_or_blank(card, k + 2 + ndim, "NSM", nsms[0]))
        k += 3 + ndim
    return Prop("PBEAML", pid, mid, nsm=np.array(nsms), beam_type=shape, dim=np.array(rows), xxb=tuple(xxb))


def _pbush(card: Card) -> Prop:
    pid = integer(card, 1, "PID")
    keys, Ki = [], ()
    for k in range(2, len(card.fields), 8):
        key = card.get(k)
        if not key:
            continue
        keys.append(key)
        if key == "K":
            Ki = tuple(real_or_blank(card, k + 1 + m, "K") for m in range(6))
    return Prop("PBUSH", pid, None, Ki=Ki, vars=tuple(keys))


def _properties(card: Card) -> list:
    name = card.name
    if name == "PBAR":
        pid = integer(card, 1, "PID")
        vals = _reals(card, 3, 8, "section property")
        k1 = real_or_blank(card, 17, "K1")
        k2 = real_or_blank(card, 18, "K2")
        i12 = real_or_blank(card, 19, "I12", 0.0)
        return [Prop("PBAR", pid, integer(card, 2, "MID"), A=vals[0], i1=vals[1], i2=vals[2], j=vals[3],
                     nsm=vals[4], k1=k1, k2=k2, i12=i12)]
    if name == "PBEAM":
        return [_pbeam(card)]
    if name in ("PBARL", "PBEAML"):
        return [_pbarl(card)]
    if name == "PROD":
        return [Prop("PROD", integer(card, 1, "PID"), integer(card, 2, "MID"), A=real(card, 3, "A"),
                     j=real_or_blank(card, 4, "J", 0.0), nsm=real_or_blank(card, 6, "NSM", 0.0))]
    if name == "PTUBE":
        od1 = real(card, 3, "OD")
        t = real_or_blank(card, 4, "T")
        od2 = real_or_blank(card, 6, "OD2", od1)
        return [Prop("PTUBE", integer(card, 1, "PID"), integer(card, 2, "MID"),
                     nsm=real_or_blank(card, 5, "NSM", 0.0), OD1=od1, OD2=od2, t=t)]
    if name == "PELAS":
        out = []
        for base in (1, 5):
            if card.get(base):
                out.append(Prop("PELAS", integer(card, base, "PID"), k=real(card, base + 1, "K")))
        return out
    if name == "PBUSH":
        return [_pbush(card)]
    if name == "PMASS":
        out = []
        for base in (1, 3, 5, 7):
            if card.get(base):
                out.append(Prop("PMASS", integer(card, base, "PID"), mass=real(card, base + 1, "M")))
        return out
    raise AssertionError(name)


def _scalar(card: Card) -> Scalar:
    f = card.fields
    if len(f) <= 9 and card.name in ("CELAS2", "CMASS2"):
        try:  # fast path, as in _bar
            v = to_real(f[2]) if len(f) > 2 and f[2] else None
            if v is not None:
                g = [int(t) if t else 0 for t in f[3:7]] + [0] * (7 - max(len(f), 3))
                return Scalar(card.name, int(f[1]), 0, v, (g[0], g[2]), g[1], g[3])
        except ValueError:
            pass
    eid = integer(card, 1, "EID")
    if card.name in ("CELAS1", "CMASS1"):
        pid, value = integer_or_blank(card, 2, "PID", eid), None
    else:
        pid, value = 0, real(card, 2, "K" if card.name == "CELAS2" else "M")
    g1 = integer_or_blank(card, 3, "G1", 0)
    c1 = integer_or_blank(card, 4, "C1", 0)
    g2 = integer_or_blank(card, 5, "G2", 0)
    c2 = integer_or_blank(card, 6, "C2", 0)
    return Scalar(card.name, eid, pid, value, (g1, g2), c1, c2)


def _rbe3(card: Card) -> Rigid:
    eid = integer(card, 1, "EID")
    ref = integer(card, 3, "REFGRID")
    refc = _comp(card, 4)
    weights, comps, grids, um = [], [], [], []
    k, n = 5, len(card.fields)
    mode = "w"
    while k < n:
        t = card.get(k)
        if not t:
            k += 1
            continue
        if t in ("UM", "ALPHA", "TREF"):
            mode = t
            k += 1
            continue
        if mode == "UM":
            um.extend([integer(card, k, "GM"), _comp(card, k + 1)])
            k += 2
            continue
        if mode in ("ALPHA", "TREF"):
            k += 1
            continue
        w = to_real(t)
        if w is not None:
            weights.append(w)
            comps.append(_comp(card, k + 1))
            grids.append([])
            k += 2
            continue
        if not grids:
            raise card.error(k, f"WT1 must be a real number, got {t!r}")
        grids[-1].append(integer(card, k, "G"))
        k += 1
    return Rigid("RBE3", eid, refgrid=ref, refc=refc, weights=tuple(weights), comps=tuple(comps),
                 Gijs=tuple(tuple(g) for g in grids), Gmi=tuple(um[0::2]))


def _rigid(card: Card) -> Rigid:
    if card.name == "RBE2":
        eid = integer(card, 1, "EID")
        gm = []
        for k in range(4, len(card.fields)):
            t = card.get(k)
            if not t:
                continue
            if to_real(t) is not None:  # ALPHA (thermal expansion) ends the list
                break
            if t == "THRU":
                hi = integer(card, k + 1, "GM")
                gm.extend(range(gm[-1] + 1, hi + 1))
                break
            gm.append(integer(card, k, "GM"))
        return Rigid("RBE2", eid, gn=integer(card, 2, "GN"), cm=_comp(card, 3), Gmi=tuple(gm))
    if card.name == "RBAR":
        return Rigid("RBAR", integer(card, 1, "EID"), ga=integer(card, 2, "GA"), gb=integer(card, 3, "GB"),
                     cna=_comp(card, 4), cnb=_comp(card, 5), cma=_comp(card, 6), cmb=_comp(card, 7))
    return _rbe3(card)


def _pairs(card: Card, start: int, what: str) -> tuple:
    ids, comps = [], []
    for k in range(start, len(card.fields), 2):
        if card.get(k):
            ids.append(integer(card, k, what))
            comps.append(_comp(card, k + 1))
    return tuple(ids), comps


def build_bulk(parsed: ParsedDeck, typed: frozenset) -> Bulk:
    """Typed entries of the cards named in ``typed`` (the others stay raw); GRDSET,
    BAROR/BEAMOR defaults applied, coordinate systems and grid positions resolved."""
    # Long: one branch per entry type (the QRG's field layouts), in one pass over the cards.
    nodes, elements, masses, props, pmass, mats, rigid = {}, {}, {}, {}, {}, {}, {}
    spcs, spcadds, mpcs, mpcadds, suport1, methods, loads = {}, {}, {}, {}, {}, {}, {}
    omits, asets, bsets, qsets, suport = [], [], [], [], []
    spoints: set = set()
    raw: dict = {}
    counts: dict = {}
    coord_cards = []
    grid_cards = []
    orient = {}
    grdset = None
    cards = parsed.cards
    for card in cards:
        counts[card.name] = counts.get(card.name, 0) + 1
    for card in cards:
        if card.name in ("BAROR", "BEAMOR") and card.name in typed:
            orient["CBAR" if card.name == "BAROR" else "CBEAM"] = _baror(card)
        if card.name == "GRDSET" and "GRDSET" in typed:
            grdset = GrdSet(integer_or_blank(card, 2, "CP", 0), integer_or_blank(card, 6, "CD", 0),
                            _comp(card, 7), integer_or_blank(card, 8, "SEID", 0))

    first_card: dict = {}

    def unique(table, key, entry, card):
        # NASTRAN accepts an entry repeated word for word (decks assembled from INCLUDEs
        # often are); two different entries with one id are an error
        if key in table:
            other = first_card[(id(table), key)]
            if other.name == card.name and other.fields == card.fields:
                return
            raise card.error(1, f"duplicate id {key} (also on {other.name} {key}, {other.file} line {other.line})")
        table[key] = entry
        first_card[(id(table), key)] = card

    for card in cards:
        name = card.name
        if name not in typed:
            raw.setdefault(name, []).append(card)
            continue
        if name == "GRID":
            grid_cards.append(card)
        elif name in ("CBAR", "CBEAM"):
            e = _bar(card, orient)
            unique(elements, e.eid, e, card)
        elif name == "CROD":
            eid = integer(card, 1, "EID")
            unique(elements, eid, Rod("CROD", eid, integer_or_blank(card, 2, "PID", eid),
                                      (integer(card, 3, "G1"), integer(card, 4, "G2"))), card)
        elif name == "CONROD":
            eid = integer(card, 1, "EID")
            unique(elements, eid, Rod("CONROD", eid, 0, (integer(card, 2, "G1"), integer(card, 3, "G2")),
                                      integer(card, 4, "MID"), real(card, 5, "A"),
                                      real_or_blank(card, 6, "J", 0.0), real_or_blank(card, 8, "NSM", 0.0)), card)
        elif name in ("CELAS1", "CELAS2"):
            e = _scalar(card)
            unique(elements, e.eid, e, card)
        elif name in ("CMASS1", "CMASS2"):
            e = _scalar(card)
            unique(masses, e.eid, e, card)
        elif name == "CBUSH":
            eid = integer(card, 1, "EID")
            gb = integer_or_blank(card, 4, "GB")
            x, g0 = _orientation(card, 5, (None, None))
            si = tuple(real_or_blank(card, k, "S") for k in (11, 12, 13))
            unique(elements, eid, Bush("CBUSH", eid, integer_or_blank(card, 2, "PID", eid),
                                       (integer(card, 3, "GA"), gb), x, g0, integer_or_blank(card, 8, "CID"),
                                       real_or_blank(card, 9, "S"), integer_or_blank(card, 10, "OCID"), si), card)
        elif name == "CONM2":
            eid = integer(card, 1, "EID")
            unique(masses, eid, Conm2("CONM2", eid, integer(card, 2, "G"), integer_or_blank(card, 3, "CID", 0),
                                      real_or_blank(card, 4, "M", 0.0), tuple(_reals(card, 5, 8, "X")),
                                      tuple(_reals(card, 9, 15, "I"))), card)
        elif name in ("PBAR", "PBEAM", "PBARL", "PBEAML", "PROD", "PTUBE", "PELAS", "PBUSH"):
            for p in _properties(card):
                unique(props, p.pid, p, card)
        elif name == "PMASS":
            for p in _properties(card):
                unique(pmass, p.pid, p, card)
        elif name == "MAT1":
            m = _mat1(card)
            unique(mats, m.mid, m, card)
        elif name in ("RBE2", "RBE3", "RBAR"):
            r = _rigid(card)
            unique(rigid, r.eid, r, card)
        elif name == "SPC":
            sid = integer(card, 1, "SID")
            ids, comps, enf = [], [], []
            for base in (2, 5):
                if card.get(base):
                    ids.append(integer(card, base, "G"))
                    comps.append(_comp(card, base + 1))
                    enf.append(real_or_blank(card, base + 2, "D", 0.0))
            spcs.setdefault(sid, []).append(Spc("SPC", sid, tuple(ids), comps, tuple(enf)))
        elif name == "SPC1":
            sid = integer(card, 1, "SID")
            spcs.setdefault(sid, []).append(Spc("SPC1", sid, tuple(_ints_thru(card, 3, "G")), _comp(card, 2)))
        elif name in ("SPCADD", "MPCADD"):
            sid = integer(card, 1, "SID")
            (spcadds if name == "SPCADD" else mpcadds).setdefault(sid, []).append(
                SetAdd(sid, tuple(_ints_thru(card, 2, "S"))))
        elif name == "MPC":
            sid = integer(card, 1, "SID")
            g, c, a = [], [], []
            for row in range(0, (len(card.fields) + 7) // 8):
                for base in ((2, 5) if row == 0 else (8 * row + 2, 8 * row + 5)):
                    if card.get(base):
                        g.append(integer(card, base, "G"))
                        c.append(_comp(card, base + 1))
                        a.append(real_or_blank(card, base + 2, "A", 0.0))
            mpcs.setdefault(sid, []).append(Mpc(sid, tuple(g), tuple(c), tuple(a)))
        elif name in ("OMIT", "ASET", "BSET", "QSET", "SUPORT"):
            ids, comps = _pairs(card, 1, "ID")
            {"OMIT": omits, "ASET": asets, "BSET": bsets, "QSET": qsets, "SUPORT": suport}[name].append(
                DofSet(name, ids, comps))
        elif name in ("OMIT1", "ASET1", "BSET1", "QSET1"):
            ids = tuple(_ints_thru(card, 2, "G"))
            {"OMIT1": omits, "ASET1": asets, "BSET1": bsets, "QSET1": qsets}[name].append(
                DofSet(name, ids, _comp(card, 1)))
        elif name == "SUPORT1":
            sid = integer(card, 1, "SID")
            ids, comps = _pairs(card, 2, "ID")
            suport1[sid] = DofSet(name, ids, comps)
        elif name == "SPOINT":
            spoints.update(_ints_thru(card, 1, "ID"))
        elif name == "EIGRL":
            sid = integer(card, 1, "SID")
            methods[sid] = Eigrl("EIGRL", sid, real_or_blank(card, 2, "V1"), real_or_blank(card, 3, "V2"),
                                 integer_or_blank(card, 4, "ND"))
        elif name in ("FORCE", "MOMENT"):
            sid = integer(card, 1, "SID")
            loads.setdefault(sid, []).append(Load(name, sid, integer(card, 2, "G"), real(card, 4, "F"),
                                                  cid=integer_or_blank(card, 3, "CID", 0),
                                                  xyz=tuple(_reals(card, 5, 8, "N"))))
        elif name in ("FORCE1", "MOMENT1"):
            sid = integer(card, 1, "SID")
            loads.setdefault(sid, []).append(Load(name, sid, integer(card, 2, "G"), real(card, 3, "F"),
                                                  g1=integer(card, 4, "G1"), g2=integer(card, 5, "G2")))
        elif name.startswith("CORD"):
            coord_cards.append(card)
        elif name in ("GRDSET", "BAROR", "BEAMOR"):
            pass
        else:
            raw.setdefault(name, []).append(card)
    nodes, xyz = _grids(grid_cards, grdset)
    coords, xyz = resolve_coordinates(coord_cards, nodes, xyz)
    return Bulk(parsed, nodes, coords, elements, masses, props, pmass, mats, rigid, spcs, spcadds, mpcs,
                mpcadds, omits, asets, bsets, qsets, suport, suport1, spoints, methods, loads, grdset, raw,
                counts, xyz)


def _grids(cards: list, grdset: GrdSet | None) -> tuple:
    """GRID id -> :class:`Grid` (GRDSET defaults in blank CP, CD, PS, SEID fields)."""
    cp0 = grdset.cp if grdset else 0
    cd0 = grdset.cd if grdset else 0
    ps0 = grdset.ps if grdset else ""
    se0 = grdset.seid if grdset else 0
    nodes = {}
    xyz = np.empty((len(cards), 3))
    for card in cards:
        f = card.fields
        try:
            nid = int(f[1])
            cp = int(f[2]) if f[2] else cp0
            # fast path: plain reals (the bulk of a large deck); NASTRAN's forms below
            x = (float(f[3]) if f[3] else 0.0, float(f[4]) if f[4] else 0.0, float(f[5]) if f[5] else 0.0)
            if any("." not in t and "E" not in t for t in f[3:6] if t):
                raise ValueError
            cd = int(f[6]) if len(f) > 6 and f[6] else cd0
        except (ValueError, IndexError):
            nid = integer(card, 1, "ID")
            cp = integer_or_blank(card, 2, "CP", cp0)
            x = (real_or_blank(card, 3, "X1", 0.0), real_or_blank(card, 4, "X2", 0.0),
                 real_or_blank(card, 5, "X3", 0.0))
            cd = integer_or_blank(card, 6, "CD", cd0)
        seid = integer_or_blank(card, 8, "SEID", se0) if len(f) > 8 and f[8] else se0
        ps = _comp(card, 7) or ps0
        if nid in nodes:
            if nodes[nid] == Grid(nid, cp, x, cd, ps, seid):
                continue  # repeated word for word: NASTRAN accepts it
            raise card.error(1, f"duplicate id {nid} (another GRID has it)")
        xyz[len(nodes)] = x
        nodes[nid] = Grid(nid, cp, x, cd, ps, seid)
    return nodes, xyz[:len(nodes)]


