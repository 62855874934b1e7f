"""The values TROL returns: small immutable sequences, so ``numpy.asarray(pose)`` works."""

from __future__ import annotations

from typing import NamedTuple

MM_DECIMALS = 3
"""Decimals a length in mm is shown with: the arm's 0.001 mm."""
RAD_DECIMALS = 6
"""Decimals an angle in radians is shown with: 1e-6 rad."""


def fixed(x: float, decimals: int) -> str:
    """``x`` to ``decimals`` places as a person reads it: no trailing zeros, no exponent, no
    ``-0`` (TROL prints locations so on every surface; the fields keep the full value)."""
    text = f"{x:.{decimals}f}"
    if "." in text:
        text = text.rstrip("0").rstrip(".")
    return "0" if text == "-0" else text


class Pose(NamedTuple):
    """A cartesian location (POS_CART): mm and radians. Shown to the arm's precision
    (0.001 mm, 1e-6 rad); the fields are the full floats."""

    x: float
    y: float
    z: float
    yaw: float
    pitch: float
    roll: float

    def __repr__(self) -> str:
        return "Pose({})".format(
            ", ".join(
                f"{name}={fixed(v, MM_DECIMALS if i < 3 else RAD_DECIMALS)}"
                for i, (name, v) in enumerate(zip(self._fields, self))
            )
        )


class Joints(NamedTuple):
    """A joint location (POS_JOINT): radians, joint 1 first. Shown to 1e-6 rad; the
    fields are the full floats."""

    j1: float
    j2: float
    j3: float
    j4: float
    j5: float
    j6: float

    def __repr__(self) -> str:
        return "Joints({})".format(
            ", ".join(f"{n}={fixed(v, RAD_DECIMALS)}" for n, v in zip(self._fields, self))
        )


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
