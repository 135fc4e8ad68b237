"""The lab bench's hardware (``driver: {kind: lab}``): each cartesian robot's axes on its own
GRBL 1.1 controller over USB serial (grbl_link.py), both played from one clock
(lab_stream.py).

- configure: every controller answers with its banner (version 1.1), its status, and
  settings that can play the cell: each axis' maximum rate ($110...) and acceleration
  ($120...) at least the joint's limits, its travel ($130...) at least the joint's range,
  the steps per unit ($100...) stated; else refused, naming the setting.
- activate: a homing cycle ($H) when the cell says ``home``; a controller in alarm is
  refused unless the cell says ``unlock`` ($X).
- deactivate: a feed hold and a reset on every controller; finalize closes the ports.

Each robot's gripper is a Dynamixel servo (dynamixel_grip.py; grippers on one bus share its
port), its gripper events set on the axes' clock (lab_grippers.py); a robot's load cell is
a serial one (loadcell.py), tared when the driver activates (the grippers empty).
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from cellengine.arrays import FloatArray
from cellengine.drivers.base import Driver, GripperState
from cellengine.drivers.dynamixel import DynamixelError
from cellengine.drivers.dynamixel_grip import Gripper
from cellengine.drivers.dynamixel_joint import ServoError, ServoJoint
from cellengine.drivers.fault import DriverFault, DriverRefused, Fault
from cellengine.drivers.gcode import AxisMap
from cellengine.drivers.grbl_link import GrblError, GrblLink, GrblLost
from cellengine.drivers.lab_grippers import Grippers
from cellengine.drivers.lab_servos import ServoJoints
from cellengine.drivers.lab_stream import STOPPED, Sides, play
from cellengine.drivers.loadcell import LoadCell, LoadCellError
from cellengine.drivers.record import AppliedEvent, Played
from cellengine.info.cell import Cell, DynamixelJoint, LabDriver
from cellengine.info.objects import Objects
from cellengine.program import CompiledSegment, TimedEvent

HOME_TIMEOUT = 60.0  # s for a homing cycle
STATUS_WAIT = 0.5  # s for a status report asked for


@dataclass(frozen=True)
class JointSpec:
    """What the driver checks a controller's settings against (SI: m or rad)."""

    prismatic: bool
    lower: float
    upper: float
    velocity: float
    acceleration: float


