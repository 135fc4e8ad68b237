"""A rotation joint turned by a Dynamixel XL430-W250 (the cell file's
``robots.R.servos``): in extended position mode (multi-turn: a cap unscrewed in 2.5 turns),
its profile velocity and acceleration set from the joint's limits, so that the servo's own
profile follows each goal the driver streams (lab_servos.py) as fast as the plan may move."""

from __future__ import annotations

import math

from cellengine.drivers.dynamixel import (
    GOAL,
    MODE,
    POSITION,
    PROFILE_ACCELERATION,
    PROFILE_VELOCITY,
    RPM2_UNIT,
    RPM_UNIT,
    TICKS_PER_TURN,
    TORQUE,
    DynamixelError,
    Servo,
)

EXTENDED_POSITION = 4  # operating mode: goals over +-256 turns
# the profile's room over the joint's limits, so the servo keeps up with the streamed goals
HEADROOM = 1.5


class ServoError(DynamixelError):
    """A joint's servo did not answer, or reported an error."""


class ServoJoint(Servo):
    error = ServoError

    def __init__(
        self,
        port: str,
        ident: int,
        *,
        sign: int = 1,
        zero: int = 2048,
        baud: int = 57600,
        bus: object = None,
    ) -> None:
        super().__init__(port, ident, baud=baud, bus=bus)
        self.sign, self.zero = sign, zero

    def open(self, velocity: float, acceleration: float) -> None:
        """Ping, then (torque off, as the servo requires to change its mode) extended position
        mode and a profile of ``velocity`` (rad/s) and ``acceleration`` (rad/s^2) with
        headroom, torque on."""
        self.connect()
        self.write(1, TORQUE, 0)
        self.write(1, MODE, EXTENDED_POSITION)
        rpm = velocity * HEADROOM * 60.0 / (2.0 * math.pi)
        rpm2 = acceleration * HEADROOM * 3600.0 / (2.0 * math.pi)
        self.write(4, PROFILE_VELOCITY, max(1, math.ceil(rpm / RPM_UNIT)))
        self.write(4, PROFILE_ACCELERATION, max(1, math.ceil(rpm2 / RPM2_UNIT)))
        self.write(1, TORQUE, 1)

    def ticks(self, q: float) -> int:
        return self.zero + self.sign * round(q * TICKS_PER_TURN / (2.0 * math.pi))

    def goal(self, q: float) -> None:
        """Turn to joint value ``q`` (rad), without waiting."""
        self.write(4, GOAL, self.ticks(q))

    def position(self) -> float:
        """The joint's value (rad) from the servo's present position."""
        ticks = self.read(4, POSITION, signed=True)
        return self.sign * (ticks - self.zero) * 2.0 * math.pi / TICKS_PER_TURN
