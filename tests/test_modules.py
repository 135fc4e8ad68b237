"""The engine's modules: no import cycle between them, and no module-level mutable cache
(state that would outlive one compile and leak into the next)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import numpy as np

from cellengine.context import build_context
from cellengine.info.load import load_plan
from cellengine.pipeline import compile_loaded
from tests.conftest import CELLS, ROOT

PACKAGE = ROOT / "cellengine"
# calls that change a container in place
MUTATORS = {"append", "add", "clear", "extend", "insert", "pop", "popitem", "remove",
            "setdefault", "update", "discard"}  # fmt: skip
# memoised on purpose: read-only data of the installed package, the same for every compile
ALLOWED_CACHES = {
    "cellengine.family": "families",  # the entry points installed
    "cellengine.info.models_xml": "_schema",  # the XSD shipped with the package
    "cellengine.cache": "engine_fingerprint",  # the installed engine's files and libraries
}


def modules() -> dict[str, Path]:
    """Every module of cellengine (skills/ through the cellengine/skills link)."""
    out = {}
    for top in (PACKAGE, ROOT / "skills"):
        base = "cellengine" if top == PACKAGE else "cellengine.skills"
        for f in sorted(top.rglob("*.py")):
            parts = f.relative_to(top).with_suffix("").parts
            name = ".".join((base, *parts)).removesuffix(".__init__")
            out[name] = f
    return out


def imports(tree: ast.Module) -> set[str]:
    """cellengine modules a module imports, at load or in a function (an import in a
    function is a dependency all the same), but not under ``if TYPE_CHECKING`` (types only).
    The engine uses absolute imports only."""
    typing_only = {
        id(n)
        for node in ast.walk(tree)
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test)
        for n in ast.walk(node)
    }
    found: set[str] = set()
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            assert node.level == 0, "relative import"
            # `from package import module` depends on that module (the package is loaded
            # before any of its modules anyway)
            base = node.module or ""
            subs = {f"{base}.{a.name}" for a in node.names} & MODULES.keys()
            found |= subs or {base}
    return {m for m in found if m in MODULES}


MODULES = modules()


def test_every_module_imports() -> None:
    for name in MODULES:
        if not name.endswith("__main__"):  # runs the CLI
            importlib.import_module(name)


def test_no_import_cycle_between_cellengine_modules() -> None:
    graph = {name: imports(ast.parse(f.read_text())) - {name} for name, f in MODULES.items()}
    state: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(n: str) -> None:
        state[n] = 1
        stack.append(n)
        for m in sorted(graph[n]):
            if state.get(m) == 1:
                cycles.append([*stack[stack.index(m) :], m])
            elif m not in state:
                visit(m)
        stack.pop()
        state[n] = 2

    for n in sorted(graph):
        if n not in state:
            visit(n)
    assert cycles == []


def test_the_engine_imports_no_skill_module() -> None:
    """Skills come in through their families: the compiler, the commands, the runner and
    the report know no skill."""
    engine = ("cellengine.pipeline", "cellengine.commands", "cellengine.runner",
              "cellengine.report", "cellengine.execute", "cellengine.motion")  # fmt: skip
    found = {
        name: sorted(
            m for m in imports(ast.parse(f.read_text())) if m.startswith("cellengine.skills")
        )
        for name, f in MODULES.items()
        if name.startswith(engine)
    }
    assert {k: v for k, v in found.items() if v} == {}


def mutable_globals(tree: ast.Module) -> set[str]:
    """Module-level names bound to a dict, list or set (a display, a comprehension or a
    call of a container type)."""
    names = set()
    containers = {"dict", "list", "set", "defaultdict", "OrderedDict", "WeakKeyDictionary",
                  "WeakValueDictionary", "WeakSet", "deque"}  # fmt: skip
    for node in tree.body:
        targets: list[ast.expr] = []
        value = None
        if isinstance(node, ast.Assign):
            targets, value = node.targets, node.value
        elif isinstance(node, ast.AnnAssign) and node.value is not None:
            targets, value = [node.target], node.value
        mutable = isinstance(
            value, ast.Dict | ast.List | ast.Set | ast.DictComp | ast.ListComp | ast.SetComp
        ) or (
            isinstance(value, ast.Call)
            and isinstance(value.func, ast.Name | ast.Attribute)
            and (value.func.id if isinstance(value.func, ast.Name) else value.func.attr)
            in containers
        )
        if mutable:
            names |= {t.id for t in targets if isinstance(t, ast.Name)}
    return names


def changed_in_functions(tree: ast.Module, names: set[str]) -> set[str]:
    """Those of ``names`` that a function changes: item assignment or deletion, a mutating
    call, or a ``global`` statement."""
    out = set()
    for fn in ast.walk(tree):
        if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        for node in ast.walk(fn):
            if isinstance(node, ast.Global):
                out |= set(node.names)
            elif isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store | ast.Del):
                if isinstance(node.value, ast.Name) and node.value.id in names:
                    out.add(node.value.id)
            elif (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr in MUTATORS
                and isinstance(node.func.value, ast.Name)
                and node.func.value.id in names
            ):
                out.add(node.func.value.id)
    return out


def memoised(tree: ast.Module) -> set[str]:
    """Module-level functions decorated with functools' cache or lru_cache."""
    out = set()
    for node in tree.body:
        if isinstance(node, ast.FunctionDef):
            for d in node.decorator_list:
                target = d.func if isinstance(d, ast.Call) else d
                name = (
                    target.attr if isinstance(target, ast.Attribute) else getattr(target, "id", "")
                )
                if name in ("cache", "lru_cache"):
                    out.add(node.name)
    return out


