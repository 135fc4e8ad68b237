"""`validate --cluster`: a local Ray head on the loopback address with two worker processes
checks the repository's cells and generated boards exactly as one process and two local
workers do; a Ray worker killed mid-compile is its plan's problem only."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from bench.boards import make_board
from bench.ray_head import ray_head as local_ray_head
from cellengine.cache import Cache
from cellengine.cli import main
from cellengine.cluster import CONNECT_ATTEMPTS, connect
from cellengine.errors import UsageError
from tests.conftest import CELLS, ROOT


@pytest.fixture(scope="module")
def ray_head() -> Iterator[str]:
    """A Ray head on 127.0.0.1 with two CPUs (two workers at a time), stopped after the
    module's tests; its Ray Client address."""
    with local_ray_head(cpus=2) as address:
        yield address


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The cable-routing and lab reference cells, two generated boards, a board whose cable
    is too short and a cell that does not parse. (Not the harness cell: its plans take 10 s
    each to compile, three times over here, and add nothing to what is compared.)"""
    top = tmp_path_factory.mktemp("cells")
    for name in ("cable_routing", "lab_bench"):
        shutil.copytree(CELLS / name, top / "cells" / name)
    for seed in (1, 2):
        make_board(seed, top / "boards" / f"board_{seed}")
    make_board(3, top / "boards" / "short")
    objects = top / "boards" / "short" / "objects.yaml"
    text = objects.read_text()
    objects.write_text(text.replace("    length: ", "    length: 300  # ", 1))
    (top / "broken").mkdir()
    (top / "broken" / "cell.yaml").write_text("robots: [\n")
    (top / "broken" / "plan.yaml").write_text("cell: cell.yaml\nsteps: []\n")
    return top


FOLDERS = ("cells", "boards", "broken", "--format", "json")


def _validate(folder: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "cellengine", "validate", *FOLDERS, "--no-cache", *args],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=900,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )


def test_the_cluster_one_process_and_two_workers_agree(folder: Path, ray_head: str) -> None:
    one = _validate(folder, "--jobs", "1")
    two = _validate(folder, "--jobs", "2")
    ray = _validate(folder, "--cluster", ray_head)
    assert one.returncode == two.returncode == ray.returncode == 1, ray.stderr
    assert one.stdout == two.stdout == ray.stdout
    assert '"file": "boards/board_1/plan.yaml",\n      "kind": "plan",\n      "ok": true' in (
        ray.stdout
    )
    assert "is too short for the route" in ray.stdout
    assert '"file": "cells/cable_routing/plan_two_turns.yaml",\n      "kind": "plan",\n' in (
        ray.stdout
    )


KILLING = """
import os, signal, sys
import cellengine.commands.validate as validate
from cellengine.cli import main

original = validate.check_file

def killing(task):
    if str(task[0]) == "b/plan_straight.yaml":
        os.kill(os.getpid(), signal.SIGKILL)
    return original(task)

validate.check_file = killing
sys.exit(main(["validate", "a", "b", "--cluster", sys.argv[1], "--cache-dir", "cache"]))
"""


def test_a_killed_ray_worker_is_its_plan_only(tmp_path: Path, ray_head: str) -> None:
    for name in ("a", "b"):
        shutil.copytree(CELLS / "cable_routing", tmp_path / name)
        for plan in ("plan_one_turn.yaml", "plan_two_turns.yaml"):
            (tmp_path / name / plan).unlink()
    run = subprocess.run(
        [sys.executable, "-c", KILLING, ray_head],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert run.returncode == 1, run.stderr
    out = run.stdout.splitlines()
    assert "a/plan_straight.yaml: ok (plan)" in out
    assert "b/objects.yaml: ok (objects)" in out
    (killed,) = [line for line in out if line.startswith("b/plan_straight.yaml")]
    assert killed.startswith("b/plan_straight.yaml: not checked: its Ray worker died (")
    # what the cluster compiled is kept with the sender's paths: found again here
    os.chdir(tmp_path)
    request = {
        "command": "validate",
        "plan": "a/plan_straight.yaml",
        "real": str((tmp_path / "a" / "plan_straight.yaml").resolve()),
        "cwd": str(tmp_path),
    }
    hit = Cache(tmp_path / "cache").lookup(request)
    assert hit is not None and hit.result == {"problems": [], "warnings": []}


def test_without_ray_the_flag_says_what_to_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "a")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray: ImportError
    assert main(["validate", "a", "--cluster", "auto", "--no-cache"]) == 2
    assert capsys.readouterr().err == "--cluster needs Ray: pip install 'cellengine[cluster]'\n"


DIED = (
    "Initialization failure from server:\nRuntimeError: Starting Ray client server failed. "
    "See ray_client_server_23002.err for detailed logs."
)


def test_a_client_server_that_dies_at_birth_is_asked_for_again(
    ray_head: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    import ray

    calls: list[str] = []
    real_init = ray.init

    def init(**kwargs: Any) -> Any:  # Ray's proxy losing the first two servers it forks
        calls.append(kwargs["address"])
        if len(calls) <= 2:
            raise ConnectionAbortedError(DIED)
        return real_init(**kwargs)

    monkeypatch.setattr(ray, "init", init)
    try:
        assert connect(ray_head, pause=0.0) is ray and ray.is_initialized()
        assert ray.get(ray.remote(lambda: 6 * 7).remote()) == 42
    finally:
        ray.shutdown()
    assert calls == [ray_head] * 3


def test_a_cluster_whose_servers_keep_dying_is_refused_after_some_attempts(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import ray

    calls: list[str] = []

    def init(**kwargs: Any) -> Any:
        calls.append(kwargs["address"])
        raise ConnectionAbortedError(DIED)

    monkeypatch.setattr(ray, "init", init)
    with pytest.raises(UsageError) as e:
        connect("ray://127.0.0.1:1", pause=0.0)
    shown = DIED.replace("\n", "\\n")  # a problem is one line
    assert str(e.value) == f"cannot reach the Ray cluster at 'ray://127.0.0.1:1': {shown}"
    assert len(calls) == CONNECT_ATTEMPTS


def test_a_sweep_on_the_cluster_gives_the_local_table(tmp_path: Path, ray_head: str) -> None:
    shutil.copytree(CELLS / "cable_routing", tmp_path / "cell")
    vary = ["--vary", "objects:cables.cable1.length=[650, 300]", "--no-cache"]

    def sweep(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            [sys.executable, "-m", "cellengine", "sweep", "plan_straight.yaml", *vary, *args],
            cwd=tmp_path / "cell",
            capture_output=True,
            text=True,
            timeout=600,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
        )

    # on the cluster with a time limit: each variant in a process of its own on its node
    local, ray = sweep("-j", "1"), sweep("--cluster", ray_head, "--timeout", "600")
    assert local.returncode == ray.returncode == 0, ray.stderr
    assert local.stdout == ray.stdout
    assert [line.split(",")[2] for line in ray.stdout.splitlines()] == ["feasible", "true", "false"]
