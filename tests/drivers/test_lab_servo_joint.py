"""A rotation joint on a Dynamixel servo instead of a GRBL axis (``robots.R.servos``):
robot2's turn on an emulated XL430 (id 3) beside its emulated GRBL controller. Its goals
stream on the driver's clock beside the G-code, the servo's profile follows them, and a
servo that stops following holds both robots."""

from __future__ import annotations

import math
import shutil
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.lab  # noqa: F401  (registers the lab skills)
from cellengine.drivers.fault import DriverFault, DriverRefused
from cellengine.drivers.lab import LabBenchDriver
from cellengine.emulate.dynamixel import DynamixelBus, Servo
from cellengine.emulate.grbl import DEFAULTS, Grbl
from cellengine.emulate.serial_pty import Port, open_port, serve
from cellengine.execute.retime import timed
from cellengine.info.load import load_plan
from cellengine.motion.robot import build_cell_model
from cellengine.program import CompiledSegment, Segment
from cellengine.runner.driver import joint_specs
from tests.conftest import CELLS
from tests.drivers.labbench import machine
from tests.drivers.test_lab_grbl import AXES, AXES_1, SETTINGS

AXES_2 = AXES[:-2] + "}"  # robot2's z, x, y: its turn is on the servo
HOME = np.array([0.25, 0.75, 0.0, 0.0, 0.25, 0.75, 0.0, 0.0])  # cell.yaml's homes (m, rad)


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[tuple[Path, list[Port], Port]]:
    ports = []
    for k in range(2):
        grbl = Grbl({**DEFAULTS, **SETTINGS, 22: 0.0})
        grbl.position = machine(HOME[4 * k : 4 * k + 4])
        ports.append(open_port(grbl))
    bus = open_port(DynamixelBus({3: Servo(3, position=2048.0)}))
    stop = [False]
    thread = threading.Thread(target=serve, args=([*ports, bus], stop), daemon=True)
    thread.start()
    folder = _cell(
        tmp_path,
        ports[0].path,
        ports[1].path,
        f", servos: {{turn: {{port: {bus.path}, id: 3}}}}",
    )
    yield folder, ports, bus
    stop[0] = True
    thread.join(timeout=2)


def _cell(tmp_path: Path, port1: str, port2: str, robot2: str) -> Path:
    """A copy of the lab cell driven by GRBL controllers at ``port1`` and ``port2``, robot2's
    turn on no axis (``robot2``: the rest of its entry, its servos)."""
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "lab_bench", folder)
    cell = folder / "cell.yaml"
    driver = (
        f"driver: {{kind: lab, robots: {{robot1: {{port: {port1}, axes: {AXES_1}}}, "
        f"robot2: {{port: {port2}, axes: {AXES_2}{robot2}}}}}}}"
    )
    cell.write_text(cell.read_text().replace("driver: {kind: sim, mass_noise: 0.2}", driver))
    return folder


def _driver(folder: Path) -> tuple[LabBenchDriver, CompiledSegment]:
    """The driver, and a segment turning robot2's gripper a quarter turn while its X axis
    moves 100 mm."""
    world = load_plan(folder / "plan_relocate.yaml").world
    cell = build_cell_model(world)
    end = HOME.copy()
    end[5] -= 0.1
    end[7] = math.pi / 2
    traj = timed(np.vstack([HOME, end]), cell.timing_limits(), cell.joint_names)
    segment = CompiledSegment(Segment(0, "turn"), "split", traj, {})
    joints = {name: arm.joint_names for name, arm in cell.arms.items()}
    return LabBenchDriver(world.cell, joints, specs=joint_specs(cell)), segment


def test_the_turn_follows_the_plan_on_its_servo(bench: tuple[Path, list[Port], Port]) -> None:
    folder, ports, bus = bench
    driver, segment = _driver(folder)
    with driver:
        driver.configure()
        driver.activate()
        played = driver.execute(segment)
        assert played.completed
        assert abs(driver.joint_state()[7] - math.pi / 2) < 0.01  # rad
        # robot2's turn read from the servo all along, within the tracking window
        turn = played.measured[:, 7]
        assert turn[-1] > 1.5 and np.all(np.diff(turn) >= -1e-3)
    servo = bus.device.servos[3]
    assert servo.word(11, 1) == 4  # extended position mode
    assert servo.position == pytest.approx(2048 + 1024, abs=1.0)
    goals = [line for line in bus.device.log if "instruction 0x03 params 7400" in line]
    assert len(goals) > segment.trajectory.duration / 0.02 / 2  # streamed, not one goal
    assert not any(line.startswith("G1") and "A" in line for line in ports[1].device.log)


def test_a_servo_that_stops_following_holds_both_robots(
    bench: tuple[Path, list[Port], Port],
) -> None:
    folder, ports, bus = bench
    driver, segment = _driver(folder)
    bus.device.servos[3].stuck = True
    driver.configure()
    driver.activate()
    with pytest.raises(DriverFault) as e:
        driver.execute(segment)
    fault = e.value.fault
    assert (fault.kind, fault.arm, fault.joint) == ("tracking", "robot2", "robot2_turn")
    assert "robot 'robot2' joint 'robot2_turn' (Dynamixel) is " in fault.message
    assert fault.details["hold_commands_s"] < 0.02
    driver.finalize()
    assert all("!" in p.device.realtime[3:] for p in ports)


def test_a_joint_in_neither_axes_nor_servos_is_refused(tmp_path: Path) -> None:
    folder = _cell(tmp_path, "/dev/null", "/dev/null", "")
    with pytest.raises(DriverRefused) as e:
        _driver(folder)
    assert str(e.value) == (
        "lab driver: robots.robot2: joint(s) robot2_turn in neither axes nor servos: each "
        "joint is a GRBL axis or a Dynamixel servo"
    )


def test_a_servo_joint_that_does_not_answer_is_refused_at_configure(
    bench: tuple[Path, list[Port], Port],
) -> None:
    folder, _, bus = bench
    cell = folder / "cell.yaml"
    cell.write_text(cell.read_text().replace("id: 3}", "id: 9}"))
    driver, _ = _driver(folder)
    with pytest.raises(DriverRefused) as e:
        driver.configure()
    assert str(e.value) == (
        f"lab driver: {bus.path} id 9: ping: [TxRxResult] There is no status packet!"
    )
    assert driver.links == {}  # nothing left open
