"""The fault channel: faults injected at a given time (``--fault HOST@T:KIND``, T seconds
after the first RTDE start on any controller) or at once through a Unix socket
(``--fault-socket PATH``: one line ``HOST KIND`` per fault, answered ``ok`` or
``error: ...``).

Kinds: ``protective_stop`` (safety mode 3, safety status bits 2 and 10, the arm stops, the
program stops), ``emergency_stop`` (safety mode 7, bits 6, 7 and 10, the arm stops and
powers off), ``frozen`` (the arm stops following its setpoint and reports no fault),
``drop`` (every connection of the controller closed; new ones refused until cleared),
``kill`` (the emulator process dies at once, SIGKILL), and ``clear`` (undo the faults of a
controller: stops released, the arm moving again, connections accepted again).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from cellengine.emulate.net import Conn

KINDS = ("protective_stop", "emergency_stop", "frozen", "drop", "kill", "clear")


@dataclass(frozen=True)
class Fault:
    host: str
    kind: str
    at: float | None = None  # s after the first RTDE start; None: now


def _checked(host: str, kind: str, at: float | None) -> Fault:
    if not host:
        raise ValueError("no host")
    if kind not in KINDS:
        raise ValueError(f"unknown fault '{kind}'; known: {', '.join(KINDS)}")
    if at is not None and not at >= 0:
        raise ValueError(f"the time must be a number of seconds >= 0, not {at}")
    return Fault(host, kind, at)


def parse_flag(spec: str) -> Fault:
    """``HOST@T:KIND``, e.g. ``127.0.0.2@1.5:protective_stop``."""
    where, colon, kind = spec.rpartition(":")
    host, at, time = where.partition("@")
    if not colon or not at:
        raise ValueError(f"'{spec}' is not HOST@T:KIND")
    try:
        seconds = float(time)
    except ValueError:
        raise ValueError(f"'{time}' in '{spec}' is not a number of seconds") from None
    return _checked(host, kind.strip(), seconds)


def parse_line(line: str) -> Fault:
    """``HOST KIND`` from the fault socket."""
    parts = line.split()
    if len(parts) != 2:
        raise ValueError(f"'{line.strip()}' is not 'HOST KIND'")
    return _checked(parts[0], parts[1], None)


class FaultSession:
    """One client of the fault socket: each line a fault, each answered."""

    def __init__(self, conn: Conn, apply: Callable[[Fault], str | None]) -> None:
        self.conn, self.apply = conn, apply
        self._buf = b""

    def received(self, data: bytes) -> None:
        self._buf += data
        while b"\n" in self._buf:
            raw, self._buf = self._buf.split(b"\n", 1)
            line = raw.decode("utf-8", "replace")
            if not line.strip():
                continue
            try:
                error = self.apply(parse_line(line))
            except ValueError as e:
                error = str(e)
            self.conn.send(b"ok\n" if error is None else f"error: {error}\n".encode())
            self.conn.flush()

    def closed(self) -> None:
        pass
