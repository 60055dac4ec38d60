"""Model files out to the controls toolchain: MATLAB ``.mat`` and python-control code.

Two targets, chosen for what a controls engineer does next:

- MATLAB/Octave: a ``.mat`` file (``scipy.io.savemat``, format 5) with ``A, B, C, D, Ts``
  (``Ts`` = 0 for a continuous model, as MATLAB's ``ss`` takes it), ``K`` when the file has
  a predictor gain, ``InputName`` and ``OutputName`` as cell arrays of char, and for a
  plant file the continuous model as ``Ac, Bc, Cc, Dc``. One line makes the ``ss`` object::

      s = load('plant.mat'); G = ss(s.A, s.B, s.C, s.D, s.Ts, 'InputName', s.InputName, 'OutputName', s.OutputName);

- python-control: a small Python source file that builds ``control.ss(...)`` with the
  channel names (and ``K``) from literal arrays. Chosen over a pickle: it needs only numpy
  and python-control (not trussid), is safe to load (a pickle runs arbitrary code and breaks
  across python-control versions), and can be read and diffed. Floats are written with
  ``repr``, which round-trips every double exactly.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.io

from trussid._util.files import atomic_path
from trussid.plid.errors import DataError

__all__ = ["write_mat", "python_code", "write_python", "MATLAB_LOAD"]

#: The MATLAB/Octave line that turns an exported ``.mat`` into an ``ss`` object.
MATLAB_LOAD = ("s = load('{name}'); G = ss(s.A, s.B, s.C, s.D, s.Ts, 'InputName', s.InputName, "
               "'OutputName', s.OutputName);")


def _cell(names) -> np.ndarray:
    """A 1 x n cell array of char for savemat (an object array of str)."""
    cell = np.empty((1, len(names)), dtype=object)
    for j, s in enumerate(names):
        cell[0, j] = str(s)
    return cell


def write_mat(path, sys, K=None, continuous=None, input_names=None, output_names=None) -> Path:
    """Write a state-space model as a MATLAB ``.mat`` file (atomically).

    Parameters
    ----------
    path : path-like
        Output ``.mat`` file.
    sys : control.StateSpace
        The model (``dt`` 0 or the sampling interval [s]).
    K : ndarray (n, p), optional
        One-step predictor gain, stored as ``K``.
    continuous : control.StateSpace, optional
        A continuous model stored beside ``sys`` as ``Ac, Bc, Cc, Dc``.
    input_names, output_names : sequence of str, optional
        Default: the system's labels.
    """
    path = Path(path)
    if path.suffix.lower() != ".mat":
        raise DataError(f"{path}: a MATLAB file must end in .mat")
    ins = list(input_names) if input_names is not None else list(sys.input_labels)
    outs = list(output_names) if output_names is not None else list(sys.output_labels)
    arrays = {k: np.asarray(getattr(sys, k), dtype=float) for k in "ABCD"}
    arrays["Ts"] = float(0.0 if sys.dt in (0, None) else sys.dt)
    arrays["InputName"] = _cell(ins)
    arrays["OutputName"] = _cell(outs)
    if K is not None:
        arrays["K"] = np.asarray(K, dtype=float)
    if continuous is not None:
        arrays.update({f"{k}c": np.asarray(getattr(continuous, k), dtype=float) for k in "ABCD"})
    with atomic_path(path) as tmp:
        scipy.io.savemat(tmp, arrays, format="5", do_compression=True, oned_as="column")
    return path


def _array(M) -> str:
    M = np.atleast_2d(np.asarray(M, dtype=float))
    rows = ",\n    ".join("[" + ", ".join(repr(float(v)) for v in row) + "]" for row in M)
    return f"np.array([\n    {rows}\n], dtype=float).reshape({M.shape[0]}, {M.shape[1]})"


def python_code(sys, K=None, input_names=None, output_names=None, name: str = "model",
                source: str | None = None) -> str:
    """Python source that builds ``sys`` as a ``control.StateSpace`` with its channel names.

    The code defines ``A, B, C, D, dt``, ``K`` (or None) and ``{name} = control.ss(...)``;
    ``exec`` it, ``import`` it, or copy it into a script.
    """
    ins = list(input_names) if input_names is not None else list(sys.input_labels)
    outs = list(output_names) if output_names is not None else list(sys.output_labels)
    dt = 0.0 if sys.dt in (0, None) else float(sys.dt)
    head = f"from {source}" if source else "exported by trussid"
    kind = ("continuous" if dt == 0 else
            f"discrete, sampling interval {dt!r} s ({1 / dt:g} Hz)")
    lines = [
        f'"""State-space model {head}: {sys.nstates} states, {sys.ninputs} input(s), '
        f'{sys.noutputs} output(s), {kind}.',
        "",
        "Needs numpy and python-control only. Gives " + name + " (control.StateSpace, channels",
        "named) and K (one-step predictor gain, or None).",
        '"""',
        "",
        "import control",
        "import numpy as np",
        "",
        f"A = {_array(sys.A)}",
        f"B = {_array(sys.B)}",
        f"C = {_array(sys.C)}",
        f"D = {_array(sys.D)}",
        f"dt = {dt!r}  # [s]; 0: continuous",
        f"K = {_array(K) if K is not None else 'None'}",
        f"input_names = {ins!r}",
        f"output_names = {outs!r}",
        "",
        f"{name} = control.ss(A, B, C, D, dt, inputs=input_names, outputs=output_names)",
        "",
    ]
    return "\n".join(lines)


def write_python(path, sys, K=None, input_names=None, output_names=None,
                 source: str | None = None) -> Path:
    """Write :func:`python_code` to ``path`` (a ``.py`` file, atomically)."""
    path = Path(path)
    if path.suffix.lower() != ".py":
        raise DataError(f"{path}: python-control code is written to a .py file")
    code = python_code(sys, K, input_names, output_names, source=source)
    with atomic_path(path) as tmp:
        tmp.write_text(code)
    return path
