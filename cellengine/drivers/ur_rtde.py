"""Two (or more) Universal Robots arms through ur-rtde: ``driver: {kind: ur_rtde, arms: {...}}``.

Per arm one ``RTDEReceiveInterface`` (state), one ``RTDEControlInterface`` (servoJ,
stops, watchdog) and, when the cell wires grippers to digital outputs, one
``RTDEIOInterface``, to the addresses in the cell file only. Each arm's clients live in a
process of their own (ur_arm.py, reached through ur_link.py): the vendor library can crash
or hang its process when a controller goes away, and that must become a connection fault
here, with the other arm stopped, not the end of this process.

Execution streams the validated trajectory with servoJ at the servo period (2 ms) to every
arm from one loop and one clock, so the arms start together and stay in step. servoJ feeds
the controller's watchdog itself: a kickWatchdog after it would overwrite its command in the
control script's register before the script reads it (the arm then lags). Each tick
checks, on every arm: the connections, the controller's safety status bits (protective or
emergency stop), each joint against what was commanded over the last lookahead (servoJ's
delay, see ur_watch.py), and the segment's wall time against its duration times
``overrun_scale`` plus ``overrun_margin``. Any of them stops every arm (the others too: they
may hold one cable), records the safety status bits, and puts the driver in its error
state; it never resumes on its own (``recover`` checks the controllers first).

Every request to an arm's process has a deadline: an address that does not answer is
refused before anything moves, an arm that stops answering mid-run is lost.
"""

from __future__ import annotations

import dataclasses
import importlib.util
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from cellengine.arrays import FloatArray
from cellengine.drivers.base import Driver as Base
from cellengine.drivers.base import GripperState
from cellengine.drivers.clock import sleep_until
from cellengine.drivers.fault import DriverFault, DriverRefused, Fault
from cellengine.drivers.lead_in import lead_in
from cellengine.drivers.record import AppliedEvent, Played
from cellengine.drivers.servo_timing import servo_timing
from cellengine.drivers.sim import servo_ticks
from cellengine.drivers.ur_link import ArmLink, LinkError, exchange
from cellengine.drivers.ur_watch import safety_stop, set_bits, tracking_deviation
from cellengine.info.cell import Cell
from cellengine.info.cell import UrRtdeDriver as Config
from cellengine.info.objects import Objects
from cellengine.program import CompiledSegment, TimedEvent

SERVO_PERIOD = 0.002  # s: 500 Hz, the e-Series controller's rate
CONNECT_TIMEOUT = 5.0  # s for each connection (dashboard, receive, control, IO)
WATCHDOG_HZ = 10.0  # the control script stops an arm not kicked for 0.1 s
TICK_TIMEOUT = 0.2  # s for an arm's answer to a servo command or a reading: else it is lost
STOP_DECELERATION = 10.0  # rad/s^2 for servoStop / stopJ on a fault
STOP_TIMEOUT = 0.5  # s: a stop command not sent by then is given up (its arm's watchdog fires)
DISCONNECT_TIMEOUT = 5.0  # s for every arm's clients to disconnect
VENDOR_MODULES = ("dashboard_client", "rtde_control", "rtde_receive", "rtde_io")
SAFETY_NORMAL = 1  # getSafetyMode()
ROBOT_RUNNING = 7  # getRobotMode()
MODEL_NAMES = {"ur3e": "UR3", "ur5e": "UR5", "ur10e": "UR10", "ur5": "UR5"}
STOPPED = "every arm stopped"
LAG_WINDOWS = 2.0  # how many lookaheads behind its command a joint may be
SETTLE_TIME = 1.0  # s a segment's end may take to be reached after its last command
# settled: every joint within this share of the start tolerance of the end, and slower than
# SETTLE_SPEED (rad/s), so that servoStop's deceleration moves it no further to speak of
SETTLE_SHARE = 0.25
SETTLE_SPEED = 0.01


