"""Two (or more) Universal Robots arms through ur-rtde: ``driver: {kind: ur_rtde, arms: {...}}``.

Per arm one ``RTDEReceiveInterface`` (state), one ``RTDEControlInterface`` (servoJ,
stops, watchdog) and one ``RTDEIOInterface`` (the gripper's digital outputs), to the
addresses in the cell file only. The vendor modules are imported when the driver
configures, never before.

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

The vendor's constructors wait for their controller without a timeout: they run in a
helper thread with a deadline, and an address that does not answer is refused before
anything moves.
"""

from __future__ import annotations

import contextlib
import ctypes
import dataclasses
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

import numpy as np

from cellengine.drivers.base import Driver as Base
from cellengine.drivers.base import GripperState
from cellengine.drivers.fault import Fault, Refused
from cellengine.drivers.lead_in import lead_in
from cellengine.drivers.record import AppliedEvent, Played
from cellengine.drivers.servo_timing import servo_timing
from cellengine.drivers.sim import servo_ticks
from cellengine.drivers.ur_watch import safety_stop, set_bits, tracking_deviation
from cellengine.info.cell import Cell
from cellengine.info.cell import UrRtdeDriver as Config
from cellengine.info.objects import Objects
from cellengine.program import CompiledSegment, TimedEvent

T = TypeVar("T")
FloatArray = np.ndarray

