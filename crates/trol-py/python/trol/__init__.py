"""TROL for Python: drive a CRS A465 through its C500 controller, or its simulation.

>>> import trol
>>> with trol.Robot.open("sim", time_scale=20) as robot:
...     robot.home()
...     robot.joint(1, 0.5)
...     robot.finish()
...     round(robot.joints().j1, 3)
0.5

TROL's semantics and units (mm, radians): motions return once the controller accepted them,
``finish()`` waits. Errors are exceptions with the manual's codes (``trol.TrolError``).
See docs/python.md.
"""

from trol._errors import (
    ArgumentError,
    ArgumentTypeError,
    BadReplyError,
    IncompatibleError,
    LinkError,
    RefusedError,
    SetupError,
    TimeoutError,
    TrolError,
)
from trol._trol import Robot, describe
from trol._types import Gripper, Joints, Pose, Precision

__all__ = [
    "ArgumentError",
    "ArgumentTypeError",
    "BadReplyError",
    "Gripper",
    "IncompatibleError",
    "Joints",
    "LinkError",
    "Pose",
    "Precision",
    "RefusedError",
    "Robot",
    "SetupError",
    "TimeoutError",
    "TrolError",
    "describe",
]
