"""The cell page (`cellengine show CELL --html`): its data, and in headless Chromium the
keypoints drawn labelled and coloured by the arms that reach them."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from cellengine.info.load import load_world
from cellengine.motion.robot import build_cell_model
from cellengine.reach import keypoint_reach
from cellengine.report.cell_page import cell_page, cell_page_data
from tests.report.png import read_png
from tests.report.test_browser import dump_dom, run_chromium, screenshot
from tests.test_reach import HOLDER, ROUTE, moved_cell


def write_page(folder: Path, all_reached: bool = False) -> Path:
    """The page of the reference cell with the right arm far out (the U guides are the left
    arm's only) and the holder out of both arms' reach; or, to compare, of the same cell
    said to be reached everywhere."""
    world = load_world(moved_cell(folder / "cell"))
    cell = build_cell_model(world)
    reach = keypoint_reach(world, cell)
    if all_reached:
        reach = dict.fromkeys(reach, ("left", "right"))
    out = folder / "cable_routing.html"
    out.write_text(cell_page(world, cell, reach), encoding="utf-8")
    return out


@pytest.fixture(scope="module")
def page(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_page(tmp_path_factory.mktemp("cell_page"))


def colours(page: Path, tmp_path: Path, canvas: str) -> tuple[int, int]:
    """How many pixels of the 3D view are the page's red (no arm, #dc2626) and green (every
    arm, #16a34a). The axes' x and y are drawn in the same colours: compare pages."""
    x, y, w, h = (int(v) for v in canvas.split(","))
    shot = screenshot(page, tmp_path / "profile", tmp_path / "shot.png")
    pixels = read_png(shot.read_bytes(), rows=y + h)[y : y + h, x : x + w, :3].astype(int)
    r, g, b = (pixels[..., k] for k in range(3))
    red = (r > 190) & (g < 70) & (b < 70)
    green = (g > 130) & (r < 60) & (b < 110) & (g > b + 40)
    return int(red.sum()), int(green.sum())


def test_the_replay_says_which_arms_reach_each_keypoint(tmp_path: Path) -> None:
    world = load_world(moved_cell(tmp_path / "cell"))
    cell = build_cell_model(world)
    report, replay = cell_page_data(world, cell, keypoint_reach(world, cell))
    assert report["segments"] == [] and report["cell"] == str(world.cell_file)
    assert [k["name"] for k in replay["keypoints"]] == list(replay["reach"])
    assert replay["reach"]["routing.guide1.slot"] == ["left"]  # out of the right arm's reach
    assert replay["reach"]["routing.connector.slot"] == ["left", "right"]
    assert [k for k, arms in replay["reach"].items() if not arms] == HOLDER
    assert replay["duration"] == 0.0 and len(replay["times"]) == 1  # the robots at home


def test_keypoints_are_drawn_labelled_in_their_reach_colours(page: Path, tmp_path: Path) -> None:
    attrs, errors = dump_dom(page, tmp_path / "profile")
    assert attrs.get("data-status") == "ok", errors
    assert attrs["data-labelled"] == "15"  # every keypoint, each with its name
    assert attrs["data-reach"] == f"all:2,left:{len(ROUTE)},none:{len(HOLDER)}"

    dom = run_chromium(page.as_uri(), tmp_path / "profile", "--dump-dom").stdout
    rows = re.findall(r"<tr><td>([^<]+)</td><td[^>]*>[^<]*</td><td><span[^>]*></span>([^<]+)", dom)
    assert dict(rows)["routing.guide1.slot"] == "left only"
    assert dict(rows)["routing.connector.exit"] == "every arm"
    assert dict(rows)["holder.comb_b.slot"] == "no arm"

    red, green = colours(page, tmp_path, attrs["data-canvas"])
    other = write_page(tmp_path / "all", all_reached=True)
    red_all, green_all = colours(other, tmp_path, attrs["data-canvas"])
    # a dot has a radius of 5 px (78 px), partly under its label's halo or the next dot
    assert red - red_all > 80, (red, red_all)  # the holder's two combs (dots overlap)
    assert green_all - green > 13 * 20, (green, green_all)  # and the seven U guides
