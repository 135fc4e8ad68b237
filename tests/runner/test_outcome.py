"""What a run did goes into its report: report.json's and report.html's ``run``, written as
``running`` when the arms start and again when the run ends (a fault, a resume, the masses a
load cell read and the runtime choices they resolved), through the runner's own path on the
simulated cell."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import cellengine.skills.cable  # noqa: F401  (registers the cable skills)
from cellengine.cli import main
from cellengine.drivers.fault import DriverFault
from cellengine.drivers.sim import SimDriver
from cellengine.journal import Entry, append
from cellengine.pipeline import compile_plan, write_plan_outputs
from cellengine.report.outcome import DATA_OPEN
from cellengine.runner.identity import run_identity
from cellengine.runner.outcome import journaled, timed
from cellengine.runner.play import play
from tests.conftest import CELLS
from tests.helpers import vial1_heavier_sim

PLAN = CELLS / "cable_routing" / "plan_straight.yaml"
LAB_PLAN = CELLS / "lab_bench" / "plan_pour_heavier.yaml"
STOP_AT = 12  # a segment in the middle of the pick


def reports(out: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """report.json, and the report embedded in report.html."""
    page = (out / "report.html").read_text(encoding="utf-8")
    start = page.index(DATA_OPEN) + len(DATA_OPEN)
    embedded = json.loads(page[start : page.index("</script>", start)])["report"]
    return json.loads((out / "report.json").read_text(encoding="utf-8")), embedded


def test_a_fault_then_a_resume_are_in_the_report(tmp_path: Path) -> None:
    """A joint frozen in segment STOP_AT: the report says fault, its kind, arm and time, where
    the run stopped and how far it got; resumed, it says completed and from where."""
    c = compile_plan(PLAN)
    write_plan_outputs(c, tmp_path)
    joints = {name: arm.joint_names for name, arm in c.cell.arms.items()}
    segment = c.program.segments[STOP_AT].trajectory
    t_fault = float(np.mean([segment.start_time, segment.end_time]))
    seen: list[dict[str, Any]] = []
    with (tmp_path / "journal.jsonl").open("a") as journal:
        append(journal, Entry.START, run=run_identity(c))
        q0 = c.program.segments[0].trajectory.q[0]
        driver = SimDriver(c.world.cell, joints, objects=c.world.objects, q0=q0)
        driver.freeze_joint(c.cell.joint_names[1], at=t_fault)  # the left shoulder lift
        with pytest.raises(DriverFault), timed(journal, driver, tmp_path, True, c):
            seen.append(reports(tmp_path)[0]["run"])  # as the arms start
            driver.configure()
            driver.activate()
            journaled(journal, driver, lambda: play(c, driver, journal, True, tmp_path))
    assert seen[0]["outcome"] == "running" and seen[0]["segments_finished"] == 0
    report, embedded = reports(tmp_path)
    assert report == embedded
    run = report["run"]
    assert (run["driver"], run["outcome"]) == ("sim", "fault")
    fault = run["fault"]
    assert (fault["kind"], fault["arm"], fault["joint"]) == ("tracking", "left", joints["left"][1])
    assert t_fault <= fault["time"] <= segment.end_time
    assert run["message"] == fault["message"]
    label = c.program.segments[STOP_AT].segment.label
    assert run["stopped_in"] == {"segment": STOP_AT, "label": label}
    assert (run["segments_finished"], run["segments"]) == (STOP_AT, len(c.program.segments))
    assert (run["resumed"], run["measured"], run["choices"], run["servo"]) == ([], [], [], None)

    assert main(["run", str(PLAN), "--resume", str(tmp_path), "-q"]) == 0
    report, embedded = reports(tmp_path)
    assert report == embedded
    run = report["run"]
    assert (run["outcome"], run["fault"], run["stopped_in"]) == ("completed", None, None)
    assert run["resumed"] == [{"from_segment": STOP_AT, "label": label}]
    assert run["segments_finished"] == run["segments"] == len(c.program.segments)


def test_masses_measured_and_the_choice_they_changed_are_in_the_report(tmp_path: Path) -> None:
    """objects.yaml says vial2 is the heavier; the simulated load cell reads vial1 at 50 g:
    the report gives both readings, the run's replanning and heavier_of resolved to vial1."""
    c = compile_plan(LAB_PLAN)
    write_plan_outputs(c, tmp_path)
    with (
        vial1_heavier_sim(c) as driver,
        (tmp_path / "journal.jsonl").open("a") as journal,
    ):
        append(journal, Entry.START, run=run_identity(c))
        with timed(journal, driver, tmp_path, True, c):
            driver.configure()
            driver.activate()
            play(c, driver, journal, quiet=True, out=tmp_path)
            driver.deactivate()
    report, embedded = reports(tmp_path)
    assert report == embedded
    run = report["run"]
    assert run["outcome"] == "completed" and run["replanned"] == 1
    assert [(m["object"], m["arm"], m["step"]) for m in run["measured"]] == [
        ("vial1", "robot1", 0),
        ("vial2", "robot1", 1),
    ]
    # the cell's load cell: 0.2 g standard deviation
    masses = [m["mass_kg"] for m in run["measured"]]
    assert masses == pytest.approx([0.050, 0.042], abs=0.002)
    assert run["choices"] == [
        {
            "step": step,
            "field": "object",
            "rule": "heavier_of",
            "of": ["vial1", "vial2"],
            "chose": "vial1",
            "by": "measured",
        }
        for step in (2, 3)
    ]
    # the replanned program's segments (both robots' streams), all finished
    assert run["segments"] == len(report["streams"]["lanes"]["robot1"]) + len(
        [s for s in report["streams"]["lanes"]["robot2"] if "robot1" not in s["arms"]]
    )
    assert run["segments"] == run["segments_finished"]
