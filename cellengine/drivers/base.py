"""The one interface every driver implements, with the lifecycle and the checks they share.

A driver plays :class:`~cellengine.program.CompiledSegment` s on a cell: both arms' joints
in cell order on one time axis, with gripper events at given times. Users of a driver call::

    driver.configure()        # connect, read where the arms are
    driver.activate()         # ready to move
    driver.execute(segment, events)   # one segment at a time; returns what was played
    driver.joint_state()      # q, cell order
    driver.gripper("left")    # (mode, holds)
    driver.deactivate(); driver.finalize()

This class owns the lifecycle (:mod:`cellengine.drivers.lifecycle`), the recorder, and the
checks made before anything is sent (joint names, events, the arms at the segment's first
point); a concrete driver implements the ``_on_*`` hooks and the readings. Everything a hook
raises is a fault (the arms are stopped, the driver goes to ``error``) except a
:class:`DriverRefused`, which leaves the state alone. A hook that finds a fault while executing
returns the :class:`Played` record with ``fault`` set, after stopping both arms; this
class then moves to ``error`` and raises :class:`DriverFault`.
"""

from __future__ import annotations

import contextlib
import functools
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping, Sequence
from types import TracebackType
from typing import Any, ClassVar, NamedTuple, TypeVar

import numpy as np

from cellengine.arrays import FloatArray
from cellengine.drivers.fault import DriverFault, DriverRefused, Fault
from cellengine.drivers.layout import CellLayout
from cellengine.drivers.lifecycle import Lifecycle, LifecycleError, State
from cellengine.drivers.record import (
    FaultRecord,
    Played,
    Recorder,
    Sent,
    ToolChanged,
    Transition,
    Triggered,
)
from cellengine.errors import known
from cellengine.info.bounds import MAX_MASS
from cellengine.info.cell import Cell
from cellengine.info.objects import Objects
from cellengine.program import CompiledSegment, Program, TimedEvent

T = TypeVar("T")

# how far (rad or m) a joint may be from a segment's first point when the segment is sent
START_TOLERANCE = 0.01
# how far outside a segment's time span an event may be and still belong to it (s)
EVENT_TIME_SLACK = 1e-9


class GripperState(NamedTuple):
    mode: str | None  # a name in the tool's jaw table; None: not known / no gripper
    holds: str | None  # the object held, None: nothing


