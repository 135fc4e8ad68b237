"""`cellengine emulate ur` against the real ur-rtde clients (rtde_control, rtde_receive,
rtde_io, dashboard_client of the pinned version), each side in its own process, one
loopback address per emulated arm, a deadline on every wait (harness.py)."""

from __future__ import annotations

import itertools
import math
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from cellengine.cli import main
from tests.emulate.harness import (
    ROOT,
    ClientError,
    Emulator,
    Worker,
    free_hosts,
    rtde_packages,
    wait_for,
)

HOME = [0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]
PROTECTIVE, EMERGENCY, STOPPED_FOR_SAFETY = 1 << 2, 1 << 7, 1 << 10


@pytest.fixture
def emulate() -> Iterator[Callable[..., tuple[Emulator, list[str]]]]:
    """Start an emulator on ``n`` free loopback addresses; killed at the end whatever
    happens."""
    started: list[Emulator] = []

    def start(n: int, *extra: str | Callable[[list[str]], list[str]]) -> tuple[Emulator, list[str]]:
        hosts = free_hosts(n)
        args: list[str] = []
        for e in extra:
            args += e(hosts) if callable(e) else [e]
        started.append(Emulator(hosts, *args))
        return started[-1], hosts

    yield start
    for emulator in started:
        emulator.close()


@pytest.fixture
def worker() -> Iterator[Worker]:
    w = Worker()
    yield w
    w.close()


def stable(read: Callable[[], Any], timeout: float = 2.0) -> Any:
    """A reading that no longer changes (two 20 ms apart agree)."""
    last = read()
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        time.sleep(0.02)
        now = read()
        if now == last:
            return now
        last = now
    raise AssertionError(f"still changing after {timeout} s: {last}")


def connect(w: Worker, host: str, prefix: str = "") -> None:
    """Receive, control and IO interfaces (and a dashboard client) to ``host``."""
    w.new(prefix + "r", "receive", host)
    w.new(prefix + "c", "control", host)
    w.new(prefix + "io", "io", host)
    w.new(prefix + "d", "dashboard", host)
    w.call(prefix + "d", "connect")


def q0_flag(q: list[float]) -> Callable[[list[str]], list[str]]:
    return lambda hosts: [a for h in hosts for a in ("--q0", f"{h}={','.join(map(str, q))}")]


def test_ready_connect_and_clean_exit(emulate: Any, worker: Worker) -> None:
    """'ready' with the address; every client connects; the arm is at --q0; the dashboard
    answers as PolyScope 5.11; recipes are parsed by name; SIGTERM ends it with 0."""
    q0 = [0.1, -1.2, 1.3, -1.4, -1.5, 0.6]
    emu, (host,) = emulate(1, q0_flag(q0))
    assert "ready" in emu.ready_line and host in emu.ready_line
    connect(worker, host)
    assert worker.call("r", "getActualQ") == q0
    assert worker.call("r", "getTargetQ") == q0
    assert worker.call("c", "isConnected") and worker.call("c", "isProgramRunning")
    assert (worker.call("r", "getSafetyMode"), worker.call("r", "getRobotMode")) == (1, 7)
    assert worker.call("r", "getRuntimeState") == 2
    assert worker.call("d", "getRobotModel") == "UR5"
    assert worker.call("d", "polyscopeVersion") == "5.11.6.108249"
    assert worker.call("d", "isInRemoteControl") is True
    assert worker.call("d", "running") is True
    # a name the controller does not know is refused, by name
    with pytest.raises(ClientError, match=r"not found by the controller: \[bogus_variable\]"):
        worker.new("bad", "receive", host, 500.0, ["timestamp", "bogus_variable"])
    # the control script's input registers belong to the first control interface
    with pytest.raises(ClientError, match="already in use"):
        worker.new("c2", "control", host)
    assert emu.terminate() == 0
    wait_for(lambda: not worker.call("r", "isConnected"), what="receive connected")
    assert "data packages" in emu.stderr()


