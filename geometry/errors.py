"""The error raised for a bad testbed parameter or parameter file."""

from trussid._util.errors import UserError


class ParameterError(UserError):
    """A testbed parameter is invalid; the message names the parameter (e.g. ``struts.length``)."""
