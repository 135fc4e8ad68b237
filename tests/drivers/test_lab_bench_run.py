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
