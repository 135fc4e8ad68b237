"""One GRBL 1.1 controller over USB serial (pyserial): the lab bench's cartesian robot axes.

Lines are streamed with GRBL's character-counting protocol: the bytes of every line sent
and not yet answered (``ok`` or ``error:N``) are counted, and a line is sent only while they
fit in GRBL's 128-byte receive buffer, so the buffer never overflows and GRBL never waits
for the host between lines (send-and-wait would starve its planner on short blocks).
Real-time commands (``?`` status, ``!`` feed hold, 0x18 soft reset) bypass the buffer.

Every answer is read by :meth:`GrblLink.poll`: ``ok``/``error`` settle the oldest line
pending, a ``<...>`` status report updates :attr:`GrblLink.last`, an ``ALARM:N`` is kept in
:attr:`GrblLink.alarm`. A port that goes away raises :class:`GrblLost`.
"""

from __future__ import annotations

import contextlib
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

RX_BUFFER = 128  # GRBL's serial receive buffer (bytes)
WAKE_TIMEOUT = 3.0  # s for the banner after opening (an Arduino resets when opened)
ERRORS = {
    1: "G-code words consist of a letter and a value; letter was not found",
    2: "numeric value format is not valid or missing an expected value",
    3: "Grbl '$' system command was not recognized or supported",
    5: "homing cycle is not enabled via settings",
    9: "G-code locked out during alarm or jog state",
    20: "unsupported or invalid g-code command found in block",
    22: "feed rate has not yet been set or is undefined",
    24: "two G-code commands that both require the use of the XYZ axis words were detected",
}
ALARMS = {
    1: "hard limit triggered: position lost, re-homing is highly recommended",
    2: "soft limit: the motion target exceeds the machine travel",
    3: "reset while in motion: position lost, re-homing is highly recommended",
    8: "homing fail: the cycle failed to clear the limit switch when pulling off",
    9: "homing fail: could not find the limit switch within the search distance",
}


class GrblError(RuntimeError):
    """GRBL answered a line with ``error:N`` or is in alarm."""


class GrblLost(GrblError):
    """The serial port went away (unplugged, closed)."""


@dataclass(frozen=True)
class Status:
    state: str  # Idle, Run, Hold:0, Hold:1, Home, Alarm, ...
    mpos: tuple[float, ...]  # machine position (mm; a rotary axis in degrees)
    planner_free: int | None
    rx_free: int | None
    pins: str
    time: float  # time.perf_counter() when it arrived


def parse_status(text: str, at: float) -> Status:
    """``<Idle|MPos:0.000,0.000,0.000|Bf:15,128|FS:0,0>`` as a :class:`Status`."""
    fields = text.strip("<>").split("|")
    state, pins = fields[0], ""
    mpos: tuple[float, ...] = ()
    bf: tuple[int | None, int | None] = (None, None)
    for f in fields[1:]:
        key, _, value = f.partition(":")
        if key == "MPos":
            mpos = tuple(float(v) for v in value.split(","))
        elif key == "Bf":
            a, b = value.split(",")
            bf = (int(a), int(b))
        elif key == "Pn":
            pins = value
    return Status(state, mpos, bf[0], bf[1], pins, at)


