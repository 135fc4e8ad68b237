"""The UR driver end to end: `cellengine run` with the real ur-rtde client streaming to two
emulated controllers (`cellengine emulate ur`, each on its own loopback address), and a
protective stop injected mid-run, then the run resumed once it is cleared.

Both the emulator and `cellengine run` are subprocesses with deadlines (the client's calls
block without one), killed at the end whatever happens."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import skills.cable  # noqa: F401  (registers the cable skills)
from cellengine.pipeline import compile_plan
from tests.conftest import CELLS, ROOT
from tests.emulate.harness import Emulator, free_hosts


def _cell(tmp_path: Path, hosts: list[str]) -> Path:
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", folder)
    path = folder / "cell.yaml"
    driver = f"{{kind: ur_rtde, arms: {{left: {hosts[0]}, right: {hosts[1]}}}}}"
    path.write_text(path.read_text().replace("driver: {kind: sim}", f"driver: {driver}"))
    return folder


def _run(*args: str, timeout: float) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "cellengine.cli", "run", *args, "--yes", "-q"]
    return subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout)


def _journal(run: Path) -> list[dict]:
    return [json.loads(line) for line in (run / "journal.jsonl").read_text().splitlines()]


@pytest.fixture
def emulated(tmp_path: Path) -> Iterator[tuple[Path, list[str], list[Emulator]]]:
    hosts = free_hosts(2)
    started: list[Emulator] = []
    yield _cell(tmp_path, hosts), hosts, started
    for e in started:
        e.close()


def _start(hosts: list[str], q0: np.ndarray, started: list[Emulator], *extra: str) -> Emulator:
    args: list[str] = []
    for host, q in zip(hosts, (q0[:6], q0[6:]), strict=True):
        args += ["--q0", f"{host}=" + ",".join(f"{v:.9f}" for v in q)]
    started.append(Emulator(hosts, *args, *extra))
    return started[-1]


def test_the_four_guide_plan_runs_on_two_emulated_arms(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    folder, hosts, started = emulated
    plan = folder / "plan_two_turns.yaml"
    program = compile_plan(plan).program
    _start(hosts, program.segments[0].trajectory.q[0], started)
    run = tmp_path / "run"
    result = _run(str(plan), "--out", str(run), timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    entries = _journal(run)
    assert entries[-1]["entry"] == "end"
    finished = [e for e in entries if e["entry"] == "finished"]
    assert [e["segment"] for e in finished] == list(range(len(program.segments)))
    # where the controllers said the arms were after each segment: where it ends
    for e, seg in zip(finished, program.segments, strict=True):
        assert np.allclose(e["q"], seg.trajectory.q[-1], atol=0.005), seg.segment.label


def test_a_protective_stop_stops_the_run_and_resume_completes_it(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    folder, hosts, started = emulated
    plan = folder / "plan_straight.yaml"
    program = compile_plan(plan).program
    emulator = _start(
        hosts,
        program.segments[0].trajectory.q[0],
        started,
        "--fault",
        f"{hosts[1]}@6:protective_stop",
    )
    run = tmp_path / "run"
    result = _run(str(plan), "--out", str(run), timeout=300)
    assert result.returncode == 3, result.stderr[-2000:]
    assert f"arm 'right' at {hosts[1]}: " in result.stderr and "protective stop" in result.stderr
    fault = next(e for e in _journal(run) if e["entry"] == "fault")["fault"]
    assert fault["kind"] == "protective_stop" and fault["arm"] == "right"
    assert fault["details"]["safety_status_bits"] & 1 << 2
    # not cleared yet: the resumed run is refused before anything moves
    again = _run(str(plan), "--resume", str(run), timeout=120)
    assert again.returncode == 3, again.stderr[-2000:]
    assert emulator.fault(hosts[1], "clear")
    done = _run(str(plan), "--resume", str(run), timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    entries = _journal(run)
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == list(range(len(program.segments)))
    assert entries[-1]["entry"] == "end"


def test_a_controller_reporting_another_model_is_refused(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """The cell says ur5e; the right controller says it is a UR10: refused at configure,
    before anything moves, naming the arm, the address and both models."""
    folder, hosts, started = emulated
    plan = folder / "plan_straight.yaml"
    program = compile_plan(plan).program
    _start(hosts, program.segments[0].trajectory.q[0], started, "--model", f"{hosts[1]}=UR10")
    result = _run(str(plan), "--out", str(tmp_path / "run"), timeout=120)
    assert result.returncode == 3, result.stderr[-2000:]
    assert (
        f"arm 'right' at {hosts[1]} reports robot model 'UR10', but the cell says 'ur5e' (UR5)"
    ) in result.stderr
    kinds = [e["entry"] for e in _journal(tmp_path / "run")]
    assert "sent" not in kinds


def test_arms_far_from_the_plans_start_get_a_planned_move_there_first(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """The emulated arms start 0.3 rad off the plan's start on two joints each: the run
    begins with a planned move there (journaled), then runs the plan."""
    folder, hosts, started = emulated
    plan = folder / "plan_straight.yaml"
    program = compile_plan(plan).program
    q0 = program.segments[0].trajectory.q[0].copy()
    q0[[0, 2, 6, 8]] += 0.3
    _start(hosts, q0, started)
    run = tmp_path / "run"
    result = _run(str(plan), "--out", str(run), timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    kinds = [e["entry"] for e in _journal(run)]
    assert kinds.index("recovery") < kinds.index("sent") and kinds[-1] == "end"
