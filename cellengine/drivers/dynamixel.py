"""One Dynamixel XL430-W250 on a Protocol 2.0 bus (a U2D2 adapter), through ROBOTIS'
dynamixel-sdk: the port opened once per bus and shared by the servos on it, ping, and
reads and writes of the control table, each answer checked. The lab bench's grippers
(dynamixel_grip.py) and rotation joints (dynamixel_joint.py) are such servos."""

from __future__ import annotations

import contextlib
from typing import Any

MODEL_XL430 = 1060
MODEL_XM430 = 1020  # XM430-W350: current sensing, current-based position control
MODELS = {"xl430": MODEL_XL430, "xm430": MODEL_XM430}
# control table (XL430-W250 and XM430-W350, e-Manuals): operating mode, torque enable,
# hardware error status, goal current (XM), profile acceleration and velocity, goal position,
# moving, present load (XL; present current on the XM) and position
MODE, TORQUE, HW_ERROR, GOAL_CURRENT = 11, 64, 70, 102
PROFILE_ACCELERATION, PROFILE_VELOCITY, GOAL, MOVING, LOAD, POSITION = 108, 112, 116, 122, 126, 132
TICKS_PER_TURN = 4096
RPM_UNIT = 0.229  # rev/min of profile velocity 1
RPM2_UNIT = 214.577  # rev/min^2 of profile acceleration 1
MA_UNIT = 2.69  # mA of goal and present current 1 (XM430)


class DynamixelError(RuntimeError):
    """A servo did not answer, or answered with an error."""


class Servo:
    error: type[DynamixelError] = DynamixelError  # what a servo of this kind raises

    def __init__(
        self, port: str, ident: int, *, baud: int = 57600, bus: Any = None, model: str = "xl430"
    ) -> None:
        self.port, self.ident, self.baud, self.model = port, ident, baud, model
        self._bus = bus  # (PortHandler, PacketHandler), shared with the bus' other servos

    def connect(self) -> None:
        """Open the bus (unless another servo on it has) and ping this servo: the model the
        cell file says (an XL430-W250 or an XM430-W350)."""
        if self._bus is None:
            from dynamixel_sdk import PacketHandler, PortHandler

            port = PortHandler(self.port)
            try:
                opened = port.openPort() and port.setBaudRate(self.baud)
            except Exception as e:
                raise self.error(f"cannot open {self.port}: {e}") from None
            if not opened:
                raise self.error(f"cannot open {self.port} at {self.baud} baud")
            self._bus = (port, PacketHandler(2.0))
        port, handler = self._bus
        model, result, error = handler.ping(port, self.ident)
        self._check(handler, result, error, "ping")
        if model != MODELS[self.model]:
            raise self.error(
                f"{self.port} id {self.ident}: model number {model}, not the cell file's "
                f"{self.model} ({MODELS[self.model]})"
            )

    @property
    def bus(self) -> Any:
        """The (port, packet handler) the bus' other servos share."""
        return self._bus

    def torque_off(self) -> None:
        """Best effort: the port may be gone."""
        with contextlib.suppress(Exception):
            self.write(1, TORQUE, 0)

    def close(self) -> None:
        if self._bus is not None and self._bus[0].is_open:
            self._bus[0].closePort()

    def hardware_error(self) -> None:
        error = self.read(1, HW_ERROR)
        if error:
            raise self.error(f"{self.port} id {self.ident}: hardware error status {error:#04x}")

    def write(self, size: int, address: int, value: int) -> None:
        port, handler = self._bus
        call = {1: handler.write1ByteTxRx, 2: handler.write2ByteTxRx, 4: handler.write4ByteTxRx}
        result, error = call[size](port, self.ident, address, value & (1 << 8 * size) - 1)
        self._check(handler, result, error, f"write {address}")

    def read(self, size: int, address: int, signed: bool = False) -> int:
        port, handler = self._bus
        call = {1: handler.read1ByteTxRx, 2: handler.read2ByteTxRx, 4: handler.read4ByteTxRx}
        value, result, error = call[size](port, self.ident, address)
        self._check(handler, result, error, f"read {address}")
        if signed and value >= 1 << (8 * size - 1):
            value -= 1 << 8 * size
        return int(value)

    def _check(self, handler: Any, result: int, error: int, what: str) -> None:
        if result != 0:  # COMM_SUCCESS
            raise self.error(
                f"{self.port} id {self.ident}: {what}: {handler.getTxRxResult(result)}"
            )
        if error:
            raise self.error(
                f"{self.port} id {self.ident}: {what}: {handler.getRxPacketError(error)}"
            )
