"""The skill-family contract: a third-party family, installed as a package of its own with
its own entry point, compiles and runs on the simulated cell like the built-in ones, and the
compiler takes a family's next candidate when the first cannot run."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cellengine.errors import InputError
from tests.conftest import CELLS, DATA, ROOT

PLAN = """\
cell: cell.yaml
units: {length: mm}
steps:
  - skill: Hover
    over: routing.guide1
    arm: left
    heights: [1500, 100]   # 1.5 m over the guide is out of the arm's reach
  - skill: Hover
    over: routing.guide3
    arm: right
"""


@pytest.fixture(scope="module")
def site(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """tests/data/tinyfamily installed (pip, with its entry point) into a folder of its own."""
    source = tmp_path_factory.mktemp("src") / "tinyfamily"
    shutil.copytree(DATA / "tinyfamily", source)  # pip builds in the tree it is given
    target = tmp_path_factory.mktemp("site")
    pip = [sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation"]
    subprocess.run([*pip, "--no-index", "--target", str(target), str(source)], check=True)
    assert list(target.glob("tinyfamily-*.dist-info"))
    return target


def cellengine(site: Path, *args: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(site), str(ROOT)])}
    return subprocess.run(
        [sys.executable, "-m", "cellengine", *args], capture_output=True, text=True, env=env
    )


def test_a_third_party_family_compiles_and_runs_on_the_simulated_cell(
    site: Path, tmp_path: Path
) -> None:
    cell = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", cell)
    (cell / "plan.yaml").write_text(PLAN)
    out = tmp_path / "run"
    done = cellengine(site, "run", str(cell / "plan.yaml"), "--out", str(out), "-q")
    assert done.returncode == 0, done.stderr
    journal = [json.loads(line) for line in (out / "journal.jsonl").read_text().splitlines()]
    finished = [e["label"] for e in journal if e["entry"] == "finished"]
    # the 1500 mm hover cannot be reached: the compiler took the family's next candidate
    assert finished == [
        "Hover routing.guide1: 100 mm over",
        "Hover routing.guide1: back",
        "Hover routing.guide3: 100 mm over",
        "Hover routing.guide3: back",
    ]
    assert journal[-1]["entry"] == "end"
    points = json.loads((out / "trajectory.json").read_text())["points"]
    assert len(points) > 2 and points[-1]["time_from_start"] > 0.0


def test_a_family_skill_is_validated_and_has_a_schema(site: Path, tmp_path: Path) -> None:
    cell = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", cell)
    (cell / "plan.yaml").write_text(PLAN.replace("routing.guide3", "routing.guide9"))
    done = cellengine(site, "validate", str(cell / "plan.yaml"), "--no-compile")
    assert done.returncode == 1
    assert done.stdout == (
        f"{cell / 'plan.yaml'}:9:11: steps[1].over: unknown element 'routing.guide9'; known: "
        "connector, guide1, guide2, guide3, guide4, guide5, guide6, guide7\n"
    )
    schemas = tmp_path / "schemas"
    assert cellengine(site, "schema", "--out", str(schemas)).returncode == 0
    assert "Hover" in (schemas / "plan.schema.json").read_text()


def test_every_candidate_failing_gives_the_first_error(site: Path, tmp_path: Path) -> None:
    cell = tmp_path / "cell"
    shutil.copytree(CELLS / "cable_routing", cell)
    plan = cell / "plan.yaml"
    plan.write_text(PLAN.replace("[1500, 100]", "[1500, 1600]"))
    done = cellengine(site, "plan", str(plan), "--out", str(tmp_path / "out"), "-q")
    assert done.returncode == 1
    assert f"{plan}:4:5: step 1 (Hover routing.guide1: 1500 mm over): " in done.stderr
    # the report of the failure, nothing to run
    assert not (tmp_path / "out" / "trajectory.json").exists()
    assert (tmp_path / "out" / "report.html").is_file()


def test_a_plan_mixing_families_is_refused_at_the_step(tmp_path: Path) -> None:
    from cellengine.pipeline import compile_plan

    cell = tmp_path / "cell"
    shutil.copytree(CELLS / "lab_bench", cell)
    objects = cell / "objects.yaml"
    objects.write_text(objects.read_text() + "cables:\n  cable1: {length: 650, diameter: 6}\n")
    plan = cell / "mixed.yaml"
    plan.write_text(
        "cell: cell.yaml\nobjects: objects.yaml\nsteps:\n"
        "  - skill: Weigh\n    object: vial1\n"
        "  - skill: PickCable\n    cable: cable1\n    from: [bench.rack1, bench.rack1]\n"
    )
    with pytest.raises(InputError) as e:
        compile_plan(plan)
    (problem,) = e.value.problems
    assert (problem.file, problem.line) == (str(plan), 6)
    assert problem.message.startswith(
        "steps[1]: PickCable cannot be compiled to motion in a plan with lab skills (a plan's "
        "skills are all of one family: "
    )
