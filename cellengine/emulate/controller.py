"""One emulated controller: robot and safety modes, I/O, registers, the running program and
the arm. RTDE packages and dashboard answers are read from here; the servers only talk."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Protocol

from cellengine.emulate.arm import DT, Arm
from cellengine.emulate.control_script import ControlScript
from cellengine.emulate.kinematics import tcp_pose
from cellengine.emulate.rtde_protocol import Value
from cellengine.emulate.rtde_types import FORMATS, output_type

VERSION = (5, 11, 6, 108249)  # the PolyScope version the controller reports
SERIAL = "20235500001"
POWER_OFF, IDLE, RUNNING = 3, 5, 7  # robot modes
STOPPED, PLAYING = 1, 2  # runtime states
SAFETY_MODES = {"normal": 1, "protective": 3, "emergency": 7}  # 7: robot emergency stop
SAFETY_BITS = {"normal": 1 << 0, "protective": 1 << 2 | 1 << 10, "emergency": 0xC0 | 1 << 10}
SAFETY_DECELERATION = 20.0  # rad/s^2, a stop for safety
PROGRAM_STOP_DECELERATION = 10.0  # rad/s^2, a program that ends while the arm moves
UNLOCK_DELAY = 5.0  # s before a protective stop may be unlocked from the dashboard


class Program(Protocol):
    name: str

    def tick(self) -> bool: ...


class LoadedProgram:
    """A program loaded through the dashboard: it plays, and does nothing."""

    def __init__(self, name: str) -> None:
        self.name = name

    def tick(self) -> bool:
        return True


def _zero(kind: str) -> Value:
    fmt = FORMATS[kind]
    scalar: float | int | bool = 0.0 if fmt[-1] == "d" else False if fmt == "?" else 0
    return tuple([scalar] * int(fmt[:-1])) if len(fmt) > 1 else scalar


class Controller:
    """Everything one emulated controller knows, stepped once per 2 ms tick."""

    def __init__(
        self, host: str, q0: Sequence[float], model: str, log: Callable[[str], None]
    ) -> None:
        self.host, self.model, self._log = host, model, log
        self.arm = Arm(q0)
        self.inputs: dict[str, Value] = {}  # the last value a client wrote to each input
        # and when it did, by the wall clock: the watchdog must not fire because the emulator
        # itself was late reading (a controller is never late)
        self.input_time: dict[str, float] = {}
        self.outputs: dict[str, Value] = {}  # output registers the program wrote
        self.program: Program | None = None
        self.loaded: str | None = None  # a program loaded through the dashboard
        self.robot_mode, self.safety = RUNNING, "normal"
        self.safety_tick = 0
        self.tick_count = 0
        self.watchdog: tuple[str, float] | None = None  # input variable, minimum frequency
        self.digital_out = 0  # standard 0-7, configurable 8-15, tool 16-17
        self.speed_fraction = 1.0
        self.analog_out = [0.0, 0.0]
        self.payload, self.payload_cog = 0.0, (0.0, 0.0, 0.0)
        self.payload_inertia: tuple[float, ...] = (0.0,) * 6
        self.tcp: tuple[float, ...] = (0.0,) * 6
        self._poses: dict[str, tuple[float, ...]] = {}
        self._getters = self._make_getters()

    def log(self, message: str) -> None:
        self._log(f"{self.host}: {message}")

    # -- what RTDE reports ----------------------------------------------------------------

    def _make_getters(self) -> dict[str, Callable[[], Value]]:
        arm = self.arm
        return {
            "timestamp": lambda: self.tick_count * DT,
            "target_q": lambda: tuple(arm.target),
            "target_qd": lambda: tuple(arm.target_qd),
            "target_qdd": lambda: tuple(arm.target_qdd),
            "actual_q": lambda: tuple(arm.actual),
            "actual_qd": lambda: tuple(arm.actual_qd),
            "actual_TCP_pose": lambda: self._pose("actual", arm.actual),
            "target_TCP_pose": lambda: self._pose("target", arm.target),
            "tcp_offset": lambda: self.tcp,
            "actual_digital_output_bits": lambda: self.digital_out,
            "robot_mode": lambda: self.robot_mode,
            "joint_mode": lambda: (253,) * 6 if self.robot_mode == RUNNING else (239,) * 6,
            "safety_mode": lambda: SAFETY_MODES[self.safety],
            "safety_status": lambda: SAFETY_MODES[self.safety],
            "safety_status_bits": lambda: SAFETY_BITS[self.safety],
            "runtime_state": lambda: self.runtime_state,
            "robot_status_bits": lambda: (
                (1 if self.robot_mode != POWER_OFF else 0) | (2 if self.program else 0)
            ),
            "speed_scaling": lambda: self.speed_fraction if self.safety == "normal" else 0.0,
            "target_speed_fraction": lambda: self.speed_fraction,
            "standard_analog_output0": lambda: self.analog_out[0],
            "standard_analog_output1": lambda: self.analog_out[1],
            "payload": lambda: self.payload,
            "payload_cog": lambda: self.payload_cog,
            "payload_inertia": lambda: self.payload_inertia,
            "actual_main_voltage": lambda: 48.0,
            "actual_robot_voltage": lambda: 48.0 if self.robot_mode != POWER_OFF else 0.0,
            "actual_joint_voltage": lambda: (48.0,) * 6,
            "joint_temperatures": lambda: (30.0,) * 6,
            "actual_tool_accelerometer": lambda: (0.0, 0.0, 9.81),
        }

    def value(self, name: str) -> Value:
        """The current value of an output variable (the name is known to rtde_types)."""
        getter = self._getters.get(name)
        if getter is not None:
            return getter()
        if name in self.outputs:
            return self.outputs[name]
        if name in self.inputs:
            return self.inputs[name]
        kind = output_type(name)
        return _zero(kind) if kind else 0

    def number(self, name: str) -> float:
        """An input register or variable as a number (0 until a client writes it)."""
        v = self.inputs.get(name, 0)
        return float(v[0] if isinstance(v, tuple) else v)

    def pose(self, q: Sequence[float], tcp: Sequence[float] | None = None) -> tuple[float, ...]:
        return tcp_pose(self.model, q, self.tcp if tcp is None else tcp)

    def _pose(self, which: str, q: Sequence[float]) -> tuple[float, ...]:
        if which not in self._poses:  # forward kinematics once a tick
            self._poses[which] = self.pose(q)
        return self._poses[which]

    @property
    def runtime_state(self) -> int:
        return PLAYING if self.program is not None else STOPPED

    # -- what clients write ---------------------------------------------------------------

    def write_inputs(self, values: dict[str, Value]) -> None:
        """An input package: registers are kept; masked outputs are set as a controller
        sets them (the bits whose mask bit is 1)."""
        for name, v in values.items():
            self.inputs[name] = v
            self.input_time[name] = time.monotonic()

        def num(name: str, default: float = 0.0) -> float:
            v = values.get(name, default)
            return float(v[0] if isinstance(v, tuple) else v)

        before = self.digital_out
        for prefix, shift in (("standard", 0), ("configurable", 8), ("tool", 16)):
            mask = int(num(f"{prefix}_digital_output_mask"))
            bits = int(num(f"{prefix}_digital_output"))
            self.digital_out = (self.digital_out & ~(mask << shift)) | (bits & mask) << shift
        if self.digital_out != before:  # tests read the sequence of outputs from the log
            self.log(f"digital outputs {self.digital_out:#x} at tick {self.tick_count}")
        if int(num("speed_slider_mask")) & 1:
            self.speed_fraction = max(0.0, min(1.0, num("speed_slider_fraction", 1.0)))
        mask = int(num("standard_analog_output_mask"))
        for i in (0, 1):
            if mask >> i & 1:
                self.analog_out[i] = num(f"standard_analog_output_{i}")

    def set_watchdog(self, variable: str, frequency: float) -> None:
        """The program stops when ``variable`` is not written at ``frequency`` Hz or more."""
        self.watchdog = (variable, frequency) if frequency > 0 else None
        self.input_time[variable] = time.monotonic()

    # -- programs ---------------------------------------------------------------------------

    def start_program(self, name: str, text: str) -> None:
        """A program arrived on the script port: it replaces the running one."""
        if self.safety != "normal" or self.robot_mode != RUNNING:
            self.log(f"program '{name}' not started: safety {self.safety}, mode {self.robot_mode}")
            return
        self.stop_program(f"replaced by program '{name}'")
        if name == ControlScript.name:
            self.program = ControlScript(self, text)
            self.log("control script running")
        else:  # not the control script: it runs, does nothing here, and ends
            self.log(f"program '{name}' is not emulated: it ends at once")

    def stop_program(self, why: str, deceleration: float = PROGRAM_STOP_DECELERATION) -> None:
        if self.program is not None:
            self.log(f"program '{self.program.name}' stopped: {why}")
            self.program, self.watchdog = None, None
            self.arm.stop(deceleration)

    def tick(self) -> None:
        self.tick_count += 1
        self._poses.clear()
        if self.program is not None:
            if self.watchdog is not None:
                variable, frequency = self.watchdog
                if time.monotonic() - self.input_time.get(variable, 0.0) > 1.0 / frequency:
                    self.stop_program(f"RTDE watchdog: {variable} not written at {frequency:g} Hz")
            if self.program is not None and not self.program.tick():
                self.stop_program("the script ended")
        self.arm.step(self.speed_fraction)

    # -- safety -----------------------------------------------------------------------------

    def protective_stop(self, why: str) -> None:
        if self.safety == "normal":
            self.safety, self.safety_tick = "protective", self.tick_count
            self.log(f"protective stop: {why}")
            self._halt("protective stop")

    def emergency_stop(self, why: str) -> None:
        if self.safety != "emergency":
            self.safety, self.safety_tick = "emergency", self.tick_count
            self.robot_mode = POWER_OFF  # arm power is cut once it has stopped
            self.log(f"emergency stop: {why}")
            self._halt("emergency stop")

    def _halt(self, why: str) -> None:
        self.stop_program(why, SAFETY_DECELERATION)
        self.arm.stop(SAFETY_DECELERATION)

    def clear(self) -> None:
        """The operator clears the fault: a protective stop is unlocked, an emergency stop
        released (the arm stays powered off until power on and brake release), a frozen arm
        moves again."""
        if self.safety != "normal":
            self.log(f"{self.safety} stop cleared")
            self.safety = "normal"
        if self.arm.frozen:
            self.log("arm moves again")
            self.arm.unfreeze()

    def unlock_protective_stop(self) -> str:
        if self.safety == "protective":
            if (self.tick_count - self.safety_tick) * DT < UNLOCK_DELAY:
                return (
                    "Cannot unlock protective stop until 5s after occurrence. "
                    "Always inspect cause of protective stop before unlocking"
                )
            self.clear()
        return "Protective stop releasing"
