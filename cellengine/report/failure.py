"""The report of a plan that failed to compile: report.json and report.html of what was
compiled before the failure, with a ``failure`` section.

report.json's ``failure``: ``compiled_segments`` (how many segments were compiled before the
first failure: the report's ``segments``) and ``failures``, each ``{messages, step,
step_label, segment, segment_index, kind, pair, q, time_s, targets}``: the messages as
printed; the plan step (0-based, as the report's steps); the segment's label and the index it
would have had in ``segments`` (None when a skill refused the step before any segment of
it); ``kind`` (:data:`~cellengine.execute.failure.Kind`, or ``refused``: the skill refused the
step); the two objects that collide or come too close (scene names); the whole cell's
configuration shown (``joint_names`` order, rad or m); the time on the program's axis; and
{arm: [x, y, z]} (m) the TCP positions an arm could not reach. ``totals.checks_passed`` is
false.

The replay's ``failure``: ``poses``, one per failure with a configuration, each with the
arms' link shapes at it (as the replay's ``links``, one sample each, those of the pair
``highlight``), the TCPs, the pair, the static meshes it names (``statics``) and the
targets; the page shows the first at the start.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from cellengine.execute.failure import Failure
from cellengine.motion.robot import CellModel
from cellengine.program import Program
from cellengine.report.data import report_data
from cellengine.report.jsonable import jsonable
from cellengine.report.page import render_page
from cellengine.report.replay import (
    DECIMALS,
    jaw_openings,
    link_shapes,
    placements,
    replay_data,
    static_meshes,
)
from cellengine.report.write import REPORT_HTML, REPORT_JSON
from cellengine.world import World


class Found(NamedTuple):
    """One failure: its messages as printed, and where (None: known only in words)."""

    messages: tuple[str, ...]
    failure: Failure | None


def failure_texts(
    program: Program,
    world: World,
    cell: CellModel,
    found: Sequence[Found],
    extra: Mapping[str, Any] | None = None,
    *,
    step_labels: Mapping[int, str] | None = None,
    title: str = "",
) -> dict[str, str]:
    """report.json's and report.html's text of a failed plan, by file name: ``program`` is
    what was compiled before the first of ``found``."""
    labels = step_labels or {}
    section = {
        "compiled_segments": len(program.segments),
        "failures": [failure_entry(f, labels) for f in found],
    }
    report = report_data(
        program, cell, step_labels=labels, extra={**(extra or {}), "failure": section}
    )
    report["totals"]["checks_passed"] = False
    replay = replay_data(program, cell, world, step_labels=labels)
    replay["failure"] = {"poses": failure_poses(found, program, cell, world)}
    return {
        REPORT_JSON: json.dumps(report, indent=1, allow_nan=False) + "\n",
        REPORT_HTML: render_page(report, replay, title),
    }


def failure_entry(found: Found, step_labels: Mapping[int, str]) -> dict[str, Any]:
    """report.json's entry of one failure (see the module's notes)."""
    f = found.failure
    at = f.at if f is not None else None
    step = f.step if f is not None else None
    segment = f.segment if f is not None else None
    index = None
    if segment is not None and f is not None and f.before is not None:
        index = len(f.before.segments)
    kind = at.kind if at is not None else ("refused" if f is not None and segment is None else None)
    return {
        "messages": list(found.messages),
        "step": step,
        "step_label": step_labels.get(step) if step is not None else None,
        "segment": segment.label if segment is not None else None,
        "segment_index": index,
        "kind": kind,
        "pair": list(at.pair) if at is not None and at.pair is not None else None,
        "q": jsonable(at.q) if at is not None and at.q is not None else None,
        "time_s": at.time if at is not None else None,
        "targets": {a: jsonable(p) for a, p in at.targets.items()} if at is not None else {},
    }


def failure_poses(
    found: Sequence[Found], program: Program, cell: CellModel, world: World
) -> list[dict[str, Any]]:
    """The replay's failing poses (see the module's notes), the grippers as the program
    leaves them."""
    statics = {s["name"] for s in static_meshes(world)}
    jaw = jaw_openings(program, cell, np.array([program.duration]))
    out = []
    for k, item in enumerate(found):
        at = item.failure.at if item.failure is not None else None
        if at is None or at.q is None:
            continue
        pair = list(at.pair or ())
        M, tcp = placements(cell, np.asarray(at.q, dtype=float)[None], jaw)
        links = link_shapes(cell, M)
        for link in links:
            link["fixed"] = True  # one sample: the page draws it at every time
            link["highlight"] = link["name"] in pair
        out.append(
            {
                "failure": k,
                "kind": at.kind,
                "pair": pair or None,
                "links": links,
                "tcp": {arm: _round(p[0]) for arm, p in tcp.items()},
                # an element of several boxes is named name, name#2, ...: drawn as one mesh
                "statics": sorted({n.split("#", 1)[0] for n in pair} & statics),
                "targets": {arm: _round(p) for arm, p in at.targets.items()},
            }
        )
    return out


def _round(p: Any) -> list[float]:
    return np.round(np.asarray(p, dtype=float), DECIMALS).tolist()  # type: ignore[no-any-return]
