"""An arm's process (ur_arm.py) through its link: whatever happens to the process (a crash,
a hang, an error in the vendor library), the driver's process gets a LinkError in time and
is never itself crashed or blocked. Real processes: mostly without a controller (an
address where none answers); the watchdog's kicks against an emulated one."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from cellengine.drivers.ur_link import ArmLink, LinkError, exchange
from tests.conftest import ROOT
from tests.emulate.harness import Emulator, free_hosts, wait_for

NOWHERE = "127.0.0.9"  # no controller answers here


def test_a_vendor_error_is_answered_and_the_process_serves_on() -> None:
    link = ArmLink("left", NOWHERE)
    try:
        with pytest.raises(LinkError) as e:
            link.call("model", timeout=10.0)
        assert not e.value.lost and e.value.arm == "left" and e.value.why
        link.call("idle", False, timeout=2.0)  # still serving
        assert link.live
    finally:
        link.close(2.0)
    assert link.process.poll() is not None and not link.live


def test_a_crashed_process_is_a_lost_link_naming_the_signal() -> None:
    link = ArmLink("right", NOWHERE)
    link.call("idle", False, timeout=5.0)
    os.kill(link.process.pid, signal.SIGSEGV)
    with pytest.raises(LinkError) as e:
        link.call("idle", False, timeout=2.0)
    assert e.value.lost and e.value.why == "its process crashed (SIGSEGV)"
    with pytest.raises(LinkError, match="crashed"):  # nothing more is asked of it
        link.send("idle", False)
    link.close(1.0)


def test_a_process_that_does_not_answer_in_time_is_killed() -> None:
    link = ArmLink("left", NOWHERE)
    link.call("idle", False, timeout=5.0)
    os.kill(link.process.pid, signal.SIGSTOP)
    t0 = time.perf_counter()
    with pytest.raises(LinkError) as e:
        link.call("idle", False, timeout=0.2)
    assert time.perf_counter() - t0 < 2.0
    assert e.value.lost and e.value.why == "no answer within 0.2 s"
    assert link.process.poll() == -signal.SIGKILL


def test_exchange_asks_every_arm_at_once_and_keeps_each_answer() -> None:
    links = {"left": ArmLink("left", NOWHERE), "right": ArmLink("right", NOWHERE)}
    try:
        for link in links.values():
            link.call("idle", False, timeout=5.0)
        os.kill(links["right"].process.pid, signal.SIGKILL)
        answers = exchange(links, {arm: ("idle", False) for arm in links}, 1.0)
        assert answers["left"] is None
        assert isinstance(answers["right"], LinkError) and answers["right"].lost
        assert "SIGKILL" in answers["right"].why
    finally:
        for link in links.values():
            link.close(1.0)


def test_an_answer_no_one_waited_for_is_dropped_before_the_next_request() -> None:
    link = ArmLink("left", NOWHERE)
    try:
        link.send("idle", False)  # as if the caller were interrupted before receiving
        with pytest.raises(LinkError) as e:  # the next answer is the next request's
            link.call("read", timeout=5.0)
        assert e.value.why == f"not connected to {NOWHERE} yet"
    finally:
        link.close(2.0)


def test_an_arm_process_ends_when_the_driver_process_is_killed() -> None:
    """SIGKILL on the driver's process: its arms' processes see their socket close and end
    (closing their connections; the controllers' watchdogs stop the arms)."""
    code = (
        "from cellengine.drivers.ur_link import ArmLink\n"
        f"link = ArmLink('left', {NOWHERE!r})\n"
        "link.call('idle', False, timeout=5.0)\n"
        "print(link.process.pid, flush=True)\n"
        "import time; time.sleep(60)\n"
    )
    driver = subprocess.Popen(
        [sys.executable, "-c", code], cwd=ROOT, stdout=subprocess.PIPE, text=True
    )
    try:
        assert driver.stdout is not None
        pid = int(driver.stdout.readline())
        driver.kill()
        driver.wait(5.0)
        deadline = time.monotonic() + 5.0
        while _running(pid):
            assert time.monotonic() < deadline, "the arm's process outlived the driver's"
            time.sleep(0.01)
    finally:
        driver.kill()


def _running(pid: int) -> bool:
    """Whether ``pid`` runs (an orphan is reaped by init; a zombie counts as ended)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(") ")[-1][0] != "Z"
    except FileNotFoundError:
        return False


def test_an_idle_arm_process_kicks_the_watchdog_however_often_it_is_asked() -> None:
    """Between segments the arm's process kicks the RTDE watchdog every KICK_PERIOD, also
    while requests come back to back (they leave it no quiet moment); once told to stop
    kicking, the emulated controller's watchdog stops the control script."""
    (host,) = free_hosts(1)
    emulator = Emulator([host])
    link = ArmLink("left", host)
    try:
        link.call("connect_receive", timeout=10.0)
        link.call("connect_control", timeout=10.0)
        assert link.call("watchdog", 10.0, timeout=5.0) is True
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            link.call("read", timeout=1.0)
        time.sleep(0.3)
        assert "RTDE watchdog" not in emulator.stderr(), emulator.stderr()[-2000:]
        link.call("idle", False, timeout=1.0)
        wait_for(lambda: "RTDE watchdog" in emulator.stderr(), timeout=2.0, what="watchdog")
        link.call("disconnect", timeout=5.0)
    finally:
        link.close(5.0)
        emulator.close()