def test_movej_takes_a_trapezoid_and_stopj_stops_it(emulate: Any, worker: Worker) -> None:
    """moveJ: 0.8 rad at 1 rad/s and 2 rad/s^2 takes 0.8 / 1 + 1 / 2 = 1.3 s and ends on
    the target; an async moveJ stopped by stopJ stands still short of its target."""
    _, (host,) = emulate(1, q0_flag(HOME))
    connect(worker, host)
    goal = [HOME[0] + 0.8, HOME[1] + 0.4, *HOME[2:]]
    start = time.monotonic()
    assert worker.call("c", "moveJ", goal, 1.0, 2.0) is True
    elapsed = time.monotonic() - start
    assert 1.3 - 0.005 <= elapsed < 1.3 + 0.15, elapsed  # a tick's slack: clocks differ
    # the receive interface may be a package behind the control interface
    wait_for(lambda: worker.call("r", "getActualQd") == [0.0] * 6, 1, "standing")
    actual = worker.call("r", "getActualQ")
    assert max(abs(a - g) for a, g in zip(actual, goal, strict=True)) < 1e-3

    assert worker.call("c", "moveJ", HOME, 1.0, 2.0, True) is True  # async: at once
    time.sleep(0.4)
    assert worker.call("c", "getAsyncOperationProgress") >= 0  # running
    assert abs(worker.call("r", "getActualQd")[0]) > 0.5
    worker.call("c", "stopJ", 4.0, False)
    wait_for(lambda: worker.call("r", "getActualQd") == [0.0] * 6, 1, "stopped")
    stopped = worker.call("r", "getActualQ")
    assert HOME[0] + 0.1 < stopped[0] < goal[0] - 0.1  # stopped on the way
    assert worker.call("c", "getAsyncOperationProgress") < 0  # no longer running
    time.sleep(0.1)
    assert worker.call("r", "getActualQ") == stopped


# 1 s of servoJ on joint 0: a 0.2 rad, 0.5 Hz sine about HOME, lookahead 0.1 s, gain 300
SINE: dict[str, Any] = {
    "control": "c",
    "receive": "r",
    "q0": HOME,
    "joint": 0,
    "amplitude": 0.2,
    "frequency": 0.5,
    "seconds": 1.0,
    "lookahead": 0.1,
    "gain": 300,
}


def test_servoj_at_500_hz_follows_a_sine(emulate: Any, worker: Worker) -> None:
    """servoJ streamed for 1 s with initPeriod / waitPeriod: the arm follows the commanded
    sine (0.2 rad, 0.5 Hz) delayed by about lookahead / 2 + 1 / gain (53 ms at 0.1 s and
    300) within 0.02 rad (0.002 on an idle machine); meanwhile a bare RTDE reader gets 500
    packages a second."""
    _, (host,) = emulate(1, q0_flag(HOME))
    connect(worker, host)
    worker.send(op="servo_sine", **SINE)
    packages = rtde_packages(host, "timestamp,actual_q", 0.8)
    run = Worker.check(worker.answer(timeout=15))
    cmd, actual = run["commanded"], run["actual"]
    assert run["stopped"] is True
    errors = {
        lag: max(abs(actual[k] - cmd[k - lag]) for k in range(60, len(cmd))) for lag in range(0, 60)
    }
    best = min(errors, key=errors.__getitem__)
    assert 20 <= best <= 32, best  # ticks of 2 ms
    assert errors[best] < 0.02, errors[best]
    assert errors[0] < 0.05  # undelayed: about amplitude * omega * delay
    # the data rate a client gets while the arm is streamed to
    stamps = [struct.unpack_from(">d", p, 1)[0] for _, p in packages]
    rate = (len(packages) - 1) / (packages[-1][0] - packages[0][0])
    assert rate == pytest.approx(500, rel=0.2), rate  # 500.0 idle, 430 on a crowded CPU
    # controller time: 2 ms a package; a late tick is caught up and only its last package
    # sent (a controller short of time skips packages): none on an idle machine, 7 to 18 %
    # with the two cores crowded by busy loops
    steps = [round((b - a) / 0.002, 6) for a, b in itertools.pairwise(stamps)]
    assert all(n >= 1 and n == int(n) for n in steps)
    assert sum(n - 1 for n in steps) <= 0.25 * len(steps)


