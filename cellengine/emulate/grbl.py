"""An emulated GRBL 1.1 controller: what a cartesian robot's Arduino does with the bytes a
host sends it, for tests of the real client code (drivers/grbl_link.py) over a
pseudo-terminal (emulate/grbl_pty.py).

Emulated as GRBL 1.1 behaves (gnea/grbl wiki, "Grbl v1.1 Interface" and "Commands"):

- a 128-byte serial receive buffer: a host that sends more than it holds loses bytes (the
  emulator counts them: ``overflows``), which is what character counting prevents;
- real-time commands taken out of the stream as they arrive: ``?`` (status report), ``!``
  (feed hold; when idle, the lines that follow are planned and wait), ``~`` (cycle start),
  0x18 (soft reset);
- lines executed when the 15-block planner has room: G-code (G0, G1, G4, G90, G91, G21, F,
  axis words X Y Z A) answered ``ok`` or ``error:N``; ``$$`` (settings), ``$N=V``, ``$I``,
  ``$H`` (homing, answered when done), ``$X`` (unlock);
- motion along the planned blocks with each axis' acceleration ($120...) and rate
  ($110...) limits, planned to stop at the end of the queue, junction speeds from the
  junction deviation ($11);
- alarms: a soft limit (a target outside an axis' travel, ALARM:2), a hard limit (injected,
  ALARM:1), a reset while moving (ALARM:3), homing required after power-up when homing is
  on ($22); in alarm, G-code is refused with error:9 until ``$X`` or ``$H``.

Machine positions are in mm, the travel of each axis from -max_travel to 0 as GRBL has it
after homing towards the positive end.
"""

from __future__ import annotations

import math
import re
from collections import deque
from dataclasses import dataclass, field

RX_BUFFER = 128  # bytes: the serial receive buffer (1.1's ring holds all 128)
PLANNER_BLOCKS = 15
AXES = ("X", "Y", "Z", "A")
BANNER = b"\r\nGrbl 1.1h ['$' for help]\r\n"
RESET = 0x18
# settings a host reads ($$), GRBL 1.1's numbers and defaults but the ones a cell sets
DEFAULTS: dict[int, float] = {
    0: 10, 1: 25, 2: 0, 3: 0, 4: 0, 5: 0, 6: 0, 10: 3, 11: 0.010, 12: 0.002, 13: 0,
    20: 1, 21: 0, 22: 1, 23: 0, 24: 25.0, 25: 500.0, 26: 250, 27: 1.0, 30: 1000, 31: 0,
    32: 0,
    100: 80.0, 101: 80.0, 102: 400.0, 103: 10.0,
    110: 6000.0, 111: 6000.0, 112: 1500.0, 113: 3600.0,
    120: 500.0, 121: 500.0, 122: 200.0, 123: 500.0,
    130: 1500.0, 131: 930.0, 132: 400.0, 133: 0.0,
}  # fmt: skip
NUMBER = re.compile(r"([A-Z])([-+]?(?:\d+\.?\d*|\.\d+))")


@dataclass
class Block:
    target: list[float]  # mm (A: degrees), machine coordinates
    start: list[float]
    feed: float  # mm/min
    dwell: float = 0.0  # s (G4): no motion
    entry: float = 0.0  # mm/s, planned
    progress: float = 0.0  # mm along it

    @property
    def length(self) -> float:
        return math.dist(self.target, self.start)

    def unit(self) -> list[float]:
        n = self.length
        return [(b - a) / n for a, b in zip(self.start, self.target, strict=True)] if n else []


