"""Issue 16: both lab robots at once on the simulated cell. A fault on one robot while both
move stops both; the journal records each robot's finished and running segments, and
`--resume` completes each robot's stream with every segment run once (the one stopped part
way goes on from where the run left it)."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.lab  # noqa: F401  (registers the lab skills)
from cellengine.cli import main
from cellengine.drivers.fault import DriverFault
from cellengine.drivers.record import Played
from cellengine.drivers.sim import SimDriver
from cellengine.journal import Entry, append, read_progress
from cellengine.pipeline import Compiled, compile_plan, write_plan_outputs
from cellengine.runner.identity import run_identity
from cellengine.runner.outcome import journaled
from cellengine.runner.play import play as _play
from tests.conftest import CELLS

PLAN = CELLS / "lab_bench" / "plan_pour_heavier.yaml"


def _entries(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


def _both_moving(c: Compiled) -> int:
    """The first part played at once in which both robots move."""
    both = {"robot1", "robot2"}
    return next(k for k, s in enumerate(c.program.segments) if both <= set(s.report["arms"]))


def test_a_fault_while_both_move_stops_both_and_resume_runs_each_segment_once(
    tmp_path: Path,
) -> None:
    c = compile_plan(PLAN)
    assert c.program.streams
    write_plan_outputs(c, tmp_path)
    k = _both_moving(c)
    piece = c.program.segments[k].trajectory
    t_fault = float(np.mean([piece.start_time, piece.end_time]))
    joints = {name: arm.joint_names for name, arm in c.cell.arms.items()}
    q0 = c.program.segments[0].trajectory.q[0]
    with (tmp_path / "journal.jsonl").open("a") as journal:
        append(journal, Entry.START, run=run_identity(c))
        driver = SimDriver(c.world.cell, joints, objects=c.world.objects, q0=q0)
        driver.configure()
        driver.activate()
        driver.drop_connection(at=t_fault, arm="robot1")
        with pytest.raises(DriverFault):
            journaled(journal, driver, lambda: _play(c, driver, journal, True, tmp_path))
        # both stopped: robot2, which had no fault, is where it was at the fault, not
        # where the piece would have taken it
        (last,) = [p for p in driver.recorder.of(Played) if p.fault is not None]
        assert last.fault is not None and t_fault <= last.fault.time < piece.end_time
        r2 = c.cell.slices["robot2"]
        at_fault = piece.sample(last.fault.time)[0][r2]
        assert np.allclose(last.measured[-1][r2], at_fault, atol=1e-2)
        assert not np.allclose(last.measured[-1][r2], piece.q[-1][r2], atol=1e-2)
    progress = read_progress(tmp_path / "journal.jsonl")
    assert progress.done == k and progress.fault is not None and progress.streams is not None
    done, running, q = progress.streams
    assert running  # both robots were part way through a segment at the fault
    # where the program had the arms at the fault: the recovery move brings them there
    assert np.allclose(q, piece.sample(last.fault.time)[0], atol=1e-8)
    every = {s.index for s in c.program.streams}
    rest = c.rest(done, running, np.asarray(q))
    left = {s.index for s in rest.program.streams}
    assert left == every - done and not (left & done)  # nothing finished is run again

    assert main(["run", str(PLAN), "--resume", str(tmp_path), "-q"]) == 0
    entries = _entries(tmp_path)
    kinds = [e["entry"] for e in entries]
    assert kinds.count("fault") == 1 and kinds.count("resume") == 1 and kinds[-1] == "end"
    # the rest begins where the fault stopped the program (the arms stopped there: no move
    # back is needed)
    assert np.allclose(rest.program.segments[0].trajectory.q[0], q, atol=1e-8)
    assert kinds.count("recovery") == 0
    resumed = [e for e in entries[kinds.index("resume") :] if e["entry"] == "finished"]
    # each finished entry after the resume finishes the next piece of the rest, once
    assert [e["segment"] for e in resumed] == list(range(len(rest.program.segments)))
    # the robots' finished segments only grow, to every one of them
    finished = [set(e["streams"]["done"]) for e in entries if e["entry"] == "finished"]
    assert all(a <= b for a, b in itertools.pairwise(finished))
    assert finished[-1] == every
    end = read_progress(tmp_path / "journal.jsonl")
    assert end.ended and np.allclose(end.q, c.program.segments[-1].trajectory.q[-1], atol=1e-6)
