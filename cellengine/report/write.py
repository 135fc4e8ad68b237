"""Writing the run directory's report.json and report.html."""

from __future__ import annotations

import json
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from cellengine.motion.robot import CellModel
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
    needed); return both paths. ``extra``: top-level keys of report.json (plan, execution,
    merge comparison, ...), also listed on the page."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    report = report_data(program, cell, step_labels=step_labels, extra=extra)
    replay = replay_data(program, cell, world, step_labels=step_labels)
    json_path, html_path = out_dir / REPORT_JSON, out_dir / REPORT_HTML
    json_path.write_text(json.dumps(report, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    page = render_page(report, replay, title or _title(world, extra))
    html_path.write_text(page, encoding="utf-8")
    return json_path, html_path


def _title(world: World, extra: Mapping[str, Any] | None) -> str:
    plan = (extra or {}).get("plan")
    name = f"cellengine run: {world.cell.name}"
    return f"{name}, {Path(str(plan)).name}" if plan else name
