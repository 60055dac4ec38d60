"""CSV data files as lab software writes them (:func:`read_csv_data`): delimiters, decimal
commas, comment lines, units in the header, an unnamed index column; the rules are in
:mod:`trussid.plid.datafile`'s module docstring, which reads files through here.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np

from trussid.plid.data import IOData, unknown_name
from trussid.plid.errors import DataError
from trussid.plid.timebase import TIME_NAMES, fs_from_time, time_unit

__all__ = ["read_csv_data"]


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


_COMMENT = ("#", "%", "//")
_UNIT_RE = re.compile(r"^(?P<name>.*?)\s*(?:\[(?P<u1>[^\]]*)\]|\((?P<u2>[^)]*)\))\s*$")


def _split_unit(cell: str) -> tuple[str, str | None]:
    """``'y1 [V]'`` -> ``('y1', 'V')``; ``'t (ms)'`` -> ``('t', 'ms')``; ``'y1'`` -> ``('y1', None)``."""
    m = _UNIT_RE.match(cell)
    if m and m.group("name").strip():
        unit = m.group("u1") if m.group("u1") is not None else m.group("u2")
        return m.group("name").strip(), unit.strip()
    return cell, None


def _decode(path: Path) -> str:
    raw = path.read_bytes()
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError:  # Windows lab software often writes Latin-1 (e.g. "µs")
        return raw.decode("latin-1")


def _sniff_delimiter(header: str, body: list[str]) -> str | None:
    """The delimiter that splits the header and the first rows into the same number of
    cells (more than one); tab before ``;`` before ``,``, since a decimal comma may sit
    inside ``;``- or tab-separated cells. None: a single column."""
    sample = body[:20]
    for d in ("\t", ";", ","):
        n = len(next(csv.reader([header], delimiter=d)))
        if n > 1 and all(len(next(csv.reader([r], delimiter=d))) == n for r in sample):
            return d
    for d in ("\t", ";", ","):  # ragged rows: let the row check name the bad one
        if d in header:
            return d
    if len(header.split()) > 1 and all(len(r.split()) == len(header.split()) for r in sample):
        return " "
    return None


def _to_float(rows, delim: str):
    try:
        return np.array(rows, dtype=float)
    except ValueError:
        pass
    if delim != ",":  # a decimal comma (e.g. German Excel: ';' and '1,5')
        try:
            return np.array([[c.replace(",", ".") for c in r] for r in rows], dtype=float)
        except ValueError:
            pass
    return None


def _parse_cells(rows, lines, header, source, delim):
    values = np.empty((len(rows), len(header)))
    for k, row in enumerate(rows):
        if len(row) != len(header):
            raise DataError(f"{source}: sample {k} (line {lines[k]}) has {len(row)} values, "
                            f"the header has {len(header)}")
        for j, cell in enumerate(row):
            text = cell.strip()
            if delim != ",":
                text = text.replace(",", ".")
            try:
                values[k, j] = float(text)
            except ValueError:
                raise DataError(f"{source}: column '{header[j]}' sample {k} (line {lines[k]}) "
                                f"is not a number: '{cell}'") from None
    return values


def _csv_roles(header, time_name, inputs, outputs, source):
    """Input and output column names: listed, or by the u*/y* convention."""
    others = [h for h in header if h != time_name]
    for lst in (inputs, outputs):
        for name in lst or []:
            if name not in header:
                raise unknown_name(name, header, source)
    if inputs is None and outputs is None:
        in_names = [h for h in others if h[:1] in "uU"]
        out_names = [h for h in others if h[:1] in "yY"]
        rest = [h for h in others if h not in in_names and h not in out_names]
        if rest:
            raise DataError(f"{source}: cannot tell whether column '{rest[0]}' is an input "
                            "or an output: name inputs u* and outputs y*, or list them "
                            "with --inputs/--outputs")
    elif outputs is None:
        in_names = list(inputs)
        out_names = [h for h in others if h not in in_names]
    elif inputs is None:
        out_names = list(outputs)
        in_names = [h for h in others if h not in out_names]
    else:
        in_names, out_names = list(inputs), list(outputs)
    both = set(in_names) & set(out_names)
    if both:
        raise DataError(f"{source}: column '{sorted(both)[0]}' is listed as both input and "
                        "output")
    if not in_names:
        raise DataError(f"{source}: no input columns (name them u* or use --inputs)")
    if not out_names:
        raise DataError(f"{source}: no output columns (name them y* or use --outputs)")
    return in_names, out_names


def read_csv_data(path: Path, inputs, outputs, fs_given=None) -> IOData:
    source = str(path)
    text = _decode(path)
    kept = [(i + 1, ln) for i, ln in enumerate(text.splitlines())
            if ln.strip() and not ln.lstrip().startswith(_COMMENT)]
    if not kept:
        raise DataError(f"{source}: empty file (a header row is required)")
    (_, head_line), body = kept[0], kept[1:]
    delim = _sniff_delimiter(head_line, [ln for _, ln in body])
    if delim is None:
        header_raw = [head_line.strip()]
        rows = [[ln.strip()] for _, ln in body]
    elif delim == " ":
        header_raw = head_line.split()
        rows = [ln.split() for _, ln in body]
    else:
        header_raw = next(csv.reader([head_line], delimiter=delim))
        rows = list(csv.reader(io.StringIO("\n".join(ln for _, ln in body)), delimiter=delim))
    lines = [n for n, _ in body]
    header_raw = [h.strip() for h in header_raw]
    # pandas' to_csv writes its row index as a first column with an empty name
    drop_index = (len(header_raw) > 1 and header_raw[0] == "" and rows
                  and all(len(r) == len(header_raw) and r[0].strip() == str(k)
                          for k, r in enumerate(rows)))
    if drop_index:
        header_raw, rows = header_raw[1:], [r[1:] for r in rows]
    if any(h == "" for h in header_raw):
        raise DataError(f"{source}: header column {header_raw.index('') + 1} has no name")
    if _is_number(header_raw[0].replace(",", ".")):
        raise DataError(f"{source}: the first row (line {kept[0][0]}) must be a header of "
                        f"column names, found a number '{header_raw[0]}'")
    split = [_split_unit(h) for h in header_raw]
    header = [s[0] for s in split]
    units = {s[0]: s[1] for s in split if s[1] is not None}
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise DataError(f"{source}: column name '{dup}' appears more than once in the header")
    values = None
    if rows and all(len(r) == len(header) for r in rows):
        values = _to_float(rows, delim or ",")  # fast path; the loop below names a bad cell
    if values is None:
        values = _parse_cells(rows, lines, header, source, delim or ",")
    cols = {h: values[:, j] for j, h in enumerate(header)}
    full = dict(zip(header_raw, header))  # 'y1 [V]' -> 'y1': names may be given either way
    inputs = None if inputs is None else [full.get(w, w) for w in inputs]
    outputs = None if outputs is None else [full.get(w, w) for w in outputs]
    time_cols = [h for h in header if h.lower() in TIME_NAMES
                 and h not in (inputs or []) and h not in (outputs or [])]
    time_name = time_cols[0] if time_cols else None
    if len(time_cols) > 1:
        raise DataError(f"{source}: two time columns ('{time_cols[0]}', '{time_cols[1]}')")
    in_names, out_names = _csv_roles(header, time_name, inputs, outputs, source)
    u = np.column_stack([cols[h] for h in in_names]) if rows else np.empty((0, len(in_names)))
    y = np.column_stack([cols[h] for h in out_names]) if rows else np.empty((0, len(out_names)))
    t, fs, notes = None, None, []
    if time_name is not None and rows:
        scale, note = time_unit(cols[time_name], units.get(time_name), fs_given, source,
                                 header_raw[header.index(time_name)])
        t = cols[time_name] * scale
        fs = fs_from_time(t, source, time_name)
        if note:
            notes.append(note)
    return IOData(u=u, y=y, fs=fs, input_names=in_names, output_names=out_names, t=t,
                  units={k: v for k, v in units.items() if k in in_names + out_names},
                  notes=notes)


# ----------------------------------------------------------------- NPZ / MAT arrays
