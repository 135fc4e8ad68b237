"""The simulated cell: the default driver, a real implementation of the driver interface.

Execution steps the segment at the servo period (500 Hz by default) on program time: each
tick it commands the trajectory's position, lets the simulated arms follow
(:mod:`~cellengine.drivers.sim_arms`: exactly, or through a first-order lag), compares the
measured with the commanded position of every joint, and applies the gripper events that
are due. Simulated time runs as fast as possible; with ``realtime=True`` each tick waits for
its wall-clock time. Everything commanded and measured is recorded (:class:`Played`).

A fault (a joint deviating from its command by more than ``tracking_tolerance``, a gripper
that did not reach its mode, a lost connection, an interrupt) stops both arms where they
are at that tick and ends the segment; the driver goes to its error state. For tests,
faults are injected with :meth:`SimDriver.freeze_joint`, :meth:`SimDriver.fail_gripper`
and :meth:`SimDriver.drop_connection`; :meth:`SimDriver.clear_faults` repairs them, after
which :meth:`~cellengine.drivers.base.Driver.recover` succeeds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from cellengine.arrays import FloatArray
from cellengine.drivers.base import START_TOLERANCE, Driver, GripperState
from cellengine.drivers.clock import Clock, RealClock, SimulatedClock
from cellengine.drivers.fault import DriverFault, DriverRefused, Fault
from cellengine.drivers.injection import Injection, Injections
from cellengine.drivers.record import AppliedEvent, Played
from cellengine.drivers.sim_arms import SimArms
from cellengine.drivers.sim_grippers import SimGrippers
from cellengine.info.cell import Cell
from cellengine.info.objects import Objects
from cellengine.program import CompiledSegment, TimedEvent

SERVO_PERIOD = 0.002  # s: the UR controllers' 500 Hz
TRACKING_TOLERANCE = 0.05  # rad or m between commanded and measured, at any tick
EVENT_SLACK = 1e-9  # s: an event this close after a tick is applied at that tick
STOPPED = "both arms stopped"


def servo_ticks(start: float, end: float, period: float) -> FloatArray:
    """Tick times from ``start`` every ``period``, the last one exactly at ``end``."""
    count = math.floor((end - start) / period + 1e-9)
    ticks = start + period * np.arange(count + 1, dtype=np.float64)
    if end - ticks[-1] > 1e-9:
        return np.append(ticks, end)
    ticks[-1] = end
    return ticks


@dataclass
class _Log:
    """What one segment's ticks did, filled as they run."""

    ticks: FloatArray
    commanded: FloatArray
    measured: FloatArray = field(init=False)
    count: int = 0
    late: float = 0.0
    events: list[AppliedEvent] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.measured = np.empty_like(self.commanded)

    def add(self, q: FloatArray, late: float) -> None:
        self.measured[self.count] = q
        self.count += 1
        self.late = max(self.late, late)


