"""Emulated GRBL controllers on pseudo-terminals (`cellengine emulate grbl`): each a
:class:`~cellengine.emulate.grbl.Grbl` behind a pty whose slave path a host opens as it would
an Arduino's /dev/ttyACM0. One loop serves them all on the wall clock, every millisecond.

Faults for tests (``--fault I@T:KIND``, controller I at T s after the first byte it got):
``alarm1`` (a hard limit switch), ``lost`` (the port goes away: the pty is closed),
``error`` (the next line is answered ``error:24``)."""

from __future__ import annotations

import json
import os
import select
import time
import tty
from dataclasses import dataclass, field
from typing import IO

from cellengine.emulate.grbl import Grbl

TICK = 0.001  # s between the emulator's steps
FAULTS = ("alarm1", "lost", "error")


@dataclass
class Port:
    grbl: Grbl
    master: int
    slave: int
    path: str
    faults: list[tuple[float, str]] = field(default_factory=list)
    started: float | None = None  # wall time of the first byte received
    closed: bool = False
    next_error: bool = False


def open_port(grbl: Grbl) -> Port:
    master, slave = os.openpty()
    tty.setraw(slave)  # no echo, no line editing: bytes as a USB serial port passes them
    os.set_blocking(master, False)
    return Port(grbl, master, slave, os.ttyname(slave))


def serve(ports: list[Port], stop: list[bool], log: IO[str] | None = None) -> None:
    """Run every controller until ``stop[0]``; each line executed is logged (JSON lines:
    controller, time, line) to ``log``."""
    last = time.monotonic()
    logged = [0] * len(ports)
    while not stop[0]:
        live = [p for p in ports if not p.closed]
        readable, _, _ = select.select([p.master for p in live], [], [], TICK)
        now = time.monotonic()
        for i, p in enumerate(ports):
            if p.closed:
                continue
            if p.master in readable:
                _read(p, now)
            _faults(p, now)
            if p.closed:
                continue
            p.grbl.advance(now - last)
            _write(p)
            if log is not None:
                for line in p.grbl.log[logged[i] :]:
                    log.write(json.dumps({"controller": i, "time": now, "line": line}) + "\n")
                logged[i] = len(p.grbl.log)
                log.flush()
        last = now


def _read(p: Port, now: float) -> None:
    try:
        data = os.read(p.master, 4096)
    except (BlockingIOError, InterruptedError):
        return
    except OSError:  # the host closed its end
        return
    if data and p.started is None:
        p.started = now
    if p.next_error and b"\n" in data:
        p.next_error = False
        head, _, rest = data.partition(b"\n")
        p.grbl.log.append(head.decode(errors="replace").strip())
        p.grbl.output += b"error:24\r\n"
        data = rest
    p.grbl.receive(data)


def _write(p: Port) -> None:
    if not p.grbl.output:
        return
    try:
        n = os.write(p.master, bytes(p.grbl.output))
    except BlockingIOError:
        return
    del p.grbl.output[:n]


def _faults(p: Port, now: float) -> None:
    if p.started is None:
        return
    due = [f for f in p.faults if now - p.started >= f[0]]
    for f in due:
        p.faults.remove(f)
        kind = f[1]
        if kind == "alarm1":
            p.grbl.trip(1, pins="X")
        elif kind == "error":
            p.next_error = True
        elif kind == "lost":
            os.close(p.master)
            os.close(p.slave)
            p.closed = True


def ready_line(ports: list[Port]) -> str:
    return "cellengine emulate grbl: ready: " + " ".join(p.path for p in ports)
