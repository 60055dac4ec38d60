"""Errors for finite-element input: each names the offending node, element, card or value."""

from trussid._util.errors import UserError

__all__ = ["ModelError"]


class ModelError(UserError):
    """The model as given cannot be built or solved (bad value, unknown node, mechanism)."""
