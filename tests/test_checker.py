"""One file's check: a checker keeps the last few cells' worlds, not every one it met."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cellengine.checker import KEPT_CELLS, Checker
from tests.conftest import CELLS


def test_a_checker_keeps_only_the_last_cells(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    checker = Checker(compile_plans=False)
    names = [f"c{i}" for i in range(KEPT_CELLS + 2)]
    for name in names:
        shutil.copytree(CELLS / "cable_routing", tmp_path / name)
        result = checker.check((Path(name) / "plan_straight.yaml", True))
        assert result is not None and result.problems == [] and result.kind == "plan"
    kept = [p.parent.name for p in checker._worlds]
    assert kept == names[-KEPT_CELLS:]