def test_no_module_level_mutable_cache() -> None:
    found = {}
    for name, f in MODULES.items():
        tree = ast.parse(f.read_text())
        changed = changed_in_functions(tree, mutable_globals(tree))
        cached = memoised(tree) - {ALLOWED_CACHES.get(name)}
        if changed or cached:
            found[name] = sorted(changed | cached)
    assert found == {}


def test_the_checks_see_a_cache() -> None:
    """The checks above find what they look for."""
    tree = ast.parse(
        "import functools\n_SEEN: dict[int, int] = {}\nKEEP = {1: 2}\n"
        "def f(x):\n    _SEEN[x] = 1\n    return KEEP[x]\n"
        "@functools.lru_cache(maxsize=1)\ndef g():\n    return 1\n"
    )
    assert changed_in_functions(tree, mutable_globals(tree)) == {"_SEEN"}
    assert memoised(tree) == {"g"}


def test_two_compiles_of_different_cells_share_no_state() -> None:
    """A cable plan, a lab plan, then the cable plan again in one process: the same program
    as the first time, and nothing built for one compile used by the other."""
    cable = load_plan(CELLS / "cable_routing" / "plan_straight.yaml")
    lab = load_plan(CELLS / "lab_bench" / "plan_weigh_handover.yaml")
    first = compile_loaded(cable)
    other = compile_loaded(lab)
    again = compile_loaded(load_plan(CELLS / "cable_routing" / "plan_straight.yaml"))
    a, b = first.context, again.context
    assert a.cell is not b.cell and a.scene is not b.scene and a.checker is not b.checker
    for arm in a.cell.arms:
        assert a.iks[arm] is not b.iks[arm]
        assert a.cell.arms[arm].model is not b.cell.arms[arm].model
    assert not set(map(id, other.context.iks.values())) & set(map(id, a.iks.values()))
    assert [s.segment.label for s in again.program.segments] == [
        s.segment.label for s in first.program.segments
    ]
    for s, t in zip(first.program.segments, again.program.segments, strict=True):
        np.testing.assert_allclose(s.trajectory.q, t.trajectory.q, rtol=0, atol=1e-9)
        np.testing.assert_allclose(s.trajectory.t, t.trajectory.t, rtol=0, atol=1e-6)


def test_a_context_is_built_once_per_compile() -> None:
    loaded = load_plan(CELLS / "cable_routing" / "plan_straight.yaml")
    ctx = build_context(loaded.world)
    compiled = compile_loaded(loaded, context=ctx)
    assert compiled.context is ctx and compiled.cell is ctx.cell
