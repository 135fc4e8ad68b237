"""A plan that fails to compile: `plan` and `run` print its failures as they always did and
exit 1, and write report.json and report.html of what was compiled before the failure, with
where it failed; never a trajectory.json, and nothing into a folder holding a run to resume."""

from __future__ import annotations

import contextlib
import io
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from cellengine.cli import main
from tests.helpers import walled_lab

MESSAGE = (
    "{plan}:17:5: step 2 (steps[1] Place: carry vial5): no collision-free transit for robot2: "
    "RRTConnect: no path found within 1 s\n"
)
UNFINISHED = '{"entry": "start", "run": {"plan": "x"}}\n{"entry": "sent", "segment": 0}\n'


@pytest.fixture(scope="module")
def failed(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, str, str]:
    """The walled lab's plan, planned into a folder where an earlier plan left a trajectory:
    the plan, the folder, stdout and stderr."""
    base = tmp_path_factory.mktemp("failed")
    plan = walled_lab(base / "cell")
    out = base / "run"
    out.mkdir()
    (out / "trajectory.json").write_text('{"joint_names": [], "points": [], "events": []}\n')
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        assert main(["plan", str(plan), "--out", str(out)]) == 1
    return plan, out, stdout.getvalue(), stderr.getvalue()


def _report(out: Path) -> dict[str, Any]:
    data: dict[str, Any] = json.loads((out / "report.json").read_text())
    return data


def test_the_failure_is_printed_as_before_and_the_report_named(
    failed: tuple[Path, Path, str, str],
) -> None:
    plan, out, stdout, stderr = failed
    assert stderr.splitlines()[-1] + "\n" == MESSAGE.format(plan=plan)
    assert stdout == f"report: {out / 'report.html'}\n"


def test_the_folder_holds_the_report_and_no_trajectory(
    failed: tuple[Path, Path, str, str],
) -> None:
    _, out, _, _ = failed
    assert sorted(p.name for p in out.iterdir()) == [".lock", "report.html", "report.json"]


def test_report_json_has_what_was_compiled_and_where_it_failed(
    failed: tuple[Path, Path, str, str],
) -> None:
    plan, out, _, _ = failed
    report = _report(out)
    assert [s["label"] for s in report["segments"]] == [
        "steps[1] Place: to vial5",
        "steps[1] Place: grasp vial5",
        "steps[1] Place: lift vial5",
    ]
    assert report["totals"]["checks_passed"] is False
    failure = report["failure"]
    assert failure["compiled_segments"] == 3
    (only,) = failure["failures"]
    assert only["messages"] == [MESSAGE.format(plan=plan).rstrip("\n")]
    assert (only["step"], only["step_label"]) == (1, "Place vial5: bench.free_s2")
    assert (only["segment"], only["segment_index"]) == ("steps[1] Place: carry vial5", 3)
    # the straight way to the goal runs the gripper into the wall
    assert (only["kind"], only["pair"], only["time_s"]) == (
        "transit",
        ["robot2/gripper", "wall"],
        None,
    )
    assert len(only["q"]) == len(report["joint_names"]) == 8
    # robot1 has not moved: it is at its home (z, x, y, roll)
    np.testing.assert_allclose(only["q"][:4], [0.25, 0.75, 0.0, 0.0], atol=1e-9)
    # robot2's transit goal: over bench.free_s2 (1000, 850) mm
    np.testing.assert_allclose(only["targets"]["robot2"][:2], [1.0, 0.85], atol=1e-6)


