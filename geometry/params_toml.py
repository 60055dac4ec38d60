"""Testbed parameter files in TOML: one table per section, SI values, keys = field names.

A file may be partial: missing sections and keys take their defaults. Example::

    [struts]
    length = 0.9144                 # m
    walls = [0.0007, 0.0009, 0.0011, 0.0012, 0.0015, 0.0017]

    [base]
    support = "clamped"

Unknown keys and wrong types are errors naming the key (with the closest valid name).
:func:`save_testbed` writes every parameter, each preceded by a comment with its meaning,
source and unit.
"""

from __future__ import annotations

import dataclasses
import difflib
import os
import tomllib

import tomli_w

from trussid.geometry.errors import ParameterError
from trussid.geometry.spec import SECTIONS, Testbed
from trussid._util.files import atomic_path

_HEADER = """\
# trussid testbed parameters. SI units throughout (m, kg, s, Pa, N, V, F, Hz, rad).
# Any key may be left out: it then takes the default of the Vallone (1997) reconstruction.
"""


def _unknown(key: str, section: str | None, where: str) -> ParameterError:
    """Error for an unknown key, suggesting the closest valid name (same section first)."""
    if section is None:
        candidates = {name: name for name in SECTIONS}
        probe = key
    else:
        candidates = {f.name: f"{section}.{f.name}" for f in dataclasses.fields(SECTIONS[section])}
        probe = key.split(".", 1)[1]
    close = difflib.get_close_matches(probe, list(candidates), n=1, cutoff=0.6)
    if not close and section is not None:  # maybe a parameter put in the wrong section
        others = {f.name: f"{name}.{f.name}" for name, cls in SECTIONS.items() if name != section
                  for f in dataclasses.fields(cls)}
        close = difflib.get_close_matches(probe, list(others), n=1, cutoff=0.8)
        candidates = others
    hint = f"; did you mean {candidates[close[0]]!r}?" if close else ""
    return ParameterError(f"{where}unknown parameter {key!r}{hint}")


def testbed_to_dict(tb: Testbed) -> dict:
    """The parameters as ``{section: {field: value}}`` with plain Python values."""
    out = {}
    for section in SECTIONS:
        values = {}
        for f in dataclasses.fields(getattr(tb, section)):
            value = getattr(getattr(tb, section), f.name)
            values[f.name] = list(value) if isinstance(value, tuple) else value
        out[section] = values
    return out


def testbed_from_dict(data: dict, source: str = "") -> Testbed:
    """A :class:`Testbed` from ``{section: {field: value}}``; missing entries take defaults.

    Parameters
    ----------
    data : dict
        Possibly partial parameters.
    source : str
        Prefix for error messages (e.g. the file name).

    Raises
    ------
    ParameterError
        Naming the unknown key (with a suggestion) or the invalid parameter.
    """
    where = f"{source}: " if source else ""
    sections = {}
    for section, values in data.items():
        if section not in SECTIONS:
            raise _unknown(section, None, where)
        if not isinstance(values, dict):
            raise ParameterError(f"{where}{section} must be a table ([{section}]), "
                                 f"got {type(values).__name__} {values!r}")
        cls = SECTIONS[section]
        fields = {f.name for f in dataclasses.fields(cls)}
        for key in values:
            if key not in fields:
                raise _unknown(f"{section}.{key}", section, where)
        try:
            sections[section] = cls(**values)
        except ParameterError as exc:
            raise ParameterError(f"{where}{exc}") from None
    try:
        return Testbed(**sections)
    except ParameterError as exc:
        raise ParameterError(f"{where}{exc}") from None


def load_testbed(path: str | os.PathLike) -> Testbed:
    """Read a testbed parameter file (TOML).

    Raises
    ------
    ParameterError
        If the file is missing or not TOML, or has an unknown key or an invalid value; the
        message names the file and the key.
    """
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise ParameterError(f"{os.fspath(path)}: no such parameter file") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError(f"{os.fspath(path)}: not valid TOML: {exc}") from None
    return testbed_from_dict(data, source=os.fspath(path))


def dumps_testbed(tb: Testbed) -> str:
    """The TOML text of ``tb``: every parameter, each after a comment with its doc and unit."""
    parts = [_HEADER]
    for section in SECTIONS:
        params = getattr(tb, section)
        parts.append(f"\n[{section}]\n")
        for f in dataclasses.fields(params):
            value = getattr(params, f.name)
            value = list(value) if isinstance(value, tuple) else value
            parts.append(f"# {f.metadata['doc']} [{f.metadata['unit']}]\n")
            parts.append(tomli_w.dumps({f.name: value}))
    return "".join(parts)


def save_testbed(tb: Testbed, path: str | os.PathLike) -> None:
    """Write ``tb`` as a complete, commented TOML parameter file (atomically)."""
    text = dumps_testbed(tb)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
