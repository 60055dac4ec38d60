"""The one JSON sanitiser: what numpy and dataclasses produce, made JSON-representable."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np


def json_safe(obj):
    """``obj`` with JSON-safe values, recursively.

    Non-finite floats (which JSON cannot hold) become ``None``; numpy scalars and arrays
    become Python numbers and lists; dataclass instances become dicts of their fields, or
    what their ``json_form()`` method gives where they have one (a record whose JSON keys
    are not its field names, e.g. a key that is a Python keyword); dictionary keys become
    strings; tuples become lists.
    """
    if hasattr(obj, "json_form") and not isinstance(obj, type):
        return json_safe(obj.json_form())
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return json_safe({f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)})
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, complex):
        return {"real": json_safe(obj.real), "imag": json_safe(obj.imag)}
    return obj


def dumps(obj, indent: int | None = 2) -> str:
    """``json.dumps`` of :func:`json_safe` (``obj``), with a final newline."""
    return json.dumps(json_safe(obj), indent=indent) + "\n"
