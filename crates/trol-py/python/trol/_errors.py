"""TROL's exceptions. Each carries ``code``, the manual's return value."""

from __future__ import annotations

import builtins


class TrolError(Exception):
    """Any TROL failure; ``code`` is the manual's return value (``trol.describe(code)``)."""

    code: int

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


class RefusedError(TrolError):
    """The controller said no: a BIOS code (> -32000) or a TROL code it detected.

    ``command`` is the API function's name (``TROLMove``), ``name`` the code's name
    (``BIOS_NOT_HOMED``, ``TROL_ERR_LOCATION``; empty if unknown).
    """

    command: str
    name: str

    def __init__(self, message: str, code: int, command: str, name: str) -> None:
        super().__init__(message, code)
        self.command = command
        self.name = name


class LinkError(TrolError):
    """TROL_ERR_COMM: the link failed and the error handler could not mend it.

    ``last_comm`` is the last layer-2 code (GetLastCommErr), or None.
    """

    last_comm: int | None

    def __init__(self, message: str, code: int, last_comm: int | None) -> None:
        super().__init__(message, code)
        self.last_comm = last_comm


class ArgumentError(TrolError, ValueError):
    """TROL_ERR_ARG_RANGE: an argument is out of its range; nothing was sent."""


class ArgumentTypeError(ArgumentError, TypeError):
    """TROL_ERR_ARG_RANGE: an argument is of a kind that cannot mean the values asked for
    (a dict, a set, a generator, a range where an ordered sequence of numbers is expected);
    nothing was sent. Both an ``ArgumentError`` and a ``TypeError``."""


class BadReplyError(TrolError):
    """TROL_ERR_BAD_RSIZE: the reply does not fit the command."""


class SetupError(TrolError):
    """The port could not be opened, the configuration is wrong, or the robot is closed."""


class IncompatibleError(SetupError):
    """The controller speaks another TROL protocol version than this library.

    ``ours`` is this library's version, ``theirs`` the controller's (None: it does not know
    TROLGetVersion, so it is older). Run the same TROL release on both sides.
    """

    ours: int
    theirs: int | None

    def __init__(self, message: str, code: int, ours: int, theirs: int | None) -> None:
        super().__init__(message, code)
        self.ours = ours
        self.theirs = theirs


class TimeoutError(TrolError, builtins.TimeoutError):
    """A wait ran out (``finish(timeout=...)``); the arm keeps moving."""
