"""NPZ and MAT data files (:func:`read_array_data`): the standard variables, variables of
any name picked by the caller, samples x channels or channels x samples; the rules are in
:mod:`trussid.plid.datafile`'s module docstring, which reads files through here.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import scipy.io

from trussid.plid.data import IOData, select_channels, unknown_name
from trussid.plid.errors import DataError
from trussid.plid.timebase import fs_from_time, time_unit

__all__ = ["read_array_data"]


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


def read_array_data(path: Path, inputs, outputs, fs_given=None) -> IOData:
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
        scale, note = time_unit(t_vec, None, fs_given, source, t_key)
        if note:
            notes.append(note)
        return fs_from_time(t_vec * scale, source, t_key)
    return None


# --------------------------------------------------------------------------- writing
