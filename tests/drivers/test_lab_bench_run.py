"""Issue 17: every lab plan end to end on the emulated bench through the real drivers:
`cellengine run` streams both robots' G-code to two emulated GRBL 1.1 controllers (pyserial,
character counting), sets both Dynamixel grippers (ROBOTIS' dynamixel-sdk, Protocol 2.0)
and reads robot1's serial load cell, all on pseudo-terminals (tests/drivers/labbench.py).
Each plan meets a fault while it runs: a limit switch, a lost port, a gripper that does not
close, a silent load cell. Both robots are held (the one still connected, for a lost port),
the run exits 3 with the fault journaled, and once the fault is gone `--resume` completes
the plan, each robot where the plan ends."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import cellengine.skills.lab  # noqa: F401  (registers the lab skills)
from cellengine.pipeline import compile_plan
from tests.conftest import CELLS, ROOT
from tests.drivers.labbench import Bench, emulated_bench, machine

# when the fault happens, the fault, and what takes it away (before --resume)
Fault = tuple[Callable[[], bool], Callable[[], None], Callable[[], None]]


def test_an_alarm_mid_overlap_holds_both_and_resume_completes(tmp_path: Path) -> None:
    """plan_relocate: robot1's limit switch trips while both robots move (robot2 back to its
    rest, robot1 on its way to vial4). Both controllers get a feed hold, the run exits 3
    with the fault and each robot's segments journaled; once unlocked ($X: the cell says
    unlock), --resume goes on from where each robot stopped and ends."""
    plan = "plan_relocate.yaml"
    c = compile_plan(CELLS / "lab_bench" / plan)
    both = next(s for s in c.program.segments if {"robot1", "robot2"} <= set(s.report["arms"]))
    t_fault = float(np.mean([both.trajectory.start_time, both.trajectory.end_time]))
    with emulated_bench(tmp_path, c.program.segments[0].trajectory.q[0], []) as bench:
        cell = bench.folder / "cell.yaml"
        cell.write_text(cell.read_text().replace("axes: {z:", "unlock: true, axes: {z:"))
        bench.grbl[0].faults.append((t_fault, "alarm1"))
        run = tmp_path / "run"
        cmd = [sys.executable, "-m", "cellengine.cli", "run", str(bench.folder / plan)]

        def cli(*args: str) -> subprocess.CompletedProcess[str]:
            full = [*cmd, *args, "--yes", "-q"]
            return subprocess.run(full, cwd=ROOT, capture_output=True, text=True, timeout=300)

        stopped = cli("--out", str(run))
        assert stopped.returncode == 3, stopped.stderr[-3000:]
        assert (
            "robot 'robot1'" in stopped.stderr and "ALARM:1 (hard limit triggered" in stopped.stderr
        )
        journal = [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]
        fault = next(e for e in journal if e["entry"] == "fault")
        assert fault["fault"]["kind"] == "alarm" and fault["streams"]["running"]
        for port in bench.grbl:  # held, then reset, both
            assert port.device.realtime[-2:] == ["!", "^X"]
        resumed = cli("--resume", str(run))
        assert resumed.returncode == 0, resumed.stderr[-3000:]
        journal = [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]
        assert journal[-1]["entry"] == "end"
        last = [e for e in journal if e["entry"] == "finished"][-1]
        assert set(last["streams"]["done"]) == {s.index for s in c.program.streams}


def _lost(bench: Bench) -> Fault:
    """robot1's USB cable pulled once it is under way, plugged back in after."""
    port = bench.grbl[0]

    def moving() -> bool:
        return sum(line.startswith("G1") for line in port.device.log) >= 40

    return moving, lambda: port.faults.append((0.0, "lost")), lambda: bench.replug(port)


def _stuck(bench: Bench) -> Fault:
    """The grippers' servos stop moving before the run: the first grasp never closes."""

    def stick(stuck: bool) -> None:
        for servo in bench.bus.device.servos.values():
            servo.stuck = stuck

    return lambda: True, lambda: stick(True), lambda: stick(False)


