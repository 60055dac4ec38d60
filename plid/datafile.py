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

This module is the front door (:func:`read_data`, :func:`write_data`); the CSV reader is
:mod:`trussid.plid.csvfile`, the NPZ/MAT reader :mod:`trussid.plid.arrayfile`, and the time
base they share (time column, unit, sample rate) :mod:`trussid.plid.timebase`.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import scipy.io

from trussid._util.files import atomic_path
from trussid.plid.arrayfile import read_array_data
from trussid.plid.csvfile import read_csv_data
from trussid.plid.data import IOData, check_enough_samples, validate, with_channels
from trussid.plid.errors import DataError
from trussid.plid.timebase import FS_PLAUSIBLE_MIN, fs_from_time
from trussid.plid.uff import read_uff_data, write_uff_data

SUFFIXES = (".csv", ".npz", ".mat", ".uff", ".unv")

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
        data = read_csv_data(path, inputs, outputs, fs)
    elif suffix in (".npz", ".mat"):
        data = read_array_data(path, inputs, outputs, fs)
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