class SimDriver(Driver):
    kind = "sim"

    def __init__(
        self,
        cell: Cell,
        joints: Mapping[str, Sequence[str]],
        *,
        objects: Objects | None = None,
        realtime: bool = False,
        lag: float = 0.0,
        tracking_tolerance: float = TRACKING_TOLERANCE,
        start_tolerance: float = START_TOLERANCE,
        servo_period: float = SERVO_PERIOD,
        q0: ArrayLike | Mapping[str, ArrayLike] | None = None,
        grippers: Mapping[str, GripperState] | None = None,
        mass_noise: float = 0.0,
        seed: int = 0,
        tools: Mapping[str, str | None] | None = None,
    ) -> None:
        """``lag``: the arms' time constant (s; 0: they follow exactly). ``q0``: where the
        arms start (cell order, or per arm; default zeros). ``grippers``: their starting
        modes (default 'open' where the tool has it). ``mass_noise``: the load cell's
        standard deviation (kg), drawn from a generator seeded with ``seed``."""
        super().__init__(
            cell, joints, objects=objects, start_tolerance=start_tolerance, tools=tools
        )
        for name, value in (
            ("tracking_tolerance", tracking_tolerance),
            ("servo_period", servo_period),
        ):
            if not value > 0:
                raise ValueError(f"{name} must be > 0, got {value!r}")
        if not mass_noise >= 0:
            raise ValueError(f"mass_noise must be >= 0 kg, got {mass_noise!r}")
        self.realtime = realtime
        self.tracking_tolerance = float(tracking_tolerance)
        self.servo_period = float(servo_period)
        self.mass_noise = float(mass_noise)
        self.arms = SimArms(self._initial_q(q0), lag, self.servo_period)
        self.grippers = SimGrippers(self._initial_grippers(grippers))
        self.injections = Injections(len(self.joint_names))
        self.now: float | None = None  # program time of the last tick played
        self._rng = np.random.default_rng(seed)
        self._lost: Fault | None = None  # the lost connection, until recovered

    # -- fault injection (tests) ----------------------------------------------------------

    def freeze_joint(self, joint: str, at: float = 0.0) -> None:
        """From program time ``at`` on, ``joint`` stops following its command."""
        if joint not in self.joint_names:
            raise KeyError(f"unknown joint '{joint}'; the cell's joints: {self.joint_names}")
        self.injections.add(Injection("freeze", at, joint=self.joint_names.index(joint)))

    def fail_gripper(self, arm: str, at: float = 0.0) -> None:
        """From program time ``at`` on, ``arm`` 's gripper no longer changes mode."""
        self._check_arm(arm)
        self.injections.add(Injection("gripper", at, arm=arm))

    def drop_connection(self, at: float = 0.0, arm: str | None = None) -> None:
        """At program time ``at`` the connection to ``arm`` (None: to the cell) is lost."""
        if arm is not None:
            self._check_arm(arm)
        self.injections.add(Injection("connection", at, arm=arm))

    def clear_faults(self) -> None:
        """Repair everything injected (fired or not): the joint follows, the gripper works,
        the connection can be made again. The driver stays in error until recover()."""
        self.injections.clear()

    # -- lifecycle hooks --------------------------------------------------------------------

    def _on_configure(self) -> None:
        """Nothing to connect to: the simulated arms are where ``q0`` put them."""

    def _on_activate(self) -> None:
        """Nothing to arm: the simulated arms hold their command."""

    def _on_deactivate(self) -> None:
        self.arms.stop()

    def _on_finalize(self) -> None:
        """Nothing to release."""

    def _on_recover(self) -> None:
        now = self.now if self.now is not None else -math.inf
        persisting = [_describe(i, self.joint_names) for i in self.injections.active(now)]
        if persisting:
            raise DriverRefused(
                self.kind,
                "cannot recover: " + "; ".join(persisting) + " (clear the fault first)",
            )
        self._lost = None
        self.arms.stop()

    def _on_fault(self) -> None:
        self.arms.stop()

    # -- readings ---------------------------------------------------------------------------

    def _read_joints(self) -> FloatArray:
        self._check_connection()
        return self.arms.q.copy()

    def _read_gripper(self, arm: str) -> GripperState:
        self._check_connection()
        return self.grippers[arm]

    def _last_known(self) -> tuple[FloatArray, dict[str, GripperState]]:
        return self.arms.q.copy(), self.grippers.snapshot()

    def _read_mass(self, arm: str) -> float:
        self._check_connection()
        held = self.grippers[arm].holds
        mass = 0.0 if held is None else self._object_mass(arm, held)
        noise = float(self._rng.normal(0.0, self.mass_noise)) if self.mass_noise > 0 else 0.0
        return mass + noise

    def _check_changer(self, arm: str) -> None:
        """Every simulated arm has a tool changer."""

    def _check_trigger(self, arm: str, tool: str | None) -> None:
        """Every simulated tool works on a trigger."""

    def _on_trigger(self, arm: str, tool: str, on: bool) -> None:
        """The simulated tool works at once; the recorder keeps when (Triggered)."""
        if on:
            self._check_connection()

    def _on_change_tool(self, arm: str, tool: str | None) -> None:
        """The changer locks or unlocks at once; the gripper it now has is in no known mode."""
        self._check_connection()
        self.grippers.set(arm, GripperState(None, None))

    def commanded(self) -> FloatArray:
        """The position the arms are commanded to hold now (cell order; a copy)."""
        return self.arms.command.copy()

    # -- execution ----------------------------------------------------------------------

    def _on_execute(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> Played:
        traj = segment.trajectory
        ticks = servo_ticks(traj.start_time, traj.end_time, self.servo_period)
        commanded = np.atleast_2d(traj.sample(ticks)[0])
        commanded[-1] = traj.q[-1]  # the end point itself, not the polynomial's rounding of it
        log = _Log(ticks, commanded)
        clock: Clock = RealClock() if self.realtime else SimulatedClock()
        fault = self._play(clock, log, list(events))
        if fault is not None:
            self.arms.stop()
        m = log.count
        return Played(
            segment.segment.step,
            segment.segment.label,
            self.joint_names,
            ticks[:m],
            commanded[:m],
            log.measured[:m],
            tuple(log.events),
            fault,
            log.late if self.realtime else None,
        )

    def _play(self, clock: Clock, log: _Log, pending: list[TimedEvent]) -> Fault | None:
        clock.start(float(log.ticks[0]))
        try:
            for k in range(len(log.ticks)):
                fault = self._tick(clock, log, k, pending)
                if fault is not None:
                    return fault
        except KeyboardInterrupt:
            t = self.now if self.now is not None else float(log.ticks[0])
            return Fault("interrupted", f"interrupted at t = {t:.3f} s; {STOPPED}", time=t)
        return None

    def _tick(self, clock: Clock, log: _Log, k: int, pending: list[TimedEvent]) -> Fault | None:
        t = float(log.ticks[k])
        late = clock.wait_until(t)
        self.now = t
        lost = self._connection_fault(t)
        if lost is not None:
            return lost
        measured = self.arms.step(log.commanded[k], self.injections.frozen(t))
        log.add(measured, late)
        return self._tracking_fault(t, log.commanded[k], measured) or self._apply_due(
            t, pending, log
        )

    def _connection_fault(self, t: float) -> Fault | None:
        lost = self.injections.connection_lost(t)
        if lost is None:
            return None
        to = f"arm '{lost.arm}'" if lost.arm is not None else "the cell"
        self._lost = Fault(
            "connection", f"connection to {to} lost at t = {t:.3f} s; {STOPPED}", lost.arm, time=t
        )
        return self._lost

    def _tracking_fault(self, t: float, command: FloatArray, measured: FloatArray) -> Fault | None:
        deviation = np.abs(command - measured)
        j = int(np.argmax(deviation))
        if deviation[j] <= self.tracking_tolerance:
            return None
        arm, joint, d = self.layout.arm_of(j), self.joint_names[j], float(deviation[j])
        message = (
            f"arm '{arm}' joint '{joint}' does not follow at t = {t:.3f} s: commanded "
            f"{command[j]:.4f}, measured {measured[j]:.4f} (deviation {d:.4f} > tolerance "
            f"{self.tracking_tolerance:g}); {STOPPED}"
        )
        return Fault("tracking", message, arm, joint, t, d)

    def _apply_due(self, t: float, pending: list[TimedEvent], log: _Log) -> Fault | None:
        while pending and pending[0].time <= t + EVENT_SLACK:
            event = pending.pop(0).event
            before = self.grippers[event.arm].mode
            done = self.grippers.apply(event, not self.injections.gripper_fails(event.arm, t))
            log.events.append(AppliedEvent(t, event.arm, event.mode, event.holds, done))
            if not done:
                message = (
                    f"gripper of arm '{event.arm}' did not reach mode '{event.mode}' at "
                    f"t = {t:.3f} s (still '{before}'); {STOPPED}"
                )
                return Fault("gripper", message, event.arm, None, t, before)
        return None

    # -- helpers ------------------------------------------------------------------------

    def _check_connection(self) -> None:
        if self._lost is not None:
            raise DriverFault(self.kind, self._lost)

    def _object_mass(self, arm: str, name: str) -> float:
        objects = self.objects
        thing = None
        if objects is not None:
            thing = objects.cable(name) or objects.containers.get(name)
        if thing is None:
            raise DriverRefused(
                self.kind, f"arm '{arm}' holds '{name}', which is not in the objects"
            )
        if thing.mass is None:
            raise DriverRefused(self.kind, f"arm '{arm}' holds '{name}', whose mass is not given")
        return float(thing.mass)

    def _initial_q(self, q0: ArrayLike | Mapping[str, ArrayLike] | None) -> FloatArray:
        n = len(self.joint_names)
        if q0 is None:
            return np.zeros(n)
        if isinstance(q0, Mapping):
            if set(q0) != set(self.layout.arms):
                raise ValueError(f"q0 gives arms {sorted(q0)}; the cell's: {self.layout.arms}")
            q = np.zeros(n)
            for arm, s in self.layout.slices.items():
                q[s] = np.asarray(q0[arm], dtype=np.float64)
            return q
        q = np.asarray(q0, dtype=np.float64)
        if q.shape != (n,):
            raise ValueError(f"q0 has shape {q.shape}; the cell has {n} joints")
        return q.copy()

    def _initial_grippers(
        self, given: Mapping[str, GripperState] | None
    ) -> dict[str, GripperState]:
        out: dict[str, GripperState] = {}
        for arm, name in self.tools.items():
            tool = self.cell.tools[name] if name is not None else None
            mode = "open" if tool is not None and "open" in tool.jaw else None
            out[arm] = GripperState(mode, None)
        for arm, state in (given or {}).items():
            self._check_arm(arm)
            out[arm] = GripperState(*state)
        return out


def _describe(injection: Injection, joints: tuple[str, ...]) -> str:
    if injection.kind == "freeze" and injection.joint is not None:
        return f"joint '{joints[injection.joint]}' is still frozen"
    if injection.kind == "gripper":
        return f"the gripper of arm '{injection.arm}' still fails"
    to = f"arm '{injection.arm}'" if injection.arm is not None else "the cell"
    return f"the connection to {to} is still down"
