"""Input/output data files: CSV, NPZ and MAT, read and written with validation.

File formats (design.md)
------------------------
CSV
    One header row, then one row per sample. An optional column named ``t`` holds the
    time [s]; when present, the sampling frequency is taken from it (it must be uniform).
    Which columns are inputs and which outputs is told by name: by default a column whose
    name starts with ``u`` (or ``U``) is an input and one whose name starts with ``y`` (or
    ``Y``) is an output, e.g. ``t,u1,u2,y_acc1,y_acc2``. Explicit ``inputs=`` and/or
    ``outputs=`` name lists override the convention (any column may then be used; with only
    one of the two lists given, every other column except ``t`` is of the other kind).
    :func:`write_data` keeps to the convention, prefixing ``u_``/``y_`` to a name that does
    not already start with the right letter.
NPZ / MAT
    Arrays ``u`` (N x m), ``y`` (N x p), scalar ``fs`` [Hz], optional ``input_names``,
    ``output_names`` (strings) and, as an extension written by ``trussid simulate``,
    ``y_clean`` (N x p, the noise-free outputs of a simulated experiment). ``inputs=`` /
    ``outputs=`` then select channels by name.

Every problem is a :class:`trussid.plid.errors.DataError` naming the file and the offending column
or sample.
"""

from __future__ import annotations

import csv
import difflib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from trussid.plid.errors import DataError
from trussid._util.files import atomic_path

#: Relative jitter of the time column tolerated before it is called non-uniform (times
#: printed with few decimals, e.g. 1/3 ms, are not exactly uniform).
TIME_JITTER = 1e-2

SUFFIXES = (".csv", ".npz", ".mat")


@dataclass
class IOData:
    """Sampled input/output data of one experiment.

    Attributes
    ----------
    u : ndarray, shape (N, m)
        Inputs, one column per channel.
    y : ndarray, shape (N, p)
        Outputs (measured, i.e. with noise).
    fs : float
        Sampling frequency [Hz].
    input_names, output_names : list of str
        Channel names (length m and p).
    t : ndarray, shape (N,), optional
        Sample times [s], when the file had them.
    y_clean : ndarray, shape (N, p), optional
        Noise-free outputs (known only for simulated data).
    """

    u: np.ndarray
    y: np.ndarray
    fs: float
    input_names: list[str] = field(default_factory=list)
    output_names: list[str] = field(default_factory=list)
    t: np.ndarray | None = None
    y_clean: np.ndarray | None = None

    def __post_init__(self):
        self.u = np.asarray(self.u, dtype=float)
        self.y = np.asarray(self.y, dtype=float)
        if self.u.ndim == 1:
            self.u = self.u[:, None]
        if self.y.ndim == 1:
            self.y = self.y[:, None]
        if not self.input_names:
            self.input_names = [f"u{j + 1}" for j in range(self.u.shape[1])]
        if not self.output_names:
            self.output_names = [f"y{j + 1}" for j in range(self.y.shape[1])]
        self.input_names = [str(s) for s in self.input_names]
        self.output_names = [str(s) for s in self.output_names]

    @property
    def n_samples(self) -> int:
        return self.u.shape[0]

    @property
    def n_inputs(self) -> int:
        return self.u.shape[1]

    @property
    def n_outputs(self) -> int:
        return self.y.shape[1]

    @property
    def dt(self) -> float:
        """Sampling interval [s]."""
        return 1.0 / self.fs


# --------------------------------------------------------------------------- validation