def test_servoj_alone_feeds_the_watchdog(emulate: Any, worker: Worker) -> None:
    """The watchdog watches input_int_register_0, which every servoJ writes: 1 s of servoJ
    without a kick keeps a 2 Hz watchdog from stopping the script. (A kick after each
    servoJ would overwrite its command before the script reads it: next test.)"""
    _, (host,) = emulate(1, q0_flag(HOME))
    connect(worker, host)
    assert worker.call("c", "setWatchdog", 2.0) is True
    run = worker.loop(
        "servo_sine", **SINE
    )  # fails if a servoJ returns False: the script would have been stopped
    assert run["stopped"] is True
    time.sleep(0.7)  # and with nothing written for more than 0.5 s, it is stopped
    assert worker.call("c", "isProgramRunning") is False


def test_registers_hold_the_last_value_received() -> None:
    """The controller alone: a servoJ command overwritten by a 0 before the script's tick
    is never seen; one that stays until the tick starts the servo. Through the real
    client, servoJ then kickWatchdog every 2 ms made the arm lag 0.03 to 0.07 rad behind a
    0.2 rad, 0.5 Hz sine instead of 0.002 on an idle machine (on a busy one the two
    packages fall into different ticks more often and the effect is smaller)."""
    from cellengine.emulate.arm import Hold, Servo
    from cellengine.emulate.controller import Controller

    ctl = Controller("arm", [0.0] * 6, "UR5", lambda _: None)
    ctl.start_program("rtde_control", "def rtde_control():\n    global reg_offset_int = 0\nend\n")
    args = [0.1, 0, 0, 0, 0, 0, 0, 0, 0.002, 0.03, 2000]
    servo = {"input_int_register_0": 11} | {
        f"input_double_register_{i}": float(v) for i, v in enumerate(args)
    }
    ctl.write_inputs(servo)
    ctl.write_inputs({"input_int_register_0": 0})  # kickWatchdog
    ctl.tick()
    assert isinstance(ctl.arm.motion, Hold) and ctl.arm.actual == [0.0] * 6
    ctl.write_inputs(servo)
    for _ in range(100):
        ctl.tick()
    assert isinstance(ctl.arm.motion, Servo)
    assert ctl.arm.actual[0] == pytest.approx(0.1, abs=1e-6)
    assert ctl.value("output_int_register_0") == 1  # ready


def test_speedj_then_speedstop(emulate: Any, worker: Worker) -> None:
    _, (host,) = emulate(1, q0_flag(HOME))
    connect(worker, host)
    qd = [0.3, 0.0, 0.0, 0.0, 0.0, -0.2]
    moving = worker.loop("speed", control="c", receive="r", qd=qd, a=2.0, seconds=0.5)
    assert moving["qd"] == pytest.approx(qd, abs=1e-9)
    assert worker.call("c", "speedStop", 1.0) is True  # blocks until the arm stands
    wait_for(lambda: worker.call("r", "getActualQd") == [0.0] * 6, 1, "standing")
    q = worker.call("r", "getActualQ")
    # 0.5 s at up to 0.3 rad/s, then 0.045 rad to stop at 1 rad/s^2
    assert 0.12 < q[0] - HOME[0] < 0.2
    assert q[5] < HOME[5] - 0.06


