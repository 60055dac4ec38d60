"""NASTRAN input text to cards: trussid's own parser of executive control, case control and
bulk data.

Written for trussid rather than taken from a library: pyNastran, the one maintained Python
reader, declares ``numpy<2`` in every release and fails at import on numpy >= 2.4, and its
development line changed its card objects and INCLUDE handling (issue 30). What is read here
is only the text layer; :mod:`trussid.fem.nastran.bulk` turns the cards trussid translates
into typed entries.

Formats (MSC/NX Quick Reference Guide, "Format of Bulk Data Entries"):

* small field: ten 8-character fields (columns 73-80 hold the continuation field);
* large field: the name followed by ``*``, four 16-character data fields per line, each line
  pair holding what one small-field line holds; a continuation starting with ``*`` is large;
* free field: fields separated by commas (``GRID*,...`` is large free field: four data fields
  per line); a free-field line with more than ten fields continues by itself
  (auto-continuation: every ten fields make one line);
* continuations: a line whose first character is ``+``, ``*``, a blank or a comma continues
  the entry above it, whatever its name (NASTRAN's "+name"/"*name" markers and the implicit
  blank continuation); continuation lines out of order are not supported;
* comments: ``$`` to the end of the line; blank lines are ignored; tabs expand to 8 columns;
* ``INCLUDE 'file'`` (quoted or bare, a quoted name continued over several lines, Windows
  ``\\`` separators) is read relative to the including file, nested to any depth;
* fields are upper case; a blank field is ``""``.

Field conversion (:func:`integer`, :func:`real` ...) follows NASTRAN's rules: an integer has
no decimal point; a real has one or an exponent (``1.5``, ``.5``, ``1.E5``, ``1.5D-3`` and the
implicit exponents ``1.-3``, ``-2.5+4``); a blank takes the entry's default. A field that
breaks a rule raises a one-line :class:`~trussid.fem.errors.ModelError` naming the file, the
line, the entry with its id and the field.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path, PureWindowsPath
from typing import NamedTuple

from trussid.fem.errors import ModelError

__all__ = ["Card", "CaseControl", "ParsedDeck", "parse_deck", "integer", "real", "integer_or_blank",
           "real_or_blank", "string_or_blank", "number", "nastran_value", "to_real", "to_int", "deck_text"]


class Card(NamedTuple):
    """One bulk-data entry as written (immutable; a named tuple because a large deck makes
    one per entry, and it is built three times faster than a frozen dataclass).

    Attributes
    ----------
    name : str
        Entry name, upper case, without the large-field ``*`` (``"GRID"``).
    fields : tuple of str
        Field texts, upper case and stripped, in NASTRAN's order with the continuation
        fields left out: ``fields[0]`` is the name, ``fields[1:9]`` fields 2-9 of the first
        line, ``fields[9:17]`` fields 2-9 of the first continuation, and so on.
    file : str
        The file the entry is in (an INCLUDEd file names itself).
    lines : tuple of int
        1-based line number of each of the entry's physical lines.
    per_line : tuple of int
        Data fields on each physical line (8 small field, 4 large field), to name the line a
        field is on.
    """

    name: str
    fields: tuple
    file: str
    lines: tuple
    per_line: tuple

    @property
    def line(self) -> int:
        """Line of the entry's first line."""
        return self.lines[0]

    def get(self, i: int) -> str:
        """Field ``i`` (0 = name), ``""`` beyond the entry's end."""
        f = self.fields
        return f[i] if i < len(f) else ""

    def label(self) -> str:
        """``"CBAR 10"``: the name and the first field (its id), as a user finds it."""
        ident = self.get(1)
        return f"{self.name} {ident}" if ident else self.name

    def line_of(self, i: int) -> int:
        """The physical line holding field ``i``."""
        k, n = 0, 0
        for line, width in zip(self.lines, self.per_line):
            n += width
            if i <= n:
                return line
            k += 1
        return self.lines[-1]

    def error(self, i: int | None, message: str) -> ModelError:
        """A one-line error naming file, line, entry and (when ``i``) field ``i``."""
        where = f"{self.file}, line {self.line if i is None else self.line_of(i)}"
        what = "" if i is None else f": field {_field_number(i)}"
        return ModelError(f"{where}: {self.label()}{what}: {message}")


