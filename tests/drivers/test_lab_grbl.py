"""The lab driver (``driver: {kind: lab}``) on two emulated GRBL 1.1 controllers behind
pseudo-terminals: configure checks each controller's settings against the cell's joints,
activate homes or refuses an alarm, a segment of a lab plan is streamed to both from one
clock, and an alarm on one stops both with a feed hold."""

from __future__ import annotations

import shutil
import threading
import time
from collections.abc import Iterator
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.lab  # noqa: F401  (registers the lab skills)
from cellengine.drivers.fault import DriverFault, DriverRefused
from cellengine.drivers.lab import LabBenchDriver
from cellengine.emulate.grbl import DEFAULTS, Grbl
from cellengine.emulate.serial_pty import Port, open_port, serve
from cellengine.info.load import load_plan
from cellengine.pipeline import Compiled, compile_plan
from cellengine.runner.driver import joint_specs
from tests.conftest import CELLS

PLAN = CELLS / "lab_bench" / "plan_relocate.yaml"
# what the lab cell's joints need (mm/min, mm/s^2, mm; A in degrees), with room
SETTINGS = {110: 30000.0, 111: 30000.0, 112: 6000.0, 113: 20000.0}
SETTINGS |= {120: 1000.0, 121: 1000.0, 122: 200.0, 123: 500.0}
SETTINGS |= {130: 1500.0, 131: 1500.0, 132: 400.0}
AXES = "{z: {letter: Z, sign: -1}, x: {letter: X, sign: -1}, y: {letter: Y, sign: -1}, "
AXES_1 = AXES + "roll: {letter: A}}"
AXES_2 = AXES + "turn: {letter: A}}"


@cache
def _compiled() -> Compiled:
    return compile_plan(PLAN)


def _machine(q: np.ndarray) -> list[float]:
    """A robot's (z, x, y, rotation) as GRBL's machine position under AXES."""
    return [-q[1] * 1000.0, -q[2] * 1000.0, -q[0] * 1000.0, float(np.degrees(q[3]))]


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[tuple[Path, list[Port]]]:
    """Two emulated controllers where the plan starts, unlocked, and a copy of the lab
    cell driven by them."""
    q0 = _compiled().program.segments[0].trajectory.q[0]
    ports = []
    for k in range(2):
        grbl = Grbl({**DEFAULTS, **SETTINGS, 22: 0.0})
        grbl.position = _machine(q0[4 * k : 4 * k + 4])
        ports.append(open_port(grbl))
    stop = [False]
    thread = threading.Thread(target=serve, args=(ports, stop), daemon=True)
    thread.start()
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "lab_bench", folder)
    cell = folder / "cell.yaml"
    driver = (
        f"driver: {{kind: lab, robots: {{robot1: {{port: {ports[0].path}, axes: {AXES_1}}}, "
        f"robot2: {{port: {ports[1].path}, axes: {AXES_2}}}}}}}"
    )
    text = cell.read_text()
    cell.write_text(text.replace("driver: {kind: sim, mass_noise: 0.2}", driver))
    yield folder, ports
    stop[0] = True
    thread.join(timeout=2)


def _driver(folder: Path) -> LabBenchDriver:
    c = _compiled()
    world = load_plan(folder / "plan_relocate.yaml").world
    joints = {name: arm.joint_names for name, arm in c.cell.arms.items()}
    return LabBenchDriver(world.cell, joints, specs=joint_specs(c.cell))


def test_a_controller_too_slow_for_the_cell_is_refused_naming_the_setting(
    bench: tuple[Path, list[Port]],
) -> None:
    folder, ports = bench
    ports[1].device.settings[121] = 500.0  # robot2's Y axis: its y joint needs 600 mm/s^2
    driver = _driver(folder)
    with pytest.raises(DriverRefused) as e:
        driver.configure()
    assert str(e.value) == (
        f"lab driver: robot 'robot2' at {ports[1].path}: $121 (acceleration of axis Y) is "
        "500.0 mm/s^2; the cell's 'robot2_y' needs at least 600 mm/s^2"
    )
    assert driver.links == {}  # nothing left open


