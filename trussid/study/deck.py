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

import math
import re
import tempfile
from dataclasses import asdict, dataclass
from pathlib import Path

import pyarrow as pa

from trussid._util.errors import UserError
from trussid.fem.errors import ModelError
from trussid.fem.modal import solve_modes
from trussid.fem.nastran import read_bdf
from trussid.fem.nastran.cards import Card, ParsedDeck, deck_text, parse_deck

#: Parameter field -> its index in the entry's fields (0 = the name), per card type; PELAS
#: holds a second property from field 6 on (its K 4 fields further).
FIELDS = {
    "PBAR": {"A": 3, "I1": 4, "I2": 5, "J": 6},
    "PROD": {"A": 3, "J": 4},
    "PELAS": {"K": 2},
    "CONM2": {"M": 4},
    "CELAS2": {"K": 2},
}
NAME = re.compile(r"^([A-Z0-9]+)\.(\d+)\.([A-Z0-9]+)$")


class StudyDeckError(UserError):
    """A deck study's mistake (unknown card, field or id), naming it."""


def _parse(path) -> ParsedDeck:
    try:
        return parse_deck(path)
    except ModelError as exc:
        raise StudyDeckError(f"[evaluate] deck {exc}") from None


def _target(deck: ParsedDeck, name: str, where: str) -> tuple[int, int]:
    """(index of the entry in ``deck.cards``, index of the field) that parameter ``name`` sets."""
    m = NAME.match(name)
    if not m or m.group(1) not in FIELDS:
        raise StudyDeckError(f"{where}: parameter {name!r}: name it CARD.ID.FIELD with CARD one "
                             f"of {', '.join(FIELDS)} (e.g. PBAR.1.A, CONM2.901.M)")
    card, ident, fld = m.group(1), int(m.group(2)), m.group(3)
    fields = FIELDS[card]
    if fld not in fields:
        raise StudyDeckError(f"{where}: parameter {name!r}: {card} field must be one of "
                             f"{', '.join(fields)}")
    for k, c in enumerate(deck.cards):
        if c.name != card:
            continue
        for shift in ((0, 4) if card == "PELAS" else (0,)):
            if c.get(1 + shift).isdigit() and int(c.get(1 + shift)) == ident:
                return k, fields[fld] + shift
    raise StudyDeckError(f"{where}: parameter {name!r}: the deck has no {card} {ident}")


def _with_values(deck: ParsedDeck, targets: list) -> list:
    """The deck's cards with ``(card index, field index, value)`` set."""
    cards = list(deck.cards)
    for k, i, v in targets:
        c = cards[k]
        f = list(c.fields) + [""] * max(0, i + 1 - len(c.fields))
        f[i] = repr(float(v))
        cards[k] = Card(c.name, tuple(f), c.file, c.lines, c.per_line)
    return cards


@dataclass(frozen=True)
class DeckOptions:
    """Options of the ``deck`` evaluator.

    Attributes
    ----------
    deck : str or None
        The NASTRAN deck file (required).
    n_modes : int
        Lowest modes per point.
    """

    deck: str | None = None
    n_modes: int = 10


@dataclass(frozen=True)
class DeckContext:
    """What every point of a deck study shares: the parsed deck."""

    deck: object


class DeckModesEvaluator:
    """Natural frequencies [Hz] of a deck at the point's property values (module docstring)."""

    name = "deck"
    options = asdict(DeckOptions())
    default_chunk = 4

    def resolved(self, options: dict) -> dict:
        """``options`` over the defaults, as plain data."""
        return {**self.options, **options}

    def typed(self, options: dict) -> DeckOptions:
        """``options`` over the defaults as :class:`DeckOptions`."""
        return DeckOptions(**self.resolved(options))

    def check(self, spec, where: str = "spec") -> None:
        for k in spec.options:
            if k not in self.options:
                raise StudyDeckError(f"{where}: [evaluate]: unknown option {k!r} for 'deck' "
                                     f"(expected one of {', '.join(self.options)})")
        opts = self.typed(spec.options)
        n = opts.n_modes
        if isinstance(n, bool) or not isinstance(n, int) or n < 1:
            raise StudyDeckError(f"{where}: [evaluate] n_modes must be an integer >= 1, got {n!r}")
        if not isinstance(opts.deck, str):
            raise StudyDeckError(f"{where}: [evaluate] deck = \"file.bdf\" is needed")
        bdf = _parse(opts.deck)
        for a in spec.parameters:
            _target(bdf, a.name, where)
            vals = a.values if a.values is not None else (a.low, a.high)
            for v in vals:
                if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                    raise StudyDeckError(f"{where}: parameter {a.name!r} must be positive, "
                                         f"got {v!r}")

    def columns(self, options: dict):
        return [(f"f{k + 1}", pa.float64()) for k in range(self.typed(options).n_modes)]

    def context(self, options: dict) -> DeckContext:
        return DeckContext(deck=_parse(self.typed(options).deck))

    def point(self, ctx, params: dict, options: dict) -> dict:
        opts = self.typed(options)
        deck = ctx.deck
        targets = [(*_target(deck, name, "point"), v) for name, v in params.items()]
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / Path(opts.deck).name
            path.write_text(deck_text(deck, _with_values(deck, targets)))
            model, info = read_bdf(path)
            f = solve_modes(model, n_modes=opts.n_modes, autospc=info.autospc).frequencies_hz
        return {f"f{k + 1}": float(f[k]) if k < len(f) else math.nan
                for k in range(opts.n_modes)}
