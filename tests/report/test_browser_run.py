"""report.html of real runs in headless Chromium (the harness of test_browser.py): a run
stopped with Ctrl-C says so; a lab run draws its vials.

The interrupted run is `cellengine run --realtime` in a process of its own, sent SIGINT (what
Ctrl-C sends) once its journal says a segment finished: the runner's own path, the simulated
cell's own handling of the interrupt."""

from __future__ import annotations

import json
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from cellengine.report.outcome import DATA_OPEN
from tests.conftest import CELLS, ROOT
from tests.report.png import read_png
from tests.report.test_browser import dump_dom, run_chromium, screenshot

PLAN = CELLS / "cable_routing" / "plan_straight.yaml"
LAB_PLAN = CELLS / "lab_bench" / "plan_weigh_handover.yaml"
DEADLINE = 300.0  # s for the run to finish a segment (compiling comes first)


def _ctrl_c_raises() -> None:
    """In the child: SIGINT handled as at a terminal, even when this process was started with
    it ignored (a shell's background job): Python then raises KeyboardInterrupt."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _interrupted_run(out: Path) -> subprocess.CompletedProcess[str]:
    cmd = [sys.executable, "-m", "cellengine", "run", str(PLAN), "--out", str(out)]
    proc = subprocess.Popen(
        [*cmd, "--realtime", "-q"],
        preexec_fn=_ctrl_c_raises,
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    journal = out / "journal.jsonl"
    end = time.monotonic() + DEADLINE
    while proc.poll() is None and time.monotonic() < end:
        if journal.is_file() and '"entry": "finished"' in journal.read_text():
            proc.send_signal(signal.SIGINT)
            break
        time.sleep(0.05)
    else:
        proc.kill()
        _, err = proc.communicate()
        pytest.fail(f"the run finished no segment (exit {proc.returncode}): {err[-2000:]}")
    stdout, stderr = proc.communicate(timeout=120)
    return subprocess.CompletedProcess(cmd, proc.returncode, stdout, stderr)


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("interrupted") / "run"
    result = _interrupted_run(out)
    assert result.returncode != 0, result.stderr  # stopped, not completed
    return out


def test_an_interrupted_runs_report_says_interrupted(interrupted: Path, tmp_path: Path) -> None:
    report = json.loads((interrupted / "report.json").read_text())
    run = report["run"]
    assert run["outcome"] == "interrupted"
    assert 1 <= run["segments_finished"] < run["segments"]
    assert run["stopped_in"] is not None
    attrs, errors = dump_dom(interrupted / "report.html", tmp_path / "profile")
    assert attrs.get("data-status") == "ok", errors
    assert attrs["data-outcome"] == "interrupted"
    dom = run_chromium(
        (interrupted / "report.html").as_uri(), tmp_path / "profile", "--dump-dom"
    ).stdout
    chip = re.search(r'<span class="chip bad" id="run-status">run <b>([^<]*)</b>', dom)
    assert chip is not None and chip.group(1).startswith("INTERRUPTED"), dom[:2000]
    assert "plan checks" in dom and ">checks <b>" not in dom


@pytest.fixture(scope="module")
def lab_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("lab") / "run"
    cmd = [sys.executable, "-m", "cellengine", "run", str(LAB_PLAN), "--out", str(out), "-q"]
    result = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-2000:]
    return out


def _without_objects(page: Path, out: Path) -> Path:
    """The same page with no lab objects in its replay."""
    text = page.read_text(encoding="utf-8")
    start = text.index(DATA_OPEN) + len(DATA_OPEN)
    end = text.index("</script>", start)
    data = json.loads(text[start:end])
    data["replay"]["objects"] = []
    out.write_text(text[:start] + json.dumps(data).replace("<", "\\u003c") + text[end:])
    return out


def test_a_lab_report_draws_the_vials(lab_run: Path, tmp_path: Path) -> None:
    """Seen from above, fitted to the bench: the containers drawn (the vials' light blue
    where the same page without them shows the bench), their names written."""
    page = lab_run / "report.html"
    fragment = "#az=-1.5708&el=1.45&view=fit"  # from above, fitted to the bench
    attrs, errors = dump_dom(page, tmp_path / "profile", fragment)
    assert attrs.get("data-status") == "ok", errors
    assert attrs["data-outcome"] == "completed"
    assert attrs["data-objects"] == "15"  # 5 vials and their caps, a beaker, 4 bottles
    bare = _without_objects(page, tmp_path / "bare.html")
    x, y, w, h = (int(v) for v in attrs["data-canvas"].split(","))
    shots = [
        read_png(
            screenshot(p, tmp_path / "profile", tmp_path / f"{k}.png", fragment).read_bytes(),
            rows=y + h,
        )[y : y + h, x : x + w, :3].astype(int)
        for k, p in enumerate((page, bare))
    ]
    changed = np.abs(shots[0] - shots[1]).max(axis=2) > 30
    r, g, b = (shots[0][..., k] for k in range(3))
    vial_blue = changed & (b > r + 60) & (g > r + 40)  # OBJECT_COLORS.vial, #38bdf8, shaded
    assert vial_blue.sum() > 200, (int(changed.sum()), int(vial_blue.sum()))


VIEW_BUTTONS = """
<script>
(function () {
  const seen = [];
  for (const id of ['btn-top', 'btn-front', 'btn-fit', 'btn-zones', 'btn-closest', 'btn-keys']) {
    document.getElementById(id).click();
    seen.push(id);
  }
  setTimeout(function () {
    document.body.dataset.clicked = seen.join(',');
    document.body.dataset.clock = document.getElementById('clock').textContent;
  }, 500);
})();
</script>
"""


def test_view_presets_zones_closest_and_keypoint_labels(lab_run: Path, tmp_path: Path) -> None:
    """The buttons the run report adds work without an error; 'closest' goes to the moment of
    least clearance, the arms' or the environment's (report.json's totals); keypoints are
    drawn with their names."""
    report = json.loads((lab_run / "report.json").read_text())
    least = min(
        (c for c in report["totals"]["clearance"].values() if c is not None),
        key=lambda c: c["distance_m"],
    )
    page = tmp_path / "buttons.html"
    text = (lab_run / "report.html").read_text(encoding="utf-8")
    page.write_text(text.replace("</body>", VIEW_BUTTONS + "</body>"), encoding="utf-8")
    attrs, errors = dump_dom(page, tmp_path / "profile", "#keys=1")
    assert attrs.get("data-status") == "ok", errors
    assert attrs["data-clicked"].count("btn-") == 6
    assert int(attrs["data-keylabels"]) > 0
    now = float(attrs["data-clock"].split("/")[0].strip(" s"))
    assert now == pytest.approx(least["time_s"], abs=0.01)
