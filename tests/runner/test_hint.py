"""A run stopped by a fault or Ctrl-C says how to go on: the resume command with the run's
own paths and options."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from cellengine.drivers.fault import DriverFault, Fault
from cellengine.errors import EXIT_DRIVER, EXIT_USAGE, DriverError, UsageError
from cellengine.info.load import load_plan
from cellengine.runner.hint import resumable, resume_command
from tests.conftest import CELLS


@pytest.fixture
def cell(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "my cell")
    monkeypatch.chdir(tmp_path)
    return tmp_path / "my cell"


def test_the_command_names_the_plan_the_run_folder_and_the_options_given(cell: Path) -> None:
    plan = cell / "plan_straight.yaml"
    loaded = load_plan(plan)
    assert resume_command(loaded, "split", 1.0, Path("run")) == (
        "cellengine run 'my cell/plan_straight.yaml' --resume run"
    )
    assert resume_command(loaded, "sync", 0.25, cell / "out") == (
        "cellengine run 'my cell/plan_straight.yaml' --resume 'my cell/out' "
        "--execution sync --speed 0.25"
    )
    os.link(cell / "cell.yaml", cell / "other.yaml")
    other = load_plan(plan, cell=cell / "other.yaml")
    assert resume_command(other, "split", 1.0, Path("run")) == (
        "cellengine run 'my cell/plan_straight.yaml' --resume run --cell 'my cell/other.yaml'"
    )


def test_a_fault_keeps_its_exit_code_and_says_how_to_go_on() -> None:
    fault = Fault("interrupted", "interrupted at t = 2.154 s; both arms stopped", time=2.154)
    with pytest.raises(DriverError) as e, resumable("cellengine run p.yaml --resume run"):
        raise DriverFault("sim", fault)
    assert e.value.exit_code == EXIT_DRIVER
    assert str(e.value).splitlines() == [
        "sim driver: interrupted at t = 2.154 s; both arms stopped",
        "to go on from where it stopped: cellengine run p.yaml --resume run",
    ]


def test_ctrl_c_is_an_interruption_that_says_how_to_go_on() -> None:
    with pytest.raises(UsageError) as e, resumable("cellengine run p.yaml --resume run"):
        raise KeyboardInterrupt
    assert e.value.exit_code == EXIT_USAGE
    assert str(e.value).splitlines() == [
        "interrupted; both arms stopped",
        "to go on from where it stopped: cellengine run p.yaml --resume run",
    ]