def test_run_writes_the_report_and_no_journal(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plan = walled_lab(tmp_path / "cell")
    out = tmp_path / "run"
    assert main(["run", str(plan), "--out", str(out), "-q"]) == 1
    std = capsys.readouterr()
    assert (std.out, std.err) == ("", MESSAGE.format(plan=plan))
    assert sorted(p.name for p in out.iterdir()) == [".lock", "report.html", "report.json"]
    assert _report(out)["failure"]["failures"][0]["pair"] == ["robot2/gripper", "wall"]


def test_a_folder_with_an_unfinished_run_is_left_as_it_is(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plan = walled_lab(tmp_path / "cell")
    out = tmp_path / "run"
    out.mkdir()
    (out / "journal.jsonl").write_text(UNFINISHED)
    (out / "trajectory.json").write_text("{}\n")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert main(["plan", str(plan), "--out", str(out), "-q"]) == 1
    journal = out / "journal.jsonl"
    assert capsys.readouterr().err == MESSAGE.format(plan=plan) + (
        f"{journal}: no report written: the run folder holds an unfinished run: go on with "
        f"it with `cellengine run PLAN --resume {out}`, or give another --out\n"
    )
    after = {p.name: p.read_bytes() for p in out.iterdir() if p.name != ".lock"}
    assert after == before


def test_a_folder_with_an_ended_run_keeps_its_journal_and_loses_its_trajectory(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    plan = walled_lab(tmp_path / "cell")
    out = tmp_path / "run"
    out.mkdir()
    ended = '{"entry": "start", "run": {"plan": "x"}}\n{"entry": "end"}\n'
    (out / "journal.jsonl").write_text(ended)
    (out / "trajectory.json").write_text("{}\n")
    assert main(["plan", str(plan), "--out", str(out), "-q"]) == 1
    assert capsys.readouterr().err == (
        f"{out}: replacing the trajectory and report of the run that ended there "
        "(journal.jsonl keeps its record)\n" + MESSAGE.format(plan=plan)
    )
    assert sorted(p.name for p in out.iterdir()) == [
        ".lock",
        "journal.jsonl",
        "report.html",
        "report.json",
    ]
    assert (out / "journal.jsonl").read_text() == ended


def test_a_refused_step_gets_the_motion_failure_of_the_steps_before_it() -> None:
    """A family whose second step is refused (found first: candidates are grown before they
    are compiled) and whose first step runs the left fingertip into the table: both are
    found, the compile's error first, and the pose is the first step's."""
    from collections.abc import Iterator

    from cellengine.context import build_context
    from cellengine.errors import Problem, StepError
    from cellengine.execute.candidates import compile_candidates
    from cellengine.execute.compile import Compiler
    from cellengine.failed import examine
    from cellengine.family import Candidate
    from cellengine.info.load import load_plan
    from cellengine.pipeline import CompileFailed
    from cellengine.program import ArmPath, Segment
    from tests.conftest import CELLS

    plan = CELLS / "cable_routing" / "plan_straight.yaml"
    loaded = load_plan(plan)
    ctx = build_context(loaded.world)
    into_table = np.diag([1.0, -1.0, -1.0, 1.0])
    into_table[:3, 3] = [0.3, 0.35, -0.005]
    down = Segment(0, "PickCable: down", (ArmPath("left", "transit", into_table[None]),))

    def refused() -> Iterator[Candidate]:
        raise StepError(Problem("steps[1] PlaceConnector: refused"), 1)
        yield  # a generator: the family refuses when asked for the step's candidates

    first = iter([Candidate((down,), then=refused)])
    compiler = Compiler(ctx.world, ctx.cell, ctx.checker, ctx.home, clearance=ctx.clearance)
    with pytest.raises(StepError) as e:
        compile_candidates(compiler, first)
    failed = examine(CompileFailed(loaded.plan.locate(e.value), loaded, ctx, "split"))
    assert [(p.file, p.line, p.col, p.message) for p in failed.problems] == [
        (str(plan), 12, 5, "steps[1] PlaceConnector: refused"),
        (
            str(plan),
            9,
            5,
            "step 1 (PickCable: down): every IK solution of the transit goal of left is in "
            "collision (the nearest: left/tool/finger_left / table: collision)",
        ),
    ]
    refusal, motion = failed.found
    assert refusal.failure is not None and refusal.failure.segment is None
    assert motion.failure is not None and motion.failure.at is not None
    assert motion.failure.at.pair == ("left/tool/finger_left", "table")
    assert failed.program.segments == ()  # nothing compiled before the first segment
