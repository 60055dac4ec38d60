"""Input checks shared by the identification modules: one of each, one message style."""

from __future__ import annotations

import numpy as np

from trussid.plid.errors import DataError

__all__ = ["as_2d", "check_time"]


def as_2d(a, name: str, n_samples: int | None = None, finite: bool = False) -> np.ndarray:
    """``a`` as a float (samples x channels) array; a 1-D array is one channel.

    Parameters
    ----------
    a : array-like
    name : str
        Named in the error (``"u"``, ``"y"``...).
    n_samples : int, optional
        Required number of rows (e.g. the length of a time vector).
    finite : bool
        Refuse NaN and inf, naming the first sample and column.
    """
    a = np.asarray(a, dtype=float)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise DataError(f"{name} must be a 1-D or 2-D array (samples x channels), got shape "
                        f"{a.shape}")
    if n_samples is not None and a.shape[0] != n_samples:
        raise DataError(f"{name} must have {n_samples} samples (rows) like the time vector, "
                        f"got shape {a.shape}")
    if finite:
        bad = np.argwhere(~np.isfinite(a))
        if bad.size:
            raise DataError(f"{name} at sample {bad[0][0]} (column {bad[0][1]}) is not finite")
    return a


def check_time(t) -> float:
    """The sampling interval [s] of a uniformly sampled, increasing time vector ``t`` [s]."""
    t = np.asarray(t, dtype=float)
    if t.ndim != 1:
        raise DataError(f"time vector must be 1-D, got shape {t.shape}")
    if t.size < 2:
        raise DataError(f"data too short: {t.size} sample(s)")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise DataError(f"time at sample {bad[0]} is not finite")
    d = np.diff(t)
    dt = float(np.median(d))
    if dt <= 0:
        raise DataError("time must increase")
    off = np.flatnonzero(np.abs(d - dt) > 1e-2 * dt)  # times printed with few decimals jitter
    if off.size:
        raise DataError(f"time is not uniformly sampled: step before sample {off[0] + 1} is "
                        f"{d[off[0]]:g} s, the sampling interval is {dt:g} s")
    return dt
