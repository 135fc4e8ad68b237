"""Emulated serial devices on pseudo-terminals (`cellengine emulate grbl|loadcell`): each a
:class:`Device` (a GRBL controller, a load cell) behind a pty whose slave path a host opens
as it would an Arduino's /dev/ttyACM0. One loop serves them all on the wall clock, every
millisecond.

Faults for tests (``--fault I@T:KIND``, device I at T s after it was first written to, or
after it started for a device that talks first): ``lost`` (the port goes away: the pty is
closed) for any device, and the device's own (:attr:`Device.faults`)."""

from __future__ import annotations

import json
import os
import select
import sys
import time
import traceback
import tty
from dataclasses import dataclass, field
from typing import IO, Protocol

TICK = 0.001  # s between the emulator's steps


class Device(Protocol):
    output: bytearray  # what it sends the host, taken by the loop
    log: list[str]  # every line it executed or printed, for tests and --log
    faults: tuple[str, ...]  # the faults it takes besides 'lost'
    talks_first: bool  # it sends without being written to (a load cell's readings)

    def receive(self, data: bytes) -> None: ...
    def advance(self, dt: float) -> None: ...
    def fault(self, kind: str) -> None: ...


@dataclass
class Port:
    device: Device
    master: int
    slave: int
    path: str
    faults: list[tuple[float, str]] = field(default_factory=list)
    started: float | None = None  # wall time faults count from
    closed: bool = False


def open_port(device: Device) -> Port:
    master, slave = os.openpty()
    tty.setraw(slave)  # no echo, no line editing: bytes as a USB serial port passes them
    os.set_blocking(master, False)
    return Port(device, master, slave, os.ttyname(slave))


def replug(p: Port) -> None:
    """A port back after its ``lost`` fault, as a USB device plugged in again: a new
    terminal (a new path) for the same device, whose state is kept (a controller that kept
    its power, as with a USB cable pulled out and back)."""
    master, slave = os.openpty()
    tty.setraw(slave)
    os.set_blocking(master, False)
    p.master, p.slave, p.path = master, slave, os.ttyname(slave)
    p.started = time.monotonic() if p.device.talks_first else None
    p.closed = False


def serve(ports: list[Port], stop: list[bool], log: IO[str] | None = None) -> None:
    """Run every controller until ``stop[0]``; each line executed is logged (JSON lines:
    controller, time, line) to ``log``. An emulator's own error is printed before it stops
    the loop: in a test's thread it would otherwise end silently, and every device with it."""
    try:
        _serve(ports, stop, log)
    except Exception:
        traceback.print_exc(file=sys.stderr)
        raise


def _serve(ports: list[Port], stop: list[bool], log: IO[str] | None) -> None:
    last = time.monotonic()
    logged = [0] * len(ports)
    for p in ports:
        if p.device.talks_first:
            p.started = last
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
            p.device.advance(now - last)
            _write(p)
            if log is not None:
                for line in p.device.log[logged[i] :]:
                    log.write(json.dumps({"device": i, "time": now, "line": line}) + "\n")
                logged[i] = len(p.device.log)
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
    p.device.receive(data)


def _write(p: Port) -> None:
    if not p.device.output:
        return
    try:
        n = os.write(p.master, bytes(p.device.output))
    except BlockingIOError:
        return
    del p.device.output[:n]


def _faults(p: Port, now: float) -> None:
    if p.started is None:
        return
    due = [f for f in p.faults if now - p.started >= f[0]]
    for f in due:
        p.faults.remove(f)
        if f[1] == "lost":
            os.close(p.master)
            os.close(p.slave)
            p.closed = True
        else:
            p.device.fault(f[1])


def ready_line(what: str, ports: list[Port]) -> str:
    return f"cellengine emulate {what}: ready: " + " ".join(p.path for p in ports)
