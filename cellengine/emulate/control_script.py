"""ur-rtde's control script (``def rtde_control():``) as the emulated controller runs it:
one pass of the script's main loop per 2 ms tick.

The handshake: the client writes a command into ``input_int_register_0`` and its arguments
into ``input_double_register_0..`` (``input_int_register_1``: async flag, movec mode,
steps). The script answers in ``output_int_register_0``: 1 ready, 2 done. Streaming
commands (servoJ, speedJ, ...) are taken every tick and answered ready at once; any other
command runs once, answers done when finished (a blocking moveJ when the arm arrives) and
waits for the client to clear the register to 0 before it answers ready again.
``output_int_register_2`` is the async progress word.

Registers hold the last value received: a command overwritten before the script's tick is
never seen. ur-rtde's kickWatchdog() writes 0 into ``input_int_register_0``, so a kick sent
in the same 2 ms as a servoJ hides that servoJ (the watchdog watches that register, which
servoJ writes too).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING

from cellengine.emulate.arm import JointMove, Motion, Servo, Speed, Stop

if TYPE_CHECKING:
    from cellengine.emulate.controller import Controller

READY, DONE = 1, 2
# taken every tick and answered ready at once (the script's own list, ur-rtde 1.6)
STREAMING = frozenset({6, 9, 10, 11, 24, 25, 26, 27, 38, 58, 66, 67, 68, 69, 70, 71})
STOP_SCRIPT = 255
STOPS = {15: "speedStop", 16: "servoStop", 33: "stopL", 34: "stopJ"}
DEFAULT_STOP = 10.0  # rad/s^2 when a stop command carries no deceleration
# commands whose script code needs what the emulator does not model (IK, tool space, force)
UNSUPPORTED = {
    2: "moveJ_IK",
    3: "moveL",
    5: "moveC",
    6: "forceMode",
    10: "speedL",
    12: "servoC",
    24: "servoL",
    25: "toolContact",
    30: "getInverseKinematics",
    32: "moveP",
    39: "poseTrans",
    41: "jogStart",
    45: "movePath",
    46: "getInverseKinematics",
    51: "moveUntilContact",
    60: "getInverseKinematicsHasSolution",
    61: "getInverseKinematicsHasSolution",
    66: "directTorque",
    67: "getMassMatrix",
    68: "getCoriolisAndCentrifugalTorques",
    69: "getTargetJointAccelerations",
    70: "getJacobian",
    71: "getJacobianTimeDerivative",
}
_OFFSET = re.compile(r"global reg_offset_(float|int)\s*=\s*(\d+)")


class ControlScript:
    """The running control script of one controller."""

    name = "rtde_control"

    def __init__(self, ctl: Controller, text: str) -> None:
        self.ctl = ctl
        offsets = {kind: int(value) for kind, value in _OFFSET.findall(text)}
        self.off_int, self.off_float = offsets.get("int", 0), offsets.get("float", 0)
        self.executing = False
        self.waiting: Motion | None = None  # a blocking command's motion
        self.moving: Motion | None = None  # an async command's motion
        self.op_id = self.wr_count = 0
        self._progress(running=False)
        self._out_int(0, READY)

    # -- registers ------------------------------------------------------------------------

    def _in_int(self, i: int) -> int:
        return int(self.ctl.number(f"input_int_register_{i + self.off_int}"))

    def _in_double(self, i: int) -> float:
        return self.ctl.number(f"input_double_register_{i + self.off_float}")

    def _q(self, first: int) -> list[float]:
        return [self._in_double(first + j) for j in range(6)]

    def _out_int(self, i: int, value: int) -> None:
        self.ctl.outputs[f"output_int_register_{i + self.off_int}"] = value

    def _out_doubles(self, values: tuple[float, ...] | list[float]) -> None:
        for i, v in enumerate(values):
            self.ctl.outputs[f"output_double_register_{i + self.off_float}"] = float(v)

    def _progress(self, running: bool) -> None:
        """The async progress word: op id (bits 24-30), write count (16-22), running (15)."""
        self.wr_count = (self.wr_count + 1) & 0x7F
        word = self.op_id << 24 | self.wr_count << 16 | (0x8000 if running else 0)
        self._out_int(2, word)

    # -- the main loop --------------------------------------------------------------------

    def tick(self) -> bool:
        """One pass of the main loop; False when the script has ended."""
        if self.moving is not None and (self.moving.done or self.ctl.arm.motion is not self.moving):
            self.moving = None
            self._progress(running=False)
        if self.waiting is not None:
            if self.waiting.done or self.ctl.arm.motion is not self.waiting:
                self.waiting = None
                self._out_int(0, DONE)
            return True
        cmd = self._in_int(0)
        if cmd in STREAMING and cmd not in UNSUPPORTED:
            self._process(cmd)
            self._out_int(0, READY)
        elif cmd == 0:
            self.executing = False
            self._out_int(0, READY)
        elif not self.executing:
            self.executing = True
            return self._process(cmd)
        return True

    def _process(self, cmd: int) -> bool:
        ctl, arm = self.ctl, self.ctl.arm
        if cmd == STOP_SCRIPT:
            ctl.log("the control script was told to stop")
            return False
        if cmd in UNSUPPORTED:
            ctl.log(f"command {cmd} ({UNSUPPORTED[cmd]}) is not emulated: the script stops")
            return False
        if cmd in (1, 4):  # moveJ (moveL_FK: a joint move too, the tool path is not modelled)
            self._move(JointMove(arm.target, self._q(0), self._in_double(6), self._in_double(7)))
            return True
        if cmd == 9:  # speedJ
            speed = arm.motion if isinstance(arm.motion, Speed) else Speed()
            speed.set(self._q(0), self._in_double(6))
            self._replace(speed)
        elif cmd == 11:  # servoJ
            servo = arm.motion if isinstance(arm.motion, Servo) else Servo(arm.target)
            servo.set(self._q(0), self._in_double(9), self._in_double(10))
            self._replace(servo)
        elif cmd in (15, 16):  # speedStop, servoStop: block until the arm stands
            self._stop(self._in_double(0) or DEFAULT_STOP, wait=True, name=STOPS[cmd])
            return True
        elif cmd in (33, 34):  # stopL, stopJ: async flag in int register 1
            self._stop(self._in_double(0) or DEFAULT_STOP, self._in_int(1) != 1, STOPS[cmd])
            return True
        elif cmd == 31:
            ctl.protective_stop("triggered by the control script (triggerProtectiveStop)")
            return False
        elif cmd == 35:
            ctl.set_watchdog(f"input_int_register_{self.off_int}", self._in_double(0))
        elif cmd in (17, 65):  # setPayload, setTargetPayload
            ctl.payload = self._in_double(0)
            cog = (self._in_double(1), self._in_double(2), self._in_double(3))
            if any(cog) or cmd == 65:
                ctl.payload_cog = cog
            if cmd == 65:
                ctl.payload_inertia = tuple(self._in_double(4 + j) for j in range(6))
        elif cmd == 29:
            ctl.tcp = tuple(self._q(0))
        elif cmd == 40:
            self._out_doubles(ctl.tcp)
        elif cmd in (28, 43):  # target waypoint, forward kinematics of the arm as it is
            self._out_doubles(ctl.pose(arm.target if cmd == 28 else arm.actual))
        elif cmd == 44:
            self._out_doubles(ctl.pose(self._q(0), self._q(6)))
        elif cmd == 58:  # the flange pose: no TCP offset
            self._out_doubles(ctl.pose(arm.actual, (0.0,) * 6))
        elif cmd == 26:
            self._out_doubles([0.002])
        elif cmd == 27:
            self._out_doubles(arm.actual)
        elif cmd == 38:
            self._out_doubles([0.0] * 6)
        elif cmd in (36, 37):
            self._out_int(1, 1)
        elif cmd == 47:
            self._out_int(1, 1 if arm.steady else 0)
        # the rest (zero the F/T sensor, teach mode, damping, gravity...) change nothing here
        if cmd not in STREAMING:
            self._out_int(0, DONE)
        return True

    def _replace(self, motion: Motion) -> None:
        """Start a streaming motion; an async move still running is abandoned."""
        if self.ctl.arm.motion is not motion:
            self.ctl.arm.start(motion)

    def _move(self, move: JointMove) -> None:
        self.ctl.arm.start(move)
        if self._in_int(1) == 1:  # async: done now, progress in output_int_register_2
            self.op_id = (self.op_id + 1) & 0x7F
            self.moving = move
            self._progress(running=True)
            self._out_int(0, DONE)
        else:
            self.waiting = move

    def _stop(self, a: float, wait: bool, name: str) -> None:
        # logged with the tick, so that tests see which arms were told to stop, and when
        self.ctl.log(f"{name} (a = {a:g}) at tick {self.ctl.tick_count}")
        stop = Stop(a)
        self.ctl.arm.start(stop)
        if wait:
            self.waiting = stop
        else:
            self._out_int(0, DONE)
