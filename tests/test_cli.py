"""The CLI stays quick to start: the reference cells never import trimesh or scipy (half a
second of imports), which only URDF mesh files and round X3D primitives need."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from tests.conftest import CELLS, ROOT

# Runs the commands in a fresh interpreter and prints whether trimesh or scipy got imported.
SCRIPT = """
import sys
from cellengine.cli import main

def heavy():
    return sorted({m.split(".")[0] for m in sys.modules} & {"trimesh", "scipy"})

main(["validate", "--no-compile", sys.argv[1]])
print("validate", heavy())
main(["plan", sys.argv[2], "-q", "--out", sys.argv[3]])
print("plan", heavy())
"""


def test_reference_cells_need_neither_trimesh_nor_scipy(tmp_path: Path) -> None:
    plan = CELLS / "cable_routing" / "plan_two_turns.yaml"
    args = [sys.executable, "-c", SCRIPT, str(CELLS), str(plan), str(tmp_path / "out")]
    result = subprocess.run(args, capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert result.returncode == 0, result.stderr
    lines = [ln for ln in result.stdout.splitlines() if ln.startswith(("validate ", "plan "))]
    assert lines == ["validate []", "plan []"]