def _field_number(i: int) -> str:
    """NASTRAN's field number of flattened index ``i``: ``4`` or ``"3 of continuation 2"``."""
    row, col = divmod(i - 1, 8)
    return str(col + 2) if row == 0 else f"{col + 2} of continuation {row}"


# ------------------------------------------------------------------ field conversion
def to_real(text: str) -> float | None:
    """A NASTRAN real, or None when ``text`` is not one (integers are not reals)."""
    # The implicit exponent (1.5-3) is found by its sign rather than by a failed float():
    # decks written with 16-character fields use it on most values.
    if "E" in text or "D" in text:
        try:
            return float(text.replace("D", "E") if "D" in text else text)
        except ValueError:
            return None
    if "." not in text:
        return None
    k = max(text.rfind("-"), text.rfind("+"))
    try:
        return float(text[:k] + "E" + text[k:]) if k > 0 else float(text)
    except ValueError:
        return None


def to_int(text: str) -> int | None:
    """A NASTRAN integer, or None when ``text`` is not one."""
    try:
        return int(text)
    except ValueError:
        return None


def integer(card: Card, i: int, what: str) -> int:
    """Field ``i`` as an integer; blank or anything else is an error naming the field."""
    text = card.get(i)
    value = to_int(text) if text else None
    if value is None:
        got = "blank" if not text else repr(text)
        raise card.error(i, f"{what} must be an integer, got {got}")
    return value


def integer_or_blank(card: Card, i: int, what: str, default=None):
    text = card.get(i)
    if not text:
        return default
    value = to_int(text)
    if value is None:
        raise card.error(i, f"{what} must be an integer, got {text!r}")
    return value


def real(card: Card, i: int, what: str) -> float:
    text = card.get(i)
    value = to_real(text) if text else None
    if value is None:
        got = "blank" if not text else repr(text)
        raise card.error(i, f"{what} must be a real number (with a decimal point), got {got}")
    return value


def real_or_blank(card: Card, i: int, what: str, default=None):
    text = card.get(i)
    if not text:
        return default
    value = to_real(text)
    if value is None:
        raise card.error(i, f"{what} must be a real number (with a decimal point), got {text!r}")
    return value


def number(card: Card, i: int, what: str, default=None):
    """An integer or a real (fields that take either, e.g. a PARAM value)."""
    text = card.get(i)
    if not text:
        return default
    value = to_int(text)
    if value is None:
        value = to_real(text)
    if value is None:
        raise card.error(i, f"{what} must be a number, got {text!r}")
    return value


def string_or_blank(card: Card, i: int, default=None):
    text = card.get(i)
    return text if text else default


def nastran_value(text: str):
    """A field as NASTRAN reads it: int, real (also ``1.5-3`` = 1.5e-3), or the string."""
    t = text.strip().upper()
    v = to_int(t)
    if v is not None:
        return v
    v = to_real(t)
    return t if v is None else v


# ------------------------------------------------------------------ the deck
@dataclass(frozen=True)
class CaseControl:
    """The case control as ``(subcase, key, value)`` statements, in order.

    ``subcase`` is 0 for statements above the first SUBCASE (they apply to every subcase);
    ``key`` is the statement's name upper case, without its options (``DISPLACEMENT`` of
    ``DISPLACEMENT(PLOT) = ALL``); ``value`` the text after ``=`` (upper case, stripped).
    """

    statements: tuple = ()
    text: str = ""

    def values(self, key: str) -> list:
        """The distinct values of ``key`` (e.g. "SPC"), global first, then by subcase."""
        out = []
        for _sub, k, v in sorted(self.statements, key=lambda s: s[0]):
            if _key_matches(k, key) and v not in out:
                out.append(v)
        return out

    def has(self, key: str) -> bool:
        """Whether a statement names ``key`` anywhere (with options, e.g. ``EXTSEOUT(...)``)."""
        return key.upper() in self.text.upper()

    @property
    def n_subcases(self) -> int:
        return len({s for s, _k, _v in self.statements if s})


def _key_matches(written: str, key: str) -> bool:
    # NASTRAN reads a case-control name from its first four characters.
    return written == key or (len(written) >= 4 and key.startswith(written))