SERVO_PERIOD = 0.002  # s: 500 Hz, the e-Series controller's rate
CONNECT_TIMEOUT = 5.0  # s for each vendor constructor
WATCHDOG_HZ = 10.0  # the control script stops an arm not kicked for 0.1 s
KICK_PERIOD = 0.02  # s between the idle kicks, five times within the watchdog's 0.1 s
STOP_DECELERATION = 10.0  # rad/s^2 for servoStop / stopJ on a fault
STOP_TIMEOUT = 0.5  # s: a stop command not sent by then is given up (its arm's watchdog fires)
DISCONNECT_TIMEOUT = 5.0  # s for every client of a kind to disconnect
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
    ) -> None:
        if not isinstance(cell.driver, Config):
            raise Refused("ur_rtde", f"the cell's driver is '{cell.driver.kind}', not ur_rtde")
        self.config: Config = cell.driver
        super().__init__(cell, joints, objects=objects, start_tolerance=self.config.start_tolerance)
        self.addresses = {arm: str(ip) for arm, ip in self.config.arms.items()}
        self.start_move_limit = self.config.start_move_limit
        self.connect_timeout = connect_timeout
        self.servo_period = servo_period
        self._models = {name: r.model for name, r in cell.robots.items()}
        self._ctl: dict[str, Any] = {}
        self._rcv: dict[str, Any] = {}
        self._io: dict[str, Any] = {}
        self._grippers = {arm: GripperState(None, None) for arm in self.layout.arms}
        self._stuck: set[int] = set()  # ids of clients a call hangs in
        self._last_q = np.full(len(self.joint_names), np.nan)  # each arm's last reading
        self.periods: list[float] = []  # every servo period measured (s), for the report
        self._link = threading.Lock()  # one user of the control interfaces at a time
        self._alive = threading.Event()
        self._kicker: threading.Thread | None = None
        # when each fault was detected (perf_counter), and from there to every arm's stop
        # command sent (s)
        self.detections: list[float] = []
        self.stop_latencies: list[float] = []

    def timing(self) -> dict[str, Any]:
        return servo_timing(self.periods, self.servo_period, self.stop_latencies)

    # -- lifecycle hooks --------------------------------------------------------------------

    def _on_configure(self) -> None:
        try:
            import dashboard_client
            import rtde_control
            import rtde_io
            import rtde_receive
        except ImportError as e:  # pragma: no cover - a dependency
            raise Refused(self.kind, f"the ur-rtde library is not installed: {e}") from None
        for arm, ip in self.addresses.items():
            self._check_model(arm, ip, dashboard_client.DashboardClient)
            rcv = self._connect(
                arm, ip, "RTDE receive (port 30004)", rtde_receive.RTDEReceiveInterface
            )
            mode, safety = int(rcv.getRobotMode()), int(rcv.getSafetyMode())
            if safety != SAFETY_NORMAL:
                bits = set_bits(int(rcv.getSafetyStatusBits()))
                raise Refused(self.kind, f"arm '{arm}' at {ip}: safety status {', '.join(bits)}")
            if mode != ROBOT_RUNNING:
                raise Refused(self.kind, f"arm '{arm}' at {ip}: robot mode {mode}, not running (7)")
            self._rcv[arm] = rcv
            self._ctl[arm] = self._connect(
                arm, ip, "RTDE control", rtde_control.RTDEControlInterface
            )
            if self.config.gripper_io:  # the grippers' digital outputs
                self._io[arm] = self._connect(arm, ip, "RTDE IO", rtde_io.RTDEIOInterface)

    def _on_activate(self) -> None:
        for arm, ctl in self._ctl.items():
            if not ctl.setWatchdog(WATCHDOG_HZ):
                raise Refused(self.kind, f"arm '{arm}': the controller refused the watchdog")
        self._keep_alive(True)

    def _on_deactivate(self) -> None:
        self._keep_alive(False)
        self._stop_all()

    def _keep_alive(self, on: bool) -> None:
        """Between segments (planning a move back, replanning after a weighing, writing the
        journal) nothing streams: a thread kicks every arm's watchdog then, so it fires only
        when this process is gone. It holds ``_link`` for each kick; streaming holds it for
        the whole segment (a kick during servoJ would overwrite the servoJ)."""
        if not on:
            self._alive.clear()
            if self._kicker is not None:
                self._kicker.join(1.0)
                self._kicker = None
            return
        self._alive.set()

        def kick() -> None:
            while self._alive.is_set():
                with self._link:
                    for ctl in self._live(self._ctl).values():  # a lost one would block
                        _quietly(lambda c: c.kickWatchdog(), ctl)
                time.sleep(KICK_PERIOD)

        self._kicker = threading.Thread(target=kick, name="ur-watchdog", daemon=True)
        self._kicker.start()

    def _on_finalize(self) -> None:
        self._keep_alive(False)
        for group in (self._ctl, self._io, self._rcv):
            live = self._live(group)
            for arm, client in group.items():
                if arm not in live:  # e.g. an RTDEIOInterface whose controller has gone
                    _never_destroyed(client)
            self._on_each(live, lambda client: client.disconnect(), DISCONNECT_TIMEOUT)
        for group in (self._ctl, self._io, self._rcv):
            group.clear()

    def _on_recover(self) -> None:
        for arm, rcv in self._rcv.items():
            if not rcv.isConnected():
                raise Refused(self.kind, f"cannot recover: arm '{arm}' is not connected")
            bits = int(rcv.getSafetyStatusBits())
            if safety_stop(bits) is not None:
                raise Refused(
                    self.kind,
                    f"cannot recover: arm '{arm}' reports {', '.join(set_bits(bits))} "
                    "(clear it on the teach pendant first)",
                )

    def _on_fault(self) -> None:
        self._keep_alive(False)
        self._stop_all()

    # -- readings ---------------------------------------------------------------------------

    def _read_joints(self) -> FloatArray:
        q = np.zeros(len(self.joint_names))
        for arm, s in self.layout.slices.items():
            rcv = self._rcv[arm]
            if not rcv.isConnected():
                raise Refused(self.kind, f"arm '{arm}' at {self.addresses[arm]} is not connected")
            q[s] = self._last_q[s] = rcv.getActualQ()
        return q

    def _read_gripper(self, arm: str) -> GripperState:
        return self._grippers[arm]

    def _last_known(self) -> tuple[FloatArray, dict[str, GripperState]]:
        """Where the arms are; an arm whose controller has gone: its last reading."""
        q = self._last_q.copy()
        for arm, s in self.layout.slices.items():
            rcv = self._rcv.get(arm)
            with contextlib.suppress(Exception):
                if rcv is not None and rcv.isConnected():
                    q[s] = rcv.getActualQ()
        return q, dict(self._grippers)

    # -- execution ----------------------------------------------------------------------

    def _on_execute(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> Played:
        with self._link:  # no watchdog kick while servoJ streams
            return self._stream(segment, events)

    def _stream(self, segment: CompiledSegment, events: tuple[TimedEvent, ...]) -> Played:
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
        servo = self.config.servo
        # servoJ trails its target by about the lookahead: a joint is compared with the
        # commands of the last LAG_WINDOWS lookaheads (and two periods)
        span = LAG_WINDOWS * servo.lookahead + 2 * self.servo_period
        window = max(1, int(np.ceil(span / self.servo_period)))
        expected = traj.duration + len(lead) * self.servo_period
        deadline = expected * self.config.overrun_scale + self.config.overrun_margin
        wall0 = time.perf_counter()
        last = wall0
        fault: Fault | None = None
        k = 0
        for k, t in enumerate(times):
            try:
                starts = {arm: ctl.initPeriod() for arm, ctl in self._ctl.items()}
                for arm, s in self.layout.slices.items():
                    if not _connected(self._ctl[arm]):  # servoJ would try to reconnect
                        raise ConnectionError("the control interface is disconnected")
                    self._ctl[arm].servoJ(
                        list(commanded[k, s]), 0, 0, self.servo_period, servo.lookahead, servo.gain
                    )
                fault = self._watch(float(t), k, commanded, measured, window)
                if fault is None and time.perf_counter() - wall0 > deadline:
                    fault = self._overrun(float(t), traj.duration, deadline)
                if fault is None and k >= len(lead):
                    fault = self._apply_due(float(t), pending, applied)
                if fault is None:
                    first = next(iter(self._ctl))
                    self._ctl[first].waitPeriod(starts[first])  # one clock for every arm
            except Exception as e:  # the client raises when its controller has gone
                fault = self._lost(float(t), e)
            if fault is not None:
                break
            now = time.perf_counter()
            self.periods.append(now - last)
            last = now
        if fault is None:
            try:
                fault = self._settle(commanded[max(0, k - window) :], float(ticks[-1]))
            except Exception as e:
                fault = self._lost(float(ticks[-1]), e)
        if fault is not None:
            fault = self._stopped(fault)
        else:
            for ctl in self._ctl.values():
                ctl.servoStop(STOP_DECELERATION)
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

    def _lead_in(self, segment: CompiledSegment, first: FloatArray) -> FloatArray:
        """The servo targets from where the arms stand onto the segment's first point
        (lead_in.py), computed before anything is sent."""
        try:
            return lead_in(self._read_joints(), first, self.servo_period)
        except RuntimeError as e:
            raise Refused(self.kind, f"segment '{segment.segment.label}' not sent: {e}") from None

    def _stopped(self, fault: Fault) -> Fault:
        """Stop every arm; the fault with the time from its detection to every arm's stop
        command (s) in its details."""
        detected = time.perf_counter()
        self.detections.append(detected)
        latency = self._stop_all() - detected
        self.stop_latencies.append(latency)
        details = {**fault.details, "stop_commands_s": round(latency, 6)}
        return dataclasses.replace(fault, details=details)

    def _settle(self, recent: FloatArray, t: float) -> Fault | None:
        """Hold the last point until every joint is there: servoJ trails its target, and a
        segment that ends before the arm does would leave it short of the next one's start.
        Watched as the stream is (``recent``: its last lookaheads' commands); a fault when
        the arms do not settle within SETTLE_TIME."""
        servo = self.config.servo
        q_end = recent[-1]
        window = len(recent)
        tolerance = self.start_tolerance * SETTLE_SHARE
        deadline = time.perf_counter() + SETTLE_TIME
        while True:
            starts = {arm: ctl.initPeriod() for arm, ctl in self._ctl.items()}
            q = np.zeros_like(q_end)
            for arm, s in self.layout.slices.items():
                ctl = self._ctl[arm]
                if not _connected(ctl):  # servoJ would try to reconnect
                    raise ConnectionError("the control interface is disconnected")
                ctl.servoJ(list(q_end[s]), 0.0, 0.0, self.servo_period, servo.lookahead, servo.gain)
                q[s] = self._rcv[arm].getActualQ()
                bits = int(self._rcv[arm].getSafetyStatusBits())
                if safety_stop(bits) is not None or not self._rcv[arm].isConnected():
                    fault = self._watch(t, 0, q_end[None, :], q[None, :], 0)
                    if fault is not None:  # else it cleared between two readings
                        return fault
            recent = np.vstack([recent[1:], q_end]) if window > 1 else recent
            fault = self._tracking(t, q, recent)
            if fault is not None:
                return fault
            j = int(np.argmax(np.abs(q - q_end)))
            still = all(
                float(np.max(np.abs(self._rcv[arm].getActualQd()))) <= SETTLE_SPEED
                for arm in self.layout.arms
            )
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
            first = next(iter(self._ctl))
            self._ctl[first].waitPeriod(starts[first])

    def _watch(
        self, t: float, k: int, commanded: FloatArray, measured: FloatArray, window: int
    ) -> Fault | None:
        """Read every arm; the first fault found (connection, safety stop, tracking)."""
        for arm, s in self.layout.slices.items():
            rcv, ctl = self._rcv[arm], self._ctl[arm]
            if not _connected(rcv, ctl):
                return Fault(
                    "connection",
                    f"connection to arm '{arm}' at {self.addresses[arm]} lost at t = {t:.3f} s; "
                    f"{STOPPED}",
                    arm,
                    time=t,
                )
            bits = int(rcv.getSafetyStatusBits())
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
            measured[k, s] = self._last_q[s] = rcv.getActualQ()
        return self._tracking(t, measured[k], commanded[max(0, k - window) : k + 1])

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

    def _lost(self, t: float, error: Exception) -> Fault:
        """A client call raised mid-segment: the arm whose connection is gone (the first
        if every one still says it is connected)."""
        arm = next(
            (a for a in self.layout.arms if not _connected(self._rcv[a], self._ctl[a])),
            self.layout.arms[0],
        )
        return Fault(
            "connection",
            f"connection to arm '{arm}' at {self.addresses[arm]} lost at t = {t:.3f} s "
            f"({error}); {STOPPED}",
            arm,
            time=t,
        )

    def _overrun(self, t: float, duration: float, deadline: float) -> Fault:
        return Fault(
            "overrun",
            f"the segment ({duration:.2f} s of motion) still runs after {deadline:.2f} s of wall "
            f"time at t = {t:.3f} s (is the speed slider down?); {STOPPED}",
            time=t,
        )

    def _apply_due(
        self, t: float, pending: list[TimedEvent], applied: list[AppliedEvent]
    ) -> Fault | None:
        while pending and pending[0].time <= t + 1e-9:
            event = pending.pop(0).event
            pins = self.config.gripper_io
            if pins:
                high = set(pins.get(event.mode, ()))
                for pin in sorted({p for ps in pins.values() for p in ps}):
                    if not self._io[event.arm].setStandardDigitalOut(pin, pin in high):
                        message = (
                            f"gripper of arm '{event.arm}': the controller refused digital "
                            f"output {pin} for mode '{event.mode}' at t = {t:.3f} s; {STOPPED}"
                        )
                        return Fault("gripper", message, event.arm, None, t, event.mode)
            self._grippers[event.arm] = GripperState(event.mode, event.holds)
            applied.append(AppliedEvent(t, event.arm, event.mode, event.holds, True))
        return None

    # -- helpers ------------------------------------------------------------------------

    def _live(self, clients: Mapping[str, Any]) -> dict[str, Any]:
        """The clients of the arms whose connections are all up (the receive interface often
        sees a drop before the control interface's flag does) and that no call is stuck in."""
        return {
            arm: c
            for arm, c in clients.items()
            if id(c) not in self._stuck and _connected(c, self._rcv[arm], self._ctl[arm])
        }

    def _on_each(
        self, clients: Mapping[str, Any], call: Callable[[Any], object], timeout: float
    ) -> None:
        """``call`` on each live client at once (_each); a client whose call is stuck is
        never called again, nor destroyed (a second call or its destruction would crash)."""
        live = self._live(clients)
        for arm in _each(live, call, timeout):
            self._stuck.add(id(live[arm]))
            _never_destroyed(live[arm])

    def _stop_all(self) -> float:
        """Every arm stopped, best effort, each on its own thread (one failing or hanging must
        not spare the others): first an asynchronous stopJ to every arm at once, then
        servoStop on each (which returns when it stands). An arm whose connection is gone is
        left alone: its client would block trying to reconnect, and its controller stops it
        when the watchdog is no longer kicked. When every arm had its stop command
        (perf_counter)."""
        self._on_each(self._ctl, lambda ctl: ctl.stopJ(STOP_DECELERATION, True), STOP_TIMEOUT)
        sent = time.perf_counter()
        self._on_each(self._ctl, lambda ctl: ctl.servoStop(STOP_DECELERATION), SETTLE_TIME)
        return sent

    def _connect(self, arm: str, ip: str, what: str, make: Callable[[str], T]) -> T:
        return _within(
            self.connect_timeout,
            lambda: make(ip),
            lambda why: Refused(
                self.kind, f"arm '{arm}': no UR controller answers at {ip} ({what}): {why}"
            ),
        )

    def _check_model(self, arm: str, ip: str, dashboard: Callable[[str], Any]) -> None:
        """The controller's robot model must be the cell's (e.g. a UR5 for 'ur5e')."""
        model = self._models.get(arm)
        want = MODEL_NAMES.get(model) if isinstance(model, str) else None
        client = self._connect(arm, ip, "dashboard (port 29999)", dashboard)
        _within(
            self.connect_timeout,
            client.connect,
            lambda why: Refused(self.kind, f"arm '{arm}': dashboard at {ip}: {why}"),
        )
        got = str(client.getRobotModel()).strip()
        client.disconnect()
        if want is not None and got.upper() != want:
            raise Refused(
                self.kind,
                f"arm '{arm}' at {ip} reports robot model '{got}', but the cell says "
                f"'{model}' ({want})",
            )


_LEFT_BEHIND: list[Any] = []


def clients_left_behind() -> bool:
    """Whether a client was left behind (_never_destroyed): the process must then end with
    os._exit, as its native threads would crash the interpreter's teardown."""
    return bool(_LEFT_BEHIND)


def _never_destroyed(client: Any) -> None:
    """ur-rtde's clients abort the process when destroyed in some states (RTDEIOInterface
    throws from its destructor once its controller has gone; any client whose threads
    still run, stuck in a call): such a client is leaked on purpose (one reference never
    released), and the operating system closes its sockets when the process ends."""
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(client))
    _LEFT_BEHIND.append(client)


