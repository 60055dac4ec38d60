"""A deck's text to pyNastran's BDF, and what trussid reads from its raw fields: executive
control, PARAMs, case-control requests and the entries pyNastran does not parse faithfully."""

from __future__ import annotations

import contextlib
import io
import math
import re
from dataclasses import dataclass, field
from pathlib import Path


from trussid.fem.errors import ModelError
from trussid.fem.nastran.entries import (CASE_SELECTED_CARDS, HANDLED_PARAMS, IGNORED_CARDS, MODE_PARAMS,
                                         RAW_CARDS, SUPPORTED_CARDS, THERMAL_CARDS)

__all__ = ['EigenRequest', 'BdfInfo']


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


#: Loads read for a preload (rigid format 13); otherwise they are ignored, never parsed.
PRELOAD_CARDS = frozenset({"FORCE", "FORCE1", "MOMENT", "MOMENT1"})


def _is_preload_run(sol: str | None, app: str | None) -> bool:
    """NASTRAN-95 rigid format 13: normal modes with differential stiffness."""
    return sol is not None and sol.split(",")[0] == "13" and app in (None, "DISP", "DISPLACEMENT")


def _check_solution(path: Path, sol: str | None, app: str | None, text: str) -> None:
    """Refuse analyses whose printed modes trussid cannot reproduce, naming them."""
    statsub = re.search(r"^\s*STATSUB\b[^\n]*", text, re.IGNORECASE | re.MULTILINE)
    if statsub:
        raise ModelError(f"{path}: {statsub.group(0).strip()} asks for the modes of a structure preloaded by "
                         f"a static subcase with MSC/NX differential stiffness, which trussid does not compute "
                         f"(it does for NASTRAN-95 rigid format 13)")
    if not _is_preload_run(sol, app):
        return
    m = re.search(r"^\s*(CPSE[234])[\s,]+(\d+)", text, re.IGNORECASE | re.MULTILINE)
    if m:
        raise ModelError(f"{path}: SOL 13 (normal modes with differential stiffness): {m.group(1).upper()} "
                         f"{m.group(2)} adds pressure stiffness to the preload, which trussid does not compute "
                         f"(it computes the differential stiffness of frame and rod elements)")


def _bulk_text(rest: str, path: Path, include: str, notes: list) -> str:
    """Case control and bulk data as pyNastran is given them (from memory, after CEND).

    INCLUDEs are made absolute (pyNastran resolves them from the working directory when
    reading from memory), a repeated BEGIN BULK is dropped, BAROR/BEAMOR move to the front.
    """
    flags = re.IGNORECASE | re.MULTILINE
    text = re.sub(include, lambda m: m.group(1) + "'" + str((path.parent / (m.group(2) or m.group(3))).resolve())
                  + "'", rest, flags=flags)
    # A repeated BEGIN BULK (MSC's HA144D) is accepted by NASTRAN; pyNastran reads the
    # second as a superelement header.
    heads = list(re.finditer(r"^\s*BEGIN\s+BULK\b.*$\n?", text, flags))
    if len(heads) > 1:
        for h in reversed(heads[1:]):
            text = text[:h.start()] + text[h.end():]
        notes.append(f"BEGIN BULK repeated {len(heads)} times: read once, as NASTRAN")
    # BAROR/BEAMOR defaults apply to every CBAR/CBEAM wherever they stand in the deck;
    # pyNastran applies them only to the entries that follow: move them to the front.
    orient = re.compile(r"^(BAROR|BEAMOR)\b[^\n]*\n?", flags)
    start = text.find("\n", heads[0].start()) + 1 if heads else -1
    if start > 0 and orient.search(text, start):
        moved = "".join(m.group(0).rstrip("\n") + "\n" for m in orient.finditer(text, start))
        text = text[:start] + moved + orient.sub("", text[start:])
    return text