def test_digital_outputs_and_the_watchdog(emulate: Any, worker: Worker) -> None:
    """setStandardDigitalOut shows in the digital output bits; a watchdog kicked keeps the
    control script running, one not kicked stops it (and the next command fails)."""
    emu, (host,) = emulate(1)
    connect(worker, host)
    assert worker.call("io", "setStandardDigitalOut", 3, True) is True
    wait_for(lambda: worker.call("r", "getActualDigitalOutputBits") == 1 << 3, 2, "DO 3 on")
    assert worker.call("io", "setStandardDigitalOut", 5, True) is True
    wait_for(lambda: worker.call("r", "getActualDigitalOutputBits") == 0b101000, 2, "DO 5")
    assert worker.call("io", "setStandardDigitalOut", 3, False) is True
    wait_for(lambda: worker.call("r", "getActualDigitalOutputBits") == 1 << 5, 2, "DO 3 off")
    assert worker.call("r", "getDigitalOutState", 5) is True
    assert worker.call("io", "setSpeedSlider", 0.5) is True
    wait_for(lambda: worker.call("r", "getSpeedScaling") == 0.5, 2, "speed slider")
    assert worker.call("r", "getTargetSpeedFraction") == 0.5

    assert worker.call("c", "setWatchdog", 10.0) is True
    assert worker.loop("kick", control="c", hz=100, seconds=0.5) == 50
    assert worker.call("c", "isProgramRunning") is True
    time.sleep(0.3)  # no kick for 0.3 s > 1 / 10 Hz
    assert worker.call("c", "isProgramRunning") is False
    assert worker.call("c", "moveJ", HOME, 1.0, 1.0) is False
    assert "RTDE watchdog" in emu.stderr()
    assert worker.call("c", "reuploadScript") is True
    wait_for(lambda: worker.call("c", "isProgramRunning"), 2, "script running again")


def test_two_arms_at_once(emulate: Any, worker: Worker) -> None:
    _, hosts = emulate(
        2,
        lambda h: ["--q0", f"{h[0]}=0,0,0,0,0,0", "--q0", f"{h[1]}=1,1,1,1,1,1"],
        lambda h: ["--model", f"{h[1]}=ur10"],
    )
    for i, host in enumerate(hosts):
        connect(worker, host, f"{i}")
    assert [worker.call(f"{i}d", "getRobotModel") for i in (0, 1)] == ["UR5", "UR10"]
    assert worker.call("0r", "getActualQ") == [0.0] * 6
    assert worker.call("1r", "getActualQ") == [1.0] * 6
    goals = [[0.3] * 6, [0.7] * 6]
    for i, goal in enumerate(goals):
        assert worker.call(f"{i}c", "moveJ", goal, 1.0, 3.0, True) is True
    for i, goal in enumerate(goals):
        wait_for(lambda i=i, g=goal: worker.call(f"{i}r", "getActualQ") == g, 3, f"arm {i}")
    assert worker.call("1c", "moveJ", [1.0] * 6, 1.0, 3.0) is True
    assert worker.call("0r", "getActualQ") == goals[0]  # the other arm did not move


