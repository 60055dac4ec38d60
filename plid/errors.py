"""Errors the ``trussid.plid`` package raises for mistakes in what the user gave.

Both subclass :class:`trussid._util.errors.UserError`, so the command line turns them into a
one-line message. Messages name the offending item (column, sample, parameter, order).
"""

from trussid._util.errors import UserError

__all__ = ["DataError", "IdentificationError"]


class DataError(UserError):
    """Bad input/output data: NaN/inf, length mismatch, unexciting input, unknown column."""


class IdentificationError(UserError):
    """An identification request that cannot be honoured (invalid order, bad prior, bad option)."""
