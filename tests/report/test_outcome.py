"""write_run: the run's record set in report.json and in report.html's embedded report, both
or neither, the rest of the page as it was."""

from __future__ import annotations

import json
from pathlib import Path

from cellengine.report import write_report
from cellengine.report.outcome import DATA_OPEN, with_run, write_run
from tests.report.programs import cable_cell, sample_program


def _embedded(page: str) -> dict:
    start = page.index(DATA_OPEN) + len(DATA_OPEN)
    return json.loads(page[start : page.index("</script>", start)])


def test_the_run_is_written_into_both_files(tmp_path: Path) -> None:
    world, cell = cable_cell()
    json_path, html_path = write_report(tmp_path, sample_program(cell), world, cell)
    before_json, before_page = json.loads(json_path.read_text()), html_path.read_text()
    write_run(tmp_path, {"outcome": "running", "driver": "sim"})
    write_run(tmp_path, {"outcome": "interrupted", "driver": "sim", "fault": None})
    report, page = json.loads(json_path.read_text()), html_path.read_text()
    assert report == {
        **before_json,
        "run": {"outcome": "interrupted", "driver": "sim", "fault": None},
    }
    data = _embedded(page)
    assert data["report"] == report
    assert data["replay"] == _embedded(before_page)["replay"]
    start = page.index(DATA_OPEN)
    assert page[:start] == before_page[:start]  # the page's head, style and guard unchanged
    assert page.endswith(before_page[before_page.index("</script>", start) :])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report.html", "report.json"]


def test_hostile_text_stays_data(tmp_path: Path) -> None:
    page = with_run(
        f"<html>{DATA_OPEN}" + '{"report": {}}</script></html>', {"message": "</script><b>"}
    )
    assert page.count("</script>") == 1
    assert _embedded(page)["report"]["run"] == {"message": "</script><b>"}


def test_nothing_is_written_without_a_report(tmp_path: Path) -> None:
    write_run(tmp_path, {"outcome": "completed"})
    assert list(tmp_path.iterdir()) == []
