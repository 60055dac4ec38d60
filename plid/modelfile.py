"""State-space model files (.npz), per design.md.

Layout: arrays ``A, B, C, D``, ``dt`` (0 for a continuous model, the sampling interval [s]
for a discrete one), ``input_names``, ``output_names``, ``format_version`` and, when known,
``K`` (the one-step predictor gain: x[k+1|k] = A x[k|k-1] + B u[k] + K (y[k] - C x[k|k-1]
- D u[k])). A file may hold a second, continuous model beside a discrete one under the
names ``c_A, c_B, c_C, c_D`` (the ``plant`` command stores the continuous plant there);
``load_model(path, which="continuous")`` returns it. Any other arrays are kept as extras.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import warnings

import control
import numpy as np

from trussid.plid.errors import DataError
from trussid._util.files import atomic_path
from trussid.plid.stability import Stability, UnstableModelWarning, check_stability

FORMAT_VERSION = 1

_CORE = ("A", "B", "C", "D")
_RESERVED = {*_CORE, "K", "dt", "input_names", "output_names", "format_version",
             *(f"c_{k}" for k in _CORE)}


def _check_abcd(A, B, C, D, source: str, prefix: str = ""):
    A, B, C, D = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, B, C, D))
    n = A.shape[0]
    if A.ndim != 2 or A.shape != (n, n):
        raise DataError(f"{source}: array '{prefix}A' must be square, got shape {A.shape}")
    if B.ndim != 2 or B.shape[0] != n:
        raise DataError(f"{source}: array '{prefix}B' has shape {B.shape}, needs {n} rows "
                        f"to match '{prefix}A'")
    if C.ndim != 2 or C.shape[1] != n:
        raise DataError(f"{source}: array '{prefix}C' has shape {C.shape}, needs {n} columns "
                        f"to match '{prefix}A'")
    if D.ndim != 2 or D.shape != (C.shape[0], B.shape[1]):
        raise DataError(f"{source}: array '{prefix}D' has shape {D.shape}, needs "
                        f"{(C.shape[0], B.shape[1])} from '{prefix}C' and '{prefix}B'")
    for name, M in zip(_CORE, (A, B, C, D)):
        if not np.all(np.isfinite(M)):
            raise DataError(f"{source}: array '{prefix}{name}' has non-finite entries")
    return A, B, C, D


def _check_unique(input_names, output_names, source: str) -> None:
    # python-control merges repeated signal names into one signal, so refuse them here.
    for kind, names in (("input", input_names), ("output", output_names)):
        dup = sorted({s for s in names if list(names).count(s) > 1})
        if dup:
            raise DataError(f"{source}: {kind} name '{dup[0]}' is used more than once")


def _labels(sys, kind: str, letter: str) -> list[str]:
    """Channel names carried by a python-control system, or u1../y1.. for its defaults."""
    count = sys.ninputs if kind == "input" else sys.noutputs
    labels = list(getattr(sys, f"{kind}_labels", []) or [])
    if len(labels) != count or all(re.fullmatch(rf"{letter}\[\d+\]", s) for s in labels):
        return [f"{letter}{j + 1}" for j in range(count)]
    return [str(s) for s in labels]


def save_model(path, sys: control.StateSpace, K=None, input_names=None, output_names=None,
               continuous: control.StateSpace | None = None, extra: dict | None = None) -> Path:
    """Write a state-space model file atomically.

    Parameters
    ----------
    path : path-like
        Output ``.npz`` file.
    sys : control.StateSpace
        The model; ``sys.dt`` 0 (continuous) or the sampling interval [s].
    K : ndarray, shape (n, p), optional
        One-step predictor gain of a discrete model.
    input_names, output_names : sequence of str, optional
        Channel names (default: the system's signal labels, or ``u1..``, ``y1..`` when
        those are python-control's defaults ``u[0]..``).
    continuous : control.StateSpace, optional
        A continuous model stored beside ``sys`` as ``c_A .. c_D`` (same channels).
    extra : dict of str -> array, optional
        More arrays to store (names must not clash with the reserved ones).

    Examples
    --------
    >>> import control
    >>> import numpy as np
    >>> from trussid.plid import load_model, save_model
    >>> G = control.ss([[0.9, 0.1], [0.0, 0.8]], [[1.0], [0.5]], [[1.0, 0.0]], [[0.0]], 1e-3)
    >>> path = save_model("model.npz", G, input_names=["force"], output_names=["acc"])
    >>> again, meta = load_model(path)
    >>> np.array_equal(again.A, G.A), again.dt, meta.input_names, meta.output_names
    (True, 0.001, ['force'], ['acc'])
    """
    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise DataError(f"{path}: model files are .npz")
    dt = sys.dt
    if dt is True or dt is None:
        raise DataError("the model's sampling interval is unspecified (dt=True); give a number")
    A, B, C, D = _check_abcd(sys.A, sys.B, sys.C, sys.D, "model")
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    input_names = _labels(sys, "input", "u") if input_names is None else list(input_names)
    output_names = _labels(sys, "output", "y") if output_names is None else list(output_names)
    if len(input_names) != m:
        raise DataError(f"model: {len(input_names)} input names for {m} inputs")
    if len(output_names) != p:
        raise DataError(f"model: {len(output_names)} output names for {p} outputs")
    _check_unique(input_names, output_names, "model")
    arrays = dict(A=A, B=B, C=C, D=D, dt=np.float64(dt),
                  input_names=np.array(input_names, dtype=str),
                  output_names=np.array(output_names, dtype=str),
                  format_version=np.int64(FORMAT_VERSION))
    if K is not None:
        K = np.atleast_2d(np.asarray(K, dtype=float))
        if K.shape != (n, p):
            raise DataError(f"model: predictor gain K has shape {K.shape}, needs {(n, p)}")
        arrays["K"] = K
    if continuous is not None:
        if continuous.dt != 0:
            raise DataError("model: the 'continuous' model has dt != 0")
        cA, cB, cC, cD = _check_abcd(continuous.A, continuous.B, continuous.C, continuous.D,
                                     "continuous model")
        if cB.shape[1] != m or cC.shape[0] != p:
            raise DataError(f"model: the continuous model has {cB.shape[1]} inputs and "
                            f"{cC.shape[0]} outputs, the model {m} and {p}")
        arrays.update(c_A=cA, c_B=cB, c_C=cC, c_D=cD)
    for key, value in (extra or {}).items():
        if key in _RESERVED:
            raise DataError(f"model: extra array name '{key}' is reserved")
        arrays[key] = np.asarray(value)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, **arrays)
    # Writing an unstable model is allowed (a user may want to inspect it), but never silently.

    st = check_stability(sys)
    if st.unstable.size:
        warnings.warn(st.message(f"model {path}"), UnstableModelWarning, stacklevel=2)
    return path


def is_model_file(path) -> bool:
    """True if ``path`` is an ``.npz`` with the arrays of a model file (``A`` and ``dt``)."""
    path = Path(path)
    if path.suffix.lower() != ".npz" or not path.is_file():
        return False
    try:
        with np.load(path, allow_pickle=False) as z:
            return "A" in z.files and "dt" in z.files
    except Exception:  # a corrupt file is not a model file; load_model names the problem
        return False


@dataclass(frozen=True)
class ModelMeta:
    """What a model file holds beside the returned model (:func:`load_model`).

    Attributes
    ----------
    K : array (n, p) or None
        One-step predictor gain (None: none stored, or the continuous model was asked for).
    dt : float
        Sample time of the returned model [s] (0: continuous).
    input_names, output_names : list of str
        Channel names.
    format_version : int
        The file's format version (0: written before versions were recorded).
    has_continuous : bool
        Whether a continuous model can be read from the file (``which="continuous"``).
    extra : dict
        Every other array of the file, by name.
    stability : trussid.plid.stability.Stability
        Of the returned model; its ``message(...)`` is the one line to show a user (None
        when stable).
    """

    K: np.ndarray | None
    dt: float
    input_names: list
    output_names: list
    format_version: int
    has_continuous: bool
    extra: dict
    stability: Stability


def load_model(path, which: str = "auto") -> tuple[control.StateSpace, ModelMeta]:
    """Read a model file.

    Parameters
    ----------
    path : path-like
        The ``.npz`` model file.
    which : {"auto", "discrete", "continuous"}
        ``"auto"``: the file's main model (``A .. D``). ``"discrete"``: the main model, which
        must be discrete. ``"continuous"``: ``c_A .. c_D`` if present, else the main model if
        it is continuous.

    Returns
    -------
    sys : control.StateSpace
        With the channel names as its input/output labels.
    meta : ModelMeta
        What else the file holds, parsed once here.

    Examples
    --------
    See :func:`save_model`; a file that is not a model is named in the error:

    >>> from pathlib import Path
    >>> from trussid.plid import load_model
    >>> _ = Path("notes.npz").write_bytes(b"not a model")
    >>> load_model("notes.npz")
    Traceback (most recent call last):
    ...
    trussid.plid.errors.DataError: notes.npz: not a model file (cannot read it as .npz: ...)
    """
    path = Path(path)
    source = str(path)
    if which not in ("auto", "discrete", "continuous"):
        raise DataError(f"which must be 'auto', 'discrete' or 'continuous', not '{which}'")
    if not path.exists():
        raise DataError(f"no such model file: {path}")
    if path.is_dir():
        raise DataError(f"{path} is a directory, not a model file")
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception as exc:  # numpy raises several types for foreign/corrupt files
        raise DataError(f"{source}: not a model file (cannot read it as .npz: {exc})") from None
    for key in (*_CORE, "dt"):
        if key not in arrays:
            raise DataError(f"{source}: not a model file: missing array '{key}'")
    A, B, C, D = _check_abcd(*(arrays[k] for k in _CORE), source)
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    dt = float(np.asarray(arrays["dt"]).ravel()[0])
    if not (np.isfinite(dt) and dt >= 0):
        raise DataError(f"{source}: 'dt' must be 0 or a positive interval, got {dt}")
    in_names = [str(s) for s in np.atleast_1d(arrays.get("input_names",
                                                         [f"u{j + 1}" for j in range(m)]))]
    out_names = [str(s) for s in np.atleast_1d(arrays.get("output_names",
                                                          [f"y{j + 1}" for j in range(p)]))]
    if len(in_names) != m:
        raise DataError(f"{source}: {len(in_names)} input_names for {m} inputs (columns of B)")
    if len(out_names) != p:
        raise DataError(f"{source}: {len(out_names)} output_names for {p} outputs (rows of C)")
    _check_unique(in_names, out_names, source)
    K = arrays.get("K")
    if K is not None:
        K = np.asarray(K, dtype=float)
        if K.shape != (n, p):
            raise DataError(f"{source}: array 'K' has shape {K.shape}, needs {(n, p)}")
    has_c = "c_A" in arrays
    if has_c:
        for key in (f"c_{k}" for k in _CORE):
            if key not in arrays:
                raise DataError(f"{source}: continuous model incomplete: missing array '{key}'")
    version = int(np.asarray(arrays.get("format_version", 0)).ravel()[0])
    extra = {k: v for k, v in arrays.items() if k not in _RESERVED}
    if which == "discrete" and dt == 0:
        raise DataError(f"{source}: the model is continuous (dt = 0); a discrete one is needed "
                        "(make one with a sampling frequency, e.g. trussid plant --fs HZ)")
    if which == "continuous" and dt != 0:
        if not has_c:
            raise DataError(f"{source}: no continuous model in the file (no 'c_A' array)")
        cA, cB, cC, cD = _check_abcd(*(arrays[f"c_{k}"] for k in _CORE), source, "c_")
        if cB.shape[1] != m or cC.shape[0] != p:
            raise DataError(f"{source}: continuous model has {cB.shape[1]} inputs and "
                            f"{cC.shape[0]} outputs, the main model {m} and {p}")
        K, dt_out = None, 0.0
        sys = control.ss(cA, cB, cC, cD, inputs=in_names, outputs=out_names)
    else:
        dt_out = dt
        sys = control.ss(A, B, C, D, dt, inputs=in_names, outputs=out_names)
    return sys, ModelMeta(K, dt_out, in_names, out_names, version, has_c or dt == 0, extra,
                          check_stability(sys))


__all__ = ["ModelMeta", "save_model", "load_model", "is_model_file", "FORMAT_VERSION"]