def _parse(path: Path):
    """pyNastran's BDF of ``path``, quietly; any failure becomes a one-line ModelError."""
    from cpylog import SimpleLogger
    from pyNastran.bdf.bdf import BDF

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
    include = r"^(\s*INCLUDE\s+)(?:'([^']+)'|([^'\s$]+))"  # quoted, or a bare file name
    includes = [q or bare for _, q, bare in re.findall(include, text, flags)]
    for inc in includes:
        if not (path.parent / inc).is_file():
            raise ModelError(f"{path}: INCLUDE '{inc}': no such file (looked in {path.parent})")
    notes = []
    executive, rest, _ = _executive(text, path)
    sol, app = _solution(executive)
    _check_solution(path, sol, app, text)
    punch = re.search(r"^\s*BEGIN\s+(BULK|SUPER)", text, flags) is None
    source = str(path) if punch else io.StringIO("CEND\n" + _bulk_text(rest, path, include, notes))
    bdf = BDF(log=SimpleLogger(level="critical"), debug=None)
    # Cards this reader does not translate are only counted, never parsed, so that a
    # malformed one is reported as unsupported rather than failing the parse; those read
    # from their raw fields (RAW_CARDS, PARAM) too.
    readable = SUPPORTED_CARDS | (PRELOAD_CARDS if _is_preload_run(sol, app) else frozenset())
    bdf.disable_cards(sorted((set(bdf.cards_to_read) - readable) | RAW_CARDS | {"PARAM", "EIGR"}))
    # Entries pyNastran builds through a "prepare" function raise without saying which
    # entry failed: name it (this BDF instance's table only).
    prepare = getattr(bdf, "_card_parser_prepare", {})
    for name in list(prepare):
        prepare[name] = _named_entry(name, prepare[name])
    bdf.trussid_blank_cp_cd = ({}, {})
    if re.search(r"^\s*GRDSET", text, flags) and "GRID" in getattr(bdf, "_card_parser", {}):
        # A GRID's blank CP/CD takes the GRDSET default, an explicit 0 does not; pyNastran's
        # GRID reads both as 0, so the blank fields are recorded from the raw card here.
        cls, add = bdf._card_parser["GRID"]
        bdf._card_parser["GRID"] = (_GridBlanks(cls, bdf.trussid_blank_cp_cd), add)
    try:
        # pyNastran also print()s some complaints; keep them off the user's terminal (the
        # exception carries the message).
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            bdf.read_bdf(source, xref=False, validate=False, punch=punch)
    except Exception as exc:  # pyNastran raises many types for malformed decks
        n95 = _nastran95_free_field(path.read_text(errors="replace"))
        if n95:
            raise ModelError(f"{path}: {n95}") from None
        raise ModelError(f"{path}: not a readable bulk-data deck ({_parser_message(exc)})") from None
    if not bdf.card_count:
        raise ModelError(f"{path}: no bulk-data cards found")
    bdf.params = _raw_params(bdf)
    bdf.trussid_notes = notes
    bdf.trussid_solution = (sol, app)
    return bdf


class _GridBlanks:
    """pyNastran's GRID class, recording the ids of GRIDs whose CP / CD field is blank."""

    def __init__(self, cls, blanks: tuple):
        self.cls, self.blanks = cls, blanks

    def add_card(self, card_obj, comment=""):
        grid = self.cls.add_card(card_obj, comment=comment)
        for k, field_no in ((0, 2), (1, 6)):
            if card_obj.field(field_no) in (None, ""):
                self.blanks[k][grid.nid] = True
        return grid


def _named_entry(name: str, prepare):
    """``prepare`` whose failure says the entry and its id."""
    def call(card, card_obj, comment=""):
        try:
            return prepare(card, card_obj, comment=comment)
        except Exception as exc:  # pyNastran raises many types; re-raised naming the entry
            ident = card_obj.field(1)
            msg = " ".join(str(exc).split())
            if "defining plane 1 is not defined" in msg:
                msg = "no orientation (give X1-X3 or G0 on the entry, or a BAROR/BEAMOR default)"
            raise ValueError(f"{name} {'' if ident is None else ident}".strip() + f": {msg}") from None
    return call


