"""Localisation on synthetic pictures of the lab bench: the camera's pose from the world
markers, each container where it stands, and the refusals."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from cellengine.emulate.camera import world_markers
from cellengine.locate.extrinsics import PoseError, camera_pose
from cellengine.locate.markers import detect
from cellengine.locate.objects import locate
from tests.locate.bench_images import T_CAMERA, bench_world, moved, picture


@pytest.fixture(scope="module")
def scene():  # type: ignore[no-untyped-def]
    world = bench_world()
    places = moved(world)
    return world, places, picture(world, places)


def test_the_pictures_markers_are_where_opencvs_camera_model_puts_them(scene) -> None:  # type: ignore[no-untyped-def]
    """The renderer undoes the lens with its own code: its world markers land where
    OpenCV's projectPoints puts them, to a fraction of a pixel (their centres: the
    detector's corners sit within a square about 0.5 px smaller than the marker's edge
    on these 30 px markers, the same on every side)."""
    import cv2

    from cellengine.locate.extrinsics import world_corners
    from cellengine.locate.lens import distortion, matrix

    world, _, image = scene
    camera = world.cell.camera
    seen, _ = detect(camera, image)
    T = np.linalg.inv(T_CAMERA)
    rvec = cv2.Rodrigues(T[:3, :3])[0]
    for m in camera.world:
        true = cv2.projectPoints(
            world_corners(camera, m), rvec, T[:3, 3], matrix(camera), distortion(camera)
        )[0].reshape(4, 2)
        assert np.linalg.norm(seen[m].mean(axis=0) - true.mean(axis=0)) < 0.25  # px
        assert np.abs(seen[m] - true).max() < 1.0


def test_the_cameras_pose_comes_from_the_world_markers(scene) -> None:  # type: ignore[no-untyped-def]
    world, _, image = scene
    pose = camera_pose(world.cell.camera, detect(world.cell.camera, image)[0])
    assert pose.used == (0, 1, 2, 3)
    assert np.linalg.norm(pose.T_cell_camera[:3, 3] - T_CAMERA[:3, 3]) < 0.001  # m
    turn = pose.T_cell_camera[:3, :3].T @ T_CAMERA[:3, :3]
    assert math.degrees(math.acos(min(1.0, (np.trace(turn) - 1) / 2))) < 0.1


def test_containers_are_found_where_they_stand(scene) -> None:  # type: ignore[no-untyped-def]
    world, places, image = scene
    found = {f.name: f for f in locate(world, world.cell.camera, image).found}
    vial1, vial3 = found["vial1"], found["vial3"]
    # vial1 on the table, 20 mm from the nearest keypoint: a pose, turned as it stands
    assert vial1.keypoint is None
    assert np.linalg.norm(vial1.xyz - places["vial1"][:3, 3]) < 0.001
    assert abs(vial1.yaw - 0.3) < math.radians(2.0)
    # vial3 2.2 mm off its slot: within camera.snap (5 mm), so standing there, found 6 mm up
    assert vial3.keypoint == "bench.rack2.slot2"
    assert abs(vial3.off - math.hypot(0.002, 0.001)) < 0.001
    assert np.linalg.norm(vial3.xyz - places["vial3"][:3, 3]) < 0.001
    assert found["vial2"].keypoint == "bench.rack1.slot2"
    assert found["beaker"].keypoint == "bench.beaker.place"


def test_what_the_picture_does_not_show_is_said(scene) -> None:  # type: ignore[no-untyped-def]
    world, _, image = scene
    located = locate(world, world.cell.camera, image)
    # the clutter targets stand behind their taller blockers, as seen from the camera
    assert located.unseen == ("target1", "target2")
    assert located.strangers == ()


def test_too_few_world_markers_give_no_pose() -> None:
    world = bench_world()
    camera = world.cell.camera
    two = {m: T for m, T in world_markers(camera).items() if m in (0, 2)}
    image = picture(world, {}, markers=two)
    with pytest.raises(PoseError) as e:
        locate(world, camera, image)
    assert str(e.value) == (
        "2 of the world markers seen (0, 2); the camera's pose needs 3 (world_seen); not seen: 1, 3"
    )


def test_a_world_marker_moved_from_its_place_is_named() -> None:
    world = bench_world()
    camera = world.cell.camera
    shifted = world_markers(camera)
    shifted[2] = shifted[2].copy()
    shifted[2][:2, 3] += (0.03, 0.0)  # 30 mm from where cell.yaml has it
    with pytest.raises(PoseError) as e:
        locate(world, camera, picture(world, {}, markers=shifted))
    said = re.search(r": world marker 2 is ([0-9.]+) mm from its place in cell.yaml", str(e.value))
    assert said is not None and abs(float(said.group(1)) - 30.0) < 1.0
    assert str(e.value).endswith("; put it back, or correct camera.world.2")
