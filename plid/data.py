"""The data types of identification and their validation: the ground of :mod:`trussid.plid`.

- :class:`IOData`: sampled input/output data of one experiment (what the file readers return
  and the experiments produce), :func:`validate`, :func:`check_enough_samples`,
  :func:`with_channels`.
- :class:`ModeShapes`: a set of modes (frequencies, damping, shapes at some DOFs), what the
  modal analysis returns and UFF 55 records hold.

Imports nothing of :mod:`trussid.plid` but its errors, so that every other module (readers,
experiments, estimators, modal analysis) can stand on it.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass, field, replace

import numpy as np

from trussid.plid.errors import DataError

__all__ = ["IOData", "validate", "check_enough_samples", "with_channels", "select_channels", "unknown_name",
           "ModeShapes"]


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
    units : dict of str to str
        Unit of each channel as the file gave it (e.g. ``{"y1": "V"}``); empty if unknown.
    notes : list of str
        What the reader decided that the user may want to know (e.g. the time unit).
    """

    u: np.ndarray
    y: np.ndarray
    fs: float
    input_names: list[str] = field(default_factory=list)
    output_names: list[str] = field(default_factory=list)
    t: np.ndarray | None = None
    y_clean: np.ndarray | None = None
    units: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    def __post_init__(self):
        if self.fs is not None:  # a plain float (read from a file it is a numpy scalar)
            self.fs = float(self.fs)
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


def unknown_name(name: str, known: list[str], source: str, what: str = "column") -> DataError:
    """The error for a name not among ``known``, with the closest one as a hint."""
    close = difflib.get_close_matches(name, known, n=1)
    hint = f"; did you mean '{close[0]}'?" if close else f"; {what}s are {', '.join(known)}"
    return DataError(f"{source}: unknown {what} '{name}'{hint}")


def select_channels(names: list[str], arr: np.ndarray, wanted, kind: str, source: str):
    """Pick channels ``wanted`` (names) out of ``arr``; ``None`` keeps all."""
    if wanted is None:
        return list(names), arr
    idx = []
    for w in wanted:
        if w not in names:
            raise unknown_name(w, list(names), source)
        idx.append(names.index(w))
    if not idx:
        raise DataError(f"{source}: empty list of {kind}s")
    return [names[i] for i in idx], arr[:, idx]


def with_channels(data: IOData, inputs=None, outputs=None) -> IOData:
    """A copy of ``data`` restricted to the named input/output channels (in that order)."""
    in_names, u = select_channels(data.input_names, data.u, inputs, "input", "data")
    out_names, y = select_channels(data.output_names, data.y, outputs, "output", "data")
    y_clean = None
    if data.y_clean is not None:
        _, y_clean = select_channels(data.output_names, data.y_clean, outputs, "output", "data")
    return replace(data, u=u, y=y, input_names=in_names, output_names=out_names,
                   y_clean=y_clean)


# --------------------------------------------------------------------------- modes


@dataclass
class ModeShapes:
    """A set of modes: frequencies, damping and shapes at some degrees of freedom.

    Attributes
    ----------
    frequencies_hz : ndarray, shape (n_modes,)
        Undamped natural frequencies [Hz].
    damping : ndarray, shape (n_modes,)
        Damping ratios [-] (1 for a real pole).
    shapes : ndarray, shape (n_dof, n_modes)
        Mode shapes, one column per mode (complex for identified modes).
    labels : list of str, optional
        Name of each DOF (e.g. the model's output names).
    dofs : list of (int, int), optional
        (node id, direction 1-6) of each DOF, for UFF 55 export and FE comparison.
    participation : ndarray, shape (n_modes, n_inputs), optional
        Modal participation factors of the inputs (see the module docstring).
    input_names : list of str, optional
    poles : ndarray, shape (n_modes,), optional
        Continuous-time poles [rad/s], one per mode (positive imaginary part).
    """

    frequencies_hz: np.ndarray
    damping: np.ndarray
    shapes: np.ndarray
    labels: list | None = None
    dofs: list | None = None
    participation: np.ndarray | None = None
    input_names: list | None = None
    poles: np.ndarray | None = None

    @property
    def n_modes(self) -> int:
        return int(np.asarray(self.frequencies_hz).size)

    def select(self, index) -> "ModeShapes":
        """The modes ``index`` (indices or a boolean mask), in that order."""
        idx = np.arange(self.n_modes)[index]
        pick = (lambda a: None if a is None else np.asarray(a)[idx])
        return ModeShapes(
            frequencies_hz=np.asarray(self.frequencies_hz)[idx],
            damping=np.asarray(self.damping)[idx], shapes=np.asarray(self.shapes)[:, idx],
            labels=self.labels, dofs=self.dofs, participation=pick(self.participation),
            input_names=self.input_names, poles=pick(self.poles))
