"""Input/output data files: CSV, NPZ, MAT and UFF, read and written with validation.

File formats
------------
CSV (and what lab software writes as such)
    One header row of column names, then one row per sample. Accepted as lab programs write
    them: ``,``, ``;`` or tab delimiters (detected), a decimal comma with ``;`` or tab
    delimiters, quoted cells, a byte-order mark, comment lines starting with ``#``, ``%`` or
    ``//`` (anywhere), units in the header (``y1 [V]``, ``t (ms)``) and a leading unnamed
    index column of 0, 1, 2, ... (pandas ``to_csv``).
    An optional time column (named ``t`` or ``time``, any case) gives the sampling frequency;
    it must be uniform. Its unit is read from the header (s, ms, us, ns); a time column
    without a unit is taken in seconds only where that is plausible: with ``fs`` given, the
    column is read in whichever of s, ms or us agrees with it (and refused if none does);
    without ``fs``, a unitless column that would mean less than :data:`FS_PLAUSIBLE_MIN` Hz
    is refused (a column in milliseconds would otherwise silently give a model 1000 times
    too slow).
    Which columns are inputs and which outputs is told by name: by default a column whose
    name starts with ``u`` (or ``U``) is an input and one whose name starts with ``y`` (or
    ``Y``) is an output, e.g. ``t,u1,u2,y_acc1,y_acc2``. Explicit ``inputs=`` and/or
    ``outputs=`` name lists override the convention (any column may then be used; with only
    one of the two lists given, every other column except the time column is of the other
    kind). A name may be given with or without its unit.
    :func:`write_data` keeps to the convention, prefixing ``u_``/``y_`` to a name that does
    not already start with the right letter.
NPZ / MAT
    Arrays ``u`` (N x m), ``y`` (N x p), scalar ``fs`` [Hz], optional ``input_names``,
    ``output_names`` (strings) and, as an extension written by ``trussid simulate``,
    ``y_clean`` (N x p, the noise-free outputs of a simulated experiment). ``inputs=`` /
    ``outputs=`` then select channels by name.
    Files with other variable names are read too: ``input``/``output`` are found without
    help; otherwise ``inputs=``/``outputs=`` name the variables (``F1,F2``) or columns of a
    variable (``data:1,2`` or ``data:3-5``, numbered from 1 as in MATLAB). The sampling
    frequency comes from ``fs``/``Fs``, from a sample interval ``Ts``/``dt`` [s] or from a
    time vector ``t``/``time``. Arrays may be stored samples x channels or channels x samples
    (MATLAB's habit): the sample axis is the one whose length every array shares (the time
    vector's length when there is one) and that exceeds the channel count; a file where both
    axes qualify is refused as ambiguous.
UFF (``.uff``, ``.unv``)
    Universal File Format data sets 58 (time histories, one record per channel), read and
    written through :mod:`trussid.plid.uff`.

Every problem is a :class:`trussid.plid.errors.DataError` naming the file and the offending
column (variable, record) or sample.
"""

from __future__ import annotations

import csv
import io
import re
from pathlib import Path

import numpy as np
import scipy.io

from trussid._util.files import atomic_path
from trussid.plid.data import (IOData, check_enough_samples, select_channels, unknown_name,
                               validate, with_channels)
from trussid.plid.errors import DataError
from trussid.plid.uff import read_uff_data, write_uff_data

#: Relative jitter of the time column tolerated before it is called non-uniform (times
#: printed with few decimals, e.g. 1/3 ms, are not exactly uniform).
TIME_JITTER = 1e-2

#: Lowest sampling frequency [Hz] a time column without a unit may imply: below it the
#: column is more likely in milliseconds than a structural test this slow.
FS_PLAUSIBLE_MIN = 10.0

SUFFIXES = (".csv", ".npz", ".mat", ".uff", ".unv")

#: Names of a time column (compared in lower case, without the unit).
TIME_NAMES = ("t", "time", "zeit", "temps")