def validate(data: IOData, source: str = "data") -> IOData:
    """Check data for the mistakes that would spoil an identification; return it unchanged.

    Raises :class:`DataError` naming the column (and sample) for: wrong array rank, length
    mismatch between inputs and outputs, no samples or no channels, names that do not match
    the column count or repeat, NaN/inf (first bad sample), a constant (unexciting) input,
    and a missing or non-positive sampling frequency.
    """
    u, y = data.u, data.y
    for what, arr in (("u", u), ("y", y)):
        if arr.ndim != 2:
            raise DataError(f"{source}: array '{what}' must be 2-D (samples x channels), "
                            f"got shape {arr.shape}")
    if u.shape[0] != y.shape[0]:
        raise DataError(f"{source}: length mismatch: inputs have {u.shape[0]} samples, "
                        f"outputs have {y.shape[0]}")
    if u.shape[0] == 0:
        raise DataError(f"{source}: no samples")
    if u.shape[1] == 0:
        raise DataError(f"{source}: no input columns")
    if y.shape[1] == 0:
        raise DataError(f"{source}: no output columns")
    for kind, names, arr in (("input", data.input_names, u), ("output", data.output_names, y)):
        if len(names) != arr.shape[1]:
            raise DataError(f"{source}: {len(names)} {kind} names for {arr.shape[1]} {kind} "
                            "columns")
    all_names = list(data.input_names) + list(data.output_names)
    dup = sorted({s for s in all_names if all_names.count(s) > 1})
    if dup:
        raise DataError(f"{source}: column name '{dup[0]}' is used more than once")
    for names, arr in ((data.input_names, u), (data.output_names, y)):
        bad = ~np.isfinite(arr)
        if bad.any():
            k, j = np.argwhere(bad)[0]
            raise DataError(f"{source}: column '{names[j]}' has a non-finite value "
                            f"({arr[k, j]}) at sample {k}")
    span = np.ptp(u, axis=0)
    flat = np.flatnonzero(span <= 1e-12 * np.maximum(np.max(np.abs(u), axis=0), 1e-300))
    if flat.size:
        j = flat[0]
        raise DataError(f"{source}: input column '{data.input_names[j]}' is constant "
                        f"({u[0, j]:g}) and excites nothing")
    if data.fs is None or not np.isfinite(data.fs) or data.fs <= 0:
        raise DataError(f"{source}: sampling frequency missing or not positive (fs={data.fs}); "
                        "give it (e.g. --fs HZ) or add a time column 't'")
    if data.y_clean is not None and data.y_clean.shape != y.shape:
        raise DataError(f"{source}: array 'y_clean' has shape {data.y_clean.shape}, "
                        f"outputs have {y.shape}")
    return data


def check_enough_samples(data: IOData, n_params: int, what: str = "the model") -> None:
    """Raise :class:`DataError` if ``data`` has fewer samples than ``n_params`` parameters."""
    if data.n_samples < n_params:
        raise DataError(f"only {data.n_samples} samples for {n_params} parameters of {what}; "
                        f"need at least {n_params} samples")


def _unknown(name: str, known: list[str], source: str) -> DataError:
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean '{close[0]}'?" if close else f"; columns are {', '.join(known)}"
    return DataError(f"{source}: unknown column '{name}'{hint}")


def _select(names: list[str], arr: np.ndarray, wanted, kind: str, source: str):
    """Pick channels ``wanted`` (names) out of ``arr``; ``None`` keeps all."""
    if wanted is None:
        return list(names), arr
    idx = []
    for w in wanted:
        if w not in names:
            raise _unknown(w, list(names), source)
        idx.append(names.index(w))
    if not idx:
        raise DataError(f"{source}: empty list of {kind}s")
    return [names[i] for i in idx], arr[:, idx]


def fs_from_time(t: np.ndarray, source: str = "data") -> float:
    """Sampling frequency [Hz] from a uniform time column; :class:`DataError` if not uniform."""
    t = np.asarray(t, dtype=float)
    if t.size < 2:
        raise DataError(f"{source}: column 't' needs at least 2 samples to give fs")
    span = t[-1] - t[0]
    if not span > 0:
        raise DataError(f"{source}: column 't' does not increase")
    dt = span / (t.size - 1)
    dev = np.abs(t - t[0] - dt * np.arange(t.size))
    k = int(np.argmax(dev))
    if dev[k] > TIME_JITTER * dt:
        raise DataError(f"{source}: column 't' is not uniformly sampled (sample {k}: "
                        f"t={t[k]:.9g} s, expected {t[0] + dt * k:.9g} s)")
    return 1.0 / dt


# --------------------------------------------------------------------------- reading


def read_data(path, inputs=None, outputs=None, fs=None) -> IOData:
    """Read and validate input/output data from a CSV, NPZ or MAT file.

    Parameters
    ----------
    path : path-like
        ``.csv``, ``.npz`` or ``.mat`` file (see the module docstring for the layouts).
    inputs, outputs : sequence of str, optional
        Channel (column) names to use as inputs/outputs, in this order.
    fs : float, optional
        Sampling frequency [Hz]; required when the file has neither ``fs`` nor ``t``. If the
        file has them too, they must agree within 1 %.

    Returns
    -------
    IOData
    """
    path = Path(path)
    if not path.exists():
        raise DataError(f"no such data file: {path}")
    if path.is_dir():
        raise DataError(f"{path} is a directory, not a data file")
    suffix = path.suffix.lower()
    if suffix == ".csv":
        data = _read_csv(path, inputs, outputs)
    elif suffix in (".npz", ".mat"):
        data = _read_arrays(path, inputs, outputs)
    else:
        raise DataError(f"{path}: unknown data file type '{path.suffix}' "
                        f"(use {', '.join(SUFFIXES)})")
    if fs is not None:
        fs = float(fs)
        if not (np.isfinite(fs) and fs > 0):
            raise DataError(f"fs must be a positive number of Hz, got {fs}")
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


