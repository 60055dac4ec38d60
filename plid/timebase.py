"""The time base of a data file: the sampling frequency from a time column, and the
time column's unit (read from its header, or judged from a given sample rate).

The rules are those of :mod:`trussid.plid.datafile` (its module docstring); the CSV and
NPZ/MAT readers (:mod:`trussid.plid.csvfile`, :mod:`trussid.plid.arrayfile`) share them.
"""

from __future__ import annotations

import numpy as np

from trussid.plid.errors import DataError

__all__ = ["fs_from_time", "time_unit", "TIME_JITTER", "FS_PLAUSIBLE_MIN", "TIME_NAMES",
           "TIME_UNITS"]

#: Relative jitter of the time column tolerated before it is called non-uniform (times
#: printed with few decimals, e.g. 1/3 ms, are not exactly uniform).
TIME_JITTER = 1e-2

#: Lowest sampling frequency [Hz] a time column without a unit may imply: below it the
#: column is more likely in milliseconds than a structural test this slow.
FS_PLAUSIBLE_MIN = 10.0

#: Names of a time column (compared in lower case, without the unit).
TIME_NAMES = ("t", "time", "zeit", "temps")

#: Time units [s per unit] accepted in a header.
TIME_UNITS = {"s": 1.0, "sec": 1.0, "secs": 1.0, "second": 1.0, "seconds": 1.0,
              "ms": 1e-3, "msec": 1e-3, "millisecond": 1e-3, "milliseconds": 1e-3,
              "us": 1e-6, "\u00b5s": 1e-6, "\u03bcs": 1e-6, "usec": 1e-6,
              "microsecond": 1e-6, "microseconds": 1e-6, "ns": 1e-9, "min": 60.0}

_UNIT_NAMES = {1.0: "seconds", 1e-3: "milliseconds", 1e-6: "microseconds"}


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


def time_unit(raw_t, unit: str | None, fs_given, source: str, name: str):
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
