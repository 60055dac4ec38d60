"""The ``deck`` evaluator: natural frequencies of any NASTRAN deck with property values
varied (issue 24: studies for any structure).

A study names the deck in ``[evaluate]`` and varies entries of it, each parameter named
``CARD.ID.FIELD``::

    [study]
    evaluate = "deck"

    [evaluate]
    deck = "tower.bdf"          # read relative to the working directory
    n_modes = 10

    [parameters]
    "PBAR.1.A" = {low = 1e-4, high = 3e-4, num = 3}
    "CONM2.901.M" = {values = [0.5, 1.0, 2.0]}

Fields: PBAR A, I1, I2, J; PROD A, J; CONM2 M; CELAS2 K; PELAS K (in the deck's units).
Each point writes the deck with the new values and reads it as ``trussid modes`` would
(:func:`trussid.fem.nastran.read_bdf`, :func:`trussid.fem.modal.solve_modes`): the same
conventions, the same answer as a serial loop over decks.

The evaluator has the interface of :class:`trussid.study.evaluators.Evaluator` without
importing it (the registry there imports this module).
"""

from __future__ import annotations

import json
import math
import re
import tempfile
from pathlib import Path

import pyarrow as pa
from cpylog import SimpleLogger
from pyNastran.bdf.bdf import BDF

from trussid._util.errors import UserError
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf

#: Parameter field -> (pyNastran card dictionary, attribute) per card type.
FIELDS = {
    "PBAR": ("properties", {"A": "A", "I1": "i1", "I2": "i2", "J": "j"}),
    "PROD": ("properties", {"A": "A", "J": "j"}),
    "PELAS": ("properties", {"K": "k"}),
    "CONM2": ("masses", {"M": "mass"}),
    "CELAS2": ("elements", {"K": "k"}),
}
NAME = re.compile(r"^([A-Z0-9]+)\.(\d+)\.([A-Z0-9]+)$")


class StudyDeckError(UserError):
    """A deck study's mistake (unknown card, field or id), naming it."""


def _parse(path) -> BDF:
    bdf = BDF(log=SimpleLogger(level="critical"), debug=None)
    try:
        bdf.read_bdf(str(path), xref=False, punch=False)
    except FileNotFoundError:
        raise StudyDeckError(f"[evaluate] deck {path}: no such file") from None
    except Exception as exc:  # pyNastran's many exception types: the deck is unreadable
        raise StudyDeckError(f"[evaluate] deck {path}: not a readable deck ({exc})") from None
    return bdf


def _target(bdf: BDF, name: str, where: str):
    """(card object, attribute) that parameter ``name`` sets."""
    m = NAME.match(name)
    if not m or m.group(1) not in FIELDS:
        raise StudyDeckError(f"{where}: parameter {name!r}: name it CARD.ID.FIELD with CARD one "
                             f"of {', '.join(FIELDS)} (e.g. PBAR.1.A, CONM2.901.M)")
    card, ident, fld = m.group(1), int(m.group(2)), m.group(3)
    table, fields = FIELDS[card]
    if fld not in fields:
        raise StudyDeckError(f"{where}: parameter {name!r}: {card} field must be one of "
                             f"{', '.join(fields)}")
    obj = getattr(bdf, table).get(ident)
    if obj is None or obj.type != card:
        raise StudyDeckError(f"{where}: parameter {name!r}: the deck has no {card} {ident}")
    return obj, fields[fld]


class DeckModesEvaluator:
    """Natural frequencies [Hz] of a deck at the point's property values (module docstring)."""

    name = "deck"
    options = {"deck": None, "n_modes": 10}
    default_chunk = 4

    def resolved(self, options: dict) -> dict:
        return {**self.options, **options}

    def check(self, spec, where: str = "spec") -> None:
        for k in spec.options:
            if k not in self.options:
                raise StudyDeckError(f"{where}: [evaluate]: unknown option {k!r} for 'deck' "
                                     f"(expected one of {', '.join(self.options)})")
        opts = self.resolved(spec.options)
        n = opts["n_modes"]
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise StudyDeckError(f"{where}: [evaluate] n_modes must be an integer >= 1, got {n!r}")
        if not isinstance(opts["deck"], str):
            raise StudyDeckError(f"{where}: [evaluate] deck = \"file.bdf\" is needed")
        bdf = _parse(opts["deck"])
        for a in spec.parameters:
            _target(bdf, a.name, where)
            vals = a.values if a.values is not None else (a.low, a.high)
            for v in vals:
                if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                    raise StudyDeckError(f"{where}: parameter {a.name!r} must be positive, "
                                         f"got {v!r}")

    def columns(self, options: dict):
        return [(f"f{k + 1}", pa.float64()) for k in range(self.resolved(options)["n_modes"])]

    def context(self, options: dict):
        opts = self.resolved(options)
        return {"bdf": _parse(opts["deck"]), "key": json.dumps(opts, sort_keys=True)}

    def point(self, ctx, params: dict, options: dict) -> dict:
        opts = self.resolved(options)
        bdf = ctx["bdf"]
        saved = []
        try:
            for name, v in params.items():
                obj, attr = _target(bdf, name, "point")
                saved.append((obj, attr, getattr(obj, attr)))
                setattr(obj, attr, float(v))
            with tempfile.TemporaryDirectory() as tmp:
                path = Path(tmp) / Path(opts["deck"]).name
                bdf.write_bdf(str(path), size=16, is_double=False, enddata=True)
                model, info = read_bdf(path)
                f = solve_modes(model, n_modes=opts["n_modes"],
                                autospc=info.autospc).frequencies_hz
        finally:
            for obj, attr, old in reversed(saved):  # the shared deck back as read
                setattr(obj, attr, old)
        return {f"f{k + 1}": float(f[k]) if k < len(f) else math.nan
                for k in range(opts["n_modes"])}
