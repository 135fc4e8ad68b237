"""`run --resume`: a run stopped by a fault goes on from the last segment it finished, after
a planned move back from where the arms stopped, repeating nothing."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.cable  # noqa: F401  (registers the cable skills)
from cellengine.cli import main
from cellengine.drivers.fault import DriverFault
from cellengine.drivers.sim import SimDriver
from cellengine.errors import display_path
from cellengine.journal import Entry, append, read_progress
from cellengine.pipeline import Compiled, compile_plan, write_plan_outputs
from cellengine.runner.identity import run_identity
from cellengine.runner.outcome import journaled
from cellengine.runner.play import play as _play
from tests.conftest import CELLS

PLAN = CELLS / "cable_routing" / "plan_straight.yaml"


def _entries(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


STOP_AT = 12  # a segment in the middle of the pick


def _faulted_run(tmp_path: Path) -> Compiled:
    """The straight plan run on the simulated cell into ``tmp_path`` until a frozen joint
    stops it in segment STOP_AT."""
    c = compile_plan(PLAN)
    write_plan_outputs(c, tmp_path)
    joints = {name: arm.joint_names for name, arm in c.cell.arms.items()}
    q0 = c.program.segments[0].trajectory.q[0]
    segment = c.program.segments[STOP_AT].trajectory
    t_fault = float(np.mean([segment.start_time, segment.end_time]))
    with (tmp_path / "journal.jsonl").open("a") as journal:
        append(journal, Entry.START, run=run_identity(c))
        driver = SimDriver(c.world.cell, joints, objects=c.world.objects, q0=q0)
        driver.configure()
        driver.activate()
        driver.freeze_joint(c.cell.joint_names[1], at=t_fault)  # the left shoulder lift
        with pytest.raises(DriverFault):
            journaled(journal, driver, lambda: _play(c, driver, journal, True, tmp_path))
    return c


def test_a_faulted_run_resumes_where_it_stopped(tmp_path: Path) -> None:
    c = _faulted_run(tmp_path)
    q0 = c.program.segments[0].trajectory.q[0]
    stop_at = STOP_AT
    progress = read_progress(tmp_path / "journal.jsonl")
    assert progress.done == stop_at and progress.fault is not None
    assert progress.fault["kind"] == "tracking" and len(progress.fault["q"]) == len(q0)

    assert main(["run", str(PLAN), "--resume", str(tmp_path), "-q"]) == 0
    entries = _entries(tmp_path)
    kinds = [e["entry"] for e in entries]
    assert kinds.count("start") == 1 and kinds.count("fault") == 1 and kinds.count("resume") == 1
    assert kinds.count("recovery") == 1  # the arm stopped mid-segment: a move back first
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == list(range(len(c.program.segments)))  # each once, none repeated
    assert kinds[-1] == "end"
    done = read_progress(tmp_path / "journal.jsonl")
    assert done.ended and np.allclose(done.q, c.program.segments[-1].trajectory.q[-1], atol=1e-6)
    # resuming a complete run does nothing
    assert main(["run", str(PLAN), "--resume", str(tmp_path), "-q"]) == 0
    assert _entries(tmp_path) == entries


def test_a_torn_last_line_is_dropped_before_the_resumed_run_appends(tmp_path: Path) -> None:
    """A kill in the middle of writing an entry leaves a line without its end: resume
    drops it, so that its own entries start on a line of their own and the journal stays
    readable to the end."""
    c = _faulted_run(tmp_path)
    path = tmp_path / "journal.jsonl"
    with path.open("a") as journal:
        journal.write('{"entry": "sent", "seg')
    assert main(["run", str(PLAN), "--resume", str(tmp_path), "-q"]) == 0
    entries = _entries(tmp_path)  # every line an entry
    assert entries[-1]["entry"] == "end" and read_progress(path).done == len(c.program.segments)


def test_a_torn_last_line_is_ignored_and_a_bad_one_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "journal.jsonl"
    ok = '{"entry": "finished", "segment": 0, "label": "a", "q": [0.0], "grippers": {}}\n'
    path.write_text(ok + '{"entry": "sent", "seg')
    assert read_progress(path).labels == ("a",)
    path.write_text('{"entry": "sent", "seg\n' + ok)
    from cellengine.errors import InputError

    with pytest.raises(InputError) as e:
        read_progress(path)
    assert str(e.value) == f"{path}:1: not a journal entry (JSON)"


def test_a_run_begins_with_a_move_to_the_plans_start(tmp_path: Path) -> None:
    """Arms left elsewhere (here 0.3 rad off on two joints of each arm): a planned move to
    where the first segment starts, journaled; arms already there: nothing."""
    from cellengine.runner.move import move_to

    c = compile_plan(PLAN)
    joints = {name: arm.joint_names for name, arm in c.cell.arms.items()}
    start = c.program.segments[0].trajectory.q[0]
    off = start.copy()
    off[[0, 2, 6, 8]] += 0.3
    with (tmp_path / "journal.jsonl").open("a") as journal:
        driver = SimDriver(c.world.cell, joints, objects=c.world.objects, q0=off)
        driver.configure()
        driver.activate()
        move_to(c, driver, journal, 0)
        assert np.allclose(driver.joint_state(), start, atol=1e-6)
        move_to(c, driver, journal, 0)  # there already
    kinds = [e["entry"] for e in _entries(tmp_path)]
    assert kinds == ["recovery"]


def test_resume_refuses_a_run_of_other_files_or_another_execution(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _faulted_run(tmp_path)
    before = _entries(tmp_path)
    argv = ["run", str(PLAN), "--resume", str(tmp_path), "-q", "--execution", "sync"]
    assert main(argv) == 1
    assert capsys.readouterr().err == (
        f"{display_path(PLAN)}: the run in {tmp_path} started from other inputs: the execution "
        "was split, now sync. Resume it with the files and options it started with, or start a "
        "new run in another folder\n"
    )
    assert _entries(tmp_path) == before  # nothing ran, nothing journaled


def test_resume_refuses_a_journal_without_its_runs_identity(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "journal.jsonl"
    path.write_text(
        '{"entry": "finished", "segment": 0, "label": "a", "q": [0.0], "grippers": {}}\n'
    )
    assert main(["run", str(PLAN), "--resume", str(tmp_path), "-q"]) == 1
    assert capsys.readouterr().err == (
        f"{path}: the journal records no run identity (its start entry is missing, or an older "
        "cellengine wrote it): the run cannot be resumed safely; start a new run in another "
        "folder\n"
    )


def test_progress_is_of_the_last_run_started_in_the_folder(tmp_path: Path) -> None:
    """A plan run again into a finished folder and killed in its first segment has finished
    nothing: the earlier run's segments are not this run's."""
    path = tmp_path / "journal.jsonl"
    done = '{"entry": "finished", "segment": %d, "label": "s%d", "q": [0.0], "grippers": {}}\n'
    lines = ['{"entry": "start", "run": {"plan": "x"}}\n']
    lines += [done % (i, i) for i in range(7)] + ['{"entry": "end"}\n']
    lines += ['{"entry": "start", "run": {"plan": "y"}}\n', '{"entry": "sent", "segment": 0}\n']
    path.write_text("".join(lines))
    progress = read_progress(path)
    assert (progress.done, progress.ended, progress.run) == (0, False, {"plan": "y"})


def test_a_new_run_or_plan_into_a_folder_with_an_unfinished_run_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _faulted_run(tmp_path)
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    for command in ("run", "plan"):
        assert main([command, str(PLAN), "--out", str(tmp_path), "-q"]) == 1
        assert capsys.readouterr().err == (
            f"{tmp_path / 'journal.jsonl'}: the run folder holds an unfinished run: go on with "
            f"it with `cellengine run PLAN --resume {tmp_path}`, or give another --out\n"
        )
    after = {p.name: p.read_bytes() for p in tmp_path.iterdir() if p.name != ".lock"}
    assert after == before


def test_a_corrupted_journal_is_refused_with_its_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Values the run would start from are checked: in range as the journal is read (at
    the line), and against the cell once the plan is compiled (the journal named)."""
    c = _faulted_run(tmp_path)
    path = tmp_path / "journal.jsonl"
    lines = path.read_text().splitlines()
    n = max(i for i, line in enumerate(lines) if '"finished"' in line)
    finished = json.loads(lines[n])

    def resume_with(**changes: object) -> str:
        lines[n] = json.dumps({**finished, **changes})
        path.write_text("\n".join(lines) + "\n")
        assert main(["run", str(PLAN), "--resume", str(tmp_path), "-q"]) == 1
        return capsys.readouterr().err.replace(str(tmp_path), "<run>")

    nan_q = [float("nan"), *finished["q"][1:]]
    assert resume_with(q=nan_q) == (
        f"<run>/journal.jsonl:{n + 1}: 'q[0]' must be a finite joint value (rad or m, at most "
        "100 either way), got nan\n"
    )
    assert resume_with(q=finished["q"][:3]) == (
        f"<run>/journal.jsonl: the last 'finished' entry gives 3 joint values; the cell has "
        f"{len(c.cell.joint_names)}\n"
    )
    assert resume_with(grippers={"left": ["wide", "ghost"], "middle": ["open", None]}) == (
        "<run>/journal.jsonl: arm 'left': unknown jaw mode 'wide'; known: grasp, open, slide\n"
        "<run>/journal.jsonl: unknown arm 'middle'; known: left, right\n"
    )


def test_a_run_that_ended_is_replaced_with_a_word(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert main(["run", str(PLAN), "--out", str(out), "-q"]) == 0
    assert capsys.readouterr().err == ""
    assert main(["plan", str(PLAN), "--out", str(out), "-q"]) == 0
    assert capsys.readouterr().err == (
        f"{out}: replacing the trajectory and report of the run that ended there "
        "(journal.jsonl keeps its record)\n"
    )
