"""`cellengine plan` and `cellengine run` on the reference cable-routing cell."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from cellengine.cli import main
from tests.conftest import CELLS

PLAN = CELLS / "cable_routing" / "plan_straight.yaml"


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("run")
    assert main(["run", str(PLAN), "--out", str(out), "-q"]) == 0
    return out


def test_run_directory_holds_every_file(run_dir: Path) -> None:
    assert sorted(p.name for p in run_dir.iterdir()) == [
        ".lock",  # the run folder's lock (runfolder.py), kept: removing it would race
        "journal.jsonl",
        "report.html",
        "report.json",
        "trajectory.json",
    ]


def test_trajectory_json_is_one_time_axis_for_both_arms(run_dir: Path) -> None:
    data = json.loads((run_dir / "trajectory.json").read_text())
    names = data["joint_names"]
    assert len(names) == 12 and names[0] == "left_shoulder_pan_joint"
    assert names[6] == "right_shoulder_pan_joint"
    t = np.array([p["time_from_start"] for p in data["points"]])
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert all(len(p["positions"]) == 12 and len(p["velocities"]) == 12 for p in data["points"])
    modes = {(e["arm"], e["mode"]) for e in data["events"]}
    assert {("left", "grasp"), ("right", "grasp"), ("left", "open"), ("right", "open")} <= modes
    assert all(0.0 <= e["time_from_start"] <= t[-1] for e in data["events"])


def test_journal_names_every_segment_sent_and_finished(run_dir: Path) -> None:
    entries = [json.loads(line) for line in (run_dir / "journal.jsonl").read_text().splitlines()]
    kinds = [e["entry"] for e in entries]
    assert kinds[0] == "start" and kinds[-1] == "end"
    sent = [e for e in entries if e["entry"] == "sent"]
    finished = [e for e in entries if e["entry"] == "finished"]
    assert len(sent) == len(finished) > 10
    assert finished[-1]["step"] == 2  # the plan's last step (RouteCable)
    assert set(finished[-1]["grippers"]) == {"left", "right"}


def test_report_json_per_segment(run_dir: Path) -> None:
    report = json.loads((run_dir / "report.json").read_text())
    assert report["execution"] == "split"
    assert report["duration"] > 0


def test_plan_writes_no_journal(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", str(PLAN), "--out", str(tmp_path)]) == 0
    assert not (tmp_path / "journal.jsonl").exists()
    out = capsys.readouterr()
    assert "[3/3] RouteCable" in out.err
    assert out.out.splitlines()[-1] == f"report: {tmp_path / 'report.html'}"


def test_a_lab_step_on_a_cable_is_refused_at_its_line(tmp_path: Path) -> None:
    import shutil

    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    plan = tmp_path / "cell" / "weigh.yaml"
    plan.write_text(
        "cell: cell.yaml\nobjects: objects.yaml\nsteps:\n  - {skill: Weigh, object: cable1}\n"
    )
    from cellengine.errors import InputError
    from cellengine.pipeline import compile_plan

    with pytest.raises(InputError) as e:
        compile_plan(plan)
    assert str(e.value) == (
        f"{plan}:4:5: steps[0] Weigh: 'cable1' stands nowhere: the lab skills move "
        "containers, each given where it stands ('at') in objects.yaml"
    )


def test_no_such_plan_is_a_usage_error(tmp_path: Path) -> None:
    assert main(["plan", str(tmp_path / "nope.yaml")]) == 2


def test_cell_runs_the_plan_in_another_cell_file(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """--cell swaps the cell the plan names: here the same cell with the right arm moved
    out of reach of the combs, which the plan then cannot do; a missing file is a usage
    error."""
    import shutil

    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", folder)
    other = folder / "far.yaml"
    text = (folder / "cell.yaml").read_text()
    other.write_text(text.replace("xyz: [0, -350, 0]", "xyz: [-900, -350, 0]"))
    plan = folder / "plan_straight.yaml"
    assert main(["plan", str(plan), "--cell", str(other), "-q", "--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"{plan}:"), err
    assert "right" in err
    assert main(["plan", str(plan), "--cell", str(folder / "nope.yaml")]) == 2
    assert "no such cell file" in capsys.readouterr().err


def test_validate_compiles_plans_unless_told_not_to(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A PlaceConnector that names both arms passes the file checks but cannot be planned:
    validate says so at the step's line; --no-compile checks the files only."""
    import shutil

    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    plan = tmp_path / "cell" / "plan_straight.yaml"
    text = plan.read_text().replace(
        "guide: routing.connector", "guide: routing.connector\n    arm: both"
    )
    plan.write_text(text)
    monkeypatch.chdir(tmp_path / "cell")
    assert main(["validate", "--no-compile", "plan_straight.yaml"]) == 0
    capsys.readouterr()
    assert main(["validate", "plan_straight.yaml"]) == 1
    assert capsys.readouterr().out == (
        "plan_straight.yaml:12:5: steps[1] PlaceConnector routing.connector: arm must be one "
        "robot or 'auto', not 'both'; known: left, right\n"
    )


@pytest.mark.parametrize("command", ["plan", "run"])
@pytest.mark.parametrize("value", ["0", "1.5", "-0.25", "nan", "fast"])
def test_a_speed_outside_0_to_1_is_a_usage_error(
    command: str, value: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as e:
        main([command, str(PLAN), "--speed", value])
    assert e.value.code == 2
    why = (
        f"not a number: '{value}'"
        if value == "fast"
        else f"must be more than 0 and at most 1, got {value}"
    )
    assert capsys.readouterr().err.endswith(f"error: argument --speed: {why}\n")


def test_cycles_are_counted_from_1_and_a_resumed_run_keeps_its_own(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as e:
        main(["run", str(PLAN), "--cycles", "0"])
    assert e.value.code == 2
    assert capsys.readouterr().err.endswith(
        "error: argument --cycles: must be a whole number from 1 to 1000000\n"
    )
    assert main(["run", str(PLAN), "--resume", str(tmp_path), "--cycles", "2"]) == 2
    assert capsys.readouterr().err == (
        "--cycles with --resume: a resumed run goes on with its own\n"
    )