def _parse_cells(rows, header, source):
    values = np.empty((len(rows), len(header)))
    for k, row in enumerate(rows):
        if len(row) != len(header):
            raise DataError(f"{source}: sample {k} (line {k + 2}) has {len(row)} values, "
                            f"the header has {len(header)}")
        for j, cell in enumerate(row):
            try:
                values[k, j] = float(cell)
            except ValueError:
                raise DataError(f"{source}: column '{header[j]}' sample {k} (line {k + 2}) "
                                f"is not a number: '{cell}'") from None
    return values


def _read_csv(path: Path, inputs, outputs) -> IOData:
    source = str(path)
    with open(path, newline="") as fh:
        reader = csv.reader(fh)
        try:
            header = [h.strip() for h in next(reader)]
        except StopIteration:
            raise DataError(f"{source}: empty file (a header row is required)") from None
        rows = [r for r in reader if r and any(c.strip() for c in r)]
    values = None
    if rows and all(len(r) == len(header) for r in rows):
        try:  # fast path; the cell-by-cell loop below only runs to name a bad cell
            values = np.array(rows, dtype=float)
        except ValueError:
            values = None
    if len(set(header)) != len(header):
        dup = next(h for h in header if header.count(h) > 1)
        raise DataError(f"{source}: column name '{dup}' appears more than once in the header")
    if any(h == "" for h in header):
        raise DataError(f"{source}: header column {header.index('') + 1} has no name")
    if _is_number(header[0]):
        raise DataError(f"{source}: the first row must be a header of column names, "
                        f"found a number '{header[0]}'")
    if values is None:
        values = _parse_cells(rows, header, source)
    cols = {h: values[:, j] for j, h in enumerate(header)}
    others = [h for h in header if h != "t"]
    for lst in (inputs, outputs):
        for name in lst or []:
            if name not in header:
                raise _unknown(name, header, source)
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
    u = np.column_stack([cols[h] for h in in_names]) if rows else np.empty((0, len(in_names)))
    y = np.column_stack([cols[h] for h in out_names]) if rows else np.empty((0, len(out_names)))
    t = cols.get("t")
    fs = None
    if t is not None and rows:
        bad = ~np.isfinite(t)
        if bad.any():
            raise DataError(f"{source}: column 't' has a non-finite value at sample "
                            f"{int(np.argmax(bad))}")
        fs = fs_from_time(t, source)
    return IOData(u=u, y=y, fs=fs, input_names=in_names, output_names=out_names, t=t)


def _names(raw, count: int, default: str) -> list[str]:
    if raw is None:
        return [f"{default}{j + 1}" for j in range(count)]
    arr = np.atleast_1d(np.asarray(raw, dtype=object)).ravel()
    out = []
    for a in arr:  # MAT cell arrays come back as nested object/char arrays
        a = np.asarray(a)
        out.append(str(a.ravel()[0]) if a.size == 1 else "".join(str(c) for c in a.ravel()))
    return [s.strip() for s in out]


