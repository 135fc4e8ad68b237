"""The dashboard server (TCP 29999): a welcome line, then one answer line per command line,
worded as PolyScope 5 words them (ur-rtde compares some answers exactly: "Stopped",
"Starting program", "Protective stop releasing"; it takes the version from the first
d.d.d.d in PolyscopeVersion's answer and wants digits from "get serial number")."""

from __future__ import annotations

from cellengine.emulate.controller import (
    IDLE,
    POWER_OFF,
    RUNNING,
    SERIAL,
    VERSION,
    Controller,
    LoadedProgram,
)
from cellengine.emulate.net import Conn

WELCOME = "Connected: Universal Robots Dashboard Server"
ROBOT_MODES = {POWER_OFF: "POWER_OFF", IDLE: "IDLE", RUNNING: "RUNNING"}
SAFETY = {"normal": "NORMAL", "protective": "PROTECTIVE_STOP", "emergency": "ROBOT_EMERGENCY_STOP"}


def _queries(ctl: Controller) -> dict[str, str]:
    """Answers that only read the controller's state."""
    version = ".".join(map(str, VERSION))
    program = ctl.program.name if ctl.program is not None else ctl.loaded or "<unnamed>"
    return {
        "polyscopeversion": f"URSoftware {version} (Mar 22 2023)",
        "version": f"Version: {version}",
        "get serial number": SERIAL,
        "get robot model": ctl.model,
        "is in remote control": "true",
        "robotmode": f"Robotmode: {ROBOT_MODES.get(ctl.robot_mode, 'RUNNING')}",
        "safetymode": f"Safetymode: {SAFETY[ctl.safety]}",
        "safetystatus": f"Safetystatus: {SAFETY[ctl.safety]}",
        "running": f"Program running: {'true' if ctl.program else 'false'}",
        "programstate": f"{'PLAYING' if ctl.program else 'STOPPED'} {program}",
        "get loaded program": f"Loaded program: {ctl.loaded or '<unnamed>'}",
        "isprogramsaved": f"true {program}",
        "get operational mode": "NONE",
        "close popup": "closing popup",
        "close safety popup": "closing safety popup",
        "restart safety": "Restarting safety",
        "shutdown": "Shutting down",
        "clear operational mode": "No longer controlling the operational mode.",
    }


def answer(ctl: Controller, line: str) -> str:
    """The answer to one command line."""
    low = line.strip().lower()
    word, _, arg = line.strip().partition(" ")
    queries = _queries(ctl)
    if low in queries:
        return queries[low]
    if low == "unlock protective stop":
        return ctl.unlock_protective_stop()
    if low == "power on":
        if ctl.safety == "normal" and ctl.robot_mode == POWER_OFF:
            ctl.robot_mode = IDLE
        return "Powering on"
    if low == "brake release":
        if ctl.safety == "normal" and ctl.robot_mode == IDLE:
            ctl.robot_mode = RUNNING
        return "Brake releasing"
    if low == "power off":
        ctl.stop_program("power off")
        ctl.robot_mode = POWER_OFF
        return "Powering off"
    if low == "stop":
        ctl.stop_program("stopped from the dashboard")
        return "Stopped"
    if low == "pause":
        return "Pausing program" if ctl.program else "Failed to execute: pause"
    if low == "play":
        if ctl.loaded and ctl.safety == "normal" and ctl.robot_mode == RUNNING:
            ctl.program = LoadedProgram(ctl.loaded)
            return "Starting program"
        return "Failed to execute: play"
    word = word.lower()
    if word == "load" and arg:
        ctl.loaded = arg.strip()
        return f"Loading program: {ctl.loaded}"
    with_argument = {
        "popup": "showing popup",
        "addtolog": "Added log message",
        "setuserrole": f"Setting user role: {arg}",
    }
    return with_argument.get(word, f"could not understand: '{line.strip()}'")


class DashboardSession:
    def __init__(self, ctl: Controller, conn: Conn) -> None:
        self.ctl, self.conn = ctl, conn
        self._buf = b""
        conn.send((WELCOME + "\n").encode())

    def received(self, data: bytes) -> None:
        self._buf += data
        while b"\n" in self._buf:
            raw, self._buf = self._buf.split(b"\n", 1)
            line = raw.decode("utf-8", "replace").strip()
            if line.lower() == "quit":
                self.conn.send(b"Disconnected\n")
                self.conn.flush()
                self.conn.close()
                return
            self.conn.send((answer(self.ctl, line) + "\n").encode())

    def closed(self) -> None:
        pass
