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
