"""Issue 16 on the UR driver: the lab bench's UR cell with both robots at once, streamed by
`cellengine run` with the real ur-rtde client to two emulated controllers from one clock."""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import cellengine.skills.lab  # noqa: F401  (registers the lab skills)
from cellengine.pipeline import compile_plan
from tests.conftest import CELLS
from tests.drivers.urcell import journal, run_cli
from tests.emulate.harness import Emulator, free_hosts


@pytest.fixture
def lab_ur(tmp_path: Path) -> Iterator[tuple[Path, list[str], list[Emulator]]]:
    hosts = free_hosts(2)
    folder = tmp_path / "cell"
    shutil.copytree(CELLS / "lab_bench", folder)
    cell = folder / "cell_ur.yaml"
    driver = f"driver: {{kind: ur_rtde, arms: {{robot1: {hosts[0]}, robot2: {hosts[1]}}}}}"
    text = cell.read_text()
    assert "driver: {kind: sim, mass_noise: 0.2}" in text
    cell.write_text(text.replace("driver: {kind: sim, mass_noise: 0.2}", driver))
    started: list[Emulator] = []
    yield folder, hosts, started
    for e in started:
        e.close()


def test_both_lab_robots_stream_at_once_from_one_clock(
    tmp_path: Path, lab_ur: tuple[Path, list[str], list[Emulator]]
) -> None:
    folder, hosts, started = lab_ur
    plan, cell = folder / "plan_relocate.yaml", folder / "cell_ur.yaml"
    c = compile_plan(plan, cell=cell)
    program = c.program
    # robot2's return overlaps robot1's way to its vial: one part played with both moving
    both = [s for s in program.segments if {"robot1", "robot2"} <= set(s.report["arms"])]
    assert both
    q0 = program.segments[0].trajectory.q[0]
    args: list[str] = []
    for i, host in enumerate(hosts):
        args += ["--q0", f"{host}=" + ",".join(f"{v:.9f}" for v in q0[6 * i : 6 * i + 6])]
    started.append(Emulator(hosts, *args))
    run = tmp_path / "run"
    result = run_cli(str(plan), "--cell", str(cell), "--out", str(run), timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    entries = journal(run)
    assert entries[-1]["entry"] == "end"
    finished = [e for e in entries if e["entry"] == "finished"]
    assert [e["segment"] for e in finished] == list(range(len(program.segments)))
    assert set(finished[-1]["streams"]["done"]) == {s.index for s in program.streams}
    # where the controllers said the arms were after each part: where the program has them
    for e, seg in zip(finished, program.segments, strict=True):
        assert np.allclose(e["q"], seg.trajectory.q[-1], atol=0.005), seg.segment.label
    servo = next(e for e in entries if e["entry"] == "timing")["servo"]
    assert servo["ticks"] >= program.duration / 0.002  # every tick of both arms' motion
