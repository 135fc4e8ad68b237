"""Which arms reach each keypoint: the tool along the keypoint's frame, each arm's IK."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.info.load import load_world
from cellengine.motion.ik import arm_ik
from cellengine.motion.robot import build_cell_model
from cellengine.reach import approach, keypoint_reach
from tests.conftest import CELLS

ROUTE = [f"routing.guide{i}.slot" for i in range(1, 8)]
HOLDER = [f"holder.comb_{c}.{k}" for c in "ab" for k in ("slot", "slot_pos_y", "slot_neg_y")]


def moved_cell(folder: Path) -> Path:
    """The reference cell with the right arm 900 mm from the middle instead of 350 (the
    connector guide, nearest it, in its reach; the U guides out of it) and the holder 1.1 m
    farther out in x (out of both arms' reach)."""
    shutil.copytree(CELLS / "cable_routing", folder)
    cell = folder / "cell.yaml"
    text = cell.read_text()
    for old, new in (
        ("base: {xyz: [0, -350, 0]", "base: {xyz: [0, -900, 0]"),
        ("holder:   {pose: {xyz: [150, -190, 0]", "holder:   {pose: {xyz: [1250, -190, 0]"),
    ):
        assert old in text
        text = text.replace(old, new)
    cell.write_text(text)
    return cell


def test_the_tool_comes_down_the_keypoint_s_z_along_its_x() -> None:
    T_k = g.pose([0.4, 0.1, 0.065], [0.1, -0.2, 0.7])
    T, flipped = approach(T_k)
    np.testing.assert_allclose(T[:3, 3], T_k[:3, 3], atol=1e-12)
    np.testing.assert_allclose(T[:3, 2], -T_k[:3, 2], atol=1e-12)  # z down into it
    np.testing.assert_allclose(T[:3, 0], T_k[:3, 0], atol=1e-12)  # x along it
    for M in (T, flipped):  # rotations
        np.testing.assert_allclose(M[:3, :3] @ M[:3, :3].T, np.eye(3), atol=1e-12)
        assert np.linalg.det(M[:3, :3]) == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(flipped[:3, 2], T[:3, 2], atol=1e-12)  # the same axis,
    np.testing.assert_allclose(flipped[:3, 0], -T[:3, 0], atol=1e-12)  # half a turn about it


def test_every_keypoint_of_the_reference_cell_is_reached_by_both_arms() -> None:
    world = load_world(CELLS / "cable_routing" / "cell.yaml")
    reach = keypoint_reach(world, build_cell_model(world))
    assert list(reach) == list(world.keypoints())
    assert set(reach.values()) == {("left", "right")}


def test_keypoints_out_of_one_arm_s_reach_and_of_both(tmp_path: Path) -> None:
    world = load_world(moved_cell(tmp_path / "cell"))
    cell = build_cell_model(world)
    reach = keypoint_reach(world, cell)
    assert {k: reach[k] for k in ROUTE} == dict.fromkeys(ROUTE, ("left",))
    assert reach["routing.connector.slot"] == ("left", "right")
    assert [k for k, arms in reach.items() if not arms] == HOLDER
    # the right arm's IK indeed finds no pose holding guide1 (nor turned), the left's does
    tcp = approach(world.pose("routing.guide1.slot"))
    assert all(arm_ik(cell.arms["right"]).solve(t) is None for t in tcp)
    q = arm_ik(cell.arms["left"]).solve(tcp[0])
    if q is None:
        q = arm_ik(cell.arms["left"]).solve(tcp[1])
    assert q is not None
    np.testing.assert_allclose(
        cell.arms["left"].fk(q)[:3, 3], world.pose("routing.guide1.slot")[:3, 3], atol=1e-9
    )


def test_names_given_are_the_only_ones_checked(tmp_path: Path) -> None:
    world = load_world(moved_cell(tmp_path / "cell"))
    reach = keypoint_reach(world, build_cell_model(world), ["routing.guide1", "holder.comb_a"])
    # an element's name is its first keypoint
    assert reach == {"routing.guide1": ("left",), "holder.comb_a": ()}
