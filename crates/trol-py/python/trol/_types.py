"""The values TROL returns: small immutable sequences, so ``numpy.asarray(pose)`` works."""

from __future__ import annotations

from typing import NamedTuple


class Pose(NamedTuple):
    """A cartesian location (POS_CART): mm and radians."""

    x: float
    y: float
    z: float
    yaw: float
    pitch: float
    roll: float


class Joints(NamedTuple):
    """A joint location (POS_JOINT): radians, joint 1 first."""

    j1: float
    j2: float
    j3: float
    j4: float
    j5: float
    j6: float


class Precision(NamedTuple):
    """A precision point (POS_PREC): encoder counts, joint 1 first. As a motion target it
    is sent as a precision point, as TROLMoveII does with POS_PREC."""

    c1: int
    c2: int
    c3: int
    c4: int
    c5: int
    c6: int
