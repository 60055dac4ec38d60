"""Actuators and sensors for any frame model, from a small TOML file, and its plant.

The file (``IO.toml``) lists inputs and outputs by node, element and direction, in the
model's units (SI for the examples)::

    [plant]                     # optional defaults, overridden by the command line
    damping = 0.02              # modal damping ratio, every mode
    modes = 20                  # modes kept
    fs = 1000.0                 # sample rate [Hz] of the discrete (ZOH) plant

    [[actuator]]                # a point force (or moment) at a node
    name = "shaker"
    type = "force"              # "force" [N per input unit] or "moment" [N m per unit]
    node = 15
    direction = [0, 0, 1]       # global axes (normalised)
    gain = 1.0                  # load per input unit (default 1)

    [[actuator]]                # PZT wafers bonded over beam elements (fem.actuators)
    name = "pzt1"
    type = "strain"
    elements = [1, 2]
    offset = 0.0135             # beam axis to wafer mid-plane [m]
    face_axis = "y"             # local axis normal to the bonded faces
    arrangement = "bending"     # or "extension"
    n_wafers = 2
    wafer = {width = 0.02, length = 0.05, thickness = 0.0005, youngs_modulus = 6.3e10,
             d31 = -1.9e-10}

    [[sensor]]                  # a single-axis point sensor (fem.sensors)
    name = "acc1"
    node = 10
    direction = [1, 0, 0]
    quantity = "acceleration"   # or "displacement", "velocity"
    sensitivity = 1.0           # output per unit of the quantity (default 1: SI out)

Every mistake names the entry (``actuator 2 'pzt1'``) and the key.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import control
import numpy as np

from trussid.fem.errors import ModelError
from trussid.fem.actuators import strain_actuator_loads, Wafer
from trussid.fem.assembly import assemble
from trussid.fem.modal import solve_modes
from trussid.fem.plant import modal_plant
from trussid.fem.sensors import Sensor, sensor_matrix

__all__ = ["IOSpec", "PointLoad", "StrainActuator", "read_io", "io_loads", "io_plant"]

_PLANT_KEYS = {"damping", "modes", "fs"}
_FORCE_KEYS = {"name", "type", "node", "direction", "gain"}
_STRAIN_KEYS = {"name", "type", "elements", "offset", "face_axis", "arrangement", "n_wafers",
                "wafer"}
_WAFER_KEYS = {"width", "length", "thickness", "youngs_modulus", "d31", "relative_permittivity"}
_SENSOR_KEYS = {"name", "node", "direction", "quantity", "sensitivity"}


@dataclass(frozen=True)
class PointLoad:
    """A force or moment of ``gain`` per input unit at ``node`` along ``direction``."""

    name: str
    node: int
    direction: tuple
    kind: str = "force"
    gain: float = 1.0


@dataclass(frozen=True)
class StrainActuator:
    """Wafers over beam ``elements`` (arguments of :func:`fem.strain_actuator_loads`)."""

    name: str
    elements: tuple
    wafer: object
    offset: float
    face_axis: str = "y"
    arrangement: str = "extension"
    n_wafers: int = 2


@dataclass
class IOSpec:
    """Inputs, outputs and plant defaults read by :func:`read_io`."""

    actuators: list = field(default_factory=list)
    sensors: list = field(default_factory=list)
    damping: float | None = None
    modes: int | None = None
    fs: float | None = None
    source: str = ""


def _unknown(entry: dict, allowed: set, where: str) -> None:
    extra = sorted(set(entry) - allowed)
    if extra:
        raise ModelError(f"{where}: unknown key '{extra[0]}' (allowed: {', '.join(sorted(allowed))})")


def _number(entry, key, where, positive=False, default=None, integer=False):
    if key not in entry:
        if default is None:
            raise ModelError(f"{where}: missing '{key}'")
        return default
    v = entry[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise ModelError(f"{where}: '{key}' must be a number, got {v!r}")
    if integer and int(v) != v:
        raise ModelError(f"{where}: '{key}' must be a whole number, got {v!r}")
    if positive and not v > 0:
        raise ModelError(f"{where}: '{key}' must be positive, got {v!r}")
    return int(v) if integer else float(v)


def _vector(entry, key, where):
    v = entry.get(key)
    if v is None:
        raise ModelError(f"{where}: missing '{key}' (a 3-vector, global axes)")
    arr = np.asarray(v, dtype=object)
    if arr.shape != (3,) or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                    for x in v):
        raise ModelError(f"{where}: '{key}' must be three numbers, got {v!r}")
    d = np.asarray(v, dtype=float)
    if not (np.isfinite(d).all() and np.linalg.norm(d) > 0):
        raise ModelError(f"{where}: '{key}' must be a non-zero finite 3-vector, got {v!r}")
    return tuple(float(x) for x in d / np.linalg.norm(d))  # plain floats: readable reprs


def read_io(path) -> IOSpec:
    """Read an actuator/sensor file (see the module docstring).

    Raises
    ------
    ModelError
        Missing file, bad TOML, unknown keys, bad values, no actuator or no sensor; the
        message names the entry and key.

    Examples
    --------
    >>> from pathlib import Path
    >>> from trussid.fem import read_io
    >>> _ = Path("io.toml").write_text('''
    ... [[actuator]]
    ... name = "shaker"
    ... type = "force"
    ... node = 15
    ... direction = [0, 0, 2]
    ... [[sensor]]
    ... name = "acc1"
    ... node = 10
    ... direction = [1, 0, 0]
    ... ''')
    >>> spec = read_io("io.toml")
    >>> spec.actuators[0].direction, spec.sensors[0].quantity
    ((0.0, 0.0, 1.0), 'acceleration')
    """
    # Long: one validation step per key of the file format, each naming entry and key; split
    # up, the entry/key context would have to be passed around for every check.

    path = Path(path)
    if not path.is_file():
        raise ModelError(f"{path}: no such actuator/sensor file")
    try:
        doc = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ModelError(f"{path}: not valid TOML: {exc}") from None
    _unknown(doc, {"plant", "actuator", "sensor"}, str(path))
    spec = IOSpec(source=str(path))
    plant = doc.get("plant", {})
    _unknown(plant, _PLANT_KEYS, f"{path}: [plant]")
    if "damping" in plant:
        spec.damping = _number(plant, "damping", f"{path}: [plant]")
    if "modes" in plant:
        spec.modes = _number(plant, "modes", f"{path}: [plant]", positive=True, integer=True)
    if "fs" in plant:
        spec.fs = _number(plant, "fs", f"{path}: [plant]", positive=True)
    names = set()
    for k, a in enumerate(doc.get("actuator", []), 1):
        where = f"{path}: actuator {k}" + (f" '{a['name']}'" if "name" in a else "")
        kind = a.get("type", "force")
        name = str(a.get("name", f"u{k}"))
        if kind in ("force", "moment"):
            _unknown(a, _FORCE_KEYS, where)
            act = PointLoad(name, _number(a, "node", where, integer=True),
                            _vector(a, "direction", where), kind,
                            _number(a, "gain", where, default=1.0))
        elif kind == "strain":
            _unknown(a, _STRAIN_KEYS, where)
            w = a.get("wafer")
            if not isinstance(w, dict):
                raise ModelError(f"{where}: missing 'wafer' (a table with "
                                 f"{', '.join(sorted(_WAFER_KEYS - {'relative_permittivity'}))})")
            _unknown(w, _WAFER_KEYS, f"{where}: wafer")
            missing = sorted(_WAFER_KEYS - {"relative_permittivity"} - set(w))
            if missing:
                raise ModelError(f"{where}: wafer: missing '{missing[0]}'")
            try:
                wafer = Wafer(**{key: float(v) for key, v in w.items()})
            except (TypeError, ValueError) as exc:
                raise ModelError(f"{where}: wafer: {exc}") from None
            els = a.get("elements")
            if not isinstance(els, list) or not els or not all(
                    isinstance(e, int) and not isinstance(e, bool) for e in els):
                raise ModelError(f"{where}: 'elements' must be a list of element ids, got {els!r}")
            act = StrainActuator(name, tuple(els), wafer,
                                 _number(a, "offset", where, positive=True),
                                 str(a.get("face_axis", "y")),
                                 str(a.get("arrangement", "extension")),
                                 _number(a, "n_wafers", where, positive=True, default=2,
                                         integer=True))
        else:
            raise ModelError(f"{where}: type must be 'force', 'moment' or 'strain', got {kind!r}")
        if name in names:
            raise ModelError(f"{where}: the name '{name}' is used twice")
        names.add(name)
        spec.actuators.append(act)
    for k, s in enumerate(doc.get("sensor", []), 1):
        where = f"{path}: sensor {k}" + (f" '{s['name']}'" if "name" in s else "")
        _unknown(s, _SENSOR_KEYS, where)
        name = str(s.get("name", f"y{k}"))
        if name in names:
            raise ModelError(f"{where}: the name '{name}' is used twice")
        names.add(name)
        try:
            spec.sensors.append(Sensor(node=_number(s, "node", where, integer=True),
                                       direction=_vector(s, "direction", where),
                                       quantity=s.get("quantity", "acceleration"),
                                       sensitivity=_number(s, "sensitivity", where, default=1.0),
                                       name=name))
        except ModelError as exc:  # Sensor's message starts with its own label: keep the rest
            raise ModelError(f"{where}: {str(exc).split(': ', 1)[-1]}") from None
    if not spec.actuators:
        raise ModelError(f"{path}: no [[actuator]] entries (a plant needs at least one input)")
    if not spec.sensors:
        raise ModelError(f"{path}: no [[sensor]] entries (a plant needs at least one output)")
    return spec


def io_loads(model, spec: IOSpec) -> np.ndarray:
    """Nodal loads per input unit, one column per actuator, (6 n_nodes, m), model order."""
    F = np.zeros((6 * model.n_nodes, len(spec.actuators)))
    for j, a in enumerate(spec.actuators):
        where = f"{spec.source}: actuator {j + 1} '{a.name}'"
        try:
            if isinstance(a, PointLoad):
                i = int(model.index_of([a.node], what=where)[0])
                off = 0 if a.kind == "force" else 3
                F[6 * i + off:6 * i + off + 3, j] = a.gain * np.asarray(a.direction)
            else:
                F[:, j] = strain_actuator_loads(model, list(a.elements), a.wafer, a.offset,
                                                face_axis=a.face_axis,
                                                arrangement=a.arrangement,
                                                n_wafers=a.n_wafers)
        except ModelError as exc:
            msg = str(exc)
            raise ModelError(msg if msg.startswith(spec.source) else f"{where}: {msg}") from None
    return F


def _why_inert(model, node: int) -> str:
    """Why a node's DOFs are not in the solved system (for the messages below)."""
    i = int(model.index_of([node], what="node")[0])
    if model.has_supports and model.fixed_mask()[i].all():
        return f"node {node} is clamped (all six DOFs supported)"
    if model.has_supports and model.fixed_mask()[i].any():
        return f"node {node} is supported in that direction"
    return f"node {node} has no element, mass or spring acting on it in that direction"


