"""The one exception type the command line turns into a one-line message.

Every package raises a subclass of :class:`UserError` for mistakes in what the user gave
(a bad parameter, an unknown node, a malformed file), naming the offending item. Anything
else is a bug and keeps its traceback.
"""


class UserError(ValueError):
    """A mistake in user input; the message names the offending item."""
