"""TROL's exceptions. Each carries ``code``, the manual's return value."""

from __future__ import annotations

import builtins


class TrolError(Exception):
    """Any TROL failure; ``code`` is the manual's return value (``trol.describe(code)``)."""

    code: int

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


# What to do next after a refusal, in this API's terms (the interpreter and the pendant say
# the same in theirs).
NEXT_STEPS = {
    "BIOS_NOT_HOMED": "home the arm first: robot.home(), then robot.finish()",
    "BIOS_OUT_OF_REACH": (
        "the A465 reaches about 711 mm from its shoulder, 330 mm above the base; robot.pose() "
        "shows where the tool is. After home() it stands stretched upright (READY), at the "
        "edge of its reach: robot.jog([0, 0, -100], straight=True) or robot.joint(3, 0.5) first"
    ),
    "BIOS_JOINT_LIMIT": (
        "robot.joints() shows the joints; their limits (degrees): joint 1 +-175, 2 +-90, "
        "3 +-110, 4 +-180, 5 +-105, 6 +-180"
    ),
    "BIOS_BELOW_TABLE": "the tool tip would go below the table: aim higher, or lower table_z in trol.cfg",
    "BIOS_TOO_FAST": (
        "the trajectory is faster than the arm: give its waypoints later times, or "
        "robot.speed(100) if the speed was set lower"
    ),
    "BIOS_SINGULAR_PATH": "a straight line cannot pass there: leave out straight=True, or go through another point",
    "TROL_ERR_LOCATION": (
        "the controller has no location of that name: give the pose as numbers, or load a "
        "location file (locations = FILE in trol.cfg)"
    ),
}


class RefusedError(TrolError):
    """The controller said no: a BIOS code (> -32000) or a TROL code it detected.

    ``command`` is the API function's name (``TROLMove``), ``name`` the code's name
    (``BIOS_NOT_HOMED``, ``TROL_ERR_LOCATION``; empty if unknown), ``next_step`` what to do
    about it where there is an obvious next step (also at the message's end), else None.
    """

    command: str
    name: str
    next_step: str | None

    def __init__(self, message: str, code: int, command: str, name: str) -> None:
        self.next_step = NEXT_STEPS.get(name)
        super().__init__(f"{message}; {self.next_step}" if self.next_step else message, code)
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
