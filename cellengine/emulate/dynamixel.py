"""An emulated Dynamixel bus (Protocol 2.0) with XL430-W250 servos, the lab bench's
grippers, for tests of the real dynamixel-sdk client code over a pseudo-terminal
(emulate/serial_pty.py).

Packets as ROBOTIS documents Protocol 2.0: header FF FF FD 00, ID, length, instruction,
parameters, CRC-16 (polynomial 0x8005), byte stuffing (FF FF FD -> FF FF FD FD). A packet
whose CRC does not match is answered with the CRC error; instructions PING, READ, WRITE and
SYNC WRITE (no status packet). Each servo's control table holds the addresses the driver
uses: model number (0), firmware version (6), torque enable (64), hardware error status
(70), goal position (116), moving (122), present load (126), present position (132).

A servo with torque on moves its present position towards the goal at ``SPEED`` ticks/s.
What the fingers close on (``stop``, a position a test sets: the object's width) stops them
there with the load at ``HOLD_LOAD`` (an XM430, ``model=MODEL_XM430``, in current-based
position control: pressing with its goal current, read at the same address). Faults:
``stuck`` (a servo no longer moves), ``overload`` (the hardware error status' overload bit,
the torque off).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

HEADER = b"\xff\xff\xfd\x00"
PING, READ, WRITE, SYNC_WRITE, STATUS = 0x01, 0x02, 0x03, 0x83, 0x55
ERR_CRC, ERR_INSTRUCTION, ERR_LENGTH, ERR_ACCESS = 0x03, 0x02, 0x05, 0x07
MODEL_XL430 = 1060
MODEL_XM430 = 1020  # XM430-W350: present current at 126, current-based position control
MODE, GOAL_CURRENT, CURRENT_BASED_POSITION = 11, 102, 5
TABLE = 147  # bytes of control table emulated
MODEL, FIRMWARE, TORQUE, HW_ERROR = 0, 6, 64, 70
GOAL, MOVING, LOAD, POSITION = 116, 122, 126, 132
PROFILE_ACCELERATION, PROFILE_VELOCITY, VELOCITY_LIMIT = 108, 112, 44
TICKS_PER_TURN = 4096
RPM_UNIT, RPM2_UNIT = 0.229, 214.577  # rev/min per unit of profile velocity, rev/min^2 of accel
SPEED = 2000.0  # ticks/s the fingers move at
HOLD_LOAD = 600  # present load (0.1 %) while closed on something


def crc16(data: bytes) -> int:
    """Dynamixel Protocol 2.0's CRC-16: polynomial 0x8005, MSB first, from 0."""
    crc = 0
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x8005) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


def stuff(body: bytes) -> bytes:
    return body.replace(b"\xff\xff\xfd", b"\xff\xff\xfd\xfd")


def unstuff(body: bytes) -> bytes:
    return body.replace(b"\xff\xff\xfd\xfd", b"\xff\xff\xfd")


def packet(ident: int, instruction: int, params: bytes) -> bytes:
    """A whole packet: header, id, length, instruction, stuffed parameters, CRC."""
    body = stuff(params)
    head = HEADER + bytes([ident]) + (len(body) + 3).to_bytes(2, "little") + bytes([instruction])
    return head + body + crc16(head + body).to_bytes(2, "little")


@dataclass
class Servo:
    ident: int
    table: bytearray = field(default_factory=lambda: bytearray(TABLE))
    position: float = 2048.0
    stop: float | None = None  # where an object stops the fingers (ticks), if any
    stuck: bool = False
    speed: float = 0.0  # ticks/s
    model: int = MODEL_XL430

    def __post_init__(self) -> None:
        self.table[MODEL : MODEL + 2] = self.model.to_bytes(2, "little")
        self.table[FIRMWARE] = 46
        self.table[VELOCITY_LIMIT : VELOCITY_LIMIT + 4] = (265).to_bytes(4, "little")
        self.table[7] = self.ident
        self._sync()

    def word(self, address: int, size: int, signed: bool = False) -> int:
        return int.from_bytes(self.table[address : address + size], "little", signed=signed)

    def advance(self, dt: float) -> None:
        goal = float(self.word(GOAL, 4, signed=True))
        on = self.table[TORQUE] == 1 and not self.stuck
        loaded = False
        if on and abs(goal - self.position) > 0.5:
            new = self.position + self._step(goal, dt)
            if self.stop is not None and min(self.position, new) <= self.stop <= max(
                self.position, new
            ):
                new, loaded = self.stop, True
            self.position = new
        elif on and self.stop is not None and abs(self.position - self.stop) < 0.5:
            loaded = abs(goal - self.position) > 0.5
        moving = on and abs(goal - self.position) > 0.5 and not loaded and not self.stuck
        self.table[MOVING] = 1 if moving else 0
        load = self._pressing() if loaded else 0
        self.table[LOAD : LOAD + 2] = load.to_bytes(2, "little", signed=True)
        self._sync()

    def _pressing(self) -> int:
        """What it reports pressing on something: its goal current (an XM430 on current),
        else HOLD_LOAD."""
        if self.model == MODEL_XM430 and self.table[MODE] == CURRENT_BASED_POSITION:
            return self.word(GOAL_CURRENT, 2, signed=True)
        return HOLD_LOAD

    def _step(self, goal: float, dt: float) -> float:
        """The move towards ``goal`` in ``dt``: at the profile velocity (112; SPEED when 0),
        speeding up and slowing down at the profile acceleration (108; at once when 0), to
        stop on the goal, as the servo's own profile does."""
        velocity = self.word(PROFILE_VELOCITY, 4) * RPM_UNIT * TICKS_PER_TURN / 60.0 or SPEED
        accel = self.word(PROFILE_ACCELERATION, 4) * RPM2_UNIT * TICKS_PER_TURN / 3600.0
        left = goal - self.position
        direction = 1.0 if left > 0 else -1.0
        cap = min(velocity, math.sqrt(2.0 * accel * abs(left))) if accel else velocity
        target = direction * cap
        if accel:
            change = accel * dt
            self.speed = min(max(target, self.speed - change), self.speed + change)
        else:
            self.speed = target
        step = self.speed * dt
        if abs(step) >= abs(left):  # on the goal: stopped there
            self.speed, step = 0.0, left
        return step

    def _sync(self) -> None:
        self.table[POSITION : POSITION + 4] = round(self.position).to_bytes(
            4, "little", signed=True
        )