@dataclass(frozen=True)
class ParsedDeck:
    """A NASTRAN input file as read by :func:`parse_deck`.

    Attributes
    ----------
    path : str
    executive : str
        Executive control text (before CEND), as written.
    sol, app : str or None
        The SOL and APP statements' values, upper case.
    case : CaseControl
    cards : tuple of Card
        The bulk-data entries in deck order (INCLUDEd files in place).
    notes : tuple of str
        What the parser did that a user should know (a repeated BEGIN BULK...).
    """

    path: str
    executive: str
    sol: str | None
    app: str | None
    case: CaseControl
    cards: tuple
    notes: tuple = field(default=())

    def count(self) -> dict:
        """Entry name -> number of entries."""
        out: dict = {}
        for c in self.cards:
            out[c.name] = out.get(c.name, 0) + 1
        return out


_INCLUDE = re.compile(r"^\s*INCLUDE\b\s*(.*)$", re.IGNORECASE)


def _read_lines(path: Path, stack: tuple, origin: str) -> list:
    """(text, file, line number) of ``path`` with its INCLUDEs expanded in place."""
    if path in stack:
        raise ModelError(f"{origin}: INCLUDE {path} includes itself (through {' -> '.join(map(str, stack))})")
    try:
        text = path.read_text(errors="replace")
    except FileNotFoundError:
        raise ModelError(f"{origin}: INCLUDE '{path}': no such file (looked in {path.parent})") from None
    except IsADirectoryError:
        raise ModelError(f"{origin}: INCLUDE '{path}' is a directory, not a bulk-data file") from None
    except OSError as exc:
        raise ModelError(f"{origin}: cannot read {path} ({exc.strerror})") from None
    name = str(path)
    raw = text.splitlines()
    if "INCLUDE" not in text.upper():
        return [(t, name, k) for k, t in enumerate(raw, 1)]
    out = []
    k = 0
    while k < len(raw):
        t = raw[k]
        m = _INCLUDE.match(t)
        if not m:
            out.append((t, name, k + 1))
            k += 1
            continue
        start = k
        spec = m.group(1).split("$", 1)[0].strip()
        if spec.startswith("'"):
            # a quoted name may continue on the following lines until its closing quote
            while spec.count("'") < 2 and k + 1 < len(raw):
                k += 1
                spec += raw[k].split("$", 1)[0].strip()
            if spec.count("'") < 2:
                raise ModelError(f"{name}, line {start + 1}: INCLUDE: the file name's closing quote is missing")
            fname = spec[1:spec.index("'", 1)]
        else:
            fname = spec.split()[0] if spec.split() else ""
        if not fname:
            raise ModelError(f"{name}, line {start + 1}: INCLUDE without a file name")
        out.extend(_read_lines(_include_path(path.parent, fname), stack + (path,),
                               f"{name}, line {start + 1}"))
        k += 1
    return out


def _include_path(base: Path, fname: str) -> Path:
    """An INCLUDE's file: relative to the including file; Windows separators accepted."""
    p = Path(fname)
    if "\\" in fname:
        w = PureWindowsPath(fname)
        p = Path(*w.parts) if not w.drive else Path(fname)
    return p if p.is_absolute() else base / p


_SOL = re.compile(r"^\s*SOL\s+([^\s$]+)", re.IGNORECASE)
_APP = re.compile(r"^\s*APP\s+([^\s$]+)", re.IGNORECASE)
_CEND = re.compile(r"^\s*CEND\b", re.IGNORECASE)
_BEGIN = re.compile(r"^\s*BEGIN\s+(BULK|SUPER)", re.IGNORECASE)
_REPLICATOR = re.compile(r"^\s*(=\(\d+\)|==|=\s*,|\*\(\d+\))")


_HEAD_FIRST = frozenset("CcBb \t")


def _is_head(t: str) -> bool:
    u = t.lstrip()[:5].upper()
    return u == "BEGIN" or u[:4] == "CEND"


