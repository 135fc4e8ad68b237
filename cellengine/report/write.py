"""Writing the run directory's report.json and report.html."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from cellengine.motion.robot import CellModel
from cellengine.outfiles import write_files
from cellengine.program import Program
from cellengine.report.data import report_data
from cellengine.report.page import render_page
from cellengine.report.replay import replay_data
from cellengine.world import World

REPORT_JSON = "report.json"
REPORT_HTML = "report.html"


def write_report(
    out_dir: Path,
    program: Program,
    world: World,
    cell: CellModel,
    extra: Mapping[str, Any] | None = None,
    *,
    step_labels: Mapping[int, str] | None = None,
    title: str | None = None,
) -> tuple[Path, Path]:
    """Write ``out_dir``/report.json and ``out_dir``/report.html (the folder is made if
    needed), both or neither; return both paths. ``extra``: top-level keys of report.json
    (plan, execution, merge comparison, ...), also listed on the page."""
    texts = report_texts(program, world, cell, extra, step_labels=step_labels, title=title)
    paths = write_files(Path(out_dir), texts)
    return paths[REPORT_JSON], paths[REPORT_HTML]


def report_texts(
    program: Program,
    world: World,
    cell: CellModel,
    extra: Mapping[str, Any] | None = None,
    *,
    step_labels: Mapping[int, str] | None = None,
    title: str | None = None,
) -> dict[str, str]:
    """report.json's and report.html's text, by file name (see :func:`write_report`)."""
    report = report_data(program, cell, step_labels=step_labels, extra=extra)
    replay = replay_data(program, cell, world, step_labels=step_labels)
    return {
        REPORT_JSON: json.dumps(report, indent=1, allow_nan=False) + "\n",
        REPORT_HTML: render_page(report, replay, title or _title(world, extra)),
    }


def _title(world: World, extra: Mapping[str, Any] | None) -> str:
    plan = (extra or {}).get("plan")
    name = f"cellengine run: {world.cell.name}"
    return f"{name}, {Path(str(plan)).name}" if plan else name
