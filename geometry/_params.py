"""Validated parameter sections: the field helper and checks shared by the testbed spec
(:mod:`trussid.geometry.spec`) and the lab spec (:mod:`trussid.geometry.lab`)."""

from __future__ import annotations

import dataclasses
import math
import numbers
from dataclasses import field
from typing import Any, ClassVar

from trussid.geometry.errors import ParameterError


def param(default: Any, unit: str, doc: str, check: str = "positive", kind: type = float):
    """A parameter field: its unit, one-line documentation, validity check and type.

    ``check`` is one of ``positive`` (finite, > 0), ``positive_or_inf`` (> 0, inf allowed),
    ``real`` (finite), ``fraction`` (in [0, 1)), ``poisson`` (in (-1, 0.5)), ``count``
    (integer >= 1), ``choice:<a>|<b>`` or ``walls`` (validated by :class:`Testbed`).
    """
    return field(default=default, metadata={"unit": unit, "doc": doc, "check": check, "kind": kind})


def fail(path: str, message: str) -> None:
    """Raise :class:`ParameterError` for the parameter at ``path`` (``section.field``)."""
    raise ParameterError(f"{path} {message}")


def check_value(path: str, value: Any, kind: type, check: str) -> Any:
    """Validate one parameter value and return it normalised (ints to float, lists to tuples)."""
    if kind is float:
        if value is None and check == "positive_or_inf":
            value = math.inf  # None reads naturally as "no spring": a rigid (clamped) end
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            fail(path, f"must be a number, got {type(value).__name__} {value!r}")
        value = float(value)
        if math.isnan(value):
            fail(path, "must be a number, got NaN")
        if check == "positive" and not (math.isfinite(value) and value > 0):
            fail(path, f"{value!r} must be positive and finite")
        elif check == "positive_or_inf" and not value > 0:
            fail(path, f"{value!r} must be positive (inf means rigid)")
        elif check == "real" and not math.isfinite(value):
            fail(path, f"{value!r} must be finite")
        elif check == "fraction" and not (0.0 <= value < 1.0):
            fail(path, f"{value!r} must be in [0, 1)")
        elif check == "poisson" and not (-1.0 < value < 0.5):
            fail(path, f"{value!r} must be in (-1, 0.5)")
    elif kind is int:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            fail(path, f"must be an integer, got {type(value).__name__} {value!r}")
        value = int(value)
        if check == "count" and value < 1:
            fail(path, f"{value} must be at least 1")
    elif kind is str:
        if not isinstance(value, str):
            fail(path, f"must be a string, got {type(value).__name__} {value!r}")
        if check.startswith("choice:"):
            choices = check[len("choice:"):].split("|")
            if value not in choices:
                fail(path, f"{value!r} must be one of {', '.join(map(repr, choices))}")
    elif kind is tuple:
        if isinstance(value, (str, bytes)) or not hasattr(value, "__len__"):
            fail(path, f"must be a list of numbers, got {type(value).__name__} {value!r}")
        items = []
        for i, item in enumerate(value):
            if isinstance(item, bool) or not isinstance(item, numbers.Real):
                fail(f"{path}[{i}]", f"must be a number, got {type(item).__name__} {item!r}")
            items.append(float(item))
        value = tuple(items)
    return value


class Section:
    """Validation shared by all parameter sections (fields declared with :func:`param`)."""

    section: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            meta = f.metadata
            value = check_value(f"{self.section}.{f.name}", getattr(self, f.name), meta["kind"], meta["check"])
            object.__setattr__(self, f.name, value)  # frozen: normalise once at construction
        self._check_section()

    def _check_section(self) -> None:
        """Relations between fields of this section (override)."""
