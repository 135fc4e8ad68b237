"""A lab bench gripper: a Dynamixel XL430-W250 (Protocol 2.0, through a U2D2 adapter)
turning the rack and pinion of a parallel jaw, driven with ROBOTIS' dynamixel-sdk.

A jaw mode is a goal position (the cell file's ``positions``, ticks). Setting a mode writes
it and returns at once (the arms keep moving); :meth:`Gripper.settled` is asked until the
servo has stopped, and says whether the mode took: a mode that holds something (``holds``)
must stop short of its goal with the present load at least ``load`` (0.1 %: the fingers
closed on an object), any other must reach its goal. A servo that does not settle within
``timeout``, reports a hardware error, or does not answer is a fault.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from cellengine.drivers.dynamixel import GOAL, LOAD, MOVING, POSITION, TORQUE, DynamixelError, Servo

REACHED = 20  # ticks: a goal reached (the servo's own deadband is a few)


class GripperError(DynamixelError):
    """The gripper did not do what it was told, or does not answer."""


class Gripper(Servo):
    error = GripperError

    def __init__(
        self,
        port: str,
        ident: int,
        positions: Mapping[str, int],
        *,
        baud: int = 57600,
        load: int = 200,
        timeout: float = 2.0,
        bus: Any = None,
    ) -> None:
        super().__init__(port, ident, baud=baud, bus=bus)
        self.positions = dict(positions)
        self.load, self.timeout = load, timeout
        self.mode: str | None = None
        self.holds = False  # the mode set is one that holds an object
        self._since = 0.0

    def open(self) -> None:
        """Ping the servo (an XL430), then torque on."""
        self.connect()
        self.write(1, TORQUE, 1)

    def set(self, mode: str, holds: bool) -> None:
        """Move to ``mode``'s position (without waiting)."""
        if mode not in self.positions:
            raise GripperError(f"no position for jaw mode '{mode}' (positions: {self.positions})")
        self.write(4, GOAL, self.positions[mode])
        self.mode, self.holds, self._since = mode, holds, time.monotonic()

    def settled(self) -> bool:
        """Whether the last mode set has taken (False: still moving); GripperError if it
        did not, or the servo reports a hardware error."""
        self.hardware_error()
        if self.read(1, MOVING) and time.monotonic() - self._since < self.timeout:
            return False
        position = self.read(4, POSITION, signed=True)
        load = abs(self.read(2, LOAD, signed=True))
        goal = self.positions[self.mode or ""]
        if self.holds:
            if abs(position - goal) > REACHED and load >= self.load:
                return True
            why = "closed on nothing" if abs(position - goal) <= REACHED else "did not close"
        else:
            if abs(position - goal) <= REACHED:
                return True
            why = "did not reach it"
        if time.monotonic() - self._since < self.timeout:
            return False
        raise GripperError(
            f"{self.port} id {self.ident}: jaw mode '{self.mode}' {why} (position {position}, "
            f"goal {goal}, load {load / 10:.1f} %)"
        )