def test_a_segment_streams_to_both_controllers_and_ends_where_it_should(
    bench: tuple[Path, list[Port]],
) -> None:
    folder, ports = bench
    c = _compiled()
    segment = c.program.segments[0]  # robot2 to vial5, robot1 holding still
    with _driver(folder) as driver:
        driver.configure()
        driver.activate()
        assert driver.versions == {"robot1": "1.1h", "robot2": "1.1h"}
        played = driver.execute(segment)
        assert played.completed and len(played.t) >= segment.trajectory.duration * 10
        end = segment.trajectory.q[-1]
        assert np.allclose(driver.joint_state(), end, atol=1e-6 + 1e-3)
    assert all(p.device.overflows == 0 for p in ports)
    moves = [line for line in ports[1].device.log if line.startswith("G1")]
    assert len(moves) >= segment.trajectory.duration / 0.05 - 2
    assert not any(line.startswith("G1") for line in ports[0].device.log)  # robot1 dwells


def test_an_alarm_on_one_controller_holds_both(bench: tuple[Path, list[Port]]) -> None:
    folder, ports = bench
    c = _compiled()
    segment = c.program.segments[0]
    ports[1].faults.append((1.0, "alarm1"))  # robot2's X limit switch, 1 s in
    driver = _driver(folder)
    driver.configure()
    driver.activate()
    with pytest.raises(DriverFault) as e:
        driver.execute(segment)
    assert e.value.fault.kind == "alarm" and e.value.fault.arm == "robot2"
    assert "ALARM:1 (hard limit triggered" in str(e.value)
    # robot1's controller got its feed hold at once (well within 20 ms of detection), then
    # a reset that empties its queue
    (latency,) = driver.hold_latencies
    assert latency < 0.02
    driver.finalize()
    held = ports[0].device.realtime
    deadline = time.monotonic() + 2.0
    while "^X" not in held[4:] and time.monotonic() < deadline:
        time.sleep(0.01)
    # reset when opened; held while primed, started; held at the alarm, then reset
    assert held[:4] == ["^X", "!", "~", "!"] and "^X" in held[4:]


def test_a_controller_in_alarm_is_refused_unless_the_cell_homes_or_unlocks_it(
    bench: tuple[Path, list[Port]],
) -> None:
    folder, ports = bench
    for p in ports:  # as after power-up with homing on: ALARM until $H or $X
        p.device.state, p.device.settings[22] = "Alarm", 1.0
    driver = _driver(folder)
    driver.configure()
    with pytest.raises(DriverRefused, match=r"robot 'robot1' at .* is in alarm: home it"):
        driver.activate()
    driver.finalize()
    cell = folder / "cell.yaml"
    cell.write_text(cell.read_text().replace("axes: {z:", "home: true, axes: {z:"))
    driver = _driver(folder)
    driver.configure()
    driver.activate()  # $H on both: homed to GRBL's machine zero
    assert [p.device.log.count("$H") for p in ports] == [1, 1]
    assert np.allclose(driver.joint_state(), 0.0, atol=1e-9)
    driver.finalize()


def test_a_gripper_without_a_position_for_a_jaw_mode_is_refused_at_configure(
    bench: tuple[Path, list[Port]],
) -> None:
    folder, _ = bench
    cell = folder / "cell.yaml"
    grip = "gripper: {port: /dev/null, id: 1, positions: {open: 2600}}, axes: {z:"
    cell.write_text(cell.read_text().replace("axes: {z:", grip, 1))
    driver = _driver(folder)
    with pytest.raises(DriverRefused) as e:
        driver.configure()
    assert str(e.value) == (
        "lab driver: robots.robot1.gripper.positions has no position for jaw mode(s) grasp "
        "of its tool"
    )
    assert driver.links == {}