class UrDriver(Base):
    kind = "ur_rtde"

    def __init__(
        self,
        cell: Cell,
        joints: Mapping[str, Sequence[str]],
        *,
        objects: Objects | None = None,
        connect_timeout: float = CONNECT_TIMEOUT,
        servo_period: float = SERVO_PERIOD,
        tools: Mapping[str, str | None] | None = None,
    ) -> None:
        if not isinstance(cell.driver, Config):
            raise DriverRefused(
                "ur_rtde", f"the cell's driver is '{cell.driver.kind}', not ur_rtde"
            )
        self.config: Config = cell.driver
        super().__init__(
            cell, joints, objects=objects, start_tolerance=self.config.start_tolerance, tools=tools
        )
        self.addresses = {arm: str(ip) for arm, ip in self.config.arms.items()}
        self.start_move_limit = self.config.start_move_limit
        self.connect_timeout = connect_timeout
        self.servo_period = servo_period
        self._models = {name: r.model for name, r in cell.robots.items()}
        self._links: dict[str, ArmLink] = {}
        self._grippers = {arm: GripperState(None, None) for arm in self.layout.arms}
        self._last_q = np.full(len(self.joint_names), np.nan)  # each arm's last reading
        self.periods: list[float] = []  # every servo period measured (s), for the report
        # when each fault was detected (perf_counter), and from there to every arm's stop
        # command sent (s)
        self.detections: list[float] = []
        self.stop_latencies: list[float] = []

    def timing(self) -> dict[str, Any]:
        return servo_timing(self.periods, self.servo_period, self.stop_latencies)

    # -- lifecycle hooks --------------------------------------------------------------------

    def _on_configure(self) -> None:
        missing = [m for m in VENDOR_MODULES if importlib.util.find_spec(m) is None]
        if missing:  # pragma: no cover - a dependency
            raise DriverRefused(
                self.kind, f"the ur-rtde library is not installed ({', '.join(missing)})"
            )
        try:
            for arm, ip in self.addresses.items():
                self._links[arm] = ArmLink(arm, ip)
                self._configure_arm(arm, ip)
        except BaseException:
            self._close_links()  # nothing half-done: the driver stays unconfigured
            raise

    def _configure_arm(self, arm: str, ip: str) -> None:
        """The controller's robot model must be the cell's (e.g. a UR5 for 'ur5e'), its
        robot running and its safety normal."""
        model = self._models.get(arm)
        want = MODEL_NAMES.get(model) if isinstance(model, str) else None
        got = self._ask(arm, f"dashboard at {ip}", "model").strip()
        if want is not None and got.upper() != want:
            raise DriverRefused(
                self.kind,
                f"arm '{arm}' at {ip} reports robot model '{got}', but the cell says "
                f"'{model}' ({want})",
            )
        answers = f"no UR controller answers at {ip}"
        mode, safety, bits = self._ask(arm, f"{answers} (RTDE receive)", "connect_receive")
        if safety != SAFETY_NORMAL:
            raise DriverRefused(
                self.kind, f"arm '{arm}' at {ip}: safety status {', '.join(set_bits(bits))}"
            )
        if mode != ROBOT_RUNNING:
            raise DriverRefused(
                self.kind, f"arm '{arm}' at {ip}: robot mode {mode}, not running (7)"
            )
        self._ask(arm, f"{answers} (RTDE control)", "connect_control")
        outputs = self.config.gripper_io or self.config.trigger_io
        if outputs or self.config.changer_release is not None:  # digital outputs
            self._ask(arm, f"{answers} (RTDE IO)", "connect_io")

    def _ask(self, arm: str, what: str, op: str) -> Any:
        try:
            return self._links[arm].call(op, timeout=self.connect_timeout)
        except LinkError as e:
            raise DriverRefused(self.kind, f"arm '{arm}': {what}: {e.why}") from None

    def _on_activate(self) -> None:
        """The RTDE watchdog armed on every arm; each arm's process kicks it while nothing
        streams (planning a move back, a replan, writing the journal), so it fires only when
        this process is gone or stuck."""
        answers = self._exchange({arm: ("watchdog", WATCHDOG_HZ) for arm in self._links}, 1.0)
        for arm, ok in answers.items():
            if ok is not True:
                why = f": {ok.why}" if isinstance(ok, LinkError) else ""
                raise DriverRefused(
                    self.kind, f"arm '{arm}': the controller refused the watchdog{why}"
                )

    def _on_deactivate(self) -> None:
        self._stop_all()

    def _on_finalize(self) -> None:
        self._close_links()

    def _on_recover(self) -> None:
        for arm, state in self._read().items():
            if isinstance(state, LinkError):
                raise DriverRefused(
                    self.kind, f"cannot recover: arm '{arm}' is not connected ({state})"
                )
            bits = state[2]
            if safety_stop(bits) is not None:
                raise DriverRefused(
                    self.kind,
                    f"cannot recover: arm '{arm}' reports {', '.join(set_bits(bits))} "
                    "(clear it on the teach pendant first)",
                )

    def _on_fault(self) -> None:
        self._stop_all()

    # -- readings ---------------------------------------------------------------------------

    def _read(self) -> dict[str, Any]:
        """Every arm's (q, qd, safety status bits), or its LinkError."""
        return self._exchange({arm: ("read",) for arm in self._links}, TICK_TIMEOUT)

    def _read_joints(self) -> FloatArray:
        q = np.zeros(len(self.joint_names))
        states = self._read()
        for arm, s in self.layout.slices.items():
            state = states[arm]
            if isinstance(state, LinkError):
                why = f"arm '{arm}' at {self.addresses[arm]} is not connected ({state})"
                raise DriverRefused(self.kind, why)
            q[s] = self._last_q[s] = state[0]
        return q

    def _read_gripper(self, arm: str) -> GripperState:
        return self._grippers[arm]

    def _last_known(self) -> tuple[FloatArray, dict[str, GripperState]]:
        """Where the arms are; an arm whose controller has gone: its last reading."""
        q = self._last_q.copy()
        live = {arm for arm, link in self._links.items() if link.live}
        states = self._exchange({arm: ("read",) for arm in live}, TICK_TIMEOUT)
        for arm, state in states.items():
            if not isinstance(state, LinkError):
                q[self.layout.slices[arm]] = state[0]
        return q, dict(self._grippers)

    # -- execution ----------------------------------------------------------------------

    def _on_execute(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> Played:
        traj = segment.trajectory
        ticks = servo_ticks(traj.start_time, traj.end_time, self.servo_period)
        planned = np.atleast_2d(traj.sample(ticks)[0])
        planned[-1] = traj.q[-1]
        lead = self._lead_in(segment, planned[0])
        commanded = np.vstack([lead, planned])  # the program's time stands during the lead-in
        times = np.concatenate([np.full(len(lead), ticks[0]), ticks])
        measured = np.zeros_like(commanded)
        applied: list[AppliedEvent] = []
        pending = list(events)
        # servoJ trails its target by about the lookahead: a joint is compared with the
        # commands of the last LAG_WINDOWS lookaheads (and two periods)
        span = LAG_WINDOWS * self.config.servo.lookahead + 2 * self.servo_period
        window = max(1, int(np.ceil(span / self.servo_period)))
        expected = traj.duration + len(lead) * self.servo_period
        deadline = expected * self.config.overrun_scale + self.config.overrun_margin
        wall0 = last = time.perf_counter()
        fault: Fault | None = None
        k = 0
        for k, t in enumerate(times):
            tick = time.perf_counter()  # one clock for every arm
            states = self._servo(commanded[k])
            fault = self._check(
                float(t), states, measured[k], commanded[max(0, k - window) : k + 1]
            )
            if fault is None and time.perf_counter() - wall0 > deadline:
                fault = self._overrun(float(t), traj.duration, deadline)
            if fault is None and k >= len(lead):
                fault = self._apply_due(float(t), pending, applied)
            if fault is not None:
                break
            sleep_until(tick + self.servo_period)
            now = time.perf_counter()
            self.periods.append(now - last)
            last = now
        if fault is None:
            fault = self._settle(commanded[max(0, k - window) :], float(ticks[-1]))
        if fault is None:
            fault = self._end_segment(float(ticks[-1]))
        if fault is not None:
            fault = self._stopped(fault)
        # the record is the segment's: the lead-in's rows left out (but one kept, if a
        # fault came before the segment began)
        n = max(1, k + 1 - len(lead))
        rows = slice(k + 1 - n, k + 1)
        return Played(
            segment.segment.step,
            segment.segment.label,
            self.joint_names,
            ticks[:n],
            planned[:n],
            measured[rows],
            tuple(applied),
            fault,
            None,
        )

    def _servo(self, q: FloatArray) -> dict[str, Any]:
        """servoJ to ``q`` on every arm at once; every arm's state after it (or LinkError)."""
        servo = self.config.servo
        requests = {
            arm: ("servo", q[s].tolist(), self.servo_period, servo.lookahead, servo.gain)
            for arm, s in self.layout.slices.items()
        }
        return self._exchange(requests, TICK_TIMEOUT)

    def _lead_in(self, segment: CompiledSegment, first: FloatArray) -> FloatArray:
        """The servo targets from where the arms stand onto the segment's first point
        (lead_in.py), computed before anything is sent."""
        try:
            return lead_in(self._read_joints(), first, self.servo_period)
        except RuntimeError as e:
            raise DriverRefused(
                self.kind, f"segment '{segment.segment.label}' not sent: {e}"
            ) from None

    def _settle(self, recent: FloatArray, t: float) -> Fault | None:
        """Hold the last point until every joint is there: servoJ trails its target, and a
        segment that ends before the arm does would leave it short of the next one's start.
        Watched as the stream is (``recent``: its last lookaheads' commands); a fault when
        the arms do not settle within SETTLE_TIME."""
        q_end = recent[-1]
        tolerance = self.start_tolerance * SETTLE_SHARE
        deadline = time.perf_counter() + SETTLE_TIME
        while True:
            tick = time.perf_counter()
            states = self._servo(q_end)
            recent = np.vstack([recent[1:], q_end]) if len(recent) > 1 else recent
            q = np.zeros_like(q_end)
            fault = self._check(t, states, q, recent)
            if fault is not None:
                return fault
            j = int(np.argmax(np.abs(q - q_end)))
            still = all(float(np.max(np.abs(s[1]))) <= SETTLE_SPEED for s in states.values())
            if abs(q[j] - q_end[j]) <= tolerance and still:
                return None
            if time.perf_counter() > deadline:
                arm, joint = self.layout.arm_of(j), self.joint_names[j]
                return Fault(
                    "tracking",
                    f"arm '{arm}' joint '{joint}' did not reach the end of the segment within "
                    f"{SETTLE_TIME:g} s: at {q[j]:.4f}, commanded {q_end[j]:.4f}; {STOPPED}",
                    arm,
                    joint,
                    t,
                    float(abs(q[j] - q_end[j])),
                )
            sleep_until(tick + self.servo_period)

    def _end_segment(self, t: float) -> Fault | None:
        """servoStop on every arm (it returns when the arm stands); the arms' processes kick
        the watchdog again until the next segment."""
        requests = {arm: ("servo_stop", STOP_DECELERATION, True) for arm in self._links}
        for answer in self._exchange(requests, SETTLE_TIME).values():
            if isinstance(answer, LinkError):
                return self._lost(t, answer)
        return None

    def _check(
        self, t: float, states: dict[str, Any], q: FloatArray, recent: FloatArray
    ) -> Fault | None:
        """The first fault in every arm's state (connection, safety stop, tracking against
        ``recent`` commands); ``q`` filled with the arms' positions."""
        for arm, s in self.layout.slices.items():
            state = states[arm]
            if isinstance(state, LinkError):
                return self._lost(t, state)
            bits = state[2]
            kind = safety_stop(bits)
            if kind is not None:
                names = ", ".join(set_bits(bits))
                return Fault(
                    kind,  # type: ignore[arg-type]
                    f"arm '{arm}' at {self.addresses[arm]}: {names} at t = {t:.3f} s; {STOPPED}",
                    arm,
                    time=t,
                    value=bits,
                    details={"safety_status_bits": bits, "set": names},
                )
            q[s] = self._last_q[s] = state[0]
        return self._tracking(t, q, recent)

    def _tracking(self, t: float, q: FloatArray, recent: FloatArray) -> Fault | None:
        """A fault when a joint of ``q`` is farther than the tolerance from every command of
        ``recent`` (the last lookaheads' worth)."""
        j, d = tracking_deviation(q, recent)
        if d <= self.config.tracking_tolerance:
            return None
        arm, joint = self.layout.arm_of(j), self.joint_names[j]
        return Fault(
            "tracking",
            f"arm '{arm}' joint '{joint}' does not follow at t = {t:.3f} s: measured "
            f"{q[j]:.4f}, {d:.4f} rad from every command of the last "
            f"{LAG_WINDOWS * self.config.servo.lookahead:g} s (tolerance "
            f"{self.config.tracking_tolerance:g}); {STOPPED}",
            arm,
            joint,
            t,
            d,
        )

    def _lost(self, t: float, error: LinkError) -> Fault:
        return Fault(
            "connection",
            f"connection to arm '{error.arm}' at {self.addresses[error.arm]} lost at "
            f"t = {t:.3f} s ({error.why}); {STOPPED}",
            error.arm,
            time=t,
        )

    def _overrun(self, t: float, duration: float, deadline: float) -> Fault:
        return Fault(
            "overrun",
            f"the segment ({duration:.2f} s of motion) still runs after {deadline:.2f} s of wall "
            f"time at t = {t:.3f} s (is the speed slider down?); {STOPPED}",
            time=t,
        )

    def _check_changer(self, arm: str) -> None:
        if self.config.changer_release is None:
            raise DriverRefused(
                self.kind,
                f"arm '{arm}' changes tools, and the cell's ur_rtde driver names no tool "
                "changer output (driver.changer_release)",
            )

    def _check_trigger(self, arm: str, tool: str | None) -> None:
        if tool is None or tool not in self.config.trigger_io:
            raise DriverRefused(
                self.kind,
                f"arm '{arm}' works '{tool}', and the cell's ur_rtde driver names no output "
                f"for it (driver.trigger_io: {{{tool}: <output>}})",
            )

    def _on_trigger(self, arm: str, tool: str, on: bool) -> None:
        """The tool's output (driver.trigger_io) high while it works."""
        self._check_trigger(arm, tool)
        pin = self.config.trigger_io[tool]
        self._dout(arm, pin, on, f"{tool} of arm '{arm}'", "start" if on else "stop")

    def _dout(self, arm: str, pin: int, high: bool, what: str, doing: str) -> None:
        """One standard digital output of ``arm``'s controller; DriverFault if it fails."""
        try:
            refused = self._links[arm].call("dout", [(pin, high)], timeout=TICK_TIMEOUT)
        except LinkError as e:
            message = f"connection to arm '{arm}' lost ({e.why}); {STOPPED}"
            raise DriverFault(self.kind, Fault("connection", message, arm)) from None
        if refused is not None:
            message = (
                f"{what}: the controller refused digital output {pin} to {doing} it; {STOPPED}"
            )
            raise DriverFault(self.kind, Fault("tool", message, arm))

    def _on_change_tool(self, arm: str, tool: str | None) -> None:
        """The changer's release output high to unlock, low to lock."""
        self._check_changer(arm)
        pin = self.config.changer_release
        assert pin is not None
        what = "lock" if tool is not None else "unlock"
        self._dout(arm, pin, tool is None, f"tool changer of arm '{arm}'", what)

    def _apply_due(
        self, t: float, pending: list[TimedEvent], applied: list[AppliedEvent]
    ) -> Fault | None:
        while pending and pending[0].time <= t + 1e-9:
            event = pending.pop(0).event
            pins = self.config.gripper_io
            if pins:
                high = set(pins.get(event.mode, ()))
                outputs = [(p, p in high) for p in sorted({p for ps in pins.values() for p in ps})]
                try:
                    refused = self._links[event.arm].call("dout", outputs, timeout=TICK_TIMEOUT)
                except LinkError as e:
                    return self._lost(t, e)
                if refused is not None:
                    message = (
                        f"gripper of arm '{event.arm}': the controller refused digital "
                        f"output {refused} for mode '{event.mode}' at t = {t:.3f} s; {STOPPED}"
                    )
                    return Fault("gripper", message, event.arm, None, t, event.mode)
            self._grippers[event.arm] = GripperState(event.mode, event.holds)
            applied.append(AppliedEvent(t, event.arm, event.mode, event.holds, True))
        return None

    # -- stopping -----------------------------------------------------------------------

    def _stopped(self, fault: Fault) -> Fault:
        """Stop every arm; the fault with the time from its detection to every arm's stop
        command (s) in its details."""
        detected = time.perf_counter()
        self.detections.append(detected)
        latency = self._stop_all() - detected
        self.stop_latencies.append(latency)
        details = {**fault.details, "stop_commands_s": round(latency, 6)}
        return dataclasses.replace(fault, details=details)

    def _stop_all(self) -> float:
        """Every arm stopped, best effort, all at once (one failing or hanging must not spare
        the others): first an asynchronous stopJ to every arm, then servoStop on each (which
        returns when it stands). A lost arm is left alone: its process is gone, its
        connections closed, and its controller stops it when the watchdog is no longer
        kicked. When every arm had its stop command (perf_counter)."""
        live = [arm for arm, link in self._links.items() if link.live]
        self._exchange({arm: ("stop", STOP_DECELERATION) for arm in live}, STOP_TIMEOUT)
        sent = time.perf_counter()
        requests = {arm: ("servo_stop", STOP_DECELERATION, False) for arm in live}
        self._exchange(requests, SETTLE_TIME)
        return sent

    def _exchange(self, requests: Mapping[str, tuple[Any, ...]], timeout: float) -> dict[str, Any]:
        return exchange(self._links, requests, timeout)

    def _close_links(self) -> None:
        """Every arm's clients disconnected and its process ended (killed if need be)."""
        live = [arm for arm, link in self._links.items() if link.live]
        self._exchange({arm: ("disconnect",) for arm in live}, DISCONNECT_TIMEOUT)
        for link in self._links.values():
            link.close(DISCONNECT_TIMEOUT)
        self._links.clear()
