"""`cellengine locate` and `cellengine run --locate` on synthetic pictures of the lab bench."""

from __future__ import annotations

import argparse
import json
import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from cellengine.cli import main
from cellengine.commands.plan import compile_from_args
from cellengine.commands.run import at_places, journaled_places
from cellengine.errors import display_path
from cellengine.journal import JOURNAL, read_progress
from cellengine.runner.identity import differences, run_identity
from tests.conftest import CELLS
from tests.locate.bench_images import bench_world, moved, picture

BENCH = CELLS / "lab_bench"


@pytest.fixture(scope="module")
def shot(tmp_path_factory: pytest.TempPathFactory) -> Path:
    world = bench_world()
    path = tmp_path_factory.mktemp("shot") / "bench.png"
    cv2.imwrite(str(path), picture(world, moved(world)))
    return path


def test_locate_prints_where_each_container_stands(
    shot: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["locate", str(BENCH), "--image", str(shot)]) == 0
    lines = capsys.readouterr().out.splitlines()
    # the camera's true place: (762, 641, 905) mm
    assert re.fullmatch(
        r"camera at x 76[12]\.\d y 64[01]\.\d z 90[45]\.\d mm, from world markers "
        r"0, 1, 2, 3 \(\d\.\d\d px RMS\)",
        lines[0],
    )
    rows = {line.split()[0]: line.split() for line in lines[2:-2]}
    assert rows["vial1"][1] == "4" and rows["vial1"][-2:] == ["the", "table"]
    assert all(
        abs(float(v) - t) < 1.0
        for v, t in zip(rows["vial1"][2:6], [550.0, 230.0, 0.0, 17.2], strict=True)
    )
    # vial3 is 2.2 mm off its slot: standing there (camera.snap is 5 mm)
    assert rows["vial3"][6] == "bench.rack2.slot2" and rows["vial3"][8:] == ["mm", "off)"]
    assert abs(float(rows["vial3"][7][1:]) - 2.2) < 0.5
    assert lines[-2:] == [
        "not seen: target1 (marker 10): objects.yaml's place kept (bench.clutter1.target)",
        "not seen: target2 (marker 12): objects.yaml's place kept (bench.clutter2.target)",
    ]


def test_locate_json_and_the_copy_of_objects_yaml(
    shot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "objects.yaml"
    assert main(["locate", str(BENCH), "--image", str(shot), "--out", str(out), "--json"]) == 0
    found = json.loads(capsys.readouterr().out)["found"]
    assert np.allclose(found["vial1"]["xyz"], [0.55, 0.23, 0.0], atol=0.001)
    assert found["vial3"]["keypoint"] == "bench.rack2.slot2"
    before = (BENCH / "objects.yaml").read_text().splitlines()
    after = out.read_text().splitlines()
    changed = [(a, b) for a, b in zip(before, after, strict=True) if a != b]
    assert len(changed) == 1  # vial1's line; every comment and other place kept
    assert re.fullmatch(
        r"          marker: 4, at: \{xyz: \[5(49|50)(\.\d+)?, 2(29|30)(\.\d+)?, 0\]\}\}",
        changed[0][1],
    )


def test_locate_refusals(shot: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    small = tmp_path / "small.png"
    cv2.imwrite(str(small), np.zeros((540, 960), np.uint8))
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((1080, 1920), 140, np.uint8))
    text = tmp_path / "notes.png"
    text.write_text("not a picture")
    cases = [
        (
            ["locate", str(BENCH), "--image", str(small)],
            f"{small}: the picture is 960 x 540 px; cell.yaml's camera is 1920 x 1080 "
            "(camera.resolution): its intrinsics are for that size",
        ),
        (
            ["locate", str(BENCH), "--image", str(text)],
            f"{text}: not an image OpenCV can read (PNG, JPEG, TIFF, BMP, ...)",
        ),
        (
            ["locate", str(BENCH), "--image", str(blank)],
            f"{blank}: no camera pose: 0 of the world markers seen (none); the camera's pose "
            "needs 3 (world_seen); not seen: 0, 1, 2, 3",
        ),
        (
            ["locate", str(CELLS / "cable_routing"), "--image", str(shot)],
            f"{display_path(CELLS / 'cable_routing' / 'cell.yaml')}: the cell has no camera: "
            "add `camera` (resolution, matrix, distortion, marker, world markers) to locate "
            "objects",
        ),
    ]
    for argv, message in cases:
        assert main(argv) == 1
        assert capsys.readouterr().err.strip() == message


def test_run_locate_plans_with_the_places_found_and_a_resume_keeps_them(
    shot: Path, tmp_path: Path
) -> None:
    plan = BENCH / "plan_relocate.yaml"
    out = tmp_path / "run"
    assert main(["run", str(plan), "--locate", str(shot), "--out", str(out), "-q"]) == 0
    places = journaled_places(out)
    assert places is not None and places["vial3"] == "bench.rack2.slot2"
    assert places["vial1"]["xyz"] == pytest.approx([550.0, 230.0, 0.0], abs=1.0)  # mm
    args = argparse.Namespace(plan=plan, cell=None, execution=None, quiet=True, speed=1.0, out=out)
    journaled = read_progress(out / JOURNAL).run
    assert journaled is not None
    again = at_places(args, places, compile_from_args)
    assert again.world.container("vial1").at is not None
    assert not isinstance(again.world.container("vial1").at, str)
    assert differences(journaled, run_identity(again)) == []
    plain = compile_from_args(args)
    assert differences(journaled, run_identity(plain)) == [
        "the containers' places located by the camera (--locate) differ"
    ]
    assert main(["run", str(plan), "--resume", str(out), "--locate", str(shot)]) == 2


def test_emulate_camera_takes_a_picture_locate_reads(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    picture_file = tmp_path / "bench.png"
    argv = [
        "emulate",
        "camera",
        str(BENCH),
        "--out",
        str(picture_file),
        "--move",
        "vial2=700,300,30",
    ]
    assert main(argv) == 0
    assert main(["locate", str(BENCH), "--image", str(picture_file), "--json"]) == 0
    found = json.loads(capsys.readouterr().out.split("\n", 1)[1])["found"]
    assert np.allclose(found["vial2"]["xyz"], [0.7, 0.3, 0.0], atol=0.001)
    assert found["vial2"]["keypoint"] is None
    assert main(["emulate", "camera", str(BENCH), "--out", str(picture_file), "--move", "x=1"]) == 2
    assert capsys.readouterr().err.startswith("--move: unknown container 'x'; known: beaker,")
