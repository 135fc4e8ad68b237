"""report.html in headless Chromium (Debian's chromium; `make test` installs it): it loads
without errors and draws the cell.

Two runs per page: --dump-dom reads what the page says of itself (``data-status``, the 3D
canvas's rectangle, errors caught into ``#errors``), --screenshot shows what it drew. No skip:
without Chromium these tests fail, saying how to install it.
"""

from __future__ import annotations

import html as html_lib
import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from cellengine.program import Program
from cellengine.report import write_report
from tests.report.png import read_png
from tests.report.programs import cable_cell, sample_program

WINDOW = (1400, 1000)
BACKGROUND = np.array([0xE9, 0xED, 0xF3])  # the 3D view's background (assets/base.js BG)
FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--hide-scrollbars",
    "--host-resolver-rules=MAP * ~NOTFOUND",  # nothing may come from the network anyway
    f"--window-size={WINDOW[0]},{WINDOW[1]}",
    "--virtual-time-budget=5000",
)


def chromium() -> str:
    """The Chromium executable: $CELLENGINE_CHROMIUM, chromium, chromium-browser."""
    for name in (os.environ.get("CELLENGINE_CHROMIUM"), "chromium", "chromium-browser"):
        found = shutil.which(name) if name else None
        if found:
            return found
    pytest.fail(
        "Chromium not found (looked for $CELLENGINE_CHROMIUM, chromium, chromium-browser): "
        "install Debian's chromium with `apt-get install -y chromium` (`make test` does); "
        "the report's browser tests cannot run without it"
    )


def run_chromium(url: str, profile: Path, *args: str) -> subprocess.CompletedProcess[str]:
    cmd = [chromium(), *FLAGS, f"--user-data-dir={profile}", *args, url]
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=180, check=False)
    assert result.returncode == 0, f"chromium exited {result.returncode}: {result.stderr[-2000:]}"
    return result


def dump_dom(page: Path, profile: Path, fragment: str = "") -> tuple[dict[str, str], str]:
    """The body's attributes and the text of #errors after the page has run."""
    dom = run_chromium(page.as_uri() + fragment, profile, "--dump-dom").stdout
    body = re.search(r"<body([^>]*)>", dom)
    assert body is not None, f"no <body> in the dumped DOM: {dom[:500]}"
    attrs = dict(re.findall(r'([\w-]+)="([^"]*)"', body.group(1)))
    errors = re.search(r'<pre id="errors"[^>]*>(.*?)</pre>', dom, re.S)
    return attrs, html_lib.unescape(errors.group(1)) if errors else ""


def screenshot(page: Path, profile: Path, out: Path, fragment: str = "") -> Path:
    run_chromium(page.as_uri() + fragment, profile, f"--screenshot={out}")
    assert out.is_file(), "chromium wrote no screenshot"
    return out


@pytest.fixture(scope="module")
def report_page(tmp_path_factory: pytest.TempPathFactory) -> Path:
    world, cell = cable_cell()
    out = tmp_path_factory.mktemp("browser")
    _, html_path = write_report(out, sample_program(cell), world, cell, {"plan": "p.yaml"})
    return html_path


def test_report_loads_without_errors_and_draws(report_page: Path, tmp_path: Path) -> None:
    fragment = "#t=2.5"  # both grippers hold the cable: it is drawn between the hands
    attrs, errors = dump_dom(report_page, tmp_path / "profile", fragment)
    assert attrs.get("data-status") == "ok", f"page status {attrs.get('data-status')}: {errors}"
    assert errors.strip() == ""
    assert int(attrs["data-drawn"]) > 200  # triangles, link shapes, hands
    assert attrs["data-cables"] == "1"
    x, y, w, h = (int(v) for v in attrs["data-canvas"].split(","))
    assert w > 400 and h > 300 and x + w <= WINDOW[0] and y + h <= WINDOW[1]

    shot = screenshot(report_page, tmp_path / "profile", tmp_path / "shot.png", fragment)
    image = read_png(shot.read_bytes(), rows=y + h)[y : y + h, x : x + w, :3].astype(int)
    pixels = image.reshape(-1, 3)
    drawn = np.abs(pixels - BACKGROUND).max(axis=1) > 12
    share = float(drawn.mean())
    assert share > 0.15, f"only {share:.1%} of the 3D view differs from its background"
    r, g, b = pixels[:, 0], pixels[:, 1], pixels[:, 2]
    blue = (b > r + 60) & (b > g + 20)  # the left arm
    orange = (r > b + 80) & (r > g + 30)  # the right arm
    assert blue.sum() > 1000 and orange.sum() > 1000, (int(blue.sum()), int(orange.sum()))
    assert len(np.unique(pixels, axis=0)) > 200  # shaded, not flat fills


def test_errors_in_the_page_are_caught(report_page: Path, tmp_path: Path) -> None:
    """The harness sees a failing page: a script error ends in data-status 'error' with the
    message in #errors (so the test above would catch one)."""
    broken = tmp_path / "broken.html"
    text = report_page.read_text(encoding="utf-8")
    marker = "'use strict';"
    assert marker in text
    broken.write_text(text.replace(marker, marker + "\nnull.boom();", 1), encoding="utf-8")
    attrs, errors = dump_dom(broken, tmp_path / "profile")
    assert attrs.get("data-status") == "error"
    assert "null" in errors and "init" not in errors  # a top-level TypeError, from the guard