def test_faults_from_the_command_line(emulate: Any, worker: Worker) -> None:
    """--fault HOST@T:KIND, T s after the first RTDE start: a protective stop then a dropped
    connection on one arm, an emergency stop on another, a frozen arm on the third, and
    the emulator killed."""
    emu, (a, b, c) = emulate(
        3,
        lambda h: [f"--fault={h[0]}@0.8:protective_stop", f"--fault={h[1]}@0.8:emergency_stop"],
        lambda h: [f"--fault={h[2]}@0.8:frozen", f"--fault={h[0]}@1.4:drop"],
        lambda h: [f"--fault={h[1]}@2.0:kill"],
    )
    worker.new("0r", "receive", a)  # the first RTDE start: the faults' clock starts
    t0 = worker.call("0r", "getTimestamp")
    worker.new("2r", "receive", c)
    worker.new("2c", "control", c)
    assert worker.call("2c", "moveJ", [1.0] * 6, 0.5, 1.0, True) is True  # under way
    worker.new("0c", "control", a)
    worker.new("1r", "receive", b)

    wait_for(lambda: worker.call("0r", "getSafetyMode") == 3, 2, "protective stop")
    # t0 is the first package's time, or a later one when the machine is busy
    assert worker.call("0r", "getTimestamp") - t0 >= 0.8 - 0.05
    bits = worker.call("0r", "getSafetyStatusBits")
    assert bits & PROTECTIVE and bits & STOPPED_FOR_SAFETY and not bits & 1
    assert worker.call("0r", "isProtectiveStopped") is True
    wait_for(lambda: not worker.call("0c", "isProgramRunning"), 2, "script stopped")
    assert worker.call("0c", "moveJ", HOME, 1.0, 1.0) is False  # as a real controller's

    wait_for(lambda: worker.call("1r", "getSafetyMode") == 7, 2, "emergency stop")
    assert worker.call("1r", "getSafetyStatusBits") & EMERGENCY
    assert worker.call("1r", "isEmergencyStopped") is True
    assert worker.call("1r", "getRobotMode") == 3  # powered off

    frozen = stable(lambda: worker.call("2r", "getActualQ"))
    assert 0.01 < frozen[0] < 0.9  # it had moved
    wait_for(lambda: worker.call("2r", "getTargetQ")[0] > frozen[0] + 0.05, 3, "target moves")
    assert worker.call("2r", "getActualQ") == frozen  # the arm stopped following it
    assert worker.call("2r", "getSafetyMode") == 1  # and says nothing

    wait_for(lambda: not worker.call("0r", "isConnected"), 3, "receive connected")
    wait_for(lambda: not worker.call("0c", "isConnected"), 3, "control connected")
    assert worker.call("2r", "isConnected")  # the other controllers still serve

    assert emu.wait(3) < 0  # killed
    wait_for(lambda: not worker.call("2r", "isConnected"), 3, "connected after the kill")


def test_faults_from_the_socket(emulate: Any, worker: Worker) -> None:
    """The fault socket: each kind at once, each cleared (after an emergency stop the arm
    is powered off until the dashboard powers it on and releases the brakes)."""
    emu, (host,) = emulate(1, q0_flag(HOME))
    connect(worker, host)
    assert emu.fault(host, "bogus") == (
        "error: unknown fault 'bogus'; known: protective_stop, emergency_stop, frozen, drop, "
        "kill, clear"
    )
    assert emu.fault("10.1.2.3", "drop").startswith("error: no emulated controller at")

    worker.send(op="call", name="c", method="moveJ", args=[[1.0] * 6, 0.5, 1.0])
    time.sleep(0.3)
    assert emu.fault(host, "protective_stop") == "ok"
    assert Worker.check(worker.answer()) is False  # the moveJ under way fails
    wait_for(lambda: worker.call("r", "getSafetyStatusBits") & PROTECTIVE, 2, "bit 2")
    assert worker.call("r", "getSafetyMode") == 3
    with pytest.raises(ClientError, match="until 5s after occurrence"):
        worker.call("d", "unlockProtectiveStop")
    assert emu.fault(host, "clear") == "ok"
    wait_for(lambda: worker.call("r", "getSafetyMode") == 1, 2, "cleared")
    assert worker.call("c", "reuploadScript") is True
    wait_for(lambda: worker.call("c", "isProgramRunning"), 2, "script running")
    assert worker.call("c", "moveJ", HOME, 1.0, 2.0) is True

    assert emu.fault(host, "emergency_stop") == "ok"
    wait_for(lambda: worker.call("r", "getSafetyMode") == 7, 2, "emergency stop")
    assert worker.call("r", "getSafetyStatusBits") & (EMERGENCY | 1 << 6) == EMERGENCY | 1 << 6
    assert emu.fault(host, "clear") == "ok"
    wait_for(lambda: worker.call("r", "getSafetyMode") == 1, 2, "released")
    assert worker.call("r", "getRobotMode") == 3
    worker.call("d", "powerOn")
    worker.call("d", "brakeRelease")
    wait_for(lambda: worker.call("r", "getRobotMode") == 7, 2, "running")
    assert worker.call("c", "reuploadScript") is True
    wait_for(lambda: worker.call("c", "isProgramRunning"), 2, "script running")

    assert emu.fault(host, "frozen") == "ok"
    assert worker.call("c", "moveJ", [0.5, *HOME[1:]], 1.0, 2.0) is True  # the target goes
    assert worker.call("r", "getActualQ") == HOME  # the arm does not
    assert emu.fault(host, "clear") == "ok"
    assert worker.call("c", "moveJ", [0.2, *HOME[1:]], 1.0, 2.0) is True
    wait_for(lambda: abs(worker.call("r", "getActualQ")[0] - 0.2) < 1e-3, 1, "moves again")

    assert emu.fault(host, "drop") == "ok"
    wait_for(lambda: not worker.call("r", "isConnected"), 3, "receive connected")
    wait_for(lambda: not worker.call("c", "isConnected"), 3, "control connected")
    with pytest.raises(ClientError, match="Could not connect"):
        worker.new("r2", "receive", host)
    assert emu.fault(host, "clear") == "ok"
    assert worker.call("r", "reconnect") is True
    assert worker.call("c", "reconnect") is True
    assert worker.call("c", "moveJ", HOME, 1.0, 2.0) is True
    worker.call("c", "triggerProtectiveStop")  # the control script's own protective stop
    wait_for(lambda: worker.call("r", "isProtectiveStopped"), 2, "triggered protective stop")

    assert emu.fault(host, "kill") == "ok"
    assert emu.wait(3) < 0
    wait_for(lambda: not worker.call("r", "isConnected"), 3, "connected after the kill")