def _nastran95_free_field(text: str) -> str | None:
    """A message naming the first NASTRAN-95 free-field line (blank-separated fields after a
    comma, or a replicator ``=``, ``==``, ``=(n)``, ``*(n)``), or None when there is none."""
    lines = text.splitlines()
    start = next((k for k, ln in enumerate(lines) if re.match(r"\s*BEGIN\s+BULK", ln, re.IGNORECASE)), -1)
    for k, line in enumerate(lines[start + 1:], start + 2):
        body = line.split("$", 1)[0].rstrip()
        replicator = re.match(r"^\s*(=\(\d+\)|==|=\s*,|\*\(\d+\))", body)
        blanks = re.match(r"^([A-Z][A-Z0-9]*)\s*,\s*(\S+)\s+\S", body, re.IGNORECASE)
        if replicator or blanks:
            what = ("a replicator" if replicator else f"{blanks.group(1).upper()} {blanks.group(2)} with "
                    f"blank-separated fields")
            return (f"NASTRAN-95 free-field input ({what}, line {k}: {body.strip()[:40]!r}) is not "
                    f"supported: write the entries with commas or in fixed fields")
    return None


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
    msg = re.sub(r"^([A-Z0-9]+) None:", r"\1:", msg)
    if card and not msg.startswith(card.group(1)):
        name, ident = card.group(1), card.group(2).strip()
        msg = f"{name} {ident}: {msg}" if ident and ident != "None" else f"{name}: {msg}"
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
    bad, ignored, selected = {}, {}, {}
    for name, n in counts.items():
        if name in SUPPORTED_CARDS:
            continue
        if name in IGNORED_CARDS or (name in THERMAL_CARDS and not thermal_on):
            ignored[name] = n
        elif name in CASE_SELECTED_CARDS:
            if _case_values(bdf, CASE_SELECTED_CARDS[name]):
                bad[name] = n
                selected[CASE_SELECTED_CARDS[name]] = True
            else:
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
    why = "".join(f"; the case control's {key} selects them (rotordynamics: gyroscopic and spin terms, not "
                  f"computed by trussid)" for key in selected)
    raise ModelError(f"{path}: unsupported bulk-data entries: {listing}{why}; "
                     f"supported cards are {', '.join(sorted(SUPPORTED_CARDS))}")


def _first_ids(bdf, bad: dict) -> str:
    """`` [first: CQUAD4 100, PARAM,CK1 2.0]``: the first id (PARAM: value) of each refused entry."""
    found = {}
    for lines in getattr(bdf, "reject_lines", []):
        body = _card_lines(lines)
        if not body:
            continue
        name = body[0][:8].strip().rstrip("*").upper().split(",")[0]
        key = name
        if name == "PARAM":
            f = _raw_fields(body, name)
            key = f"PARAM,{f[1]}" if len(f) > 1 else name
        if key in bad and key not in found:
            f = _raw_fields(body, name)
            found[key] = f[2 if name == "PARAM" else 1] if len(f) > (2 if name == "PARAM" else 1) else ""
    if not found:
        return ""
    return " [first: " + ", ".join(f"{k} {v}".strip() for k, v in sorted(found.items())) + "]"


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


def _comps(text, card: str) -> list[int]:
    """0-based components of a NASTRAN component string such as "123456"."""
    text = "" if text is None else str(text).strip()
    if any(ch not in "123456" for ch in text):
        raise ModelError(f"{card}: components {text!r} must be digits 1-6")
    return sorted({int(ch) - 1 for ch in text})


def _raw_fields(lines: list[str], name: str) -> list[str]:
    from pyNastran.bdf.bdf_interface.utils import to_fields

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


def _raw_cards(bdf, name: str):
    """(id, fields) of every raw (unparsed) ``name`` entry, in deck order."""
    for lines in getattr(bdf, "reject_lines", []):
        body = _card_lines(lines)
        head = body[0][:8].strip().rstrip("*").upper().split(",")[0] if body else ""
        if head != name:
            continue
        f = _raw_fields(body, name)
        try:
            yield int(f[1]), f
        except (IndexError, ValueError):
            raise ModelError(f"{name}: no element id in {body[0].strip()!r}") from None


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


def _case_has(bdf, key: str) -> bool:
    """Whether the case control has a ``key`` request anywhere (with options, e.g. EXTSEOUT(...))."""
    deck = getattr(bdf, "case_control_deck", None)
    if deck is None:
        return False
    return any(key.upper() in str(p).upper() for sub in deck.subcases.values() for p in sub.params)


def _select_eigen(bdf, info: BdfInfo) -> None:
    methods = {sid: m for sid, m in bdf.methods.items() if m.type == "EIGRL"}
    methods.update(_raw_eigrs(bdf))
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
        info.notes.append(f"EIGR {sid} method {m.method}: the lowest modes are listed, whatever the method")


@dataclass
class _RawEigr:
    """An EIGR from its raw fields: pyNastran refuses methods outside its list (FEER, MGIV...),
    and trussid lists the lowest modes whatever the method."""

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
    for sid, f in _raw_cards(bdf, "EIGR"):
        f = f + [""] * 8
        try:
            num = [None if not v else _nastran_value(v) for v in f[3:7]]
            f1, f2 = (None if v is None else float(v) for v in num[:2])
            ne, nd = (None if v is None else int(v) for v in num[2:])
        except (TypeError, ValueError):
            raise ModelError(f"EIGR {sid}: F1, F2 must be numbers and NE, ND integers, got "
                             f"{', '.join(repr(v) for v in f[3:7])}") from None
        out[sid] = _RawEigr(sid, f[2] or "(blank)", f1, f2, ne, nd)
    return out