def parse_deck(path) -> ParsedDeck:
    """Read a NASTRAN input file (executive, case control, bulk data, INCLUDEs).

    A file without BEGIN BULK is taken as bulk data alone (a "punch" file); one without
    CEND has no executive control.
    """
    # Long: the sections of an input file (executive, case control, bulk) found in one place.
    path = Path(path)
    if not path.exists():
        raise ModelError(f"{path}: no such file")
    if path.is_dir():
        raise ModelError(f"{path}: is a directory, not a bulk-data file")
    lines = _read_lines(path, (), str(path))
    # the first letter before the regular expression: a large deck has 1e5 lines
    heads = [(k, t) for k, (t, _f, _n) in enumerate(lines) if t[:1] in _HEAD_FIRST and _is_head(t)]
    cend = next((k for k, t in heads if _CEND.match(t)), None)
    begins = [k for k, t in heads if _BEGIN.match(t)]
    notes = []
    executive = "\n".join(t for t, _f, _n in lines[:cend]) if cend is not None else ""
    sol = app = None
    for t, _f, _n in lines[:cend] if cend is not None else []:
        s = t.split("$", 1)[0]
        m = _SOL.match(s)
        if m and sol is None:
            sol = m.group(1).upper()
        m = _APP.match(s)
        if m and app is None:
            app = m.group(1).upper()
    if begins:
        first = begins[0]
        if _BEGIN.match(lines[first][0]).group(1).upper() == "SUPER":
            t, f, n = lines[first]
            raise ModelError(f"{f}, line {n}: {t.strip()}: superelement bulk data is not supported")
        case_lines = lines[(cend + 1 if cend is not None else 0):first]
        bulk = lines[first + 1:]
        if len(begins) > 1:
            # A repeated BEGIN BULK (MSC's HA144D) is accepted by NASTRAN: read once.
            again = [k - first - 1 for k in begins[1:]]
            for k in again:
                t, f, n = bulk[k]
                if _BEGIN.match(t).group(1).upper() == "SUPER":
                    raise ModelError(f"{f}, line {n}: {t.strip()}: superelement bulk data is not supported")
            drop = set(again)
            bulk = [ln for k, ln in enumerate(bulk) if k not in drop]
            notes.append(f"BEGIN BULK repeated {len(begins)} times: read once, as NASTRAN")
    else:
        case_lines, bulk = [], lines[(cend + 1 if cend is not None else 0):]
    case = _case_control(case_lines)
    cards = _bulk_cards(bulk)
    return ParsedDeck(str(path), executive, sol, app, case, tuple(cards), tuple(notes))


def _case_control(lines: list) -> CaseControl:
    statements = []
    sub = 0
    text = []
    pending = ""
    for t, _f, _n in lines:
        s = t.split("$", 1)[0].rstrip()
        if not s.strip():
            continue
        text.append(s)
        s = pending + s.strip()
        if s.endswith(","):  # a list continued on the next line
            pending = s
            continue
        pending = ""
        u = s.upper()
        m = re.match(r"SUBC\w*\s+(\d+)", u)
        if m:
            sub = int(m.group(1))
            continue
        if "=" not in u:
            continue
        key, value = u.split("=", 1)
        key = key.split("(", 1)[0].strip()
        statements.append((sub, key, value.strip()))
    return CaseControl(tuple(statements), "\n".join(text))


_COMPONENT_FIRST = ("OMIT1", "ASET1", "BSET1", "QSET1")  # entries whose field 2 is a component
_COMPONENT_CHARS = frozenset("0123456 ")


def _free_fields(body: str, card_name: str, file: str, lineno: int) -> list:
    parts = body.split(",")
    # NASTRAN-95's free field puts blank-separated values after the first comma. Elsewhere a
    # field with blanks is a component field written with spaces (12 4 6), read by bulk.py:
    # on a first line field 2 is an id (but for the *SET1 entries), on a continuation it
    # is taken as components when it holds only component digits.
    head = parts[0].strip().upper()
    first_line = bool(head) and head[0] not in "+*"
    for p in parts[1:2]:
        q = p.strip()
        if " " not in q or q.startswith("'"):
            continue
        name = head.rstrip("*") if first_line else card_name
        if _COMPONENT_CHARS.issuperset(q) and (not first_line or name in _COMPONENT_FIRST):
            continue
        ident = parts[1].split()[0] if first_line else ""
        raise ModelError(f"{file}, line {lineno}: NASTRAN-95 free-field input ({name} {ident} with "
                         f"blank-separated fields: {body.strip()[:40]!r}) is not supported: write the "
                         f"entries with commas or in fixed fields".replace("  with", " with"))
    return parts


