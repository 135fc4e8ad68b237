"""The GRBL client (pyserial, character counting) against the GRBL 1.1 emulator behind a
pseudo-terminal, served in a thread on the wall clock as `cellengine emulate grbl` does."""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from cellengine.drivers.grbl_link import GrblError, GrblLink, GrblLost
from cellengine.emulate.grbl import Grbl
from cellengine.emulate.serial_pty import Port
from tests.drivers.ptys import served


@pytest.fixture
def port() -> Iterator[Port]:
    with served(Grbl()) as (p,):
        yield p


def _idle(link: GrblLink, timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while True:
        link.ask_status()
        link.poll(0.02)
        if link.last is not None and link.last.state == "Idle" and not link.pending:
            return
        assert time.monotonic() < deadline, link.last


def test_open_reads_the_version_and_a_locked_controller_refuses_g_code(port: Port) -> None:
    link = GrblLink(port.path)
    assert link.open() == "1.1h"
    with pytest.raises(GrblError, match=r"error:9 \(G-code locked out during alarm"):
        link.command("G1X-10F600")
    link.command("$X")
    settings = link.settings()
    assert settings[110] == 6000.0 and settings[120] == 500.0 and len(settings) >= 30
    link.ask_status()
    link.poll(0.1)
    assert link.last is not None and link.last.state == "Idle" and link.last.planner_free == 15


def test_streaming_by_character_counting_never_overflows(port: Port) -> None:
    """500 short blocks sent as fast as the counting allows: GRBL's 128-byte buffer never
    loses a byte, every line is answered ok, and the machine ends where the last one goes."""
    link = GrblLink(port.path)
    link.open()
    link.command("$X")
    lines = [f"G1X{-0.2 * k:.3f}Y{-0.1 * k:.3f}F3000" for k in range(1, 501)]
    sent = 0
    while sent < len(lines) or link.pending:
        while sent < len(lines) and link.fits(lines[sent]):
            link.stream(lines[sent])
            sent += 1
            assert sum(n for n, _ in link.pending) <= 128
        link.poll(0.002)
    _idle(link)
    assert port.device.overflows == 0 and link.errors == []
    assert port.device.log[-len(lines) :] == lines
    assert link.last is not None and link.last.mpos[:2] == (-100.0, -50.0)


def test_an_error_answer_is_matched_to_its_line(port: Port) -> None:
    link = GrblLink(port.path)
    link.open()
    link.command("$X")
    link.stream("G1X-1F600")
    link.stream("G7")
    link.stream("G1X-2")
    link.wait_pending(5.0)
    assert link.errors == [("G7", 20)]


def test_an_alarm_is_kept_and_a_lost_port_raises(port: Port) -> None:
    link = GrblLink(port.path)
    link.open()
    link.command("$X")
    port.device.trip(1, pins="X")
    link.poll(0.2)
    assert link.alarm == 1 and not link.pending
    port.faults.append((0.0, "lost"))
    with pytest.raises(GrblLost, match="the port went away"):
        for _ in range(200):
            link.ask_status()
            link.poll(0.01)