class Driver(ABC):
    """Base of all drivers. Not thread-safe: one caller drives it."""

    kind: ClassVar[str]

    def __init__(
        self,
        cell: Cell,
        joints: Mapping[str, Sequence[str]],
        *,
        objects: Objects | None = None,
        start_tolerance: float = START_TOLERANCE,
        tools: Mapping[str, str | None] | None = None,
    ) -> None:
        if not start_tolerance > 0:
            raise ValueError(f"start_tolerance must be > 0, got {start_tolerance!r}")
        self.cell = cell
        self.layout = CellLayout.of(cell, joints)
        self.objects = objects
        self.start_tolerance = float(start_tolerance)
        # how far (rad) a run may move the arms on its own to where a segment starts
        self.start_move_limit = math.inf
        self.recorder = Recorder()
        self.fault: Fault | None = None  # the fault that put the driver in error, if any
        # the tool each arm carries: the cell file's, or where a run resumes, the program's
        self.tools: dict[str, str | None] = {a: r.tool for a, r in cell.robots.items()}
        self.tools.update(tools or {})
        self._life = Lifecycle(self.kind)

    # -- state --------------------------------------------------------------------------

    @property
    def state(self) -> State:
        return self._life.state

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.layout.joint_names

    # -- lifecycle ----------------------------------------------------------------------

    def configure(self) -> None:
        self._transition("configure", self._on_configure)

    def activate(self) -> None:
        self._transition("activate", self._on_activate)

    def deactivate(self) -> None:
        self._transition("deactivate", self._on_deactivate)

    def finalize(self) -> None:
        """Shut down from any state: an active driver stops its arms first."""

        def shut_down() -> None:
            if self.state is State.ACTIVE:
                self._on_deactivate()
            self._on_finalize()

        self._transition("finalize", shut_down)

    def recover(self) -> None:
        """Leave the error state after checking that the fault is gone (a reconnect, a joint
        that follows again); the driver is then inactive (unconfigured if the fault came
        before configuration) and must be activated again. Raises :class:`DriverRefused` and
        stays in error if the fault persists."""
        target = self._life.check_transition("recover")
        self._on_recover()
        self.fault = None
        self._move_to("recover", target)

    def __enter__(self) -> Driver:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.finalize()

    # -- operations ---------------------------------------------------------------------

    def execute(self, segment: CompiledSegment, events: Sequence[TimedEvent] = ()) -> Played:
        """Play one segment and the gripper events that happen during it (times within the
        segment's span; applied in time order, ties in the given order), with its tools at
        work (its triggers) and, at its end, its tool changes. DriverRefused, with
        nothing sent, unless the arms are at the segment's first point within
        ``start_tolerance``. A fault stops both arms and raises :class:`DriverFault`."""
        self._life.check_operation("execute")
        ordered = tuple(sorted(events, key=lambda e: e.time))
        self._check_joints(segment)
        self._check_events(segment, ordered)
        triggers = self._triggers(segment)
        q = self._guarded(self._read_joints)
        self._check_start(segment, q)
        traj = segment.trajectory
        label, step = segment.segment.label, segment.segment.step
        self.recorder.add(Sent(step, label, traj.start_time, traj.end_time, tuple(q.tolist())))
        for arm, tool in triggers:
            self._guarded(functools.partial(self._on_trigger, arm, tool, True))
        try:
            played = self._guarded(lambda: self._on_execute(segment, ordered))
        except BaseException:
            self._triggers_off(triggers)
            raise
        if played.fault is not None:
            self._triggers_off(triggers)
        for arm, tool in triggers:
            if played.fault is None:
                self._guarded(functools.partial(self._on_trigger, arm, tool, False))
            self.recorder.add(Triggered(arm, tool, traj.start_time, traj.end_time))
        self.recorder.add(played)
        if played.fault is None:
            for change in segment.segment.changes:  # the arm standing where the motion ended
                self.change_tool(change.arm, change.tool)
        if played.fault is not None:
            self._fail(played.fault)
            raise DriverFault(self.kind, played.fault)
        return played

    def check_program(self, program: Program) -> None:
        """DriverRefused, before anything moves, when the program changes tools or works a
        tool (a taping gun) this driver cannot."""
        for c in program.changes:
            self._check_arm(c.arm)
            self._check_changer(c.arm)
        for s in program.segments:
            tools = program.tools_at(s.trajectory.start_time)
            for arm in s.segment.triggers:
                self._check_arm(arm)
                self._check_trigger(arm, tools.get(arm))

    def change_tool(self, arm: str, tool: str | None) -> None:
        """``arm``'s tool changer locks ``tool`` (None: unlocks, the tool it carried seated
        in its slot); nothing is done when it carries ``tool`` already. The arm stands still
        meanwhile (a program changes tools at a segment's end)."""
        self._life.check_operation("change_tool")
        self._check_arm(arm)
        was = self.tools[arm]
        if tool == was:
            return
        if tool is not None and tool not in self.cell.tools:
            raise DriverRefused(self.kind, f"unknown tool '{tool}'" + known(self.cell.tools))
        if tool is not None and was is not None:
            raise DriverRefused(
                self.kind, f"arm '{arm}' carries '{was}': it leaves it before it takes '{tool}'"
            )
        self._guarded(lambda: self._on_change_tool(arm, tool))
        self.tools[arm] = tool
        self.recorder.add(ToolChanged(arm, tool, was))

    def joint_state(self) -> FloatArray:
        """The measured q, cell order (a copy)."""
        self._life.check_operation("joint_state")
        return np.array(self._guarded(self._read_joints), dtype=np.float64)

    def gripper(self, arm: str) -> GripperState:
        """The mode of ``arm`` 's gripper and what it holds."""
        self._life.check_operation("gripper")
        self._check_arm(arm)
        return self._guarded(lambda: self._read_gripper(arm))

    def read_mass(self, arm: str, of: str | None = None) -> float:
        """What ``arm`` 's load cell reads (kg), where the driver has one; ``of``: the object
        it weighs, whose reading must be a mass (it goes in the journal, and a runtime choice
        such as ``heavier_of`` follows it): else a fault."""
        self._life.check_operation("read_mass")
        self._check_arm(arm)
        return self._guarded(lambda: self._a_mass(arm, of, self._read_mass(arm)))

    def _a_mass(self, arm: str, of: str | None, kg: float) -> float:
        low = 0.0 if of is not None else -MAX_MASS  # empty, a load cell reads noise about 0
        if not (math.isfinite(kg) and low < kg <= MAX_MASS):
            what = f" weighing '{of}'" if of is not None else ""
            message = (
                f"the load cell of '{arm}' read {kg!r} kg{what}, which is no mass (more than "
                f"0, at most {MAX_MASS:g} kg); both arms stopped"
            )
            raise DriverFault(self.kind, Fault("load_cell", message, arm=arm, value=kg))
        return kg

    def tares(self) -> dict[str, float]:
        """Each load cell's zero (kg, by arm) as activation took it, where the driver has
        load cells that tare (a resumed run gives them back: its grippers may hold)."""
        return {}

    def timing(self) -> dict[str, Any] | None:
        """How a real-time loop kept its period (servo_timing.py), where the driver has one."""
        return None

    # -- hooks for concrete drivers -------------------------------------------------------

    @abstractmethod
    def _on_configure(self) -> None:
        """Connect; read where the arms are and the grippers' modes."""

    @abstractmethod
    def _on_activate(self) -> None:
        """Make the arms ready to move (arm a watchdog, ...)."""

    @abstractmethod
    def _on_deactivate(self) -> None:
        """Stop both arms and hold them."""

    @abstractmethod
    def _on_finalize(self) -> None:
        """Release every connection."""

    @abstractmethod
    def _on_recover(self) -> None:
        """Check the fault is gone and restore a configured, stopped state; raise DriverRefused
        if it is not."""

    @abstractmethod
    def _on_execute(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> Played:
        """Play the segment; on a fault, stop both arms and return the record with it."""

    @abstractmethod
    def _on_fault(self) -> None:
        """Stop both arms at once, best effort; must not raise."""

    @abstractmethod
    def _read_joints(self) -> FloatArray: ...

    @abstractmethod
    def _read_gripper(self, arm: str) -> GripperState: ...

    @abstractmethod
    def _last_known(self) -> tuple[FloatArray, dict[str, GripperState]]:
        """The arms' q and the grippers as last known, without talking to anything."""

    def _read_mass(self, arm: str) -> float:
        raise DriverRefused(self.kind, f"arm '{arm}': the {self.kind} driver has no load cell")

    def _on_trigger(self, arm: str, tool: str, on: bool) -> None:
        """Start (``on``) or stop the work of the tool ``arm`` carries (a taping gun)."""
        raise DriverRefused(self.kind, f"arm '{arm}': the {self.kind} driver triggers no tools")

    def _check_changer(self, arm: str) -> None:
        """DriverRefused unless ``arm``'s tool changer can be locked and unlocked."""
        raise DriverRefused(self.kind, f"arm '{arm}': the {self.kind} driver has no tool changer")

    def _check_trigger(self, arm: str, tool: str | None) -> None:
        """DriverRefused unless ``arm``'s ``tool`` can be set to work."""
        raise DriverRefused(self.kind, f"arm '{arm}': the {self.kind} driver triggers no tools")

    def _triggers(self, segment: CompiledSegment) -> list[tuple[str, str]]:
        """(arm, tool) of each tool the segment works with: DriverRefused, nothing sent,
        for an arm that carries none or a tool the driver cannot work."""
        out = []
        for arm in segment.segment.triggers:
            self._check_arm(arm)
            tool = self.tools[arm]
            if tool is None:
                raise DriverRefused(
                    self.kind,
                    f"segment '{segment.segment.label}' works the {arm} arm's tool, and it "
                    "carries none",
                )
            self._check_trigger(arm, tool)
            out.append((arm, tool))
        return out

    def _triggers_off(self, triggers: list[tuple[str, str]]) -> None:
        """The tools stopped after a fault: best effort (the arms are stopped already)."""
        for arm, tool in triggers:
            with contextlib.suppress(Exception):
                self._on_trigger(arm, tool, False)

    def _on_change_tool(self, arm: str, tool: str | None) -> None:
        """Lock (``tool``) or unlock (None) ``arm``'s tool changer."""
        raise DriverRefused(self.kind, f"arm '{arm}': the {self.kind} driver has no tool changer")

    # -- internals ------------------------------------------------------------------------

    def _transition(self, name: str, hook: Callable[[], None]) -> None:
        if self._life.is_noop(name):
            return
        target = self._life.check_transition(name)
        self._guarded(hook)
        self._move_to(name, target)

    def _move_to(self, name: str, target: State) -> None:
        source = self._life.state
        self._life.state = target
        self.recorder.add(Transition(name, str(source), str(target)))

    def _guarded(self, fn: Callable[[], T]) -> T:
        """Run a hook; anything but a refusal is a fault: stop, go to error, re-raise."""
        try:
            return fn()
        except (DriverRefused, LifecycleError):
            raise
        except DriverFault as e:
            if self.state is State.ERROR and e.fault == self.fault:
                raise  # the fault already recorded (e.g. reading over a lost connection)
            self._on_fault()
            self._fail(e.fault)
            raise
        except KeyboardInterrupt:
            self._on_fault()
            self._fail(Fault("interrupted", "interrupted; both arms stopped"))
            raise
        except Exception as e:
            self._on_fault()
            self._fail(Fault("internal", f"{type(e).__name__}: {e}; both arms stopped"))
            raise

    def _fail(self, fault: Fault) -> None:
        source = self._life.state
        self._life.fail()
        self.fault = fault
        self.recorder.add(Transition("fault", str(source), str(State.ERROR)))
        q, grippers = self._last_known()
        self.recorder.add(
            FaultRecord(
                fault,
                tuple(q.tolist()),
                tuple((arm, g.mode, g.holds) for arm, g in grippers.items()),
            )
        )

    def _check_arm(self, arm: str) -> None:
        why = self.layout.unknown_arm(arm)
        if why is not None:
            raise DriverRefused(self.kind, why)

    def _check_joints(self, segment: CompiledSegment) -> None:
        names = segment.trajectory.joint_names
        if names != self.layout.joint_names:
            raise DriverRefused(
                self.kind,
                f"segment '{segment.segment.label}' (step {segment.segment.step + 1}) moves "
                f"{list(names)}; the cell's joints are {list(self.layout.joint_names)}",
            )

    def _check_events(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> None:
        traj = segment.trajectory
        lo, hi = traj.start_time - EVENT_TIME_SLACK, traj.end_time + EVENT_TIME_SLACK
        where = f"segment '{segment.segment.label}' (step {segment.segment.step + 1})"
        for ev in events:
            arm, mode = ev.event.arm, ev.event.mode
            self._check_arm(arm)
            if not lo <= ev.time <= hi:
                raise DriverRefused(
                    self.kind,
                    f"{where}: event '{mode}' of arm '{arm}' at t = {ev.time:.3f} s is outside "
                    f"the segment ({traj.start_time:.3f} to {traj.end_time:.3f} s)",
                )
            carried = self.tools[arm]
            tool = self.cell.tools[carried] if carried is not None else None
            if tool is None:
                raise DriverRefused(
                    self.kind, f"{where}: arm '{arm}' has no tool to set to '{mode}'"
                )
            if mode not in tool.jaw:
                raise DriverRefused(
                    self.kind,
                    f"{where}: arm '{arm}' has no gripper mode '{mode}'" + known(tool.jaw),
                )

    def _check_start(self, segment: CompiledSegment, q: FloatArray) -> None:
        first = segment.trajectory.q[0]
        deviation = np.abs(q - first)
        j = int(np.argmax(deviation))
        if deviation[j] <= self.start_tolerance:
            return
        arm = self.layout.arm_of(j)
        raise DriverRefused(
            self.kind,
            f"segment '{segment.segment.label}' (step {segment.segment.step + 1}) not sent: "
            f"arm '{arm}' joint '{self.layout.joint_names[j]}' is at {q[j]:.4f}, the segment "
            f"starts at {first[j]:.4f} (deviation {deviation[j]:.4f} > tolerance "
            f"{self.start_tolerance:g})",
        )

    def describe(self) -> dict[str, Any]:
        """The driver's kind, state and fault, JSON-ready (for the journal)."""
        return {
            "kind": self.kind,
            "state": str(self.state),
            "fault": self.fault.to_json() if self.fault else None,
        }
