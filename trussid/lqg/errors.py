"""Errors of :mod:`trussid.lqg`: mistakes in what the user gave, one line naming the item."""

from trussid._util.errors import UserError

__all__ = ["ControlError"]


class ControlError(UserError):
    """A design or an evaluation that cannot be done as asked: a continuous or unstable
    model, a band with no mode, a target outside (0, 1), a controller whose sizes, names or
    sample interval do not match the plant."""
