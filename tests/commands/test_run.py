"""`cellengine run`'s options that are checked before anything compiles."""

from __future__ import annotations

from pathlib import Path

import pytest

from cellengine.cli import main
from cellengine.commands.run import DRIVER_KINDS
from cellengine.drivers.registry import DRIVERS
from tests.conftest import CELLS

PLAN = CELLS / "cable_routing" / "plan_straight.yaml"


def test_driver_kinds_are_the_registry_s() -> None:
    assert tuple(DRIVERS) == DRIVER_KINDS


def test_unknown_driver_is_a_usage_error_before_compiling(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    with pytest.raises(SystemExit) as e:
        main(["run", str(PLAN), "--out", str(out), "--driver", "foo"])
    assert e.value.code == 2
    err = capsys.readouterr().err.splitlines()
    assert err[-1] == (
        "cellengine run: error: argument --driver: unknown driver 'foo'; known: lab, sim, ur_rtde"
    )
    assert not out.exists()  # nothing compiled, nothing written
