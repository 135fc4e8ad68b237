"""A run's identity: each input file by content, the execution, the engine's version; what
differs said in words."""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

from cellengine.motion.speed import Speed
from cellengine.pipeline import Compiled, compile_plan
from cellengine.runner.identity import differences, run_identity
from tests.conftest import CELLS


def test_the_identity_follows_the_files_content_and_the_execution(tmp_path: Path) -> None:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    plan = tmp_path / "cell" / "plan_straight.yaml"
    first = run_identity(compile_plan(plan))
    assert set(first) == {"plan", "cell", "objects", "execution", "version"}
    assert run_identity(compile_plan(plan)) == first  # the same files: the same run
    plan.write_text(plan.read_text() + "\n# a comment\n")
    objects = tmp_path / "cell" / "objects.yaml"
    objects.write_text(objects.read_text() + "\n# another\n")
    now = run_identity(compile_plan(plan, "async"))
    assert differences(first, now) == [
        "the plan file changed",
        "the objects file changed",
        "the execution was split, now async",
    ]


def test_a_run_slowed_on_the_command_line_is_resumed_at_that_speed(cycling: Compiled) -> None:
    first = run_identity(cycling)
    assert "speed" not in first  # as runs were journaled before --speed
    slowed = replace(cycling, context=cycling.context.with_speed(Speed(0.25, 0.25, None, 0.25)))
    assert run_identity(slowed)["speed"] == "0.25"
    assert differences(run_identity(slowed), first) == ["--speed was 0.25, now 1"]
