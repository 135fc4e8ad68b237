"""Issue 17's faults end to end: `cellengine run` of a short plan (robot1 weighs vial1) on
the emulated bench, each fault made while it runs. Both controllers get a feed hold (the
one still connected, for a lost port), the run exits 3 with the fault journaled, and once
the fault is gone `--resume` completes the plan, each robot where the plan ends."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.lab  # noqa: F401  (registers the lab skills)
from cellengine.pipeline import compile_plan
from tests.conftest import CELLS, ROOT
from tests.drivers.labbench import Bench, emulated_bench, machine

PLAN = (
    "cell: cell.yaml\nobjects: objects.yaml\nsteps:\n  - {id: weigh, skill: Weigh, object: vial1}\n"
)


def _lost(bench: Bench) -> tuple[Callable[[], bool], Callable[[], None], Callable[[], None]]:
    """robot1's USB cable pulled while it moves to vial1, plugged back in after."""
    port = bench.grbl[0]
    moving = lambda: sum(line.startswith("G1") for line in port.device.log) >= 40  # noqa: E731
    return moving, lambda: port.faults.append((0.0, "lost")), lambda: bench.replug(port)


def _stuck(bench: Bench) -> tuple[Callable[[], bool], Callable[[], None], Callable[[], None]]:
    """Both grippers' servos stop moving before the run: robot1's grasp never closes."""

    def free() -> None:
        for servo in bench.bus.device.servos.values():
            servo.stuck = False

    def stick() -> None:
        for servo in bench.bus.device.servos.values():
            servo.stuck = True

    return lambda: True, stick, free


def _silent(bench: Bench) -> tuple[Callable[[], bool], Callable[[], None], Callable[[], None]]:
    """The load cell falls silent once robot1 holds vial1, before it weighs it."""
    scale = bench.scale.device

    def speak() -> None:
        scale.silent = False

    return lambda: bench.physics.grasps >= 1, lambda: setattr(scale, "silent", True), speak


FAULTS = {"lost port": (_lost, "connection"), "gripper": (_stuck, "gripper")}
FAULTS["silent load cell"] = (_silent, "load_cell")


@pytest.mark.parametrize("name", list(FAULTS))
def test_a_fault_holds_both_robots_and_resume_completes(tmp_path: Path, name: str) -> None:
    make, kind = FAULTS[name]
    shutil.copytree(CELLS / "lab_bench", tmp_path / "ref")
    c = compile_plan(_plan(tmp_path / "ref"))
    q0, end = c.program.segments[0].trajectory.q[0], c.program.segments[-1].trajectory.q[-1]
    with emulated_bench(tmp_path, q0, masses=[30.0]) as bench:
        plan = _plan(bench.folder)
        when, fault, mend = make(bench)
        watcher = _when(when, fault)
        run = tmp_path / "run"
        stopped = _cli(plan, "--out", str(run))
        watcher.join(timeout=1.0)
        assert stopped.returncode == 3, stopped.stderr[-3000:]
        entry = next(e for e in _journal(run) if e["entry"] == "fault")
        assert entry["fault"]["kind"] == kind, entry
        # every controller still connected was held within 20 ms of the detection
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
        (weighed,) = [e for e in journal if e["entry"] == "measured"]
        assert weighed["object"] == "vial1" and abs(weighed["mass_kg"] - 0.030) < 0.001
        assert bench.physics.grasps == 1  # the grasp that failed, done on resuming
        for k, port in enumerate(bench.grbl):
            assert port.device.overflows == 0
            assert np.allclose(port.device.position, machine(end[4 * k : 4 * k + 4]), atol=0.02)


def _plan(folder: Path) -> Path:
    path = folder / "plan_weigh1.yaml"
    path.write_text(PLAN)
    return path


def _when(condition: Callable[[], bool], action: Callable[[], None]) -> threading.Thread:
    """``action`` as soon as ``condition`` holds (polled every 2 ms, for up to 60 s)."""

    def watch() -> None:
        deadline = time.monotonic() + 60.0
        while not condition() and time.monotonic() < deadline:
            time.sleep(0.002)
        action()

    thread = threading.Thread(target=watch, daemon=True)
    thread.start()
    return thread


def _cli(plan: Path, *args: str) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "cellengine.cli", "run", str(plan), *args, "--yes", "-q"]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)


def _journal(run: Path) -> list[dict[str, object]]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]
