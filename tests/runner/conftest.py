"""A plan that ends where it starts (the straight reference plan with ``return_home:
true``), compiled once for the runner's tests."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from cellengine.pipeline import Compiled, compile_plan
from tests.conftest import CELLS


@pytest.fixture(scope="session")
def cycle_plan(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("cycle") / "cable_routing"
    shutil.copytree(CELLS / "cable_routing", folder)
    plan = folder / "plan_cycle.yaml"
    text = (folder / "plan_straight.yaml").read_text()
    plan.write_text(text.replace("execution: split\n", "execution: split\nreturn_home: true\n"))
    return plan


@pytest.fixture(scope="session")
def cycling(cycle_plan: Path) -> Compiled:
    return compile_plan(cycle_plan)