@dataclass
class DynamixelBus:
    """Servos on one bus. ``receive`` the host's bytes, ``advance`` the clock, read the
    status packets from ``output``."""

    servos: dict[int, Servo]
    output: bytearray = field(default_factory=bytearray)
    log: list[str] = field(default_factory=list)
    faults: tuple[str, ...] = ("stuck", "overload")
    talks_first: bool = False
    crc_errors: int = 0
    _rx: bytearray = field(default_factory=bytearray)

    def receive(self, data: bytes) -> None:
        self._rx += data
        while True:
            start = self._rx.find(HEADER)
            if start < 0:
                del self._rx[: max(0, len(self._rx) - 3)]
                return
            del self._rx[:start]
            if len(self._rx) < 7:
                return
            length = int.from_bytes(self._rx[5:7], "little")
            if len(self._rx) < 7 + length:
                return
            raw = bytes(self._rx[: 7 + length])
            del self._rx[: 7 + length]
            self._packet(raw)

    def _packet(self, raw: bytes) -> None:
        ident, instruction = raw[4], raw[7]
        if crc16(raw[:-2]) != int.from_bytes(raw[-2:], "little"):
            self.crc_errors += 1
            if ident in self.servos:
                self._status(ident, ERR_CRC)
            return
        params = unstuff(raw[8:-2])
        self.log.append(f"id {ident} instruction {instruction:#04x} params {params.hex()}")
        if instruction == SYNC_WRITE:
            self._sync_write(params)
            return
        servo = self.servos.get(ident)
        if servo is None:
            return  # nobody answers for an id not on the bus
        if instruction == PING:
            info = servo.table[MODEL : MODEL + 2] + bytes([servo.table[FIRMWARE]])
            self._status(ident, 0, bytes(info))
        elif instruction == READ and len(params) == 4:
            address = int.from_bytes(params[:2], "little")
            size = int.from_bytes(params[2:], "little")
            if address + size > TABLE:
                self._status(ident, ERR_ACCESS)
            else:
                self._status(ident, 0, bytes(servo.table[address : address + size]))
        elif instruction == WRITE and len(params) >= 3:
            error = self._write(servo, int.from_bytes(params[:2], "little"), params[2:])
            self._status(ident, error)
        else:
            self._status(ident, ERR_INSTRUCTION)

    def _write(self, servo: Servo, address: int, data: bytes) -> int:
        if address + len(data) > TABLE or (address < TORQUE and servo.table[TORQUE]):
            return ERR_ACCESS  # out of the table, or an EEPROM address with torque on
        if address == TORQUE and servo.table[HW_ERROR] and data[:1] == b"\x01":
            return ERR_ACCESS  # a hardware error keeps the torque off until a reboot
        servo.table[address : address + len(data)] = data
        return 0

    def _sync_write(self, params: bytes) -> None:
        address = int.from_bytes(params[:2], "little")
        size = int.from_bytes(params[2:4], "little")
        rest = params[4:]
        for k in range(0, len(rest) - size, size + 1):
            servo = self.servos.get(rest[k])
            if servo is not None:
                self._write(servo, address, rest[k + 1 : k + 1 + size])

    def _status(self, ident: int, error: int, params: bytes = b"") -> None:
        self.output += packet(ident, STATUS, bytes([error]) + params)

    def advance(self, dt: float) -> None:
        for servo in self.servos.values():
            servo.advance(dt)

    def fault(self, kind: str) -> None:
        """``stuck``: every servo stops moving; ``overload``: the hardware error status'
        overload bit, torque off."""
        for servo in self.servos.values():
            if kind == "stuck":
                servo.stuck = True
            elif kind == "overload":
                servo.table[HW_ERROR] = 0x20
                servo.table[TORQUE] = 0
            else:
                raise ValueError(f"unknown Dynamixel fault '{kind}'; known: stuck, overload")
