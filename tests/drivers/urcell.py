"""The cable cell on two emulated UR controllers, for the driver's end-to-end tests: the cell
copied with its driver pointed at loopback addresses, `cellengine run` as a subprocess with a
deadline, the run's journal, and emulators started where the plan starts."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np

from tests.conftest import CELLS, ROOT
from tests.emulate.harness import Emulator


def ur_cell(tmp_path: Path, hosts: list[str], options: str = "") -> Path:
    """The cable cell in ``tmp_path/cell`` with driver ur_rtde: left at hosts[0], right at
    hosts[1], and the driver's other ``options`` (", key: value" in flow style)."""
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", folder, dirs_exist_ok=True)
    path = folder / "cell.yaml"
    driver = f"{{kind: ur_rtde, arms: {{left: {hosts[0]}, right: {hosts[1]}}}{options}}}"
    path.write_text(path.read_text().replace("driver: {kind: sim}", f"driver: {driver}"))
    return folder


def run_cli(*args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    """`cellengine run ARGS --yes -q`."""
    cmd = [sys.executable, "-m", "cellengine.cli", "run", *args, "--yes", "-q"]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout)


def journal(run: Path) -> list[dict[str, Any]]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


def start(hosts: list[str], q0: np.ndarray, started: list[Emulator], *extra: str) -> Emulator:
    """One emulator for ``hosts`` (arm i at q0[6i:6i+6]); closed by the test's fixture."""
    args: list[str] = []
    for i, host in enumerate(hosts):
        args += ["--q0", f"{host}=" + ",".join(f"{v:.9f}" for v in q0[6 * i : 6 * i + 6])]
    started.append(Emulator(hosts, *args, *extra))
    return started[-1]
