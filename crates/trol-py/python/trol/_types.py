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


class Gripper(NamedTuple):
    """The gripper (TROLGetGripper): the fingers' opening in mm, and what they hold: the
    object's name (``""`` when the controller knows no name), ``None`` for nothing. With
    ``known`` false the controller reads the opening only and cannot tell what is held."""

    opening_mm: float
    holding: str | None
    known: bool
