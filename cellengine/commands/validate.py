"""`cellengine validate PATH...`: check cell, objects and plan files (or every one in folders)."""

from __future__ import annotations

import argparse
import errno
import json
import os
import stat
import sys
from pathlib import Path
from typing import Any

from cellengine.cache import Cache
from cellengine.checker import Checker, Result, check_file
from cellengine.commands.plan import add_cache_options, cache_of
from cellengine.dispatch import dispatch
from cellengine.errors import (
    EXIT_INVALID,
    EXIT_OK,
    Problem,
    UsageError,
    display_path,
    printable,
)
from cellengine.info.files import real
from cellengine.workers import Crashed, Raised, default_jobs


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
    add_cache_options(p)
    p.add_argument(
        "--cluster",
        metavar="ADDRESS",
        help="compile plans on a Ray cluster: ray://HOST:PORT, HOST:PORT or auto "
        "(pip install 'cellengine[cluster]')",
    )
    p.add_argument(
        "--timeout",
        type=seconds,
        metavar="SECONDS",
        help="a file not checked within SECONDS is reported so and its worker stopped",
    )
    p.set_defaults(run=run)


def seconds(text: str) -> float:
    """``--timeout``'s value: a number of seconds above 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: '{text}'") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"must be more than 0 seconds, got {text}")
    return value


def run(args: argparse.Namespace) -> int:
    if args.jobs is not None and args.jobs < 1:
        raise UsageError(Problem(f"--jobs must be at least 1, got {args.jobs}"))
    cache = cache_of(args)
    results = validate_paths(
        args.paths,
        compile_plans=not args.no_compile,
        jobs=args.jobs,
        cache=cache,
        cluster=args.cluster,
        timeout=args.timeout,
    )
    {"text": _text, "json": _json, "github": _github}[args.format](results)
    return EXIT_OK if all(not r.problems for r in results) else EXIT_INVALID


def validate_paths(
    paths: list[Path],
    compile_plans: bool = False,
    jobs: int | None = 1,
    cache: Cache | None = None,
    cluster: str | None = None,
    timeout: float | None = None,
) -> list[Result]:
    """Every cell, objects and plan file in ``paths``, in that order; with
    ``compile_plans``, every plan is also compiled to motion (skills, planning, limits,
    collisions), as `run` would: in ``jobs`` worker processes (None: one per core), or on
    the Ray ``cluster`` at that address; a plan's outcome taken from ``cache`` while none
    of its files changed."""
    files = _files(paths)
    found: list[Result | None] = [None] * len(files)
    todo = list(range(len(files)))
    if compile_plans and cache is not None:
        for i, (f, _) in enumerate(files):
            if (hit := cache.lookup(_request(f))) is not None:
                found[i] = Result.of_outcome(f, "plan", hit.result)
        todo = [i for i in todo if found[i] is None]
    tasks = [(files[i][0], files[i]) for i in todo]
    jobs = default_jobs() if jobs is None else jobs
    if compile_plans:
        outcomes = dispatch(tasks, Checker(True).check, check_file, jobs, cluster, timeout)
    else:  # checking files alone is quick
        checker = Checker(False)
        outcomes = ((k, checker.check(arg)) for k, (_, arg) in enumerate(tasks))
    for k, outcome in outcomes:
        i = todo[k]
        found[i] = result = _result(files[i][0], outcome)
        if cache is not None and result is not None and result.reads is not None:
            cache.store(_request(result.file), result.reads, result.outcome())
    return [r for r in found if r is not None]


def _request(plan: Path) -> dict[str, str]:
    """What, besides the files, decides a plan's outcome: the path as given (messages
    name it) and the working folder they are relative to."""
    return {"command": "validate", "plan": str(plan), "real": str(real(plan)), "cwd": os.getcwd()}


def _result(f: Path, outcome: Result | Crashed | Raised | None) -> Result | None:
    """A worker's answer for ``f``: a worker that died is that file's problem (the other
    files are still checked); a file's check that raised is a defect, raised as it would
    be without workers."""
    if isinstance(outcome, Crashed):
        return Result(f, None, [Problem(f"not checked: {outcome}", str(f))])
    if isinstance(outcome, Raised):
        raise outcome.error or RuntimeError(outcome.text)
    return outcome


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
