"""What a run did, written into the run folder's report after the plan's report was: report.json
and report.html get ``run`` (see :mod:`cellengine.runner.ran`), both or neither.

report.html is not rendered again (that would sample the program's replay again): its
embedded data (``#ce-data``, JSON written by :func:`~cellengine.report.page.embed_json`, so it
holds no '<') is read back, given the new report and written again in place.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from cellengine.outfiles import write_files
from cellengine.report.jsonable import jsonable
from cellengine.report.page import embed_json
from cellengine.report.write import REPORT_HTML, REPORT_JSON

DATA_OPEN = "<script type='application/json' id='ce-data'>"
DATA_CLOSE = "</script>"


def write_run(out: Path, run: Mapping[str, Any]) -> None:
    """report.json's and report.html's ``run`` in ``out`` set to ``run`` (replaced if there),
    atomically. Nothing is written when the folder has no report (nothing was compiled)."""
    json_path, html_path = out / REPORT_JSON, out / REPORT_HTML
    if not json_path.is_file() or not html_path.is_file():
        return
    value = jsonable(dict(run))
    report = json.loads(json_path.read_text(encoding="utf-8"))
    report["run"] = value
    page = html_path.read_text(encoding="utf-8")
    write_files(
        out,
        {
            REPORT_JSON: json.dumps(report, indent=1, allow_nan=False) + "\n",
            REPORT_HTML: with_run(page, value),
        },
    )


def with_run(page: str, run: Any) -> str:
    """report.html's text with its embedded report's ``run`` set to ``run``."""
    start = page.index(DATA_OPEN) + len(DATA_OPEN)
    end = page.index(DATA_CLOSE, start)
    data = json.loads(page[start:end])
    data["report"]["run"] = run
    return page[:start] + embed_json(data) + page[end:]