def test_an_empty_program_loads(tmp_path: Path) -> None:
    """No segments, no events: the cell at home, nothing to play, no error."""
    world, cell = cable_cell()
    _, page = write_report(tmp_path / "run", Program(cell.joint_names, (), ()), world, cell)
    attrs, errors = dump_dom(page, tmp_path / "profile")
    assert attrs.get("data-status") == "ok", errors
    assert int(attrs["data-drawn"]) > 100 and attrs["data-cables"] == "0"


def test_a_lab_mission_is_drawn_as_lanes_per_robot(tmp_path: Path) -> None:
    """report.json's mission (lab plans) becomes one timeline lane per robot, each part a
    bar saying its step and what the allocator inserted."""
    world, cell = cable_cell()
    mission = [
        {"step": "weigh", "arms": ["right"], "start": 0.0, "end": 1.0, "inserted": None},
        {"step": "weigh", "arms": ["right"], "start": 1.0, "end": 2.0, "inserted": "handover"},
        {"step": "weigh", "arms": ["left"], "start": 2.0, "end": 3.0, "inserted": "handover"},
        {
            "step": "cap",
            "arms": ["left", "right"],
            "start": 3.0,
            "end": 5.0,
            "inserted": "cooperation",
        },
    ]
    extra = {"plan": "p.yaml", "mission": mission}
    _, page = write_report(tmp_path / "run", sample_program(cell), world, cell, extra)
    dom = run_chromium(page.as_uri(), tmp_path / "profile", "--dump-dom").stdout
    assert 'data-status="ok"' in dom
    lanes = re.findall(r'<div class="lane ?" data-mission="(\w+)">(.*?)</div></div>', dom)
    assert sorted(arm for arm, _ in lanes) == ["left", "right"]
    right = next(body for arm, body in lanes if arm == "right")
    assert right.count('class="bar') == 3
    assert "weigh (handover)" in right and "cap (cooperation)" in right


def test_both_robots_at_once_are_drawn_as_lanes_with_their_waits(tmp_path: Path) -> None:
    """A lab plan with both robots at once: a lane per robot of its segments where they
    ran, and each wait the streams inserted drawn before its segment, saying why."""
    from cellengine.pipeline import compile_plan, write_plan_outputs
    from tests.conftest import CELLS

    c = compile_plan(CELLS / "lab_bench" / "plan_relocate.yaml")
    paths = write_plan_outputs(c, tmp_path / "run")
    dom = run_chromium(paths["html"].as_uri(), tmp_path / "profile", "--dump-dom").stdout
    assert 'data-status="ok"' in dom
    lanes = re.findall(r'<div class="lane thin" data-stream="(\w+)">(.*?)</div></div>', dom)
    assert sorted(arm for arm, _ in lanes) == ["robot1", "robot2"]
    for arm, body in lanes:
        mine = [s for s in c.program.streams if arm in s.arms]
        assert body.count('class="bar"') == len(mine)
    waits = re.findall(r'class="bar wait" title="([^"]*)"', dom)
    (wait,) = [s for s in c.program.streams if s.why is not None]
    assert len(waits) == 1 and "shared zone" in html_lib.unescape(waits[0])
    assert f"waited {wait.wait:.2f} s before {wait.label}" in html_lib.unescape(waits[0])


INTERACT = """
<script>
(function () {
  const c = document.getElementById('view');
  const r = c.getBoundingClientRect();
  const at = (type, x, y, extra) => c.dispatchEvent(new PointerEvent(type, Object.assign(
    { clientX: r.left + x, clientY: r.top + y, bubbles: true, pointerId: 7, buttons: 1 },
    extra || {})));
  at('pointerdown', 100, 100); at('pointermove', 160, 130); at('pointerup', 160, 130);
  at('pointerdown', 100, 100, { shiftKey: true }); at('pointermove', 130, 90);
  at('pointerup', 130, 90);
  c.dispatchEvent(new WheelEvent('wheel', { deltaY: -300, bubbles: true, cancelable: true }));
  c.dispatchEvent(new MouseEvent('dblclick', { bubbles: true }));
  for (const id of ['btn-trails', 'btn-keys', 'btn-wire', 'btn-reset']) {
    document.getElementById(id).click();
  }
  document.querySelectorAll('.bar')[1].click();
  document.querySelector('tr.clickable').click();
  const plot = document.querySelector('canvas.plot');
  const pr = plot.getBoundingClientRect();
  plot.dispatchEvent(new PointerEvent('pointerdown', { clientX: pr.left + pr.width / 2,
    clientY: pr.top + 20, bubbles: true, pointerId: 8, buttons: 1 }));
  document.dispatchEvent(new KeyboardEvent('keydown', { key: 'ArrowRight', bubbles: true }));
  const s = document.getElementById('slider');
  s.value = '1'; s.dispatchEvent(new Event('input'));
  const speed = document.getElementById('speed');
  speed.value = '2'; speed.dispatchEvent(new Event('change'));
  document.getElementById('play').click();
  setTimeout(function () {
    document.body.dataset.clock = document.getElementById('clock').textContent;
    document.body.dataset.play = document.getElementById('play').textContent;
  }, 1000);
})();
</script>
"""


