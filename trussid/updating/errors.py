"""The error of model updating."""

from trussid._util.errors import UserError

__all__ = ["UpdateError"]


class UpdateError(UserError):
    """Bad input to model updating (the message names the offending item)."""
