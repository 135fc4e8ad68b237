"""The CLI stays quick to start: the reference cells never import trimesh or scipy (half a
second of imports), which only URDF mesh files and round X3D primitives need. `--version`;
a broken pipe ends the program quietly."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from cellengine import __version__
from cellengine.cli import EXIT_BROKEN_PIPE, main
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


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out == f"cellengine {__version__}\n"


def test_a_reader_that_went_away_ends_the_program_quietly() -> None:
    """`cellengine show CELL | head`: stdout's reader is gone before the table is written;
    no BrokenPipe traceback, the exit code a shell gives a program its reader left."""
    read_end, write_end = os.pipe()
    os.close(read_end)  # every write to the pipe fails with EPIPE
    try:
        args = [sys.executable, "-m", "cellengine", "show", str(CELLS / "cable_routing")]
        result = subprocess.run(
            args, stdout=write_end, stderr=subprocess.PIPE, text=True, cwd=ROOT, timeout=120
        )
    finally:
        os.close(write_end)
    assert result.stderr == ""
    assert result.returncode == EXIT_BROKEN_PIPE == 141
