"""The lab bench emulated for end-to-end runs through the real lab driver: two GRBL 1.1
controllers, a Dynamixel bus with both grippers (ids 1, 2) and robot1's load cell, each on
a pseudo-terminal, served in a thread of the test process, and a copy of cells/lab_bench
whose driver points at them.

The emulators know nothing of the objects: :class:`Physics` plays that part. When a
gripper is told its grasp position, an object is between its fingers (they stop short,
with load), and robot1's load cell weighs the mass the test says that grasp holds."""

from __future__ import annotations

import shutil
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cellengine.emulate.dynamixel import GOAL, DynamixelBus, Servo
from cellengine.emulate.grbl import DEFAULTS, Grbl
from cellengine.emulate.loadcell import LoadCellEmulator
from cellengine.emulate.serial_pty import Port, open_port, replug, serve
from tests.conftest import CELLS

# what the lab cell's joints need (mm/min, mm/s^2, mm; A in degrees), with room
SETTINGS = {110: 30000.0, 111: 30000.0, 112: 6000.0, 113: 20000.0}
SETTINGS |= {120: 1000.0, 121: 1000.0, 122: 200.0, 123: 500.0}
SETTINGS |= {130: 1500.0, 131: 1500.0, 132: 400.0}
POSITIONS = {"open": 2600, "grasp": 1500}
HOLD_AT = 1700.0  # where a 28 mm vial (or a cap) stops the fingers
AXES = "{z: {letter: Z, sign: -1}, x: {letter: X, sign: -1}, y: {letter: Y, sign: -1}, "


def machine(q: np.ndarray) -> list[float]:
    """A robot's (z, x, y, rotation) as GRBL's machine position under AXES."""
    return [-q[1] * 1000.0, -q[2] * 1000.0, -q[0] * 1000.0, float(np.degrees(q[3]))]


@dataclass
class Physics:
    """What the grippers close on and what robot1's load cell then weighs: the masses (g)
    of robot1's grasps, in order."""

    bus: DynamixelBus
    scale: LoadCellEmulator
    masses: list[float] = field(default_factory=list)
    grasps: int = 0
    _closed: dict[int, bool] = field(default_factory=dict)

    def step(self) -> None:
        for ident, servo in self.bus.servos.items():
            closing = servo.word(GOAL, 4, signed=True) == POSITIONS["grasp"]
            servo.stop = HOLD_AT if closing else None
            # the object is held (and weighs on robot1's load cell) once the fingers are on it
            held = closing and servo.position <= HOLD_AT + 1.0
            if held and not self._closed.get(ident):
                if ident == 1:
                    mass = self.masses[self.grasps] if self.grasps < len(self.masses) else 0.0
                    self.scale.load = mass
                    self.grasps += 1
            elif not held and self._closed.get(ident) and ident == 1:
                self.scale.load = 0.0
            self._closed[ident] = held


@dataclass
class Bench:
    """The cell copy (cell.yaml drives the emulators), its devices, and the links that
    name their terminals in cell.yaml (dev/grbl0, ...: as /dev/serial/by-id names a USB
    device, whichever terminal it gets when plugged in)."""

    folder: Path
    grbl: list[Port]
    bus: Port
    scale: Port
    physics: Physics

    def link(self, port: Port) -> Path:
        names = {id(p): f"grbl{k}" for k, p in enumerate(self.grbl)}
        names |= {id(self.bus): "dynamixel", id(self.scale): "loadcell"}
        return self.folder / "dev" / names[id(port)]

    def replug(self, port: Port) -> None:
        """``port`` back after its ``lost`` fault, at its link."""
        replug(port)
        self.link(port).unlink()
        self.link(port).symlink_to(port.path)


@contextmanager
def emulated_bench(tmp_path: Path, q0: np.ndarray, masses: list[float]) -> Iterator[Bench]:
    """The bench with the robots at ``q0`` (the cell's q), robot1's grasps weighing
    ``masses`` (g)."""
    grbl = []
    for k in range(2):
        g = Grbl({**DEFAULTS, **SETTINGS, 22: 0.0})
        g.position = machine(q0[4 * k : 4 * k + 4])
        grbl.append(open_port(g))
    dyn = DynamixelBus({1: Servo(1, position=2600.0), 2: Servo(2, position=2600.0)})
    scale = LoadCellEmulator(zero=3.7, noise=0.2, seed=4)
    bus, cell_port = open_port(dyn), open_port(scale)
    physics = Physics(dyn, scale, list(masses))
    stop = [False]
    ports = [*grbl, bus, cell_port]
    threads = [
        threading.Thread(target=serve, args=(ports, stop), daemon=True),
        threading.Thread(target=_couple, args=(physics, stop), daemon=True),
    ]
    for th in threads:
        th.start()
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "lab_bench", folder)
    bench = Bench(folder, grbl, bus, cell_port, physics)
    (folder / "dev").mkdir()
    for port in ports:
        bench.link(port).symlink_to(port.path)
    cell = folder / "cell.yaml"
    text = cell.read_text()
    assert "driver: {kind: sim, mass_noise: 0.2}" in text
    cell.write_text(text.replace("driver: {kind: sim, mass_noise: 0.2}", _driver(bench)))
    try:
        yield bench
    finally:
        stop[0] = True
        for th in threads:
            th.join(timeout=2)


def _couple(physics: Physics, stop: list[bool]) -> None:
    while not stop[0]:
        physics.step()
        time.sleep(0.002)


def _driver(bench: Bench) -> str:
    grip = "positions: {open: 2600, grasp: 1500}, timeout: 3.0"
    grbl, bus, scale = (
        [bench.link(p) for p in bench.grbl],
        bench.link(bench.bus),
        bench.link(bench.scale),
    )
    robot1 = (
        f"robot1: {{port: {grbl[0]}, axes: {AXES}roll: {{letter: A}}}}, "
        f"gripper: {{port: {bus}, id: 1, {grip}}}, "
        f"load_cell: {{port: {scale}, settle: 0.3}}}}"
    )
    robot2 = (
        f"robot2: {{port: {grbl[1]}, axes: {AXES}turn: {{letter: A}}}}, "
        f"gripper: {{port: {bus}, id: 2, {grip}}}}}"
    )
    return f"driver: {{kind: lab, robots: {{{robot1}, {robot2}}}}}"
