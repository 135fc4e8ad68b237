"""The UR driver with the real ur-rtde client: what it refuses before anything moves.
(Streaming to emulated controllers is tested with the emulator.)"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cellengine.drivers.fault import DriverRefused
from cellengine.drivers.lifecycle import State
from cellengine.drivers.registry import make_driver
from cellengine.drivers.ur_rtde import UrDriver
from cellengine.info.load import load_cell
from tests.conftest import CELLS

JOINTS = {"left": [f"l{i}" for i in range(6)], "right": [f"r{i}" for i in range(6)]}


def _cell(tmp_path: Path, driver: str) -> Path:
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", folder)
    path = folder / "cell.yaml"
    path.write_text(path.read_text().replace("{kind: sim}", driver))
    return path


def test_an_address_where_no_controller_answers_is_refused(tmp_path: Path) -> None:
    path = _cell(tmp_path, "{kind: ur_rtde, arms: {left: 127.0.0.9, right: 127.0.0.10}}")
    cell, _ = load_cell(path)
    driver = make_driver(cell, JOINTS, connect_timeout=2.0)
    assert isinstance(driver, UrDriver)
    assert driver.addresses == {"left": "127.0.0.9", "right": "127.0.0.10"}
    with pytest.raises(DriverRefused) as e:
        driver.configure()
    assert str(e.value).startswith("ur_rtde driver: arm 'left': dashboard at 127.0.0.9: ")
    assert driver.state is State.UNCONFIGURED  # nothing half-done: still unconfigured


def test_the_ur_driver_needs_a_ur_rtde_cell(tmp_path: Path) -> None:
    cell, _ = load_cell(_cell(tmp_path, "{kind: sim}"))
    with pytest.raises(DriverRefused, match="the cell's driver is 'sim', not ur_rtde"):
        UrDriver(cell, JOINTS)


def test_run_asks_before_moving_real_arms(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """No terminal to ask and no --yes: refused (exit 2) before any connection; with --yes
    the driver tries the cell's addresses, and one that does not answer stops the run
    (exit 3) before anything moves."""
    from cellengine.cli import main

    path = _cell(tmp_path, "{kind: ur_rtde, arms: {left: 127.0.0.9, right: 127.0.0.10}}")
    plan = path.parent / "plan_straight.yaml"
    out = tmp_path / "run"
    assert main(["run", str(plan), "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert (
        "refusing to move real arms (left at 127.0.0.9, right at 127.0.0.10) without --yes: "
        "no terminal to ask"
    ) in err
    assert not (out / "journal.jsonl").exists()
    assert main(["run", str(plan), "--out", str(out), "-q", "--yes"]) == 3
    assert "arm 'left': dashboard at 127.0.0.9" in capsys.readouterr().err
    # not quiet: what is about to move, how long and how fast, before anything connects
    slow = ["--out", str(tmp_path / "slow"), "--yes", "--speed", "0.5"]
    assert main(["run", str(plan), *slow]) == 3
    said = capsys.readouterr().err
    assert (
        said.startswith("[1/3] PickCable")
        and "\nmoving real arms (left at 127.0.0.9, right at 127.0.0.10): " in said
    )
    assert "; timed at 50 % of the joints' velocity and acceleration limits (--speed 0.5)\n" in said
