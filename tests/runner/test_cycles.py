"""run --cycles N: a plan that ends where it starts played N times, journaled; any other
refused before anything moves."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cellengine.errors import InputError
from cellengine.journal import read_progress
from cellengine.pipeline import Compiled
from cellengine.program import GripperEvent, Program, TimedEvent
from cellengine.runner import DriverOptions, resume_run, run_plan
from cellengine.runner.cycles import check_cycles


def test_a_plan_that_returns_home_ends_where_it_starts(cycling: Compiled) -> None:
    segments = cycling.program.segments
    assert segments[-1].segment.label == "return home"
    assert np.abs(segments[-1].trajectory.q[-1] - segments[0].trajectory.q[0]).max() < 1e-9
    check_cycles(cycling, 2)  # no error


def test_two_cycles_run_twice_on_the_simulated_cell(cycling: Compiled, tmp_path: Path) -> None:
    run_plan(cycling, tmp_path / "run", DriverOptions(), yes=False, quiet=True, cycles=2)
    lines = (tmp_path / "run" / "journal.jsonl").read_text().splitlines()
    entries = [json.loads(line) for line in lines]
    n = len(cycling.program.segments)
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == [*range(n), *range(n)]
    assert entries[0]["entry"] == "start" and entries[0]["cycles"] == 2
    cycle = [e for e in entries if e["entry"] == "cycle"]
    assert [(e["cycle"], e["of"]) for e in cycle] == [(2, 2)]
    assert entries.index(cycle[0]) == 1 + 2 * n  # after the first cycle's sent and finished
    assert entries[-1]["entry"] == "end"
    assert entries[-1]["duration"] == pytest.approx(2 * cycling.program.duration, abs=1e-6)
    progress = read_progress(tmp_path / "run" / "journal.jsonl")
    assert (progress.ended, progress.cycle, progress.cycles, progress.done) == (True, 2, 2, n)


def test_a_plan_that_ends_elsewhere_is_refused_before_anything_moves(
    cycling: Compiled, tmp_path: Path
) -> None:
    """The same plan without its return home: its arms end where the last step leaves them."""
    program = cycling.program
    short = replace(
        cycling, program=Program(program.joint_names, program.segments[:-1], program.events)
    )
    with pytest.raises(InputError) as e:
        run_plan(short, tmp_path / "run", DriverOptions(), yes=False, quiet=True, cycles=3)
    assert str(e.value) == (
        f"{cycling.loaded.plan.file}: --cycles 3: the plan ends with the left arm 3.678 rad "
        "from where it starts (joint 'left_wrist_3_joint'): a cycle must end where the next "
        "one starts; give the plan `return_home: true`"
    )
    assert not (tmp_path / "run").exists()
    run_plan(short, tmp_path / "once", DriverOptions(), yes=False, quiet=True)  # once is fine


@pytest.mark.parametrize("kept", ["into the second cycle", "the first cycle only"])
def test_a_killed_run_of_cycles_is_resumed_in_its_cycle(
    cycling: Compiled, tmp_path: Path, kept: str
) -> None:
    """The journal of a run killed in its second cycle (or between the two) goes on from the
    first segment that cycle did not finish, and ends after the last cycle."""
    run_dir = tmp_path / "run"
    run_plan(cycling, run_dir, DriverOptions(), yes=False, quiet=True, cycles=2)
    journal = run_dir / "journal.jsonl"
    lines = journal.read_text().splitlines(keepends=True)
    n = len(cycling.program.segments)
    cut = 1 + 2 * n + (1 + 2 * 5 if kept == "into the second cycle" else 0)
    journal.write_text("".join(lines[:cut]))
    resume_run(run_dir, lambda: cycling, DriverOptions(), yes=False, quiet=True)
    entries = [json.loads(line) for line in journal.read_text().splitlines()[cut:]]
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == list(range(5 if kept == "into the second cycle" else 0, n))
    kinds = [e["entry"] for e in entries if e["entry"] not in ("sent", "finished")]
    first = ["resume"] if kept == "into the second cycle" else ["cycle", "resume"]
    assert kinds == [*first, "end"]
    progress = read_progress(journal)
    assert (progress.ended, progress.cycle, progress.done) == (True, 2, n)


def test_a_plan_that_ends_holding_something_is_refused(cycling: Compiled) -> None:
    program = cycling.program
    grasp = TimedEvent(program.duration, GripperEvent("left", "grasp", "cable1"))
    holding = Program(program.joint_names, program.segments, (*program.events, grasp))
    with pytest.raises(InputError) as e:
        check_cycles(replace(cycling, program=holding), 2)
    assert str(e.value) == (
        f"{cycling.loaded.plan.file}: --cycles 2: the plan ends with the left gripper holding "
        "'cable1': a cycle must end with nothing held"
    )
