"""`cellengine validate PATH...`: check cell, objects and plan files (or every one in folders)."""

from __future__ import annotations

import argparse
import errno
import json
import os
import stat
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from cellengine.cache import CACHE_ENV, Cache, default_folder
from cellengine.errors import (
    EXIT_INVALID,
    EXIT_OK,
    InputError,
    Problem,
    UsageError,
    display_path,
    printable,
)
from cellengine.info.files import Reads, noted, real, recording
from cellengine.info.load import LoadedPlan, load_objects, load_plan, load_world
from cellengine.info.yamlio import load_yaml
from cellengine.workers import Crashed, Raised, default_jobs, run_tasks
from cellengine.world import World

if TYPE_CHECKING:
    from cellengine.context import PlanningContext

KINDS = ("cell", "objects", "plan")
_KEYS = {"plan": ("steps",), "cell": ("robots",), "objects": ("cables", "containers")}


def add_parser(sub: Any, name: str) -> None:
    p = sub.add_parser(
        name,
        help="check cell, objects and plan files",
        description="Check cell, objects and plan files, or every one in folders.",
    )
    p.add_argument("paths", nargs="+", metavar="PATH", type=Path)
    p.add_argument("--format", choices=("text", "json", "github"), default="text")
    p.add_argument(
        "--no-compile",
        action="store_true",
        help="check files and references only; do not compile plans to motion",
    )
    p.add_argument(
        "--jobs",
        "-j",
        type=int,
        metavar="N",
        help="compile plans in N worker processes (default: one per core)",
    )
    p.add_argument(
        "--no-cache",
        action="store_true",
        help="compile every plan, neither using nor keeping the compile cache",
    )
    p.add_argument(
        "--cache-dir",
        type=Path,
        metavar="DIR",
        help=f"the compile cache's folder (default: ${CACHE_ENV}, else ~/.cache/cellengine)",
    )
    p.set_defaults(run=run)


@dataclass
class Result:
    file: Path
    kind: str | None
    problems: list[Problem] = field(default_factory=list)
    warnings: list[Problem] = field(default_factory=list)  # the file is still ok


def run(args: argparse.Namespace) -> int:
    if args.jobs is not None and args.jobs < 1:
        raise UsageError(Problem(f"--jobs must be at least 1, got {args.jobs}"))
    cache = None if args.no_cache else Cache(args.cache_dir or default_folder())
    results = validate_paths(
        args.paths, compile_plans=not args.no_compile, jobs=args.jobs, cache=cache
    )
    {"text": _text, "json": _json, "github": _github}[args.format](results)
    return EXIT_OK if all(not r.problems for r in results) else EXIT_INVALID


def validate_paths(
    paths: list[Path],
    compile_plans: bool = False,
    jobs: int | None = 1,
    cache: Cache | None = None,
) -> list[Result]:
    """Every cell, objects and plan file in ``paths``, in that order; with
    ``compile_plans``, every plan is also compiled to motion (skills, planning, limits,
    collisions), as `run` would, in ``jobs`` worker processes (None: one per core), a
    plan's outcome taken from ``cache`` while none of its files changed."""
    files = _files(paths)
    checker = Checker(compile_plans, cache)
    jobs = default_jobs() if jobs is None else jobs
    if compile_plans and jobs > 1 and len(files) > 1:  # checking files alone is quick
        found = _in_workers(checker, files, jobs)
    else:
        found = [checker.check(task) for task in files]
    return [r for r in found if r is not None]


def _files(paths: list[Path]) -> list[tuple[Path, bool]]:
    """The files to check (and whether each was named), each once, in the given order."""
    files: list[tuple[Path, bool]] = []
    for p in paths:
        if p.is_dir():
            files += [(f, False) for f in sorted(p.rglob("*.y*ml")) if _visible(f, p)]
        elif p.exists() or _loops(p):
            files.append((p, True))  # not a regular file: reading it says what it is
        else:
            raise UsageError.at("no such file or folder", p)
    seen: set[Path] = set()
    unique = []
    for f, explicit in files:
        if real(f) not in seen:
            seen.add(real(f))
            unique.append((f, explicit))
    return unique


