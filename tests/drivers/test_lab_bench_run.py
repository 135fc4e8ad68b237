"""Issue 17: a lab plan end to end on the emulated bench through the real drivers:
`cellengine run` streams both robots' G-code to two emulated GRBL 1.1 controllers (pyserial,
character counting), sets both Dynamixel grippers (ROBOTIS' dynamixel-sdk, Protocol 2.0)
and reads robot1's serial load cell, all on pseudo-terminals (tests/drivers/labbench.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import cellengine.skills.lab  # noqa: F401  (registers the lab skills)
from cellengine.pipeline import compile_plan
from tests.conftest import CELLS, ROOT
from tests.drivers.labbench import emulated_bench, machine

PLAN = "plan_weigh_handover.yaml"


def test_the_weigh_handover_plan_runs_on_the_emulated_bench(tmp_path: Path) -> None:
    c = compile_plan(CELLS / "lab_bench" / PLAN)
    q0 = c.program.segments[0].trajectory.q[0]
    with emulated_bench(tmp_path, q0, masses=[36.0]) as bench:
        run = tmp_path / "run"
        cmd = [sys.executable, "-m", "cellengine.cli", "run", str(bench.folder / PLAN)]
        result = subprocess.run(
            [*cmd, "--out", str(run), "--yes", "-q"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert result.returncode == 0, result.stderr[-3000:]
        journal = [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]
        assert journal[-1]["entry"] == "end"
        (weighed,) = [e for e in journal if e["entry"] == "measured"]
        # objects.yaml: 36 g; the emulated cell's noise 0.2 g, tared at activation
        assert weighed["object"] == "vial3" and abs(weighed["mass_kg"] - 0.036) < 0.001
        # every block went through GRBL's buffer whole, and each robot ends where the plan
        # does, within the axes' resolution (GRBL's 0.001 mm, 80 steps/mm)
        end = c.program.segments[-1].trajectory.q[-1]
        for k, port in enumerate(bench.grbl):
            assert port.device.overflows == 0
            assert sum(line.startswith("G1") for line in port.device.log) > 100
            assert np.allclose(port.device.position, machine(end[4 * k : 4 * k + 4]), atol=0.02)
        # both grippers took their modes: robot2 gave vial3 over, robot1 weighed it
        writes = [line for line in bench.bus.device.log if "instruction 0x03" in line]
        assert {line.split()[1] for line in writes} == {"1", "2"}
        assert bench.physics.grasps == 1


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
