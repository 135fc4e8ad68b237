"""Each fault the issue names, injected mid-run on one arm of two emulated UR controllers:
the run stops both arms (the healthy one is told to stop too), exits 3 naming the fault,
journals it, and `--resume` completes the plan once the fault is cleared, every segment run
once. (The protective stop on the right arm is in test_ur_emulated.py, on the whole
straight plan.)

A short plan (pick the cable, place its connector: 13.5 s of motion) keeps each case brief."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.cable  # noqa: F401  (registers the cable skills)
from cellengine.journal import read_progress
from cellengine.pipeline import compile_plan
from tests.conftest import ROOT
from tests.drivers.urcell import journal, run_cli, start
from tests.emulate.harness import Emulator, dashboard, wait_for

SHORT = """cell: cell.yaml
objects: objects.yaml
execution: split
steps:
  - skill: PickCable
    cable: cable1
    from: [holder.comb_a, holder.comb_b]
  - skill: PlaceConnector
    cable: cable1
    guide: routing.connector
"""
# the fault comes when the run sends this segment (PickCable's "turn along the cable", 1.15 s
# of motion, the first finished before it): mid-run, and mid-motion, whatever the start-up took
AT_SEGMENT = 3

# (emulated fault, the arm it hits, the driver's fault kind, what the message says): the arms
# taken in turn, so each arm meets a stop of its controller and a lost connection (the
# detection and the stop are the same code for either arm; each case is a whole run and its
# resume, about 22 s); the protective stop on the right arm is in test_ur_emulated.py
FAULTS = [
    ("protective_stop", "left", "protective_stop", "protective stop"),
    ("emergency_stop", "right", "emergency_stop", "emergency stop"),
    ("frozen", "right", "tracking", "does not follow"),
    ("drop", "right", "connection", "connection to arm '{arm}'"),
    ("kill", "left", "connection", "connection to arm '{arm}'"),
]
CASES = [(inject, arm, kind, says.format(arm=arm)) for inject, arm, kind, says in FAULTS]


@pytest.mark.parametrize(("inject", "arm", "kind", "says"), CASES)
def test_a_fault_stops_both_arms_and_resume_completes_the_plan(
    tmp_path: Path,
    emulated: tuple[Path, list[str], list[Emulator]],
    inject: str,
    arm: str,
    kind: str,
    says: str,
) -> None:
    folder, hosts, started = emulated
    plan = folder / "plan_short.yaml"
    plan.write_text(SHORT)
    program = compile_plan(plan).program
    q0 = program.segments[0].trajectory.q[0]
    i = ("left", "right").index(arm)
    host, other = hosts[i], hosts[1 - i]
    if inject == "kill":  # a controller of its own, so that killing it spares the other
        start([other], q0[6 * (1 - i) : 6 * (2 - i)], started)
        faulty = start([host], q0[6 * i : 6 * i + 6], started)
    else:
        faulty = start(hosts, q0, started)

    run = tmp_path / "run"
    result = run_with_fault(plan, run, lambda: faulty.fault(host, inject))
    assert result.returncode == 3, result.stderr[-2000:]
    assert says in result.stderr and "every arm stopped" in result.stderr, result.stderr
    entries = journal(run)
    stopped = next(e for e in entries if e["entry"] == "fault")["fault"]
    assert stopped["kind"] == kind and stopped["arm"] == arm
    assert stopped["details"]["stop_commands_s"] >= 0
    done = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert 0 < len(done) < len(program.segments)  # mid-run
    # the healthy arm was told to stop by the driver, not by its watchdog
    log = (started[0] if inject == "kill" else faulty).stderr()
    assert f"{other}: stopJ" in log, log[-2000:]

    if inject == "kill":  # the controller comes back where its arm stopped
        q_stop = np.array(stopped["q"][6 * i : 6 * i + 6])
        started.append(Emulator([host], "--q0", f"{host}=" + ",".join(map(str, q_stop))))
    else:
        assert faulty.fault(host, "clear") == "ok"
    if inject == "emergency_stop":  # the operator powers the arm on and releases the brakes
        dashboard(host, "power on")
        wait_for(lambda: "IDLE" in dashboard(host, "robotmode")[0], what="power on")
        dashboard(host, "brake release")
        wait_for(lambda: "RUNNING" in dashboard(host, "robotmode")[0], what="brake release")
    again = run_cli(str(plan), "--resume", str(run), timeout=120)
    assert again.returncode == 0, again.stderr[-2000:]
    entries = journal(run)
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == list(range(len(program.segments)))  # each once, in order
    assert entries[-1]["entry"] == "end"
    last = next(e for e in reversed(entries) if e["entry"] == "finished")
    assert np.allclose(last["q"], program.segments[-1].trajectory.q[-1], atol=0.005)


def run_with_fault(
    plan: Path, run: Path, inject: Callable[[], str]
) -> subprocess.CompletedProcess[str]:
    """`cellengine run` of ``plan``, ``inject()`` called once the journal says segment
    AT_SEGMENT was sent."""
    cmd = [sys.executable, "-m", "cellengine.cli", "run", str(plan), "--out", str(run)]
    proc = subprocess.Popen(
        [*cmd, "--yes", "-q"], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    try:
        wait_for(lambda: _sent(run, AT_SEGMENT), timeout=60.0, what="the segment to be sent")
        inject()
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def _sent(run: Path, segment: int) -> bool:
    path = run / "journal.jsonl"
    if not path.is_file():
        return False
    lines = [line for line in path.read_text().splitlines() if line.endswith("}")]
    return any(json.loads(line).get("segment") == segment for line in lines)


def test_a_run_killed_mid_segment_leaves_a_journal_that_resume_completes(
    tmp_path: Path, emulated: tuple[Path, list[str], list[Emulator]]
) -> None:
    """SIGKILL on `cellengine run` mid-segment: the journal is whole (every line an entry)
    and names the last finished segment; the arms' processes end with it and each
    controller's watchdog stops its arm; `--resume` plans a move back from where the arms
    stopped and completes the plan, no segment finished twice."""
    folder, hosts, started = emulated
    plan = folder / "plan_short.yaml"
    plan.write_text(SHORT)
    program = compile_plan(plan).program
    emulator = start(hosts, program.segments[0].trajectory.q[0], started)
    run = tmp_path / "run"
    cmd = [sys.executable, "-m", "cellengine.cli", "run", str(plan), "--out", str(run)]
    proc = subprocess.Popen([*cmd, "--yes", "-q"], cwd=ROOT, stderr=subprocess.DEVNULL)
    # killed a third into the longest segment after the first (in its motion, not between)
    durations = [s.trajectory.duration for s in program.segments]
    k = 1 + int(np.argmax(durations[1:]))
    try:
        wait_for(lambda: _finished(run) >= k, timeout=120, what=f"segment {k} sent")
        time.sleep(durations[k] / 3)
        proc.kill()
        proc.wait(10)
    finally:
        proc.kill()
    progress = read_progress(run / "journal.jsonl")
    assert progress.done == k
    assert progress.fault is None and not progress.ended  # killed: nothing more journaled
    wait_for(lambda: not _arm_processes(hosts), timeout=5, what="the arms' processes ended")
    for host in hosts:
        wait_for(
            lambda h=host: (
                f"{h}: program 'rtde_control' stopped: RTDE watchdog" in emulator.stderr()
            ),
            timeout=5,
            what=f"{host}'s watchdog",
        )
    again = run_cli(str(plan), "--resume", str(run), timeout=120)
    assert again.returncode == 0, again.stderr[-2000:]
    entries = journal(run)
    finished = [e["segment"] for e in entries if e["entry"] == "finished"]
    assert finished == list(range(len(program.segments)))  # each once, in order
    resumed = [e["entry"] for e in entries[[e["entry"] for e in entries].index("resume") :]]
    assert resumed.index("recovery") < resumed.index("sent")  # a move back first
    assert entries[-1]["entry"] == "end"


def _finished(run: Path) -> int:
    """How many segments the journal says were finished (its reader ignores a torn last
    line, as resume does)."""
    path = run / "journal.jsonl"
    return read_progress(path).done if path.exists() else 0


def _arm_processes(hosts: list[str]) -> list[int]:
    """The pids of the arm processes (ur_arm.py) serving ``hosts`` still running."""
    pids = []
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            args = (proc / "cmdline").read_bytes().split(b"\0")
            zombie = (proc / "stat").read_text().split(") ")[-1].startswith("Z")
        except OSError:
            continue
        ours = any(a.endswith(b"ur_arm.py") for a in args)
        if ours and not zombie and any(h.encode() in args for h in hosts):
            pids.append(int(proc.name))
    return pids
