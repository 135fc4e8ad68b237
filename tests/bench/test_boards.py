"""The board generator and the independent checker of bench/bench_boards.py (issue #13 point 5):
the same seed writes the same files, every board loads and validates, the checker accepts the
compiled reference plan and rejects it against a world whose slot moved by 20 mm."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

import cellengine.skills.cable  # noqa: F401  (the real skills package registers the cable skills)
from bench.bench_boards import classify, make_boards, run_one
from bench.board_check import check_compiled
from bench.boards import Guide, make_board, rejection, remodel_placements
from cellengine.info.load import load_plan
from cellengine.pipeline import Compiled, compile_plan
from tests.conftest import CELLS

ROUTING = CELLS / "cable_routing"


def _files(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def test_same_seed_same_files(tmp_path: Path) -> None:
    make_board(7, tmp_path / "a")
    make_board(7, tmp_path / "b")
    make_board(8, tmp_path / "c")
    assert _files(tmp_path / "a") == _files(tmp_path / "b")
    assert (
        _files(tmp_path / "a")["routing/routing.x3d"]
        != _files(tmp_path / "c")["routing/routing.x3d"]
    )


def test_chosen_boards_with_a_working_margin(tmp_path: Path) -> None:
    """--only 5,9 --work-clearance 3: those boards, each cell saying 3 mm."""
    plans = make_boards([5, 9], False, tmp_path, work_clearance=3.0)
    assert sorted(plans) == ["board_5", "board_9"]
    for name, plan in plans.items():
        assert plan == tmp_path / "boards" / name / "plan.yaml"
        assert load_plan(plan).world.cell.work_clearance == pytest.approx(0.003)
    (plan,) = make_boards([5], False, tmp_path / "default").values()
    assert load_plan(plan).world.cell.work_clearance == pytest.approx(0.005)


def test_every_board_loads_and_validates(tmp_path: Path) -> None:
    for seed in range(20):
        board = make_board(seed, tmp_path / str(seed))
        loaded = load_plan(tmp_path / str(seed) / "plan.yaml")
        world = loaded.world
        assert 3 <= len(board.guides) <= 8
        assert rejection(board.conn_guide, board.guides, board.base_distance) is None
        for g in board.guides:
            slot = world.pose(f"routing.{g.name}")
            assert slot[:2, 3] * 1000 == pytest.approx([g.x, g.y], abs=1e-3)  # X3D rounding
            assert world.dimensions(f"routing.{g.name}")["gap"] * 1000 > board.cable_diameter
        assert world.cable("cable1").length * 1000 > board.route_length + 149


def test_overlapping_guides_are_rejected() -> None:
    a = Guide("guide1", 400.0, 0.0, 0.0, 10.0, 24.0, 40.0, 10.0, 10.0)
    b = Guide("guide2", 405.0, 0.0, 0.0, 10.0, 24.0, 40.0, 10.0, 10.0)
    far = Guide("guide3", 900.0, 0.0, 0.0, 10.0, 24.0, 40.0, 10.0, 10.0)
    assert rejection(a, (b,), 700.0) == "guide1 overlaps guide2"
    assert rejection(a, (far,), 700.0) == "guide3 out of an arm's reach"
    # 506 mm from the right base (0, -350), 796 mm from the left one: the left arm cannot
    # hold the pivot there
    one_arm = Guide("guide3", 500.0, -270.0, 0.0, 10.0, 24.0, 40.0, 10.0, 10.0)
    assert rejection(a, (one_arm,), 700.0) == "guide3 out of an arm's reach"


@pytest.fixture(scope="module")
def straight() -> Compiled:
    return compile_plan(ROUTING / "plan_straight.yaml", "split")


def test_checker_accepts_the_reference_plan(straight: Compiled) -> None:
    result = check_compiled(straight)
    assert result.ok, result.failures
    assert result.min_arm_distance is not None


def test_checker_rejects_a_moved_slot(straight: Compiled, tmp_path: Path) -> None:
    """guide2's slot 20 mm across the cable (its gap is 10 mm): the program no longer
    passes the cable through it."""
    cell = tmp_path / "cable_routing"
    shutil.copytree(ROUTING, cell)
    x3d = cell / "routing" / "routing.x3d"
    text = x3d.read_text()
    assert text.count('translation="150.000000 260.000000 10.000000"') == 1
    x3d.write_text(
        text.replace("150.000000 260.000000 10.000000", "170.000000 260.000000 10.000000")
    )
    moved = load_plan(cell / "plan_straight.yaml").world
    result = check_compiled(straight, moved)
    assert [f.kind for f in result.failures] == ["insert"]
    assert result.failures[0].message.startswith("routing.guide2: slot 20.0 mm off the cable")


def test_failure_classes() -> None:
    msg = (
        "plan.yaml:7:5: step 1 (PickCable CA1: approach and grasp): the left arm's Cartesian "
        "path stops at 17 % of its length: waypoint 3: collision between 'left/upper_arm_link' "
        "and 'right/wrist_2_link' (within 0.98 mm)"
    )
    assert classify(msg) == "Cartesian path stops: collision between arm upper_arm and arm wrist"
    assert classify("x: no sliding angle clears the guide: theta 3") == (
        "no sliding angle clears the guide"
    )


def test_a_compile_out_of_time_is_a_failure() -> None:
    """bench_boards --timeout: a compile still running then is stopped and counted."""
    plan = str(ROUTING / "plan_straight.yaml")
    out = run_one(plan, "straight", "split", timeout=0.05)
    assert (out.ok, out.reason, out.message) == (
        False, "not done in time", "not compiled within 0.05 s (stopped)"
    )  # fmt: skip


def test_remodel_placements_nearest_and_farthest_each_way_round() -> None:
    """With an arm reach test of 700 mm from both bases, a 200 x 20 mm sample along x fits
    turned every way: near at 150 mm in front of the bases (plus half its length along x),
    far where its farthest point is at the reach; the poses put the centre there."""
    import numpy as np

    def kp(x: float, y: float) -> np.ndarray:
        T = np.eye(4)
        T[:2, 3] = x / 1000, y / 1000
        return T

    sample = [kp(-300, 40), kp(-100, 40), kp(-100, 60)]  # centre (-166.7, 46.7) mm

    def reaches(T: np.ndarray) -> bool:
        p = T[:2, 3] * 1000
        return all(np.hypot(*(p - b)) <= 700 for b in ((0, 350), (0, -350)))

    placed = dict(remodel_placements(sample, reaches))
    names = [f"remodel_{yaw}_{tag}" for yaw in (0, 90, 180, 270) for tag in ("near", "far")]
    assert list(placed) == names
    # turned 0, centre at (290, 0): its nearest point 156.7 mm in front of the bases; at
    # (530, 0) its farthest (596.7, 13.3) is 698.6 mm from the right base (540: 707 mm)
    assert placed["remodel_0_near"] == "456.7 -46.7 0 0 0 0"
    assert placed["remodel_0_far"] == "696.7 -46.7 0 0 0 0"
    assert placed["remodel_90_near"].endswith(" 0 0 0 90")