def test_sigint_stops_it_cleanly_too(emulate: Any) -> None:
    """SIGINT as SIGTERM; and a second emulator on the same address exits 2 at once."""
    emu, (host,) = emulate(1)
    assert emu.socket_path is not None and emu.socket_path.exists()
    args = [sys.executable, "-m", "cellengine.cli", "emulate", "ur", "--host", host]
    second = subprocess.run(args, cwd=ROOT, capture_output=True, text=True, timeout=20)
    assert second.returncode == 2
    assert "cannot listen: [Errno 98] Address already in use" in second.stderr
    assert "ready" not in second.stdout
    emu.proc.send_signal(signal.SIGINT)
    assert emu.wait(5) == 0
    assert not emu.socket_path.exists()  # the fault socket is removed
    with socket.socket() as s:  # its ports are free again
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind((host, 30004))


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--q0", "127.0.0.2=1,2,3"], "--q0 127.0.0.2: six joint angles in rad, not '1,2,3'"),
        (["--q0", "127.0.0.9=0,0,0,0,0,0"], "not HOST=... for one of the --host"),
        (["--fault", "127.0.0.2@x:drop"], "'x' in '127.0.0.2@x:drop' is not a number"),
        (["--fault", "127.0.0.2@1:melt"], "unknown fault 'melt'"),
        (["--fault", "127.0.0.9@1:drop"], "127.0.0.9 is not one of the --host"),
    ],
)
def test_usage_errors(args: list[str], message: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["emulate", "ur", "--host", "127.0.0.2", *args]) == 2
    assert message in capsys.readouterr().err


def test_joint_moves_are_exact_on_the_tick() -> None:
    """The arm model alone: a moveJ's profile is deterministic and ends exactly on time."""
    from cellengine.emulate.arm import DT, Arm, JointMove

    arm = Arm([0.0] * 6)
    move = JointMove(arm.target, [0.8, 0.4, 0, 0, 0, 0], 1.0, 2.0)
    arm.start(move)
    ticks = 0
    while not move.done:
        arm.step(1.0)
        ticks += 1
    assert ticks == round(1.3 / DT)
    assert arm.actual == [0.8, 0.4, 0, 0, 0, 0]
    assert max(abs(v) for v in arm.target_qd) == 0.0
    assert math.isclose(move.duration, 1.3)