def _read_arrays(path: Path, inputs, outputs) -> IOData:
    source = str(path)
    try:
        if path.suffix.lower() == ".npz":
            with np.load(path, allow_pickle=False) as z:
                arrays = {k: z[k] for k in z.files}
        else:
            import scipy.io

            arrays = {k: v for k, v in scipy.io.loadmat(path, squeeze_me=False).items()
                      if not k.startswith("__")}
    except DataError:
        raise
    except Exception as exc:  # numpy/scipy raise many types for a corrupt or foreign file
        raise DataError(f"{source}: not a readable {path.suffix} data file ({exc})") from None
    for key in ("u", "y"):
        if key not in arrays:
            raise DataError(f"{source}: not a data file: missing array '{key}' "
                            f"(found {', '.join(sorted(arrays)) or 'nothing'})")
    u, y = (np.asarray(arrays[k], dtype=float) for k in ("u", "y"))
    for key, arr in (("u", u), ("y", y)):
        if arr.ndim == 1:
            pass
        elif arr.ndim != 2:
            raise DataError(f"{source}: array '{key}' must be 2-D (samples x channels), "
                            f"got shape {arr.shape}")
    u = u[:, None] if u.ndim == 1 else u
    y = y[:, None] if y.ndim == 1 else y
    fs = None
    if "fs" in arrays:
        fs_arr = np.asarray(arrays["fs"], dtype=float).ravel()
        if fs_arr.size != 1:
            raise DataError(f"{source}: 'fs' must be a scalar, got {fs_arr.size} values")
        fs = float(fs_arr[0])
    in_names = _names(arrays.get("input_names"), u.shape[1], "u")
    out_names = _names(arrays.get("output_names"), y.shape[1], "y")
    if len(in_names) != u.shape[1]:
        raise DataError(f"{source}: {len(in_names)} input_names for {u.shape[1]} columns of 'u'")
    if len(out_names) != y.shape[1]:
        raise DataError(f"{source}: {len(out_names)} output_names for {y.shape[1]} columns "
                        "of 'y'")
    y_clean = arrays.get("y_clean")
    if y_clean is not None:
        y_clean = np.asarray(y_clean, dtype=float)
        y_clean = y_clean[:, None] if y_clean.ndim == 1 else y_clean
        if y_clean.shape != y.shape:
            raise DataError(f"{source}: array 'y_clean' has shape {y_clean.shape}, "
                            f"'y' has {y.shape}")
    if u.shape[0] != y.shape[0]:
        raise DataError(f"{source}: length mismatch: 'u' has {u.shape[0]} samples, "
                        f"'y' has {y.shape[0]}")
    known = in_names + out_names
    for w in list(inputs or []) + list(outputs or []):
        if w not in known:
            raise _unknown(w, known, source)
    # A name may move between roles only in CSV; in NPZ/MAT the arrays fix the role.
    for w in inputs or []:
        if w not in in_names:
            raise DataError(f"{source}: '{w}' is an output channel (array 'y'), not an input")
    for w in outputs or []:
        if w not in out_names:
            raise DataError(f"{source}: '{w}' is an input channel (array 'u'), not an output")
    in_names2, u = _select(in_names, u, inputs, "input", source)
    if y_clean is not None and outputs is not None:
        _, y_clean = _select(out_names, y_clean, outputs, "output", source)
    out_names2, y = _select(out_names, y, outputs, "output", source)
    return IOData(u=u, y=y, fs=fs, input_names=in_names2, output_names=out_names2,
                  y_clean=y_clean)


# --------------------------------------------------------------------------- writing


def _csv_names(names: list[str], letter: str) -> list[str]:
    return [n if n[:1] in (letter, letter.upper()) else f"{letter}_{n}" for n in names]


def write_data(data: IOData, path) -> Path:
    """Write ``data`` to ``path`` (``.csv``, ``.npz`` or ``.mat``), atomically.

    CSV gets a time column ``t`` (``data.t`` or ``k / fs``) and names kept to the ``u*``/``y*``
    convention, written with 17 significant digits so that reading it back is exact.
    NPZ/MAT get ``u``, ``y``, ``fs``, ``input_names``, ``output_names`` (and ``y_clean``
    when known). Returns the path.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise DataError(f"{path}: unknown data file type '{path.suffix}' "
                        f"(use {', '.join(SUFFIXES)})")
    validate(data, "data to write")
    if suffix == ".csv":
        in_names = _csv_names(data.input_names, "u")
        out_names = _csv_names(data.output_names, "y")
        t = data.t if data.t is not None else np.arange(data.n_samples) / data.fs
        table = np.column_stack([t, data.u, data.y])
        with atomic_path(path) as tmp:
            with open(tmp, "w", newline="") as fh:
                fh.write(",".join(["t", *in_names, *out_names]) + "\n")
                np.savetxt(fh, table, delimiter=",", fmt="%.17g")
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
                import scipy.io

                arrays["input_names"] = np.array(data.input_names, dtype=object)
                arrays["output_names"] = np.array(data.output_names, dtype=object)
                with open(tmp, "wb") as fh:
                    scipy.io.savemat(fh, arrays)
    return path


def with_channels(data: IOData, inputs=None, outputs=None) -> IOData:
    """A copy of ``data`` restricted to the named input/output channels (in that order)."""
    in_names, u = _select(data.input_names, data.u, inputs, "input", "data")
    out_names, y = _select(data.output_names, data.y, outputs, "output", "data")
    y_clean = None
    if data.y_clean is not None:
        _, y_clean = _select(data.output_names, data.y_clean, outputs, "output", "data")
    return replace(data, u=u, y=y, input_names=in_names, output_names=out_names,
                   y_clean=y_clean)


__all__ = ["IOData", "read_data", "write_data", "validate", "check_enough_samples",
           "fs_from_time", "with_channels"]