def _in_workers(checker: Checker, files: list[tuple[Path, bool]], jobs: int) -> list[Result | None]:
    """The files checked in worker processes, each outcome at its file's place; a worker
    that dies is that file's problem, and the other files are still checked."""
    import cellengine.pipeline  # noqa: F401  imported once, before the workers fork

    found: list[Result | None] = [None] * len(files)
    for i, outcome in run_tasks(checker.check, files, jobs):
        if isinstance(outcome, Crashed):
            f = files[i][0]
            found[i] = Result(f, None, [Problem(f"not checked: {outcome}", str(f))])
        elif isinstance(outcome, Raised):  # a defect, not the files': as without workers
            raise outcome.error or RuntimeError(outcome.text)
        else:
            found[i] = outcome
    return found


class Checker:
    """Checks files one at a time, in one process: each cell loaded once, whether it loads
    or not (plans sharing a broken cell do not load it again each), and its planning
    context built once for the plans that use it."""

    def __init__(self, compile_plans: bool, cache: Cache | None) -> None:
        self.compile_plans, self.cache = compile_plans, cache
        self._worlds: dict[Path, tuple[World | InputError, Reads]] = {}
        self._contexts: dict[tuple[Path, str], tuple[PlanningContext, Reads]] = {}

    def check(self, task: tuple[Path, bool]) -> Result | None:
        f, explicit = task
        return _validate_file(f, explicit, self)

    def world_of(self, cell: Path) -> World:
        key = real(cell)
        if key not in self._worlds:
            with recording() as reads:
                try:
                    from cellengine.motion.robot import build_cell_model  # pinocchio: lazily

                    world = load_world(cell)
                    build_cell_model(world)  # URDFs, meshes, tips: the robots must build
                    built: World | InputError = world
                except InputError as e:
                    built = e
            self._worlds[key] = (built, reads)
        loaded, reads = self._worlds[key]
        noted(reads)
        if isinstance(loaded, InputError):
            raise InputError(loaded.problems)
        return loaded

    def compile(self, loaded: LoadedPlan) -> None:
        # imported here: the motion stack is only needed when plans are compiled
        from cellengine.context import build_context
        from cellengine.pipeline import compile_loaded

        world = loaded.world  # the scene has the containers of the plan's objects
        key = (real(world.cell_file), world.objects.model_dump_json())
        if key not in self._contexts:
            with recording() as reads:
                built = build_context(world)
            self._contexts[key] = (built, reads)
        context, reads = self._contexts[key]
        noted(reads)
        compile_loaded(loaded, context=context)


def _visible(f: Path, top: Path) -> bool:
    return (
        f.suffix in (".yaml", ".yml")
        and not any(part.startswith(".") for part in f.relative_to(top).parts)
        and _regular_or_unreadable(f)
    )


def _regular_or_unreadable(f: Path) -> bool:
    """Whether a folder's file is for validation: a regular file, or one that cannot be
    read (a broken link, a loop of links: reported). A FIFO, a device or a folder named
    x.yaml holds no cell: never opened (a FIFO would wait for a writer forever)."""
    try:
        return stat.S_ISREG(os.stat(f).st_mode)
    except OSError:
        return True


def _loops(p: Path) -> bool:
    """Whether ``p`` is a loop of symbolic links (which exists(), like ls, calls missing)."""
    try:
        os.stat(p)
    except OSError as e:
        return e.errno == errno.ELOOP
    return False


def _validate_file(f: Path, explicit: bool, checker: Checker) -> Result | None:
    try:
        kind = classify(f)
    except InputError as e:
        return Result(f, None, list(e.problems))
    if kind is None:
        if not explicit:
            return None  # not one of ours: other YAML may live in a folder
        msg = (
            "cannot tell what this file is: a cell has 'robots', objects have 'cables' or "
            "'containers', a plan has 'steps'"
        )
        return Result(f, None, [Problem(msg, str(f), 1, 1)])
    if kind == "plan" and checker.compile_plans:
        return _compiled_plan(f, checker)
    result = Result(f, kind)
    try:
        if kind == "cell":
            result.warnings = list(checker.world_of(f).warnings)
        elif kind == "objects":
            load_objects(f)
        else:
            result.warnings = list(load_plan(f, checker.world_of).world.warnings)
    except InputError as e:
        result.problems = _unique(e.problems)
    return result


