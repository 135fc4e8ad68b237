"""Checking one file of a cell: what it is, whether it loads and, for a plan, whether it
compiles; with the files that outcome was computed from, for the compile cache."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from cellengine.errors import InputError, Problem
from cellengine.info.files import Reads, noted, real, recording
from cellengine.info.load import LoadedPlan, load_objects, load_plan, load_world
from cellengine.info.yamlio import load_yaml
from cellengine.world import World

if TYPE_CHECKING:
    from cellengine.context import PlanningContext

KINDS = ("cell", "objects", "plan")
K = TypeVar("K")
V = TypeVar("V")
_KEYS = {"plan": ("steps",), "cell": ("robots",), "objects": ("cables", "harnesses", "containers")}


@dataclass
class Result:
    """A file's outcome. ``reads``: for a compiled plan's, the files it was computed from
    (the compile cache keeps it); None when it is not to be kept."""

    file: Path
    kind: str | None
    problems: list[Problem] = field(default_factory=list)
    warnings: list[Problem] = field(default_factory=list)  # the file is still ok
    reads: Reads | None = None

    def outcome(self) -> dict[str, Any]:
        """The outcome as JSON data (what the cache keeps)."""
        return {"problems": _rows(self.problems), "warnings": _rows(self.warnings)}

    @classmethod
    def of_outcome(cls, file: Path, kind: str, outcome: dict[str, Any]) -> Result:
        return cls(file, kind, _problems(outcome["problems"]), _problems(outcome["warnings"]))


# cells whose world and planning context a checker keeps: a folder's plans of one cell are
# checked one after another, and a few hundred boards would otherwise all stay in memory
KEPT_CELLS = 4


class Checker:
    """Checks files one at a time, in one process: each cell loaded once, whether it loads
    or not (plans sharing a broken cell do not load it again each), and its planning
    context built once for the plans that use it (the last KEPT_CELLS cells' are kept)."""

    def __init__(self, compile_plans: bool) -> None:
        self.compile_plans = compile_plans
        self._worlds: dict[Path, tuple[World | InputError, Reads]] = {}
        self._contexts: dict[tuple[Path, str], tuple[PlanningContext, Reads]] = {}

    def check(self, task: tuple[Path, bool]) -> Result | None:
        """``task``: a file and whether it was named (else found in a folder: a YAML file
        that is none of ours is then passed over, None)."""
        f, explicit = task
        return _check_file(f, explicit, self)

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
            _keep(self._worlds, key, (built, reads))
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
            _keep(self._contexts, key, (built, reads))
        context, reads = self._contexts[key]
        noted(reads)
        compile_loaded(loaded, context=context)


def _keep(kept: dict[K, V], key: K, value: V) -> None:
    """``kept[key] = value``, the oldest entry dropped past KEPT_CELLS."""
    kept[key] = value
    while len(kept) > KEPT_CELLS:
        del kept[next(iter(kept))]


def check_file(task: tuple[Path, bool]) -> Result | None:
    """One file checked by a fresh checker: a task sent to another machine."""
    return Checker(compile_plans=True).check(task)


def _check_file(f: Path, explicit: bool, checker: Checker) -> Result | None:
    try:
        kind = classify(f)
    except InputError as e:
        return Result(f, None, list(e.problems))
    if kind is None:
        if not explicit:
            return None  # not one of ours: other YAML may live in a folder
        msg = (
            "cannot tell what this file is: a cell has 'robots', objects have 'cables', "
            "'harnesses' or 'containers', a plan has 'steps'"
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
        result.problems = unique(e.problems)
    return result


def _compiled_plan(f: Path, checker: Checker) -> Result:
    """A plan file loaded and compiled. Only outcomes of plans that loaded are to be kept:
    a file missing is no file to watch for a change."""
    from cellengine.pipeline import CompileFailed

    result = Result(f, "plan")
    with recording() as reads:
        try:
            loaded = load_plan(f, checker.world_of)
            result.warnings = list(loaded.world.warnings)
            checker.compile(loaded)
            result.reads = reads
        except CompileFailed as e:
            result.problems, result.reads = unique(e.problems), reads
        except InputError as e:
            result.problems = unique(e.problems)
    return result


def classify(f: Path) -> str | None:
    """What a YAML file is, from its top-level keys, else from its name."""
    data = load_yaml(f).data
    if isinstance(data, dict):
        for kind, keys in _KEYS.items():
            if any(k in data for k in keys):
                return kind
    stem = f.stem.lower()
    return next((k for k in KINDS if stem.startswith(k.rstrip("s"))), None)


def unique(problems: tuple[Problem, ...] | list[Problem]) -> list[Problem]:
    return list(dict.fromkeys(problems))


def _rows(problems: list[Problem]) -> list[list[Any]]:
    return [[p.message, p.file, p.line, p.col] for p in problems]


def _problems(rows: list[list[Any]]) -> list[Problem]:
    return [Problem(str(m), f, line, col) for m, f, line, col in rows]
