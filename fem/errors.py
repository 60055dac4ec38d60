"""Errors for finite-element input: each names the offending node, element, card or value."""

from trussid._util.errors import UserError

__all__ = ["ModelError", "RenderError", "UnitsWarning"]


class ModelError(UserError):
    """The model as given cannot be built or solved (bad value, unknown node, mechanism)."""


class RenderError(UserError):
    """A rendering request that cannot be met (mode number, output format, sizes, no
    offscreen backend)."""


class UnitsWarning(UserWarning):
    """The model's numbers look like a mix of unit systems (e.g. E in MPa with a density in
    kg/m^3): its frequencies are probably wrong by orders of magnitude."""