def _check_channels_act(model, system, spec: IOSpec, loads: np.ndarray) -> None:
    """Refuse an actuator that moves no free DOF, or a sensor that reads none: its channel
    of the plant would be identically zero (a load on a clamped node, a sensor on a node
    without elements), which is never what was meant."""
    T = system.T
    acting = np.abs(T.T @ loads).max(axis=0) if loads.size else np.zeros(0)
    for j, a in enumerate(spec.actuators):
        if not acting[j] > 0:
            where = f"{spec.source}: actuator {j + 1} '{a.name}'"
            why = (_why_inert(model, a.node) if isinstance(a, PointLoad) else
                   f"its elements {list(a.elements)} have both ends supported")
            raise ModelError(f"{where}: the input moves no free DOF ({why}): its channel "
                             f"would be identically zero")
    S = sensor_matrix(model.node_ids, list(spec.sensors))
    reading = np.abs(T.T @ S.T).max(axis=0) if S.size else np.zeros(0)
    for r, s in enumerate(spec.sensors):
        if not reading[r] > 0:
            raise ModelError(f"{spec.source}: sensor {r + 1} '{s.name}': it reads no free DOF "
                             f"({_why_inert(model, s.node)}): its output would be "
                             f"identically zero")


def io_plant(model, spec: IOSpec, *, n_modes: int | None = None, damping: float | None = None,
             fs: float | None = None, autospc: bool = False):
    """Continuous plant (and its ZOH equivalent at ``fs``) of ``model`` with ``spec``'s
    actuators and sensors, by modal superposition (:func:`fem.plant.modal_plant`).

    Parameters
    ----------
    model : fem.Model
    spec : IOSpec
    n_modes, damping, fs : optional
        Override the file's ``[plant]`` values. Defaults: every mode below the Nyquist
        frequency when ``fs`` is known, else 20; damping 0.02; no discrete plant.
    autospc : bool
        As NASTRAN's AUTOSPC (decks that ask for it).

    Returns
    -------
    continuous : control.StateSpace
    discrete : control.StateSpace or None
    modes : fem.modal.Modes
        The modes solved (the plant keeps the first ``n_kept``).
    n_kept : int

    Examples
    --------
    A shaker and an accelerometer at the tip of a steel cantilever, from an IO file: every mode
    below the 500 Hz Nyquist frequency is kept (8), the discrete plant is the ZOH at 1 kHz.

    >>> import numpy as np
    >>> from pathlib import Path
    >>> from trussid.fem import STEEL, Model, Section, io_plant, read_io
    >>> m = Model()
    >>> m.add_nodes(np.arange(1, 12), np.c_[np.linspace(0, 1, 11), np.zeros((11, 2))])
    >>> m.add_beams(np.arange(1, 11), np.c_[np.arange(1, 11), np.arange(2, 12)],
    ...             Section.rectangle(0.02, 0.01), STEEL, orient=[0, 0, 1])
    >>> m.fix(1)
    >>> _ = Path("io.toml").write_text('''
    ... [plant]
    ... damping = 0.01
    ... fs = 1000.0
    ... [[actuator]]
    ... name = "shaker"
    ... type = "force"
    ... node = 11
    ... direction = [0, 1, 0]
    ... [[sensor]]
    ... name = "tip_acc"
    ... node = 11
    ... direction = [0, 1, 0]
    ... quantity = "acceleration"
    ... ''')
    >>> continuous, discrete, modes, n_kept = io_plant(m, read_io("io.toml"))
    >>> n_kept, discrete.dt, discrete.input_labels, discrete.output_labels
    (8, 0.001, ['shaker'], ['tip_acc'])
    >>> print(np.round(modes.frequencies_hz[:n_kept], 1))
    [  8.2  16.3  51.1 102.2 143.1 280.6 286.2 464.7]
    """
    damping = spec.damping if damping is None else damping
    damping = 0.02 if damping is None else float(damping)
    if not 0 <= damping < 1:
        raise ModelError(f"damping must be in [0, 1), got {damping}")
    fs = spec.fs if fs is None else fs
    n_req = spec.modes if n_modes is None else n_modes
    system = assemble(model, autospc=autospc)
    known = set(np.asarray(model.node_ids).tolist())
    for s in spec.sensors:
        if int(s.node) not in known:
            raise ModelError(f"{spec.source}: sensor '{s.name}': unknown node {s.node}")
    loads = io_loads(model, spec)
    _check_channels_act(model, system, spec, loads)
    n_solve = n_req or 20
    modes = solve_modes(system, n_modes=n_solve)
    f = np.asarray(modes.frequencies_hz)
    if fs is not None and n_req is None:
        # every mode below Nyquist: solve more until one lies above it (or none remain)
        while f.size == n_solve and f[-1] < fs / 2 and n_solve < system.n_dof:
            n_solve = min(4 * n_solve, system.n_dof)
            modes = solve_modes(system, n_modes=n_solve)
            f = np.asarray(modes.frequencies_hz)
        n = int(np.sum(f < fs / 2))
        if n == 0:
            raise ModelError(f"no mode below the Nyquist frequency ({fs / 2:g} Hz); the "
                             f"lowest is {f[0]:.4g} Hz: raise --fs")
    else:
        n = min(n_req or n_solve, f.size)
    if fs is not None and f[n - 1] >= fs / 2:
        raise ModelError(f"sample rate {fs:g} Hz is below twice the highest kept mode "
                         f"({f[n - 1]:.1f} Hz): raise --fs or keep fewer --modes")
    sc = modal_plant(modes, loads, spec.sensors, damping, n_modes=n,
                     input_names=[a.name for a in spec.actuators])
    sd = control.c2d(sc, 1.0 / fs, "zoh") if fs is not None else None
    return sc, sd, modes, n
