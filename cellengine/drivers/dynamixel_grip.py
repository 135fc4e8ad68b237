"""A lab bench gripper: a Dynamixel XL430-W250 (Protocol 2.0, through a U2D2 adapter)
turning the rack and pinion of a parallel jaw, driven with ROBOTIS' dynamixel-sdk.

A jaw mode is a goal position (the cell file's ``positions``, ticks). Setting a mode writes
it and returns at once (the arms keep moving); :meth:`Gripper.settled` is asked until the
servo has stopped, and says whether the mode took: a mode that holds something (``holds``)
must stop short of its goal with the present load at least ``load`` (0.1 %: the fingers
closed on an object), any other must reach its goal.

An XM430 (``model: xm430``) with ``currents`` runs in current-based position control: each
jaw mode's current (mA) is its goal current, the most it squeezes with, written before its
goal position; a holding mode is confirmed when it stops short of its goal pressing with
at least ``HOLDING`` of that current. A servo that does not settle within
``timeout``, reports a hardware error, or does not answer is a fault.
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Any

from cellengine.drivers.dynamixel import (
    GOAL,
    GOAL_CURRENT,
    LOAD,
    MA_UNIT,
    MODE,
    MOVING,
    POSITION,
    TORQUE,
    DynamixelError,
    Servo,
)

REACHED = 20  # ticks: a goal reached (the servo's own deadband is a few)
CURRENT_BASED_POSITION = 5  # operating mode (XM430)
HOLDING = 0.8  # of a mode's goal current: the fingers press on something


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
        model: str = "xl430",
        currents: Mapping[str, float] | None = None,
    ) -> None:
        super().__init__(port, ident, baud=baud, bus=bus, model=model)
        self.positions = dict(positions)
        self.currents = dict(currents or {})  # mA by jaw mode
        self.load, self.timeout = load, timeout
        self.mode: str | None = None
        self.holds = False  # the mode set is one that holds an object
        self._since = 0.0

    def open(self) -> None:
        """Ping the servo; with currents, current-based position control (set with the torque
        off, as the servo requires); torque on."""
        self.connect()
        if self.currents:
            self.write(1, TORQUE, 0)
            self.write(1, MODE, CURRENT_BASED_POSITION)
        self.write(1, TORQUE, 1)

    def set(self, mode: str, holds: bool) -> None:
        """Move to ``mode``'s position (without waiting)."""
        if mode not in self.positions:
            raise GripperError(f"no position for jaw mode '{mode}' (positions: {self.positions})")
        if mode in self.currents:
            self.write(2, GOAL_CURRENT, round(self.currents[mode] / MA_UNIT))
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
            if abs(position - goal) > REACHED and self._pressing(load):
                return True
            why = "closed on nothing" if abs(position - goal) <= REACHED else "did not close"
        else:
            if abs(position - goal) <= REACHED:
                return True
            why = "did not reach it"
        if time.monotonic() - self._since < self.timeout:
            return False
        pressed = (
            f"current {load * MA_UNIT:.0f} mA" if self._current() else f"load {load / 10:.1f} %"
        )
        raise GripperError(
            f"{self.port} id {self.ident}: jaw mode '{self.mode}' {why} (position {position}, "
            f"goal {goal}, {pressed})"
        )

    def _current(self) -> float | None:
        """The mode's goal current (mA), when the servo runs on current."""
        return self.currents.get(self.mode or "")

    def _pressing(self, load: int) -> bool:
        """Whether the fingers press on something: the present current near the mode's goal
        current (an XM on current), else the present load at least ``load``."""
        current = self._current()
        if current is not None:
            return load * MA_UNIT >= HOLDING * current
        return load >= self.load