class GrblLink:
    """One controller. ``open`` it, ``command`` (sent and answered one at a time) or
    ``stream`` lines, ``poll`` for answers."""

    def __init__(self, port: str, baud: int = 115200, serial: Any = None) -> None:
        self.port, self.baud = port, baud
        self.serial = serial  # a pyserial Serial (given: tests)
        self.pending: deque[tuple[int, str]] = deque()  # (bytes, line) sent, not answered
        self.last: Status | None = None
        self.alarm: int | None = None
        self.errors: list[tuple[str, int]] = []  # (line, code) answered error:N
        self.messages: list[str] = []  # [MSG:...] and other text
        self.banner = ""
        self._partial = b""
        self._answers: deque[str] = deque()

    # --------------------------------------------------------------------- lifecycle

    def open(self) -> str:
        """Open the port and wait for GRBL's banner (a soft reset asks for it again): the
        version it reports, e.g. ``1.1h``."""
        if self.serial is None:
            import serial

            try:
                self.serial = serial.Serial(self.port, self.baud, timeout=0, write_timeout=1.0)
            except (serial.SerialException, OSError) as e:
                raise GrblLost(f"cannot open {self.port}: {e}") from None
        self.reset()
        deadline = time.monotonic() + WAKE_TIMEOUT
        while "Grbl " not in self.banner:
            self.poll(0.01)
            if time.monotonic() > deadline:
                raise GrblError(f"{self.port}: no GRBL banner within {WAKE_TIMEOUT:g} s")
        return self.banner.split()[1]

    def close(self) -> None:
        if self.serial is not None:
            with contextlib.suppress(OSError):
                self.serial.close()

    # --------------------------------------------------------------------- real time

    def reset(self) -> None:
        """Soft reset (0x18): motion stops, the queue is emptied."""
        self._write(b"\x18")
        self.pending.clear()
        self.banner = ""

    def hold(self) -> None:
        """Feed hold (!): a controlled stop, the queue kept."""
        self._write(b"!")

    def resume(self) -> None:
        """Cycle start (~): what a feed hold stopped or kept from starting goes."""
        self._write(b"~")

    def ask_status(self) -> None:
        self._write(b"?")

    # --------------------------------------------------------------------- lines

    def command(self, line: str, timeout: float = 2.0) -> list[str]:
        """Send one line when nothing else is pending and wait for its answer: the lines
        GRBL printed before ``ok``. GrblError on ``error:N`` or an alarm."""
        self.wait_pending(timeout)
        self._answers.clear()
        self.stream(line)
        deadline = time.monotonic() + timeout
        while self.pending:
            self.poll(0.01)
            if self.alarm is not None:
                raise GrblError(f"{self.port}: ALARM:{self.alarm} ({ALARMS.get(self.alarm, '')})")
            if time.monotonic() > deadline:
                raise GrblError(f"{self.port}: no answer to '{line}' within {timeout:g} s")
        if self.errors and self.errors[-1][0] == line:
            code = self.errors.pop()[1]
            raise GrblError(f"{self.port}: '{line}' answered error:{code} ({ERRORS.get(code, '')})")
        out = list(self._answers)
        self._answers.clear()
        return out

    def settings(self) -> dict[int, float]:
        """``$$``: GRBL's settings by number."""
        out: dict[int, float] = {}
        for text in self.command("$$"):
            key, _, value = text.partition("=")
            if key.startswith("$") and key[1:].isdigit():
                out[int(key[1:])] = float(value)
        return out

    def free(self) -> int:
        """Bytes of GRBL's receive buffer not taken by lines sent and not answered."""
        return RX_BUFFER - sum(n for n, _ in self.pending)

    def fits(self, line: str) -> bool:
        return len(line) + 1 <= self.free()

    def stream(self, line: str) -> None:
        """Send a line that :meth:`fits` (ValueError if it does not: that would overflow
        GRBL's buffer)."""
        data = line.encode("ascii") + b"\n"
        if len(data) > self.free():
            raise ValueError(f"'{line}' does not fit: {self.free()} bytes free")
        self.pending.append((len(data), line))
        self._write(data)

    def wait_pending(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while self.pending:
            self.poll(0.005)
            if self.alarm is not None:
                return
            if time.monotonic() > deadline:
                raise GrblError(f"{self.port}: {len(self.pending)} lines still unanswered")

    def poll(self, wait: float = 0.0) -> None:
        """Read what GRBL sent (waiting up to ``wait`` s for the first byte)."""
        assert self.serial is not None
        deadline = time.monotonic() + wait
        while True:
            try:
                data = self.serial.read(4096)
            except Exception as e:  # pyserial's SerialException, OSError: the port is gone
                raise GrblLost(f"{self.port}: the port went away ({e})") from None
            if data:
                self._take(data)
                return
            if time.monotonic() >= deadline:
                return
            time.sleep(0.0005)

    def _take(self, data: bytes) -> None:
        lines = (self._partial + data).split(b"\n")
        self._partial = lines.pop()
        now = time.perf_counter()
        for raw in lines:
            text = raw.decode("ascii", errors="replace").strip()
            if not text:
                continue
            if text == "ok":
                if self.pending:
                    self.pending.popleft()
            elif text.startswith("error:"):
                line = self.pending.popleft()[1] if self.pending else ""
                self.errors.append((line, int(text[6:] or 0)))
            elif text.startswith("<"):
                self.last = parse_status(text, now)
            elif text.startswith("ALARM:"):
                self.alarm = int(text[6:] or 0)
                self.pending.clear()  # an alarm empties GRBL's queue
            elif text.startswith("Grbl "):
                self.banner = text
            else:
                self.messages.append(text)
                self._answers.append(text)

    def _write(self, data: bytes) -> None:
        assert self.serial is not None
        try:
            self.serial.write(data)
        except Exception as e:
            raise GrblLost(f"{self.port}: the port went away ({e})") from None