def _bulk_cards(lines: list) -> list:
    """Bulk-data lines to :class:`Card` s (entries after ENDDATA are ignored)."""
    # Long: one pass over the lines with the three formats inline (the hot loop of a large
    # deck: no per-line function calls for fixed-field lines).
    cards = []
    name = None
    fields: list = []
    lns: list = []
    widths: list = []
    file = ""

    def flush():
        if name is not None:
            cards.append(Card(name, tuple(fields), file, tuple(lns), tuple(widths)))

    for raw, f, n in lines:
        s = raw.split("$", 1)[0] if "$" in raw else raw
        if not s or s.isspace():
            continue
        if "\t" in s:
            s = s.expandtabs(8)
        s = s.upper()
        c0 = s[0]
        if "," in s:
            if c0 in "=*" and _REPLICATOR.match(s):
                raise ModelError(f"{f}, line {n}: NASTRAN-95 free-field input (a replicator: "
                                 f"{s.strip()[:40]!r}) is not supported: write the entries with commas or "
                                 f"in fixed fields")
            parts = _free_fields(s, name or "", f, n)
            head = parts[0].strip()
            cont = c0 in " +*," or not head
            large = "*" in head
            width = 4 if large else 8
            # auto-continuation: a free-field line longer than a line's fields (ten; six in large
            # field) is several lines
            step = width + 2
            rows = [parts[k:k + step] for k in range(0, len(parts), step)] if len(parts) > step else [parts]
            for r, row in enumerate(rows):
                data = [x.strip() for x in row[1:1 + width]]
                data += [""] * (width - len(data))
                if r == 0 and not cont:
                    flush()
                    name, file = head.rstrip("*").strip(), f
                    if name == "ENDDATA":
                        return cards
                    fields, lns, widths = [name], [], []
                elif name is None:
                    raise ModelError(f"{f}, line {n}: a continuation line without an entry before it")
                fields.extend(data)
                lns.append(n)
                widths.append(width)
            continue
        if c0 in "=*" and _REPLICATOR.match(s):
            raise ModelError(f"{f}, line {n}: NASTRAN-95 free-field input (a replicator: {s.strip()[:40]!r}) "
                             f"is not supported: write the entries with commas or in fixed fields")
        if c0 in " +*":
            if name is None:
                raise ModelError(f"{f}, line {n}: a continuation line without an entry before it")
            if c0 == "*":
                fields.extend((s[8:24].strip(), s[24:40].strip(), s[40:56].strip(), s[56:72].strip()))
                widths.append(4)
            else:
                fields.extend((s[8:16].strip(), s[16:24].strip(), s[24:32].strip(), s[32:40].strip(),
                               s[40:48].strip(), s[48:56].strip(), s[56:64].strip(), s[64:72].strip()))
                widths.append(8)
            lns.append(n)
            continue
        flush()
        head = s[:8].strip()
        file = f
        if head.endswith("*") or "*" in head:
            name = head.split("*", 1)[0].strip()
            fields = [name, s[8:24].strip(), s[24:40].strip(), s[40:56].strip(), s[56:72].strip()]
            widths = [4]
        else:
            name = head.split()[0] if head else head
            if name == "ENDDATA" or s.strip() == "ENDDATA":
                name = None
                return cards
            fields = [name, s[8:16].strip(), s[16:24].strip(), s[24:32].strip(), s[32:40].strip(),
                      s[40:48].strip(), s[48:56].strip(), s[56:64].strip(), s[64:72].strip()]
            widths = [8]
        lns = [n]
    flush()
    return cards


def deck_text(deck: ParsedDeck, cards=None) -> str:
    """``deck`` as one self-contained input file (INCLUDEs in place): its executive and case
    control as read (comments dropped), then ``cards`` (default: its own) in free field, which
    has no field width to overflow, so every field is written exactly as it was read."""
    out = []
    if deck.executive.strip():
        out.append(deck.executive.rstrip("\n"))
    out.append("CEND")
    if deck.case.text.strip():
        out.append(deck.case.text)
    out.append("BEGIN BULK")
    for card in deck.cards if cards is None else cards:
        f = card.fields
        out.append(",".join(f[:9]).rstrip(","))
        for k in range(9, len(f), 8):
            out.append(("," + ",".join(f[k:k + 8])).rstrip(",") or ",")
    out.append("ENDDATA\n")
    return "\n".join(out)
