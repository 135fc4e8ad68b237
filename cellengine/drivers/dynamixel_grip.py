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

import contextlib
import time
from collections.abc import Mapping
from typing import Any

MODEL_XL430 = 1060
TORQUE, HW_ERROR, GOAL, MOVING, LOAD, POSITION = 64, 70, 116, 122, 126, 132
REACHED = 20  # ticks: a goal reached (the servo's own deadband is a few)


class GripperError(RuntimeError):
    """The gripper did not do what it was told, or does not answer."""


class Gripper:
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
        self.port, self.ident, self.baud = port, ident, baud
        self.positions = dict(positions)
        self.load, self.timeout = load, timeout
        self._bus = bus  # (PortHandler, PacketHandler), shared with the bus' other servos
        self.mode: str | None = None
        self.holds = False  # the mode set is one that holds an object
        self._since = 0.0

    def open(self) -> None:
        """Ping the servo (an XL430), then torque on."""
        if self._bus is None:
            from dynamixel_sdk import PacketHandler, PortHandler

            port = PortHandler(self.port)
            try:
                opened = port.openPort() and port.setBaudRate(self.baud)
            except Exception as e:
                raise GripperError(f"cannot open {self.port}: {e}") from None
            if not opened:
                raise GripperError(f"cannot open {self.port} at {self.baud} baud")
            self._bus = (port, PacketHandler(2.0))
        port, handler = self._bus
        model, result, error = handler.ping(port, self.ident)
        self._check(handler, result, error, "ping")
        if model != MODEL_XL430:
            raise GripperError(
                f"{self.port} id {self.ident}: model {model}, not an XL430-W250 ({MODEL_XL430})"
            )
        self._write(1, TORQUE, 1)

    def set(self, mode: str, holds: bool) -> None:
        """Move to ``mode``'s position (without waiting)."""
        if mode not in self.positions:
            raise GripperError(f"no position for jaw mode '{mode}' (positions: {self.positions})")
        self._write(4, GOAL, self.positions[mode])
        self.mode, self.holds, self._since = mode, holds, time.monotonic()

    def settled(self) -> bool:
        """Whether the last mode set has taken (False: still moving); GripperError if it
        did not, or the servo reports a hardware error."""
        error = self._read(1, HW_ERROR)
        if error:
            raise GripperError(f"{self.port} id {self.ident}: hardware error status {error:#04x}")
        if self._read(1, MOVING) and time.monotonic() - self._since < self.timeout:
            return False
        position = self._read(4, POSITION, signed=True)
        load = abs(self._read(2, LOAD, signed=True))
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

    @property
    def bus(self) -> Any:
        """The (port, packet handler) the bus' other grippers share."""
        return self._bus

    def torque_off(self) -> None:
        """Best effort: the port may be gone."""
        with contextlib.suppress(Exception):
            self._write(1, TORQUE, 0)

    def close(self) -> None:
        if self._bus is not None and self._bus[0].is_open:
            self._bus[0].closePort()

    # -------------------------------------------------------------------------- packets

    def _write(self, size: int, address: int, value: int) -> None:
        port, handler = self._bus
        call = {1: handler.write1ByteTxRx, 2: handler.write2ByteTxRx, 4: handler.write4ByteTxRx}
        result, error = call[size](port, self.ident, address, value & (1 << 8 * size) - 1)
        self._check(handler, result, error, f"write {address}")

    def _read(self, size: int, address: int, signed: bool = False) -> int:
        port, handler = self._bus
        call = {1: handler.read1ByteTxRx, 2: handler.read2ByteTxRx, 4: handler.read4ByteTxRx}
        value, result, error = call[size](port, self.ident, address)
        self._check(handler, result, error, f"read {address}")
        if signed and value >= 1 << (8 * size - 1):
            value -= 1 << 8 * size
        return int(value)

    def _check(self, handler: Any, result: int, error: int, what: str) -> None:
        if result != 0:  # COMM_SUCCESS
            raise GripperError(
                f"{self.port} id {self.ident}: {what}: {handler.getTxRxResult(result)}"
            )
        if error:
            raise GripperError(
                f"{self.port} id {self.ident}: {what}: {handler.getRxPacketError(error)}"
            )
