"""A study over variants of one plan's files: each variant is a set of values set over the
files (:mod:`cellengine.info.settings`), compiled as `plan` would, and summed up in one row:
feasible or why not, cycle time, the least clearance between the arms and to the cell."""

from __future__ import annotations

import csv
import io
import itertools
import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cellengine.cache import Cache
from cellengine.dispatch import dispatch
from cellengine.errors import InputError
from cellengine.info.files import real, recording
from cellengine.info.load import load_plan
from cellengine.info.platform import Platform
from cellengine.info.settings import Setting, parse_key, settings
from cellengine.info.yamlio import load_yaml, parse_yaml
from cellengine.workers import Crashed, Raised

# the columns every row has after the variant's own values
MEASURES = ("feasible", "cycle_time_s", "arm_clearance_m", "environment_clearance_m", "problem")


@dataclass(frozen=True)
class Variant:
    """A variant's name, its values by key as written, and the settings they make."""

    name: str
    values: tuple[tuple[str, Any], ...]
    settings: tuple[Setting, ...]


def from_vary(specs: Sequence[str], platforms: Mapping[str, Platform]) -> list[Variant]:
    """``KEY=[v1, v2, ...]`` for each key, every combination (the last key varying
    fastest), named v1, v2, ..."""
    axes: list[tuple[str, str, tuple[str | int, ...], list[Any]]] = []
    for spec in specs:
        key, sep, text = spec.partition("=")
        where = Path(f"--vary {key}")
        if not sep or not key:
            raise InputError.at("write KEY=[value, value, ...]", where)
        kind, loc = _key(key, platforms, where)
        values = parse_yaml(text, where).data
        if not isinstance(values, list) or not values:
            msg = f"the values are a YAML list of at least one, not '{text}'"
            raise InputError.at(msg, where)
        axes.append((key, kind, loc, values))
    out = []
    for n, combo in enumerate(itertools.product(*(a[3] for a in axes)), start=1):
        values = tuple((a[0], v) for a, v in zip(axes, combo, strict=True))
        sets = tuple((a[1], a[2], v) for a, v in zip(axes, combo, strict=True))
        out.append(Variant(f"v{n}", values, sets))
    return out


def from_file(path: Path, platforms: Mapping[str, Platform]) -> list[Variant]:
    """A YAML list of maps, each a variant: its keys and values (``name``: its name)."""
    doc = load_yaml(path)
    if not isinstance(doc.data, list) or not doc.data:
        raise doc.error("a variants file is a list of maps of KEY: value (and a name)", ())
    out = []
    for i, item in enumerate(doc.data):
        if not isinstance(item, dict) or not item:
            raise doc.error("each variant is a map of KEY: value (and a name)", (i,))
        name = str(item.get("name", f"v{i + 1}"))
        values, sets = [], []
        for key, value in item.items():
            if key == "name":
                continue
            line, col = doc.where((i, key), key=True) or (None, None)
            kind, loc = _key(str(key), platforms, path, line, col)
            values.append((str(key), value))
            sets.append((kind, loc, value))
        out.append(Variant(name, tuple(values), tuple(sets)))
    return out


def _key(
    key: str,
    platforms: Mapping[str, Platform],
    file: Path,
    line: int | None = None,
    col: int | None = None,
) -> tuple[str, tuple[str | int, ...]]:
    try:
        return parse_key(key, platforms)
    except ValueError as e:
        raise InputError.at(str(e), file, line, col) from None


def evaluate(task: tuple[Path, tuple[Setting, ...]]) -> dict[str, Any]:
    """One variant compiled: its row's measures, and ``reads``: the files it came from
    (None when the outcome is not to be kept). A variant its files' own checks refuse (a
    guide turned across the route) is a row too: not a feasible layout."""
    from cellengine.pipeline import CompileFailed, compile_loaded
    from cellengine.report.data import report_data

    plan, sets = task
    row: dict[str, Any] = dict.fromkeys(MEASURES[1:])
    with recording() as reads, settings(sets):
        try:
            compiled = compile_loaded(load_plan(plan))
        except CompileFailed as e:
            return {**row, "feasible": False, "problem": str(e.problems[0]), "reads": reads}
        except InputError as e:
            return {**row, "feasible": False, "problem": str(e.problems[0]), "reads": None}
    totals = report_data(compiled.program, compiled.context.cell)["totals"]
    clearance = totals.get("clearance") or {}
    return {
        "feasible": True,
        "cycle_time_s": totals["cycle_time_s"],
        "arm_clearance_m": (clearance.get("arms") or {}).get("distance_m"),
        "environment_clearance_m": (clearance.get("environment") or {}).get("distance_m"),
        "problem": "",
        "reads": reads,
    }


def run_sweep(
    plan: Path,
    variants: Sequence[Variant],
    jobs: int,
    cluster: str | None = None,
    cache: Cache | None = None,
    timeout: float | None = None,
) -> list[dict[str, Any]]:
    """Each variant's row, in the variants' order."""
    rows: dict[int, dict[str, Any]] = {}
    requests = [_request(plan, v) for v in variants]
    if cache is not None:
        for i, request in enumerate(requests):
            if (hit := cache.lookup(request)) is not None:
                rows[i] = hit.result
    todo = [i for i in range(len(variants)) if i not in rows]
    tasks = [(plan, (plan, variants[i].settings)) for i in todo]
    for k, answer in dispatch(tasks, evaluate, evaluate, jobs, cluster, timeout):
        i = todo[k]
        if isinstance(answer, Crashed):
            why = f"not compiled: {answer}"
            answer = {**dict.fromkeys(MEASURES), "feasible": False, "problem": why}
        elif isinstance(answer, Raised):
            raise answer.error or RuntimeError(answer.text)
        reads = answer.pop("reads", None)
        if cache is not None and reads is not None:
            cache.store(requests[i], reads, answer)
        rows[i] = answer
    return [{"variant": v.name, **dict(v.values), **rows[i]} for i, v in enumerate(variants)]


def _request(plan: Path, v: Variant) -> dict[str, Any]:
    return {
        "command": "sweep",
        "plan": [str(plan), str(real(plan))],
        "cwd": os.getcwd(),
        "settings": [[kind, list(loc), value] for kind, loc, value in v.settings],
    }


def table_text(rows: Sequence[Mapping[str, Any]], fmt: str) -> str:
    """The rows as CSV (lists as JSON in their cells) or as a JSON list."""
    if fmt == "json":
        return json.dumps(list(rows), indent=1, allow_nan=False) + "\n"
    columns = list(dict.fromkeys(k for r in rows for k in r))
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(columns)
    for r in rows:
        writer.writerow([_cell(r.get(c)) for c in columns])
    return out.getvalue()


def _cell(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return value
    return repr(value) if isinstance(value, float) else json.dumps(value)