def _silent(bench: Bench) -> Fault:
    """The load cell falls silent once robot1 holds what it weighs."""
    scale = bench.scale.device

    def speak(silent: bool) -> None:
        scale.silent = silent

    return lambda: bench.physics.grasps >= 1, lambda: speak(True), lambda: speak(False)


# plan, fault, its kind, the masses of robot1's grasps (g), what is weighed
CASES = {
    "lost port": ("plan_cluttered", _lost, "connection", [], {}),
    "gripper": ("plan_pour_heavier", _stuck, "gripper", [30.0, 42.0], {"vial1": 30, "vial2": 42}),
    "silent load cell": ("plan_weigh_handover", _silent, "load_cell", [36.0], {"vial3": 36}),
}


@pytest.mark.parametrize("name", list(CASES))
def test_a_plan_runs_through_a_fault_and_resume_completes(tmp_path: Path, name: str) -> None:
    plan_name, make, kind, masses, weighed = CASES[name]
    c = compile_plan(CELLS / "lab_bench" / f"{plan_name}.yaml")
    q0, end = c.program.segments[0].trajectory.q[0], c.program.segments[-1].trajectory.q[-1]
    with emulated_bench(tmp_path, q0, masses) as bench:
        plan = bench.folder / f"{plan_name}.yaml"
        when, fault, mend = make(bench)
        watcher = _when(when, fault)
        run = tmp_path / "run"
        stopped = _cli(plan, "--out", str(run))
        watcher.join(timeout=1.0)
        assert stopped.returncode == 3, stopped.stderr[-3000:]
        entry = next(e for e in _journal(run) if e["entry"] == "fault")
        assert entry["fault"]["kind"] == kind, entry
        # every controller still connected was held within 20 ms of the detection, then reset
        assert entry["fault"]["details"]["hold_commands_s"] < 0.020
        lost = bench.grbl[0] if name == "lost port" else None
        for port in bench.grbl:
            if port is not lost:
                assert port.device.realtime[-2:] == ["!", "^X"]
        mend()
        resumed = _cli(plan, "--resume", str(run))
        assert resumed.returncode == 0, resumed.stderr[-3000:]
        journal = _journal(run)
        assert journal[-1]["entry"] == "end"
        # the load cell tared once, empty, at the start; each weighing read with 0.2 g noise
        measured = {e["object"]: e["mass_kg"] for e in journal if e["entry"] == "measured"}
        assert set(measured) == set(weighed)
        assert all(abs(measured[k] - weighed[k] / 1000.0) < 0.001 for k in weighed)
        assert bench.physics.grasps >= len(masses)  # a grasp that failed, done on resuming
        # every block went through GRBL's buffer whole, each robot ends where the plan does
        # within the axes' resolution (GRBL's 0.001 mm, 80 steps/mm), both grippers worked
        for k, port in enumerate(bench.grbl):
            assert port.device.overflows == 0
            assert sum(line.startswith("G1") for line in port.device.log) > 100
            assert np.allclose(port.device.position, machine(end[4 * k : 4 * k + 4]), atol=0.02)
        writes = [line for line in bench.bus.device.log if "instruction 0x03" in line]
        assert {line.split()[1] for line in writes} == {"1", "2"}


def _when(condition: Callable[[], bool], action: Callable[[], None]) -> threading.Thread:
    """``action`` as soon as ``condition`` holds (polled every 2 ms, for up to 120 s)."""

    def watch() -> None:
        deadline = time.monotonic() + 120.0
        while not condition() and time.monotonic() < deadline:
            time.sleep(0.002)
        action()

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    return thread


def _cli(plan: Path, *args: str) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "cellengine.cli", "run", str(plan), *args, "--yes", "-q"]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)


def _journal(run: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]