@dataclass
class Grbl:
    """One controller. ``receive`` the host's bytes, ``advance`` the clock, and read what it
    answered from ``output``."""

    settings: dict[int, float] = field(default_factory=lambda: dict(DEFAULTS))
    position: list[float] = field(default_factory=lambda: [0.0] * len(AXES))
    output: bytearray = field(default_factory=bytearray)
    rx: bytearray = field(default_factory=bytearray)
    planner: deque[Block] = field(default_factory=deque)
    state: str = "Idle"  # Idle, Run, Hold:0, Hold:1, Home, Alarm
    alarm: int | None = None
    speed: float = 0.0  # mm/s along the current block
    overflows: int = 0  # bytes lost to a full receive buffer
    log: list[str] = field(default_factory=list)  # every line executed, for tests
    realtime: list[str] = field(default_factory=list)  # every !, ~ and reset (as ^X) taken
    feed: float = 0.0  # the modal feed rate (mm/min)
    relative: bool = False
    homing_left: float = 0.0  # s of homing still to go
    pins: str = ""  # limit switches triggered (status Pn:)
    next_error: bool = False  # the next line is answered error:24 (a fault injected)
    faults: tuple[str, ...] = ("alarm1", "error")
    talks_first: bool = False

    def fault(self, kind: str) -> None:
        """An injected fault: ``alarm1`` (a hard limit switch), ``error`` (the next line
        is answered error:24)."""
        if kind == "alarm1":
            self.trip(1, pins="X")
        elif kind == "error":
            self.next_error = True
        else:
            raise ValueError(f"unknown GRBL fault '{kind}'; known: {', '.join(self.faults)}")

    def __post_init__(self) -> None:
        if self.settings.get(22, 0):
            self.state, self.alarm = "Alarm", None  # homing required after power-up
        self.output += BANNER
        if self.state == "Alarm":
            self.output += b"[MSG:'$H'|'$X' to unlock]\r\n"

    # ------------------------------------------------------------------------ the host

    def receive(self, data: bytes) -> None:
        for byte in data:
            if byte == ord("?"):
                self.output += self.status().encode() + b"\r\n"
            elif byte == ord("!"):
                self.realtime.append("!")
                if self.state == "Run":
                    self.state = "Hold:1"
                elif self.state == "Idle":  # held before it starts: lines queue, wait for ~
                    self.state = "Hold:0"
            elif byte == ord("~"):
                self.realtime.append("~")
                if self.state.startswith("Hold"):
                    self.state = "Run" if self.planner else "Idle"
            elif byte == RESET:
                self.realtime.append("^X")
                self.reset()
            elif len(self.rx) >= RX_BUFFER:
                self.overflows += 1
            else:
                self.rx.append(byte)
                if byte == ord("\n"):  # GRBL takes lines out as they come, planner permitting
                    self._execute_lines()

    def status(self) -> str:
        pos = ",".join(f"{v:.3f}" for v in self.position)
        free = PLANNER_BLOCKS - len(self.planner)
        pins = f"|Pn:{self.pins}" if self.pins else ""
        return (
            f"<{self.state}|MPos:{pos}|Bf:{free},{RX_BUFFER - len(self.rx)}"
            f"|FS:{self.speed * 60.0:.0f},0{pins}>"
        )

    def reset(self) -> None:
        moving = self.speed > 1e-9 and self.state in ("Run", "Hold:1", "Home")
        self.planner.clear()
        self.rx.clear()
        self.speed = 0.0
        self.homing_left = 0.0
        if moving:  # position lost: GRBL requires homing again
            self.state, self.alarm = "Alarm", 3
            self.output += b"ALARM:3\r\n"
        elif self.state != "Alarm":
            self.state = "Idle"
        self.output += BANNER
        if self.state == "Alarm":
            self.output += b"[MSG:'$H'|'$X' to unlock]\r\n"

    def trip(self, alarm: int, pins: str = "") -> None:
        """An alarm from outside the stream (a limit switch: ALARM:1): motion stops at
        once, the queue is lost."""
        self.planner.clear()
        self.speed = 0.0
        self.state, self.alarm, self.pins = "Alarm", alarm, pins
        self.output += f"ALARM:{alarm}\r\n".encode()

    # ------------------------------------------------------------------------ lines

    def _execute_lines(self) -> None:
        while b"\n" in self.rx and len(self.planner) < PLANNER_BLOCKS:
            if self.state == "Home":
                return  # homing runs before anything after it
            end = self.rx.index(b"\n")
            line = self.rx[:end].decode(errors="replace").strip().upper().replace(" ", "")
            del self.rx[: end + 1]
            self.log.append(line)
            if self.next_error:
                self.next_error = False
                self.output += b"error:24\r\n"
                continue
            answer = self._line(line)
            if answer is not None:
                self.output += answer.encode() + b"\r\n"

    def _line(self, line: str) -> str | None:
        if not line:
            return "ok"
        if line == "$$":
            body = "".join(f"${k}={_number(v)}\r\n" for k, v in sorted(self.settings.items()))
            return body + "ok"
        if line == "$I":
            return "[VER:1.1h.20190825:]\r\n[OPT:V,15,128]\r\nok"
        if line == "$X":
            if self.state == "Alarm":
                self.state, self.alarm, self.pins = "Idle", None, ""
                return "[MSG:Caution: Unlocked]\r\nok"
            return "ok"
        if line == "$H":
            if not self.settings.get(22, 0):
                return "error:5"  # homing not enabled
            self.state, self.homing_left, self.alarm = "Home", HOMING_TIME, None
            return None  # ok when done
        if line.startswith("$"):
            m = re.fullmatch(r"\$(\d+)=([-+]?\d*\.?\d+)", line)
            if m is None:
                return "error:3"  # not a valid $ command
            self.settings[int(m[1])] = float(m[2])
            return "ok"
        if self.state == "Alarm":
            return "error:9"  # G-code locked out during alarm
        return self._gcode(line)

    def _gcode(self, line: str) -> str:
        words = NUMBER.findall(line)
        if "".join(a + b for a, b in words) != line:
            return "error:2"  # bad number format or stray characters
        motion: str | None = None
        target = list(self.position)
        moved = False
        dwell = None
        for letter, value in words:
            v = float(value)
            if letter == "G":
                if v in (0, 1):
                    motion = "G0" if v == 0 else "G1"
                elif v == 4:
                    motion = "G4"
                elif v == 90:
                    self.relative = False
                elif v == 91:
                    self.relative = True
                elif v not in (21, 94, 17, 54):
                    return "error:20"  # unsupported command
            elif letter == "F":
                if v <= 0:
                    return "error:22"
                self.feed = v
            elif letter == "P":
                dwell = v
            elif letter in AXES:
                k = AXES.index(letter)
                target[k] = target[k] + v if self.relative else v
                moved = True
            else:
                return "error:20"
        if motion == "G4":
            self.planner.append(Block(list(self._end()), list(self._end()), 0.0, dwell or 0.0))
            if self.state == "Idle":
                self.state = "Run"  # busy until the dwell is over
            return "ok"
        if not moved:
            return "ok"
        if motion == "G1" and self.feed <= 0:
            return "error:22"  # undefined feed rate
        if self.settings.get(20, 0) and not self._within(target):
            self.trip(2)
            return "ok"
        feed = self._rapid() if motion == "G0" else self.feed
        start = self._end()
        block = Block(target, list(start), feed)
        if block.length > 0:
            self.planner.append(block)
            if self.state == "Idle":
                self.state = "Run"
        return "ok"

    def _end(self) -> list[float]:
        return list(self.planner[-1].target) if self.planner else list(self.position)

    def _within(self, target: list[float]) -> bool:
        for k in range(3):
            travel = self.settings.get(130 + k, 0.0)
            if not -travel - 1e-6 <= target[k] <= 1e-6:
                return False
        return True

    def _rapid(self) -> float:
        return min(self.settings.get(110 + k, 1e9) for k in range(len(AXES)))

    # ------------------------------------------------------------------------ motion

    def advance(self, dt: float) -> None:
        """The machine ``dt`` s later."""
        if self.state == "Home":
            self.homing_left -= dt
            if self.homing_left <= 0:
                self.position = [0.0] * len(AXES)
                self.state = "Idle"
                self.output += b"ok\r\n"
                self._execute_lines()
            return
        while dt > 1e-12 and self.planner and self.state in ("Run", "Hold:1"):
            dt = self._move(dt)
        if self.state == "Hold:1" and self.speed <= 1e-9:
            self.state = "Hold:0"
        if self.state == "Run" and not self.planner:
            self.state, self.speed = "Idle", 0.0
            self._execute_lines()

    def _move(self, dt: float) -> float:
        """Along the first block for at most ``dt`` s; the time left."""
        block = self.planner[0]
        if block.dwell > 0 or block.length <= 1e-12:  # a dwell (G4 P0 too), or no motion
            if self.state == "Hold:1":
                return 0.0
            used = min(dt, block.dwell)
            block.dwell -= used
            if block.dwell <= 1e-12:
                self._done()
            return dt - used
        unit = block.unit()
        accel = min(self.settings[120 + k] / abs(u) for k, u in enumerate(unit) if abs(u) > 1e-12)
        rate = min(
            self.settings[110 + k] / 60.0 / abs(u) for k, u in enumerate(unit) if abs(u) > 1e-12
        )
        left = block.length - block.progress
        exit_speed = 0.0 if self.state == "Hold:1" else self._exit_speed(accel)
        # the fastest the tick may end at and still slow to exit_speed by the block's end:
        # v1^2 <= exit^2 + 2 a (left - (v0 + v1) dt / 2), solved for v1
        adt = accel * dt
        inner = adt * adt - 4.0 * (adt * self.speed - exit_speed**2 - 2.0 * accel * left)
        cap = max(0.5 * (-adt + math.sqrt(max(inner, 0.0))), 0.0)
        target = 0.0 if self.state == "Hold:1" else min(block.feed / 60.0, rate, cap)
        # speed changes by at most accel * dt towards what is allowed
        if self.speed < target:
            speed = min(target, self.speed + accel * dt)
        else:
            speed = max(target, self.speed - accel * dt)
        if speed <= 1e-9 and self.state == "Hold:1":
            self.speed = 0.0
            return 0.0
        step = 0.5 * (self.speed + speed) * dt
        if step >= left:  # the block ends within dt
            t = dt * left / max(step, 1e-12)
            self.position = list(block.target)
            self.speed = speed
            self._done()
            return dt - t
        block.progress += step
        self.position = [a + u * block.progress for a, u in zip(block.start, unit, strict=True)]
        self.speed = speed
        return 0.0

    def _exit_speed(self, accel: float) -> float:
        """The speed the first block may end at: what the blocks after it can stop from
        (GRBL plans to stop at the end of its queue), at most the junction's."""
        v = 0.0
        blocks = list(self.planner)
        for i in range(len(blocks) - 1, 0, -1):
            b, prev = blocks[i], blocks[i - 1]
            if b.dwell > 0 or prev.dwell > 0 or not b.length:
                v = 0.0
                continue
            reach = math.sqrt(v * v + 2.0 * accel * b.length)
            v = min(reach, b.feed / 60.0, prev.feed / 60.0, self._junction(prev, b, accel))
        return v

    def _junction(self, a: Block, b: Block, accel: float) -> float:
        ua, ub = a.unit(), b.unit()
        if not ua or not ub:
            return 0.0
        cos = -sum(x * y for x, y in zip(ua, ub, strict=True))  # GRBL's convention
        if cos > 0.999999:
            return 0.0  # a reversal: stop
        if cos < -0.999999:
            return math.inf  # straight on
        sin_half = math.sqrt(0.5 * (1.0 - cos))
        deviation = self.settings.get(11, 0.01)
        return math.sqrt(accel * deviation * sin_half / (1.0 - sin_half))

    def _done(self) -> None:
        self.planner.popleft()
        self._execute_lines()


HOMING_TIME = 1.5  # s an emulated homing cycle takes


def _number(v: float) -> str:
    return str(int(v)) if float(v).is_integer() else f"{v:.3f}"