def test_interactions_do_not_fail(report_page: Path, tmp_path: Path) -> None:
    """Orbit, pan, zoom, reset, toggles, timeline, table, plot, keys, slider, speed and play:
    no error; the slider sets the time and play starts playing. (Playback advances on
    requestAnimationFrame, which headless Chromium's virtual time fires a few times at most.)"""
    page = tmp_path / "interact.html"
    text = report_page.read_text(encoding="utf-8")
    page.write_text(text.replace("</body>", INTERACT + "</body>"), encoding="utf-8")
    attrs, errors = dump_dom(page, tmp_path / "profile")
    assert attrs.get("data-status") == "ok", errors
    assert "Pause" in attrs["data-play"]
    now, total = (float(v.strip(" s")) for v in attrs["data-clock"].split("/"))
    assert total == 6.0 and 1.0 <= now < 3.5, attrs["data-clock"]


FAIL_RED = (225, 29, 72)  # assets/failure.js FAIL_COLOR: the failing pair


def red_pixels(shot: Path, canvas: str) -> int:
    """Pixels of the 3D view in the failing pair's red, however shaded (not the right arm's
    orange, whose green is half its red)."""
    x, y, w, h = (int(v) for v in canvas.split(","))
    image = read_png(shot.read_bytes(), rows=y + h)[y : y + h, x : x + w, :3].astype(int)
    r, g, b = (image[..., k] for k in range(3))
    return int(((r > 120) & (g < 0.3 * r) & (b < 0.5 * r)).sum())


@pytest.fixture(scope="module")
def failed_page(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The report of the walled lab's plan, which fails (tests/helpers.py)."""
    from cellengine.cli import main
    from tests.helpers import walled_lab

    base = tmp_path_factory.mktemp("failed")
    out = base / "run"
    assert main(["plan", str(walled_lab(base / "cell")), "--out", str(out), "-q"]) == 1
    return out / "report.html"


def test_a_failed_plans_report_shows_the_failing_pose(failed_page: Path, tmp_path: Path) -> None:
    """The page opens on the pose where the compile stopped: the pair is named in the page
    and drawn in red (the wall and robot2's gripper); the replay at a time (#t=0) draws
    little red."""
    dom = run_chromium(failed_page.as_uri(), tmp_path / "profile", "--dump-dom").stdout
    body = dict(re.findall(r'([\w-]+)="([^"]*)"', re.search(r"<body([^>]*)>", dom).group(1)))
    assert body["data-status"] == "ok", dom[:2000]
    assert body["data-failures"] == "1"
    assert body["data-failure-pair"] == "robot2/gripper,wall"
    assert body["data-failure-drawn"] == "2"  # the gripper and the wall, each named by it
    panel = html_lib.unescape(
        re.search(r'<section[^>]*id="failure-panel"[^>]*>(.*?)</section>', dom, re.S).group(1)
    )
    assert "Plan failed: 1 failure; 3 segments compiled before it" in panel
    assert "no collision-free transit for robot2" in panel
    assert "in the way: robot2 gripper \u2194 wall" in panel  # the page says names as people do
    assert "plan <b>FAILED</b>" in dom

    shown = red_pixels(
        screenshot(failed_page, tmp_path / "profile", tmp_path / "fail.png"), body["data-canvas"]
    )
    replay = red_pixels(
        screenshot(failed_page, tmp_path / "profile", tmp_path / "t0.png", "#t=0"),
        body["data-canvas"],
    )
    # the replay has some red of its own (the lab's objects and marks): the pose adds far more
    assert shown > 3000 and shown > 10 * replay, (shown, replay)


FAIL_CLICKS = """
<script>
(function () {
  const btn = document.getElementById('btn-fail');
  const shown = () => btn.classList.contains('on');
  const seen = [shown()];
  btn.click(); seen.push(shown());  // off: the replay
  document.querySelector('#failure-panel li.clickable').click(); seen.push(shown());
  document.getElementById('play').click(); seen.push(shown());  // playing leaves the pose
  btn.click(); seen.push(shown());
  setTimeout(function () { document.body.dataset.seen = seen.join(','); }, 500);
})();
</script>
"""


def test_the_failing_pose_is_left_for_the_replay_and_shown_again(
    failed_page: Path, tmp_path: Path
) -> None:
    """The 'failure' button and the failure's entry show the pose; the button, the slider and
    play leave it for the replay; no error on the way."""
    page = tmp_path / "clicks.html"
    text = failed_page.read_text(encoding="utf-8")
    page.write_text(text.replace("</body>", FAIL_CLICKS + "</body>"), encoding="utf-8")
    attrs, errors = dump_dom(page, tmp_path / "profile")
    assert attrs.get("data-status") == "ok", errors
    assert attrs["data-seen"] == "true,false,true,false,true"