#: Time units [s per unit] accepted in a header.
TIME_UNITS = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0,
              "ms": 1e-3, "msec": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3,
              "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6, "usec": 1e-6,
              "microsecond": 1e-6, "microseconds": 1e-6, "ns": 1e-9, "min": 60.0}

_UNIT_NAMES = {1.0: "seconds", 1e-3: "milliseconds", 1e-6: "microseconds"}


# --------------------------------------------------------------------------- validation


def fs_from_time(t: np.ndarray, source: str = "data", name: str = "t") -> float:
    """Sampling frequency [Hz] from a uniform time column [s]; :class:`DataError` if not uniform."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        raise DataError(f"{source}: column '{name}' needs at least 2 samples to give fs")
    bad = ~np.isfinite(t)
    if bad.any():
        raise DataError(f"{source}: column '{name}' has a non-finite value at sample "
                        f"{int(np.argmax(bad))}")
    span = t[-1] - t[0]
    if not span > 0:
        raise DataError(f"{source}: column '{name}' does not increase")
    dt = span / (t.size - 1)
    dev = np.abs(t - t[0] - dt * np.arange(t.size))
    k = int(np.argmax(dev))
    if dev[k] > TIME_JITTER * dt:
        raise DataError(f"{source}: column '{name}' is not uniformly sampled (sample {k}: "
                        f"t={t[k]:.9g}, expected {t[0] + dt * k:.9g})")
    return 1.0 / dt


def _time_unit(raw_t, unit: str | None, fs_given, source: str, name: str):
    """Seconds per unit of a time column and a note, from its header unit or ``fs_given``.

    ``raw_t`` is the column as written. With a unit in the header that unit is used. Without
    one the column is read in whichever of s, ms, us agrees with ``fs_given`` within 1 %; with
    no ``fs_given`` it is read in seconds unless that implies less than
    :data:`FS_PLAUSIBLE_MIN` Hz, which is refused (it is then most likely milliseconds).
    """
    fs_raw = fs_from_time(raw_t, source, name)  # samples per unit of the column
    if unit is not None:
        key = unit.strip().lower().replace(" ", "")
        if key not in TIME_UNITS:
            raise DataError(f"{source}: column '{name}' has unit '{unit}', not a time unit "
                            f"(use one of s, ms, us, ns)")
        return TIME_UNITS[key], None
    if fs_given is not None:
        for scale in (1.0, 1e-3, 1e-6):
            if abs(fs_raw / scale - fs_given) <= 1e-2 * fs_given:
                note = None if scale == 1.0 else (
                    f"{source}: column '{name}' has no unit; it steps by {1 / fs_raw:.6g}, "
                    f"which agrees with --fs {fs_given:g} Hz in {_UNIT_NAMES[scale]}: read "
                    f"as {_UNIT_NAMES[scale]}")
                return scale, note
        raise DataError(f"{source}: fs={fs_given:g} Hz was given but the file says "
                        f"{fs_raw:.6g} Hz (column '{name}' steps by {1 / fs_raw:.6g} and has "
                        "no unit; in s, ms or us it does not match either)")
    if fs_raw < FS_PLAUSIBLE_MIN:
        raise DataError(
            f"{source}: time column '{name}' has no unit and steps by {1 / fs_raw:.6g}: in "
            f"seconds that is {fs_raw:.6g} Hz, below {FS_PLAUSIBLE_MIN:g} Hz; if it is in "
            f"milliseconds write '{name} [ms]' in the header (or give --fs), to confirm "
            f"seconds write '{name} [s]'")
    return 1.0, None


# --------------------------------------------------------------------------- reading


def read_data(path, inputs=None, outputs=None, fs=None) -> IOData:
    """Read and validate input/output data from a CSV, NPZ, MAT or UFF file.

    Parameters
    ----------
    path : path-like
        ``.csv``, ``.npz``, ``.mat``, ``.uff`` or ``.unv`` file (see the module docstring).
    inputs, outputs : sequence of str, optional
        Channel (column) names to use as inputs/outputs, in this order; in MAT/NPZ files also
        variable names or ``VAR:COLUMNS`` (1-based), in UFF files channel names.
    fs : float, optional
        Sampling frequency [Hz]; required when the file has neither ``fs`` nor a time column.
        If the file has them too, they must agree within 1 % (a time column without a unit
        may be in s, ms or us, see the module docstring).

    Returns
    -------
    IOData
        With ``notes`` saying what was assumed (e.g. a time column read as milliseconds).

    Examples
    --------
    Columns chosen by name, the sample rate from the time column (in milliseconds, as its
    header says); a column that is not there is named:

    >>> import numpy as np
    >>> from pathlib import Path
    >>> from trussid.plid import read_data
    >>> rows = "".join(f"{k:.1f},{np.sin(k)},{np.cos(k)},{k % 2}\\n" for k in range(5))
    >>> _ = Path("lab.csv").write_text("time [ms],shaker,acc,trigger\\n" + rows)
    >>> d = read_data("lab.csv", inputs=["shaker"], outputs=["acc"])
    >>> d.u.shape, d.y.shape, d.fs
    ((5, 1), (5, 1), 1000.0)
    >>> read_data("lab.csv", inputs=["shaker"], outputs=["acc9"])
    Traceback (most recent call last):
    ...
    trussid.plid.errors.DataError: lab.csv: unknown column 'acc9'; did you mean 'acc'?
    """
    path = Path(path)
    if not path.exists():
        raise DataError(f"no such data file: {path}")
    if path.is_dir():
        raise DataError(f"{path} is a directory, not a data file")
    if fs is not None:
        fs = float(fs)
        if not (np.isfinite(fs) and fs > 0):
            raise DataError(f"fs must be a positive number of Hz, got {fs}")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        data = _read_csv(path, inputs, outputs, fs)
    elif suffix in (".npz", ".mat"):
        data = _read_arrays(path, inputs, outputs, fs)
    elif suffix in (".uff", ".unv"):
        data = read_uff_data(path, inputs=inputs, outputs=outputs)
    else:
        raise DataError(f"{path}: unknown data file type '{path.suffix}' "
                        f"(use {', '.join(SUFFIXES)})")
    if fs is not None:
        if data.fs is not None and abs(data.fs - fs) > 1e-2 * fs:
            raise DataError(f"{path}: fs={fs:g} Hz was given but the file says "
                            f"{data.fs:.6g} Hz")
        data.fs = fs
    return validate(data, str(path))


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


def _read_csv(path: Path, inputs, outputs, fs_given=None) -> IOData:
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
        scale, note = _time_unit(cols[time_name], units.get(time_name), fs_given, source,
                                 header_raw[header.index(time_name)])
        t = cols[time_name] * scale
        fs = fs_from_time(t, source, time_name)
        if note:
            notes.append(note)
    return IOData(u=u, y=y, fs=fs, input_names=in_names, output_names=out_names, t=t,
                  units={k: v for k, v in units.items() if k in in_names + out_names},
                  notes=notes)


# ----------------------------------------------------------------- NPZ / MAT arrays


def _names(raw, count: int, default: str) -> list[str]:
    if raw is None:
        return [f"{default}{j + 1}" for j in range(count)]
    arr = np.atleast_1d(np.asarray(raw, dtype=object)).ravel()
    out = []
    for a in arr:  # MAT cell arrays come back as nested object/char arrays
        a = np.asarray(a)
        out.append(str(a.ravel()[0]) if a.size == 1 else "".join(str(c) for c in a.ravel()))
    return [s.strip() for s in out]


_FS_KEYS = ("fs", "Fs", "FS", "fsamp", "sample_rate", "SampleRate", "samplerate")
_TS_KEYS = ("Ts", "ts", "dt", "DT", "Dt", "T_s", "Tsamp")
_T_KEYS = ("t", "time", "Time")
_IN_KEYS = ("u", "U", "input", "inputs", "Input", "in")
_OUT_KEYS = ("y", "Y", "output", "outputs", "Output", "out")


def _load_arrays(path: Path, source: str) -> dict:
    try:
        if path.suffix.lower() == ".npz":
            with np.load(path, allow_pickle=False) as z:
                return {k: z[k] for k in z.files}

        return {k: v for k, v in scipy.io.loadmat(path, squeeze_me=False).items()
                if not k.startswith("__")}
    except NotImplementedError as exc:  # scipy: "Please use HDF reader for matlab v7.3 files"
        raise DataError(f"{source}: a MATLAB v7.3 (HDF5) file; save it with "
                        f"save(..., '-v7') ({exc})") from None
    except Exception as exc:  # numpy/scipy raise many types for a corrupt or foreign file
        raise DataError(f"{source}: not a readable {path.suffix} data file ({exc})") from None


def _numeric(arrays: dict, key: str, source: str) -> np.ndarray:
    try:
        arr = np.asarray(arrays[key], dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"{source}: variable '{key}' is not numeric") from None
    if arr.ndim > 2:
        raise DataError(f"{source}: array '{key}' must be 2-D (samples x channels), "
                        f"got shape {arr.shape}")
    return arr


_SPEC_RE = re.compile(r"^(?P<var>[A-Za-z_]\w*):(?P<cols>[\d,\- ]+)$")


def _column_spec(text: str, source: str) -> list[int]:
    cols = []
    for part in text.split(","):
        part = part.strip()
        if not part:
            continue
        a, _, b = part.partition("-")
        try:
            lo, hi = int(a), int(b) if b else int(a)
        except ValueError:
            raise DataError(f"{source}: bad column list '{text}' (use e.g. 1,2 or 3-5)") from None
        if lo < 1 or hi < lo:
            raise DataError(f"{source}: bad column list '{text}': columns count from 1")
        cols.extend(range(lo, hi + 1))
    return cols


def _join_specs(items):
    """``['data:1', '2']`` (a comma list split by the CLI) -> ``['data:1,2']``."""
    out = []
    for it in items:
        if out and ":" in out[-1] and re.fullmatch(r"[\d\- ]+", it):
            out[-1] = f"{out[-1]},{it}"
        else:
            out.append(it)
    return out


def _variable_request(items, arrays: dict) -> list[tuple[str, list[int] | None]] | None:
    """``items`` as (variable, 1-based columns or None) pairs, if every item names a
    variable (``F1`` or ``data:1,2``); None if they are channel names."""
    if items is None:
        return None
    req = []
    for it in _join_specs(list(items)):
        m = _SPEC_RE.match(it)
        if m and m.group("var") in arrays:
            req.append((m.group("var"), m.group("cols")))
        elif it in arrays:
            req.append((it, None))
        else:
            return None
    return req


def _declared_samples(arrays: dict, source: str):
    """Length of a time vector in the file (the declared sample count) and its key."""
    for key in _T_KEYS:
        if key in arrays:
            t = np.asarray(arrays[key], dtype=float).ravel()
            if t.size > 1:
                return t.size, key, t
    return None, None, None


def _sample_axis(shapes: dict, n_declared, source: str, t_key=None):
    """Number of samples and, per variable, whether it is stored channels x samples.

    The sample count is ``n_declared`` (a time vector's length) when given; otherwise the
    one axis length that every variable shares and that exceeds its channel count.
    """
    if n_declared is None:
        cands = None
        for shape in shapes.values():
            dims = set(shape)
            cands = dims if cands is None else cands & dims
        ok = []
        for n in sorted(cands or ()):
            if all(len(shape) == 1 or (shape[1] if shape[0] == n else shape[0]) < n
                   for shape in shapes.values()):
                ok.append(n)
        if not ok:
            for key, shape in shapes.items():
                if len(shape) == 2 and shape[0] == shape[1]:
                    raise DataError(f"{source}: variable '{key}' is {shape[0]}x{shape[1]}: "
                                    "cannot tell samples from channels")
            # name the lengths as samples along the longer axis, the usual layout
            pairs = [(a, sa, b, sb) for a, sa in shapes.items() for b, sb in shapes.items()
                     if max(sa) != max(sb)]
            desc = ", ".join(f"'{k}' {'x'.join(map(str, s))}" for k, s in shapes.items())
            if not pairs:
                raise DataError(f"{source}: cannot tell samples from channels ({desc})")
            k1, s1, k2, s2 = pairs[0]
            raise DataError(f"{source}: length mismatch: '{k1}' has {max(s1)} samples, "
                            f"'{k2}' has {max(s2)}")
        if len(ok) > 1:
            desc = ", ".join(f"'{k}' {'x'.join(map(str, s))}" for k, s in shapes.items())
            raise DataError(f"{source}: cannot tell samples from channels ({desc}: both "
                            "orientations fit); add a time vector 't' or store samples "
                            "along rows")
        n = ok[0]
    else:
        n = n_declared
    transposed = {}
    for key, shape in shapes.items():
        if len(shape) == 1:
            if shape[0] != n:
                raise DataError(f"{source}: length mismatch: '{key}' has {shape[0]} samples, "
                                f"{'time vector ' + repr(t_key) if t_key else 'the others'} "
                                f"{n}")
            transposed[key] = False
        elif shape[0] == n and shape[1] == n:
            raise DataError(f"{source}: variable '{key}' is {n}x{n}: cannot tell samples from "
                            "channels")
        elif shape[0] == n:
            transposed[key] = False
        elif shape[1] == n:
            transposed[key] = True
        else:
            raise DataError(f"{source}: length mismatch: variable '{key}' has shape "
                            f"{shape[0]}x{shape[1]}, neither side is the {n} samples "
                            f"{'of ' + repr(t_key) if t_key else 'of the others'}")
    return n, transposed


def _gather(req, arrays, transposed, source, kind):
    cols, names = [], []
    for var, spec in req:
        a = _numeric(arrays, var, source)
        a = a[:, None] if a.ndim == 1 else (a.T if transposed[var] else a)
        if spec is None:
            cols.append(a)
            names += [var] if a.shape[1] == 1 else [f"{var}:{j + 1}" for j in range(a.shape[1])]
        else:
            idx = _column_spec(spec, source)
            if max(idx) > a.shape[1]:
                raise DataError(f"{source}: {kind} '{var}:{spec}': variable '{var}' has only "
                                f"{a.shape[1]} channel(s)")
            cols.append(a[:, [j - 1 for j in idx]])
            names += [f"{var}:{j}" for j in idx]
    return np.column_stack(cols), names


def _named_channels(arrays, u, y, in_key, out_key, transposed, inputs, outputs, source):
    """Channel names from ``input_names``/``output_names`` and the channels picked by name."""
    y_clean = None
    in_names = _names(arrays.get("input_names"), u.shape[1], "u")
    out_names = _names(arrays.get("output_names"), y.shape[1], "y")
    if len(in_names) != u.shape[1]:
        raise DataError(f"{source}: {len(in_names)} input_names for {u.shape[1]} "
                        f"columns of '{in_key}'")
    if len(out_names) != y.shape[1]:
        raise DataError(f"{source}: {len(out_names)} output_names for {y.shape[1]} "
                        f"columns of '{out_key}'")
    if "y_clean" in arrays:
        y_clean = _numeric(arrays, "y_clean", source)
        y_clean = y_clean[:, None] if y_clean.ndim == 1 else (
            y_clean.T if transposed.get("y_clean") else y_clean)
        if y_clean.shape != y.shape:
            raise DataError(f"{source}: array 'y_clean' has shape {y_clean.shape}, "
                            f"'y' has {y.shape}")
    known = in_names + out_names
    for w in list(inputs or []) + list(outputs or []):
        if w not in known:
            raise unknown_name(w, known, source)
    # A name may move between roles only in CSV; in NPZ/MAT the arrays fix the role.
    for w in inputs or []:
        if w not in in_names:
            raise DataError(f"{source}: '{w}' is an output channel (array "
                            f"'{out_key}'), not an input")
    for w in outputs or []:
        if w not in out_names:
            raise DataError(f"{source}: '{w}' is an input channel (array "
                            f"'{in_key}'), not an output")
    if y_clean is not None and outputs is not None:
        _, y_clean = select_channels(out_names, y_clean, outputs, "output", source)
    in_names, u = select_channels(in_names, u, inputs, "input", source)
    out_names, y = select_channels(out_names, y, outputs, "output", source)
    return u, y, in_names, out_names, y_clean


def _read_arrays(path: Path, inputs, outputs, fs_given=None) -> IOData:
    source = str(path)
    arrays = _load_arrays(path, source)
    notes = []
    req_in = _variable_request(inputs, arrays)
    req_out = _variable_request(outputs, arrays)
    in_key = next((k for k in _IN_KEYS if k in arrays), None)
    out_key = next((k for k in _OUT_KEYS if k in arrays), None)
    by_variable = req_in is not None or req_out is not None
    if by_variable:
        for items, req in ((inputs, req_in), (outputs, req_out)):
            if items is not None and req is None:  # a typo among variable names
                bad = next(w for w in _join_specs(list(items))
                           if w.split(":")[0] not in arrays)
                raise unknown_name(bad, sorted(arrays), source, "variable")
        if req_in is None:
            if inputs is not None or in_key is None:
                raise DataError(f"{source}: name the input variable(s) with --inputs too "
                                f"(variables: {', '.join(sorted(arrays))})")
            req_in = [(in_key, None)]
        if req_out is None:
            if outputs is not None or out_key is None:
                raise DataError(f"{source}: name the output variable(s) with --outputs too "
                                f"(variables: {', '.join(sorted(arrays))})")
            req_out = [(out_key, None)]
    else:
        for key, kind in ((in_key, "inputs"), (out_key, "outputs")):
            if key is None:
                want = "u" if kind == "inputs" else "y"
                raise DataError(f"{source}: not a data file: missing array '{want}' (found "
                                f"{', '.join(sorted(arrays)) or 'nothing'}); name the "
                                f"variables holding the {kind} with --{kind}")
        req_in, req_out = [(in_key, None)], [(out_key, None)]
    used = {v for v, _ in req_in + req_out}
    n_declared, t_key, t_vec = _declared_samples(arrays, source)
    shapes = {}
    for var in sorted(used) + (["y_clean"] if "y_clean" in arrays and not by_variable else []):
        a = _numeric(arrays, var, source)
        if a.size == 0:
            raise DataError(f"{source}: variable '{var}' is empty: no samples")
        shapes[var] = a.shape
    n, transposed = _sample_axis(shapes, n_declared, source, t_key)
    if any(transposed.values()):
        notes.append(f"{source}: read {', '.join(repr(k) for k, v in transposed.items() if v)} "
                     f"as channels x samples ({n} samples)")
    u, in_names = _gather(req_in, arrays, transposed, source, "input")
    y, out_names = _gather(req_out, arrays, transposed, source, "output")
    y_clean = None
    if not by_variable:  # the trussid layout: names in input_names/output_names
        u, y, in_names, out_names, y_clean = _named_channels(
            arrays, u, y, in_key, out_key, transposed, inputs, outputs, source)
    fs = _fs_of_arrays(arrays, t_key, t_vec, fs_given, source, notes)
    return IOData(u=u, y=y, fs=fs, input_names=in_names, output_names=out_names,
                  y_clean=y_clean, notes=notes)


def _fs_of_arrays(arrays, t_key, t_vec, fs_given, source, notes):
    for key in _FS_KEYS:
        if key in arrays:
            v = np.asarray(arrays[key], dtype=float).ravel()
            if v.size != 1:
                raise DataError(f"{source}: '{key}' must be a scalar, got {v.size} values")
            return float(v[0])
    for key in _TS_KEYS:
        if key in arrays:
            v = np.asarray(arrays[key], dtype=float).ravel()
            if v.size != 1:
                raise DataError(f"{source}: '{key}' must be a scalar, got {v.size} values")
            if not (np.isfinite(v[0]) and v[0] > 0):
                raise DataError(f"{source}: sample interval '{key}' = {v[0]} must be positive")
            return 1.0 / float(v[0])
    if t_vec is not None:
        scale, note = _time_unit(t_vec, None, fs_given, source, t_key)
        if note:
            notes.append(note)
        return fs_from_time(t_vec * scale, source, t_key)
    return None


# --------------------------------------------------------------------------- writing


def _csv_names(names: list[str], letter: str) -> list[str]:
    return [n if n[:1] in (letter, letter.upper()) else f"{letter}_{n}" for n in names]


def write_data(data: IOData, path) -> Path:
    """Write ``data`` to ``path`` (``.csv``, ``.npz``, ``.mat``, ``.uff``/``.unv``), atomically.

    CSV gets a time column ``t`` (``data.t`` or ``k / fs``) and names kept to the ``u*``/``y*``
    convention, written with 17 significant digits so that reading it back is exact.
    NPZ/MAT get ``u``, ``y``, ``fs``, ``input_names``, ``output_names`` (and ``y_clean``
    when known). UFF gets one data set 58 per channel (:func:`trussid.plid.uff.write_uff_data`).
    Returns the path.

    Examples
    --------
    A lab record written as CSV (a time column, then ``u_*`` and ``y_*`` columns) and read back:

    >>> import numpy as np
    >>> from trussid.plid import IOData, read_data, write_data
    >>> rng = np.random.default_rng(0)
    >>> record = IOData(u=rng.standard_normal((1000, 1)), y=rng.standard_normal((1000, 2)),
    ...                 fs=1600.0, input_names=["force"], output_names=["acc1", "acc2"])
    >>> path = write_data(record, "run1.csv")
    >>> open(path).readline().strip()
    't,u_force,y_acc1,y_acc2'
    >>> again = read_data(path)
    >>> again.fs, again.input_names, again.output_names, np.allclose(again.y, record.y)
    (1600.0, ['u_force'], ['y_acc1', 'y_acc2'], True)
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise DataError(f"{path}: unknown data file type '{path.suffix}' "
                        f"(use {', '.join(SUFFIXES)})")
    validate(data, "data to write")
    if suffix in (".uff", ".unv"):
        return write_uff_data(data, path)
    if suffix == ".csv":
        in_names = _csv_names(data.input_names, "u")
        out_names = _csv_names(data.output_names, "y")
        t = data.t if data.t is not None else np.arange(data.n_samples) / data.fs
        table = np.column_stack([t, data.u, data.y])
        with atomic_path(path) as tmp:
            with open(tmp, "w", newline="") as fh:
                # csv quotes a name holding a comma, a quote or a line break, which the
                # reader takes back (a bare comma would split the name into two columns)
                csv.writer(fh, lineterminator="\n").writerow(["t", *in_names, *out_names])
                # %s of a float64 is its shortest exact form (0.000625, not %.17g's
                # 0.00062500000000000001); the channels keep 17 digits, exact on reading
                np.savetxt(fh, table, delimiter=",",
                           fmt=["%s"] + ["%.17g"] * (table.shape[1] - 1))
    else:
        arrays = dict(u=data.u, y=data.y, fs=np.float64(data.fs),
                      input_names=np.array(data.input_names, dtype=str),
                      output_names=np.array(data.output_names, dtype=str))
        if data.y_clean is not None:
            arrays["y_clean"] = data.y_clean
        with atomic_path(path) as tmp:
            if suffix == ".npz":
                with open(tmp, "wb") as fh:
                    np.savez(fh, **arrays)
            else:
                arrays["input_names"] = np.array(data.input_names, dtype=object)
                arrays["output_names"] = np.array(data.output_names, dtype=object)
                with open(tmp, "wb") as fh:
                    scipy.io.savemat(fh, arrays)
    return path


# IOData, validate, check_enough_samples and with_channels live in plid.data (imported here
# for the callers that know them from this module)
__all__ = ["read_data", "write_data", "fs_from_time", "FS_PLAUSIBLE_MIN"]