def _compiled_plan(f: Path, checker: Checker) -> Result:
    """A plan file loaded and compiled, or its outcome from the cache. Only outcomes of
    plans that loaded are kept: a missing file's absence is no file to watch."""
    from cellengine.pipeline import CompileFailed

    request = {"command": "validate", "plan": str(f), "real": str(real(f)), "cwd": os.getcwd()}
    cache = checker.cache
    if cache is not None and (hit := cache.lookup(request)) is not None:
        return Result(
            f, "plan", _problems(hit.result["problems"]), _problems(hit.result["warnings"])
        )
    result = Result(f, "plan")
    keep = False
    with recording() as reads:
        try:
            loaded = load_plan(f, checker.world_of)
            result.warnings = list(loaded.world.warnings)
            checker.compile(loaded)
            keep = True
        except CompileFailed as e:
            result.problems, keep = _unique(e.problems), True
        except InputError as e:
            result.problems = _unique(e.problems)
    if cache is not None and keep:
        outcome = {"problems": _rows(result.problems), "warnings": _rows(result.warnings)}
        cache.store(request, reads, outcome)
    return result


def _rows(problems: list[Problem]) -> list[list[Any]]:
    return [[p.message, p.file, p.line, p.col] for p in problems]


def _problems(rows: list[list[Any]]) -> list[Problem]:
    return [Problem(str(m), f, line, col) for m, f, line, col in rows]


def classify(f: Path) -> str | None:
    """What a YAML file is, from its top-level keys, else from its name."""
    data = load_yaml(f).data
    if isinstance(data, dict):
        for kind, keys in _KEYS.items():
            if any(k in data for k in keys):
                return kind
    stem = f.stem.lower()
    return next((k for k in KINDS if stem.startswith(k.rstrip("s"))), None)


def _unique(problems: tuple[Problem, ...] | list[Problem]) -> list[Problem]:
    return list(dict.fromkeys(problems))


def _text(results: list[Result]) -> None:
    bad = 0
    shown: set[tuple[object, ...]] = set()  # a plan repeats its cell's problems: print once
    for r in results:
        for w in r.warnings:  # a plan repeats its cell's: printed once
            if (key := ("warning", *_key(w))) not in shown:
                shown.add(key)
                print(w.warning())
        if r.problems:
            bad += 1
            new = [p for p in r.problems if _key(p) not in shown]
            shown.update(_key(p) for p in new)
            for p in new:
                print(p)
            if not new:
                where = printable(display_path(r.file))
                print(f"{where}: not checked: it uses files with problems above")
        else:
            print(f"{printable(display_path(r.file))}: ok ({r.kind})")
    print(f"{len(results)} file(s) checked, {bad} with problems", file=sys.stderr)


def _key(p: Problem) -> tuple[object, ...]:
    return (real(Path(p.file)) if p.file else None, p.line, p.col, p.message)


def _json(results: list[Result]) -> None:
    out = {
        "ok": all(not r.problems for r in results),
        "files": [
            {
                "file": display_path(r.file),
                "kind": r.kind,
                "ok": not r.problems,
                "problems": [_problem_json(p) for p in r.problems],
                "warnings": [_problem_json(p) for p in r.warnings],
            }
            for r in results
        ],
    }
    print(json.dumps(out, indent=2))


def _problem_json(p: Problem) -> dict[str, Any]:
    return {
        "file": display_path(p.file) if p.file else None,
        "line": p.line,
        "col": p.col,
        "message": p.message,
    }


def _escape(text: str, prop: bool = False) -> str:
    text = text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
    return text.replace(":", "%3A").replace(",", "%2C") if prop else text


def _github(results: list[Result]) -> None:
    shown: set[tuple[object, ...]] = set()
    for r in results:
        for level, problems in (("warning", r.warnings), ("error", r.problems)):
            for p in problems:
                if (level, *_key(p)) in shown:
                    continue
                shown.add((level, *_key(p)))
                props = [f"file={_escape(printable(display_path(p.file or r.file)), True)}"]
                if p.line is not None:
                    props.append(f"line={p.line}")
                    if p.col is not None:
                        props.append(f"col={p.col}")
                print(f"::{level} {','.join(props)}::{_escape(printable(p.message))}")