class LabBenchDriver(Driver):
    kind = "lab"

    def __init__(
        self,
        cell: Cell,
        joints: Mapping[str, Sequence[str]],
        *,
        objects: Objects | None = None,
        specs: Mapping[str, JointSpec] | None = None,
        serials: Mapping[str, Any] | None = None,
        tares: Mapping[str, float] | None = None,
    ) -> None:
        if not isinstance(cell.driver, LabDriver):
            raise DriverRefused("lab", f"the cell's driver is '{cell.driver.kind}', not lab")
        self.config: LabDriver = cell.driver
        super().__init__(cell, joints, objects=objects, start_tolerance=self.config.start_tolerance)
        self.start_move_limit = self.config.start_move_limit
        self.specs = dict(specs or {})
        self._serials = dict(serials or {})  # robot -> an open pyserial-like port (tests)
        # each load cell's zero from the run's start (a resumed run): not tared again, as
        # its gripper may hold what that run picked
        self._tares = dict(tares or {})
        self.addresses = {r: g.port for r, g in self.config.robots.items()}
        self.links: dict[str, GrblLink] = {}
        self.axes = self._axes(joints)
        self.versions: dict[str, str] = {}
        self.accel: dict[str, list[float]] = {}  # each robot's axes' $120... (units/s^2)
        self.hold_latencies: list[float] = []  # s from a fault's detection to the holds
        self._q = np.full(len(self.joint_names), np.nan)
        self.grippers = Grippers({}, {})
        self.servos = ServoJoints({}, self.config.tracking_tolerance_rotary)
        self.load_cells: dict[str, LoadCell] = {}
        # per segment played: its duration (s), the blocks sent after the start and the
        # least time one went before its planned start (s): the streaming's margin
        self.streamed: list[tuple[float, int, float]] = []

    def _axes(self, joints: Mapping[str, Sequence[str]]) -> dict[str, list[AxisMap]]:
        """Each robot's joints as its controller's axes (the cell file's ``axes``); every
        joint named in ``axes`` or ``servos`` is the robot's, and each joint is one of them."""
        out: dict[str, list[AxisMap]] = {}
        for robot, grbl in self.config.robots.items():
            if robot not in joints:
                raise DriverRefused(self.kind, f"robot '{robot}' is not one of the cell's")
            names = list(joints[robot])
            full = {
                (key, j): self._joint(robot, names, key, j)
                for key, table in (("axes", grbl.axes), ("servos", grbl.servos))
                for j in table
            }
            missing = ", ".join(n for n in names if n not in full.values())
            if missing:
                raise DriverRefused(
                    self.kind,
                    f"robots.{robot}: joint(s) {missing} in neither axes nor servos: each joint "
                    "is a GRBL axis or a Dynamixel servo",
                )
            mine = []
            for joint, axis in grbl.axes.items():
                name = full[("axes", joint)]
                spec = self.specs.get(name)
                prismatic = spec.prismatic if spec is not None else axis.letter != "A"
                scale = 1000.0 if prismatic else 180.0 / math.pi
                index = self.joint_names.index(name)
                mine.append(AxisMap(index, axis.letter, axis.sign, axis.offset, scale))
            out[robot] = mine
        return out

    def _joint(self, robot: str, names: Sequence[str], key: str, joint: str) -> str:
        """The robot's joint the cell file names ``joint`` in ``key`` (its URDF name, or that
        without the robot's prefix: ``z`` for ``robot1_z``)."""
        full = next((n for n in names if n == joint or n.endswith("_" + joint)), None)
        if full is None:
            raise DriverRefused(
                self.kind,
                f"robots.{robot}.{key}: '{joint}' is not a joint of '{robot}' ({', '.join(names)})",
            )
        return full

    # -- lifecycle hooks --------------------------------------------------------------------

    def _on_configure(self) -> None:
        try:
            for robot, grbl in self.config.robots.items():
                link = GrblLink(grbl.port, grbl.baud, self._serials.get(robot))
                self.links[robot] = link
                self.versions[robot] = link.open()
                if not self.versions[robot].startswith("1.1"):
                    raise DriverRefused(
                        self.kind,
                        f"robot '{robot}' at {grbl.port}: GRBL {self.versions[robot]}; "
                        "this driver speaks GRBL 1.1",
                    )
                settings = link.settings()
                self._check_settings(robot, settings)
                self.accel[robot] = [
                    settings.get(120 + "XYZA".index(a.letter), float("inf"))
                    for a in self.axes[robot]
                ]
            self._open_tools()
            self._q = self._read_joints()
        except (GrblError, DynamixelError, LoadCellError, DriverRefused) as e:
            self._close()
            if isinstance(e, DriverRefused):
                raise
            raise DriverRefused(self.kind, str(e)) from None

    def _open_tools(self) -> None:
        """Each robot's gripper (one port per bus) and load cell."""
        buses: dict[str, Any] = {}
        grippers: dict[str, Gripper] = {}
        holding: dict[str, tuple[str, ...]] = {}
        try:
            self._open_each(buses, grippers, holding)
        finally:  # what opened is closed with the rest should anything fail
            self.grippers = Grippers(grippers, holding)

    def _open_each(
        self,
        buses: dict[str, Any],
        grippers: dict[str, Gripper],
        holding: dict[str, tuple[str, ...]],
    ) -> None:
        for robot, grbl in self.config.robots.items():
            spec = grbl.gripper
            tool = self.layout.tools.get(robot)
            if spec is not None and tool is not None:
                missing = sorted(set(tool.jaw) - set(spec.positions))
                if missing:
                    raise DriverRefused(
                        self.kind,
                        f"robots.{robot}.gripper.positions has no position for jaw mode(s) "
                        f"{', '.join(missing)} of its tool",
                    )
            if spec is not None:
                g = Gripper(
                    spec.port,
                    spec.id,
                    spec.positions,
                    baud=spec.baud,
                    load=spec.load,
                    timeout=spec.timeout,
                    bus=buses.get(spec.port),
                    model=spec.model,
                    currents=spec.currents,
                )
                grippers[robot], holding[robot] = g, spec.holding
                g.open()
                buses[spec.port] = g.bus
            self._open_servos(robot, grbl.servos, buses)
            cell = grbl.load_cell
            if cell is not None:
                lc = LoadCell(
                    cell.port, cell.baud, cell.unit, cell.readings, cell.settle, cell.timeout
                )
                self.load_cells[robot] = lc
                lc.open()

    def _open_servos(
        self, robot: str, servos: Mapping[str, DynamixelJoint], buses: dict[str, Any]
    ) -> None:
        """The robot's joints on Dynamixel servos, their profiles from the joints' limits."""
        names = list(self.layout.joint_names[self.layout.slices[robot]])
        for joint, spec in servos.items():
            full = self._joint(robot, names, "servos", joint)
            servo = ServoJoint(
                spec.port,
                spec.id,
                sign=spec.sign,
                zero=spec.zero,
                baud=spec.baud,
                bus=buses.get(spec.port),
            )
            limits = self.specs.get(full)
            self.servos.joints[self.joint_names.index(full)] = (robot, full, servo)
            servo.open(
                limits.velocity if limits else math.pi, limits.acceleration if limits else math.pi
            )
            buses[spec.port] = servo.bus

    def _check_settings(self, robot: str, settings: Mapping[int, float]) -> None:
        for a in self.axes[robot]:
            k = "XYZA".index(a.letter)
            spec = self.specs.get(self.joint_names[a.joint])
            if spec is None:
                continue
            need = {
                110 + k: (spec.velocity * a.scale * 60.0, "maximum rate", "/min"),
                120 + k: (spec.acceleration * a.scale, "acceleration", "/s^2"),
            }
            if a.letter != "A":
                need[130 + k] = ((spec.upper - spec.lower) * a.scale, "travel", "")
            unit = "mm" if a.letter != "A" else "deg"
            for number, (least, what, per) in need.items():
                have = settings.get(number)
                if have is None or have < least - 1e-6:
                    raise DriverRefused(
                        self.kind,
                        f"robot '{robot}' at {self.addresses[robot]}: ${number} ({what} of "
                        f"axis {a.letter}) is {have} {unit}{per}; the cell's "
                        f"'{self.joint_names[a.joint]}' needs at least {least:.6g} {unit}{per}",
                    )

    def _on_activate(self) -> None:
        for robot, link in self.links.items():
            grbl = self.config.robots[robot]
            state = self._status(robot).state
            if grbl.home:
                self._command(robot, "$H", HOME_TIMEOUT)
            elif state == "Alarm":
                if not grbl.unlock:
                    raise DriverRefused(
                        self.kind,
                        f"robot '{robot}' at {link.port} is in alarm: home it (robots.{robot}"
                        f".home: true) or, where its position is known, unlock it "
                        f"(robots.{robot}.unlock: true)",
                    )
                self._command(robot, "$X", 2.0)
        self._q = self._read_joints()
        for robot, lc in self.load_cells.items():  # the grippers are empty: their zero
            if robot in self._tares:
                lc.tare = self._tares[robot]
                continue
            try:
                lc.zero()
            except LoadCellError as e:
                raise DriverRefused(self.kind, f"load cell of '{robot}': {e}") from None

    def _on_deactivate(self) -> None:
        self._stop_all()

    def _on_finalize(self) -> None:
        self._close()

    def _on_recover(self) -> None:
        try:
            for robot in self.links:
                link = self.links[robot]
                link.alarm, link.errors = None, []
                if self._status(robot).state == "Alarm":
                    raise DriverRefused(self.kind, f"robot '{robot}' is still in alarm")
        except GrblLost as e:
            raise DriverRefused(self.kind, str(e)) from None

    def _on_fault(self) -> None:
        self._stop_all()

    # -- execution --------------------------------------------------------------------------

    def _on_execute(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> Played:
        for ev in events:
            if ev.event.arm not in self.grippers.grippers:
                raise DriverRefused(
                    self.kind,
                    f"segment '{segment.segment.label}': arm '{ev.event.arm}' has no gripper "
                    f"in the cell's driver (robots.{ev.event.arm}.gripper) to set to "
                    f"'{ev.event.mode}'",
                )
        self.grippers.start(events)
        traj = segment.trajectory
        self.servos.start(traj)
        out = play(
            traj,
            self.links,
            self.axes,
            self.accel,
            self._q,
            (self.config.tracking_tolerance, self.config.tracking_tolerance_rotary),
            self.config.status_hz,
            self.joint_names,
            Sides((self.grippers, self.servos)),
        )
        self.servos.fill(out.times, out.measured)
        if out.hold_latency is not None:
            self.hold_latencies.append(out.hold_latency)
        if out.leads:
            self.streamed.append((traj.duration, out.blocks, min(out.leads)))
        if out.measured:
            self._q = out.measured[-1].copy()
        if out.fault is None:
            self._q = self._read_joints()
        t = np.array(out.times) if out.times else np.array([traj.start_time])
        measured = np.array(out.measured) if out.measured else traj.q[:1].copy()
        return Played(
            segment.segment.step,
            segment.segment.label,
            self.joint_names,
            t,
            traj.sample(t)[0],
            measured,
            tuple(
                AppliedEvent(e.time, e.event.arm, e.event.mode, e.event.holds, out.fault is None)
                for e in events
            ),
            out.fault,
            None,
        )

    def tares(self) -> dict[str, float]:
        return {robot: lc.tare for robot, lc in self.load_cells.items()}

    def timing(self) -> dict[str, Any] | None:
        return None  # no servo loop: GRBL plans its own motion (see streamed)

    # -- reading ----------------------------------------------------------------------------

    def _read_joints(self) -> FloatArray:
        q = np.array(self._q, dtype=float)
        for robot in self.links:
            mpos = self._status(robot).mpos
            for a in self.axes[robot]:
                q[a.joint] = a.joint_value(mpos["XYZA".index(a.letter)])
        for j, (_, _, servo) in self.servos.joints.items():
            try:
                q[j] = servo.position()
            except ServoError as e:
                raise self._stopped(Fault("connection", f"{e}; {STOPPED}")) from None
        self._q = q
        return q

    def _read_gripper(self, arm: str) -> GripperState:
        return self.grippers.states.get(arm, GripperState(None, None))

    def _last_known(self) -> tuple[FloatArray, dict[str, GripperState]]:
        return np.array(self._q), {arm: self._read_gripper(arm) for arm in self.layout.arms}

    def _read_mass(self, arm: str) -> float:
        lc = self.load_cells.get(arm)
        if lc is None:
            raise DriverRefused(self.kind, f"arm '{arm}' has no load cell in the cell's driver")
        try:
            return lc.weigh()
        except LoadCellError as e:
            fault = Fault("load_cell", f"load cell of '{arm}': {e}; {STOPPED}", arm)
            raise self._stopped(fault) from None

    # -- internals --------------------------------------------------------------------------

    def _status(self, robot: str) -> Any:
        link = self.links[robot]
        asked = time.perf_counter()
        link.ask_status()
        deadline = asked + STATUS_WAIT
        while link.last is None or link.last.time < asked:
            link.poll(0.005)
            if time.perf_counter() > deadline:
                message = (
                    f"robot '{robot}' at {link.port} did not answer a status request "
                    f"within {STATUS_WAIT:g} s; {STOPPED}"
                )
                raise self._stopped(Fault("connection", message, robot))
        return link.last

    def _command(self, robot: str, line: str, timeout: float) -> None:
        try:
            self.links[robot].command(line, timeout)
        except GrblError as e:
            raise DriverRefused(self.kind, str(e)) from None

    def _stop_all(self) -> float:
        """A feed hold then a soft reset on every controller, best effort; the time taken
        to write the holds (s)."""
        start = time.perf_counter()
        for link in self.links.values():
            with contextlib.suppress(GrblError):
                link.hold()
        latency = time.perf_counter() - start
        for link in self.links.values():
            with contextlib.suppress(GrblError):
                link.reset()
        return latency

    def _stopped(self, fault: Fault) -> DriverFault:
        """Every controller held and reset for ``fault`` found outside a segment's play;
        the fault with how long the holds took (as lab_stream's)."""
        latency = self._stop_all()
        self.hold_latencies.append(latency)
        details = {**fault.details, "hold_commands_s": round(latency, 6)}
        return DriverFault(self.kind, replace(fault, details=details))

    def _close(self) -> None:
        for link in self.links.values():
            link.close()
        self.links.clear()
        servos = [
            *self.grippers.grippers.values(),
            *(servo for _, _, servo in self.servos.joints.values()),
        ]
        for servo in servos:
            servo.torque_off()
        for servo in servos:  # a bus' port once (closing is idempotent)
            servo.close()
        self.servos = ServoJoints({}, self.config.tracking_tolerance_rotary)
        for lc in self.load_cells.values():
            lc.close()
        self.grippers = Grippers({}, {})
        self.load_cells = {}
