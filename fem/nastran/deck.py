"""A deck's text to typed entries (:mod:`~trussid.fem.nastran.cards`,
:mod:`~trussid.fem.nastran.bulk`), and what trussid reads from fields directly: PARAMs,
case-control requests, EIGR and the entries kept raw (:data:`RAW_CARDS`)."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path


from trussid.fem.errors import ModelError
from trussid.fem.nastran.bulk import Bulk, build_bulk
from trussid.fem.nastran.cards import nastran_value, parse_deck
from trussid.fem.nastran.entries import (CASE_SELECTED_CARDS, HANDLED_PARAMS, IGNORED_CARDS, MODE_PARAMS,
                                         NOTED_CARDS, RAW_CARDS, SUPPORTED_CARDS, THERMAL_CARDS)

__all__ = ['EigenRequest', 'BdfInfo', 'parse_bdf', 'check_cards', 'read_params', 'select_eigen',
           'is_preload_run', 'case_values', 'case_int', 'case_has', 'components', 'grid_ids', 'raw_cards']


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


@dataclass(frozen=True)
class _RawParam:
    """A PARAM entry from its fields (NASTRAN, MYSTRAN and NASTRAN-95 each have their own
    PARAMs; values are kept as written: int, real or string)."""

    name: str
    values: list


#: Loads read for a preload (rigid format 13); otherwise they are ignored, never parsed.
PRELOAD_CARDS = frozenset({"FORCE", "FORCE1", "MOMENT", "MOMENT1"})


def is_preload_run(sol: str | None, app: str | None) -> bool:
    """NASTRAN-95 rigid format 13: normal modes with differential stiffness."""
    return sol is not None and sol.split(",")[0] == "13" and app in (None, "DISP", "DISPLACEMENT")


def _check_solution(path: Path, sol: str | None, app: str | None, text: str) -> None:
    """Refuse analyses whose printed modes trussid cannot reproduce, naming them."""
    statsub = re.search(r"^\s*STATSUB\b[^\n]*", text, re.IGNORECASE | re.MULTILINE)
    if statsub:
        raise ModelError(f"{path}: {statsub.group(0).strip()} asks for the modes of a structure preloaded by "
                         f"a static subcase with MSC/NX differential stiffness, which trussid does not compute "
                         f"(it does for NASTRAN-95 rigid format 13)")
    if not is_preload_run(sol, app):
        return
    m = re.search(r"^\s*(CPSE[234])[\s,]+(\d+)", text, re.IGNORECASE | re.MULTILINE)
    if m:
        raise ModelError(f"{path}: SOL 13 (normal modes with differential stiffness): {m.group(1).upper()} "
                         f"{m.group(2)} adds pressure stiffness to the preload, which trussid does not compute "
                         f"(it computes the differential stiffness of frame and rod elements)")


#: Bulk-data entries read into typed entries (:mod:`trussid.fem.nastran.bulk`); the others
#: are counted and, for RAW_CARDS, PARAM and EIGR, read from their fields by the reader.
TYPED_CARDS = SUPPORTED_CARDS - RAW_CARDS - {"PARAM", "EIGR", "ENDDATA"}


def parse_bdf(path: Path) -> Bulk:
    """The deck at ``path`` as typed entries; any malformed field is a one-line ModelError
    naming the file, line, entry and field."""
    path = Path(path)
    if path.is_file():
        # analyses trussid cannot reproduce are named before any entry is read (NASTRAN-95
        # rigid format 13 decks with pressure stiffness are written in NASTRAN-95's free field)
        text = path.read_text(errors="replace")
        head = re.split(r"^\s*CEND\b", text, maxsplit=1, flags=re.IGNORECASE | re.MULTILINE)
        executive = head[0] if len(head) > 1 else ""
        sol = re.search(r"^\s*SOL\s+([^\s$]+)", executive, re.IGNORECASE | re.MULTILINE)
        app = re.search(r"^\s*APP\s+([^\s$]+)", executive, re.IGNORECASE | re.MULTILINE)
        _check_solution(path, sol.group(1).upper() if sol else None, app.group(1).upper() if app else None, text)
    parsed = parse_deck(path)
    if not parsed.cards:
        raise ModelError(f"{path}: no bulk-data cards found")
    typed = TYPED_CARDS | (PRELOAD_CARDS if is_preload_run(parsed.sol, parsed.app) else frozenset())
    return build_bulk(parsed, typed)


def _params(bdf: Bulk) -> dict:
    """PARAM name -> :class:`_RawParam` (the last entry of a name wins)."""
    params = {}
    for card in bdf.raw.get("PARAM", []):
        name = card.get(1)
        if not name:
            raise card.error(1, "PARAM without a name")
        params[name] = _RawParam(name, [nastran_value(v) for v in card.fields[2:] if v])
    return params


def check_cards(bdf: Bulk, path: Path, info: BdfInfo) -> None:
    """Every card must be translated or known to be harmless: list all the others.

    Unsupported element entries (shells, solids...) come first in the message: they are
    the reason a beam code cannot read the deck, the rest would follow from them.
    """
    counts = bdf.card_count
    thermal_on = any(counts.get(c) for c in ("TEMPD", "TEMP")) or case_values(bdf, "TEMPERATURE") \
        or case_values(bdf, "TEMP")
    bad, ignored = {}, {}
    for name, n in counts.items():
        if name in SUPPORTED_CARDS:
            continue
        if name in NOTED_CARDS:
            _check_selected(bdf, path, name)
            ignored[name] = n
            info.notes.append(f"{name} ({n}): {NOTED_CARDS[name]}: ignored")
        elif name in IGNORED_CARDS or (name in THERMAL_CARDS and not thermal_on):
            ignored[name] = n
        else:
            bad[name] = n
    params = _params(bdf)
    for name in sorted(params):
        if name in HANDLED_PARAMS:
            continue
        if name in MODE_PARAMS and params[name].values not in ([], [1], [1.0]):
            bad[f"PARAM,{name}"] = 1
        else:
            ignored[f"PARAM,{name}"] = 1
    info.ignored = [f"{k} ({v})" if not k.startswith("PARAM,") else k for k, v in sorted(ignored.items())]
    if not bad:
        return
    first = _first_ids(bdf, bad)
    elements = {k: v for k, v in bad.items() if _is_element_entry(k)}
    if elements:
        listing = ", ".join(f"{k} ({v})" for k, v in sorted(elements.items())) + first
        rest = {k: v for k, v in bad.items() if k not in elements}
        also = f"; also unsupported: {', '.join(f'{k} ({v})' for k, v in sorted(rest.items()))}" if rest else ""
        raise ModelError(f"{path}: unsupported element entries: {listing} (trussid reads beam, rod, "
                         f"spring, mass and rigid elements: CBAR, CBEAM, CROD, CONROD, CELAS1-4, "
                         f"CBUSH, GENEL, CONM1, CONM2, CMASS1-4, RBE2, RBE3, RBAR, CRIGD1/2/3/R){also}")
    listing = ", ".join(f"{k} ({v})" for k, v in sorted(bad.items())) + first
    raise ModelError(f"{path}: unsupported bulk-data entries: {listing}; "
                     f"supported cards are {', '.join(sorted(SUPPORTED_CARDS))}")


def _check_selected(bdf: Bulk, path: Path, name: str) -> None:
    """Refuse a noted entry that the case control makes count (:data:`CASE_SELECTED_CARDS`:
    rotordynamics through RGYRO, transfer functions through TFL)."""
    request = CASE_SELECTED_CARDS.get(name)
    chosen = case_values(bdf, request) if request else []
    if not chosen:
        return
    first = bdf.raw[name][0].label() if bdf.raw.get(name) else name
    what = {"RGYRO": "asks for rotordynamics (gyroscopic and spin terms), which trussid does not compute",
            "TFL": "selects transfer functions, which add terms to the equations of motion that trussid does "
                   "not translate"}[request]
    raise ModelError(f"{path}: {first}: {request} = {chosen[0]} in the case control {what}")


def _first_ids(bdf: Bulk, bad: dict) -> str:
    """`` [first: CQUAD4 100, PARAM,CK1 2.0]``: the first id (PARAM: value) of each refused entry."""
    found = {}
    for key in bad:
        if key.startswith("PARAM,"):
            card = next((c for c in bdf.raw.get("PARAM", []) if c.get(1) == key[6:]), None)
            found[key] = card.get(2) if card else ""
        elif bdf.raw.get(key):
            found[key] = bdf.raw[key][0].get(1)
    found = {k: v for k, v in found.items() if k in bad}
    if not found:
        return ""
    return " [first: " + ", ".join(f"{k} {v}".strip() for k, v in sorted(found.items())) + "]"


def _is_element_entry(name: str) -> bool:
    """Element connection entries (CQUAD4, CHEXA, CTUBE, GENEL...), not coordinate systems."""
    return (name.startswith("C") and not name.startswith("CORD") and name not in ("CONM1", "CMASS3", "CMASS4")
            ) or name in ("GENEL", "PLOTEL")


def _param(bdf, name):
    p = _params(bdf).get(name)
    if p is None:
        return None
    return p.values[0]


def read_params(bdf, info: BdfInfo) -> None:
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
        if value == "YES":
            info.autospc, info.autospc_reason = True, "PARAM,AUTOSPC,YES"
        else:
            # A DOF with neither stiffness nor mass has no equation and takes no part in any
            # mode; NASTRAN runs such decks with AUTOSPC off (Lanczos ignores the null rows),
            # so they are removed here too. A DOF with mass and no stiffness is not removed:
            # it is a mechanism either way.
            info.autospc = True
            info.autospc_reason = ("PARAM,AUTOSPC,NO: DOFs with neither stiffness nor mass are still removed "
                                   "(they take no part in the modes, as in NASTRAN's run)")


def components(text, card: str) -> list[int]:
    """0-based components of a NASTRAN component string such as "123456"."""
    text = "" if text is None else str(text).strip()
    if any(ch not in "123456" for ch in text):
        raise ModelError(f"{card}: components {text!r} must be digits 1-6")
    return sorted({int(ch) - 1 for ch in text})


def grid_ids(fields: list[str], card: str) -> list[int]:
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


def raw_cards(bdf: Bulk, name: str):
    """(id, fields) of every raw (untyped) ``name`` entry, in deck order."""
    for card in bdf.raw.get(name, []):
        f = list(card.fields)
        try:
            yield int(f[1]), f
        except (IndexError, ValueError):
            raise card.error(1, "no element id") from None


def case_values(bdf: Bulk, key: str) -> list:
    """Values of case-control ``key`` (e.g. "SPC", "METHOD") over the subcases, in order."""
    return bdf.case.values(key)


def case_int(bdf: Bulk, key: str) -> list:
    """Integer values of ``key`` (set ids), each checked."""
    out = []
    for v in case_values(bdf, key):
        try:
            out.append(int(v))
        except ValueError:
            raise ModelError(f"case control {key} = {v}: a set id (integer) is expected") from None
    return out


def case_has(bdf: Bulk, key: str) -> bool:
    """Whether the case control has a ``key`` request anywhere (with options, e.g. EXTSEOUT(...))."""
    return bdf.case.has(key)


def select_eigen(bdf, info: BdfInfo) -> None:
    methods = {sid: m for sid, m in bdf.methods.items() if m.type == "EIGRL"}
    methods.update(_raw_eigrs(bdf))
    chosen = case_int(bdf, "METHOD")
    if chosen:
        sid = chosen[0]
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
        info.notes.append(f"EIGR {sid} method {m.method}: the lowest modes are listed, whatever the method")


@dataclass(frozen=True)
class _RawEigr:
    """An EIGR from its fields: any method name (FEER, MGIV, GIV...) is accepted, since trussid
    lists the lowest modes whatever the method."""

    sid: int
    method: str
    f1: float | None
    f2: float | None
    ne: int | None
    nd: int | None
    type: str = "EIGR"


def _raw_eigrs(bdf) -> dict:
    """EIGR SID -> :class:`_RawEigr` (fields SID METHOD F1 F2 NE ND)."""
    out = {}
    for sid, f in raw_cards(bdf, "EIGR"):
        f = f + [""] * 8
        try:
            num = [None if not v else nastran_value(v) for v in f[3:7]]
            f1, f2 = (None if v is None else float(v) for v in num[:2])
            ne, nd = (None if v is None else int(v) for v in num[2:])
        except (TypeError, ValueError):
            raise ModelError(f"EIGR {sid}: F1, F2 must be numbers and NE, ND integers, got "
                             f"{', '.join(repr(v) for v in f[3:7])}") from None
        out[sid] = _RawEigr(sid, f[2] or "(blank)", f1, f2, ne, nd)
    return out
