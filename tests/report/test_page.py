"""write_report's files: report.json, and report.html self-contained with its data intact."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from cellengine.program import CompiledSegment, Program, Segment
from cellengine.report import replay_data, report_data, write_report
from cellengine.report.page import pack, pack_replay, unpack
from tests.report.programs import cable_cell, sample_program

DATA_RE = re.compile(r"<script type='application/json' id='ce-data'>(.*?)</script>", re.S)


def embedded(html: str) -> dict:
    m = DATA_RE.search(html)
    assert m is not None, "no embedded data"
    return json.loads(m.group(1))


@pytest.fixture(scope="module")
def written(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    world, cell = cable_cell()
    out = tmp_path_factory.mktemp("run") / "nested" / "run"
    return write_report(out, sample_program(cell), world, cell, {"plan": "plan_one_turn.yaml"})


def test_paths_and_report_json(written: tuple[Path, Path]) -> None:
    json_path, html_path = written
    assert (json_path.name, html_path.name) == ("report.json", "report.html")
    _, cell = cable_cell()
    report = json.loads(json_path.read_text())
    want = report_data(sample_program(cell), cell, extra={"plan": "plan_one_turn.yaml"})
    assert report == json.loads(json.dumps(want))
    assert "NaN" not in json_path.read_text()


def test_html_has_no_external_references(written: tuple[Path, Path]) -> None:
    html = written[1].read_text(encoding="utf-8")
    lower = html.lower()
    for needle in ("http://", "https://", "<script src", "<link", "@import", "url(", "//cdn"):
        assert needle not in lower, needle
    assert lower.count("<script") == 3  # the error guard, the data, the page's code
    assert lower.startswith("<!doctype html>")


def test_html_embeds_the_report_and_the_replay(written: tuple[Path, Path]) -> None:
    world, cell = cable_cell()
    data = embedded(written[1].read_text(encoding="utf-8"))
    assert data["title"] == "cellengine run: cable_routing, plan_one_turn.yaml"
    assert data["report"] == json.loads(written[0].read_text())
    replay = replay_data(sample_program(cell), cell, world)
    assert data["replay"] == json.loads(json.dumps(pack_replay(replay)))
    # the packed series decode to the replay's values
    link = replay["links"][3]
    got = unpack(data["replay"]["links"][3]["points"])
    assert got == pytest.approx(np.array(link["points"]), abs=1e-9)
    assert unpack(data["replay"]["q"][2]) == pytest.approx(replay["q"][2], abs=1e-5)


def test_pack_round_trip() -> None:
    values = [0.1234, -0.5, 0.25, 1e-4, 3.0, 0.0]
    packed = pack(values, 2, 10_000)
    assert packed["delta"][:2] == [1234, -5000]
    assert unpack(packed) == pytest.approx(values, abs=1e-9)
    assert unpack(pack([], 3, 10)).size == 0


def test_hostile_labels_stay_data(tmp_path: Path) -> None:
    """Labels are JSON inside a script element: no '</script>' or comment can close it."""
    world, cell = cable_cell()
    program = sample_program(cell)
    first = program.segments[0]
    label = "</script><script>alert(1)</script><!-- https://x & ok"
    seg = CompiledSegment(Segment(0, label), "split", first.trajectory, {})
    _, html_path = write_report(
        tmp_path, Program(program.joint_names, (seg,), ()), world, cell, title="a <b> & c"
    )
    html = html_path.read_text(encoding="utf-8")
    assert html.count("</script>") == 3
    assert "<title>a &lt;b&gt; &amp; c</title>" in html
    data = embedded(html)
    assert data["report"]["segments"][0]["label"] == label


def test_size_of_a_minute(tmp_path: Path) -> None:
    """A 60 s program at 25 Hz stays well under a megabyte."""
    world, cell = cable_cell()
    _, html_path = write_report(tmp_path, sample_program(cell, seconds=10.0), world, cell)
    size = html_path.stat().st_size
    assert 100_000 < size < 900_000, size