def _each(clients: Mapping[str, Any], call: Callable[[Any], object], timeout: float) -> list[str]:
    """``call(client)`` for every connected client at once, each in a thread of its own; the
    arms whose call had not returned within ``timeout`` (errors are ignored: leaving anyway).
    A client whose connection is gone is skipped: its calls block trying to reconnect."""
    threads = {}
    for arm, client in clients.items():
        if _connected(client):
            threads[arm] = threading.Thread(
                target=lambda c=client: _quietly(call, c), name=f"ur-{arm}", daemon=True
            )
            threads[arm].start()
    end = time.perf_counter() + timeout
    for thread in threads.values():
        thread.join(max(0.0, end - time.perf_counter()))
    return [arm for arm, thread in threads.items() if thread.is_alive()]


def _quietly(call: Callable[[Any], object], client: Any) -> None:
    with contextlib.suppress(Exception):
        call(client)


def _connected(*clients: Any) -> bool:
    try:
        return all(c.isConnected() for c in clients)
    except Exception:
        return False


def _within(timeout: float, call: Callable[[], T], refuse: Callable[[str], Refused]) -> T:
    """``call()`` in a helper thread; Refused when it raises or has not returned in time."""
    box: dict[str, Any] = {}

    def run() -> None:
        try:
            box["value"] = call()
        except Exception as e:
            box["error"] = e

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout)
    if thread.is_alive():
        raise refuse(f"no answer within {timeout:g} s")
    if "error" in box:
        raise refuse(str(box["error"]))
    return box["value"]  # type: ignore[no-any-return]
