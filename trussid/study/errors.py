"""The error of the study package (its own module, so that every study module can raise it
without importing another)."""

from trussid._util.errors import UserError

__all__ = ["StudyError"]


class StudyError(UserError):
    """A mistake in a study specification or its output directory; names the item."""
