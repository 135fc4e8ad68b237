"""Safe, line-aware YAML loading.

PyYAML's composer gives nodes with marks; we build plain dicts/lists ourselves so that
every value and key keeps its line and column, standard tags only are accepted, duplicate
keys are errors, and an alias bomb is refused from its node graph before it is expanded.

Plain scalars resolve as YAML 1.2's core schema does (what the JSON Schemas and most other
tools assume), not as PyYAML's YAML 1.1: ``1e30`` is a number, ``1:20`` and ``yes`` are
strings, ``017`` is seventeen.
"""

from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from cellengine.errors import InputError
from cellengine.info.files import read_capped

Loc = tuple[str | int, ...]
Pos = tuple[int, int]

MAX_NODES = 100_000  # after alias expansion
MAX_ALIASES = 1_000
MAX_DEPTH = 100  # nested maps and lists; cells need fewer than 10


class _TooDeep(Exception):
    def __init__(self, mark: Any) -> None:
        self.mark = mark


class _BadScalar(ValueError):
    """A scalar tagged as a number or boolean that YAML 1.2 does not read as one."""


class _Loader(yaml.SafeLoader):
    """The safe loader with YAML 1.2 core scalars, refusing deep nesting before Python's
    recursion limit is near, so the error and its place do not depend on how deep the
    caller's stack is."""

    # our own table, so PyYAML's YAML 1.1 resolvers (shared by SafeLoader) are not inherited
    yaml_implicit_resolvers: dict[Any, list[tuple[str, re.Pattern[str]]]] = {}
    depth = 0

    def compose_node(self, parent: yaml.Node | None, index: int) -> yaml.Node | None:
        self.depth += 1
        try:
            if self.depth > MAX_DEPTH:
                raise _TooDeep(self.peek_event().start_mark)  # type: ignore[no-untyped-call]
            return super().compose_node(parent, index)
        finally:
            self.depth -= 1


_STD = "tag:yaml.org,2002:"

# YAML 1.2.2, 10.3.2 (core schema). Underscores, sexagesimals and signed hex/octal are 1.1.
_NULL = re.compile(r"^(?:~|null|Null|NULL|)$")
_BOOL = re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$")
_INT = re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$")
_FLOAT = re.compile(
    r"^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?"
    r"|[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$"
)
for _tag, _regexp, _first in (
    ("null", _NULL, ["~", "n", "N", ""]),
    ("bool", _BOOL, list("tTfF")),
    ("int", _INT, list("-+0123456789")),  # before float: '1' is an int
    ("float", _FLOAT, list("-+.0123456789")),
    ("merge", re.compile(r"^<<$"), ["<"]),  # not 1.2, but merge keys are documented
):
    _Loader.add_implicit_resolver(_STD + _tag, _regexp, _first)


def _scalar(loader: yaml.SafeLoader, node: yaml.Node, pattern: re.Pattern[str], kind: str) -> str:
    """The text of ``node``; it must be ``kind`` as YAML 1.2 writes it (an explicit tag such
    as ``!!int 1_000`` skips the resolver)."""
    text = str(loader.construct_scalar(node))  # type: ignore[arg-type]
    if not pattern.match(text):
        raise _BadScalar(f"'{_shown(text)}' is not {kind} in YAML 1.2")
    return text


def _int(loader: yaml.SafeLoader, node: yaml.Node) -> int:
    text = _scalar(loader, node, _INT, "an integer")
    base = {"0o": 8, "0x": 16}.get(text[:2])
    # '017' is 17: a leading 0 is not octal in YAML 1.2
    value = int(text) if base is None else int(text[2:], base)
    if abs(value) > sys.float_info.max:  # no quantity is; pydantic would say "not a number"
        raise _BadScalar(_too_large(text))
    return value


def _float(loader: yaml.SafeLoader, node: yaml.Node) -> float:
    text = _scalar(loader, node, _FLOAT, "a number")
    if text.lstrip("+-").lower() in (".inf", ".nan"):
        return float(text.replace(".", ""))  # Python spells them inf and nan
    value = float(text)
    if math.isinf(value):  # 1e999: Python rounds it to inf, which was not written
        raise _BadScalar(_too_large(text))
    return value


def _too_large(text: str) -> str:
    return f"the number {_shown(text)} is beyond the largest float (1.8e308)"


def _bool(loader: yaml.SafeLoader, node: yaml.Node) -> bool:
    return _scalar(loader, node, _BOOL, "true or false").lower() == "true"


_Loader.add_constructor(_STD + "int", _int)
_Loader.add_constructor(_STD + "float", _float)
_Loader.add_constructor(_STD + "bool", _bool)

_ALLOWED_TAGS = {_STD + t for t in ("str", "int", "float", "bool", "null", "map", "seq")}


@dataclass(frozen=True)
class YamlDoc:
    """A loaded YAML file: the data and where each value and key was written (1-based)."""

    file: Path
    data: Any
    values: dict[Loc, Pos] = field(default_factory=dict)
    keys: dict[Loc, Pos] = field(default_factory=dict)

    def where(self, loc: Loc, key: bool = False) -> Pos | None:
        """Position of ``loc``; its key's if ``key``; else the nearest enclosing value's."""
        loc = tuple(loc)
        if key and loc in self.keys:
            return self.keys[loc]
        while loc:
            if loc in self.values:
                return self.values[loc]
            loc = loc[:-1]
        return self.values.get((), (1, 1))

    def error(self, message: str, loc: Loc, key: bool = False) -> InputError:
        line, col = self.where(loc, key) or (None, None)
        return InputError.at(message, self.file, line, col)


def load_yaml(path: Path) -> YamlDoc:
    raw = read_capped(path, "yaml")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as e:
        line = raw.count(b"\n", 0, e.start) + 1
        raise InputError.at("file is not valid UTF-8", path, line) from None
    return parse_yaml(text, path)


def parse_yaml(text: str, path: Path) -> YamlDoc:
    try:
        loader = _Loader(text)  # checks every character first
    except yaml.reader.ReaderError as e:
        line, col = _line_col(text, e.position)
        msg = f"character U+{e.character:04X} is not allowed in YAML"
        raise InputError.at(msg, path, line, col) from None
    try:
        node = loader.get_single_node()
    except _TooDeep as e:
        msg = f"YAML nests maps and lists more than {MAX_DEPTH} levels deep"
        raise InputError.at(msg, path, e.mark.line + 1, e.mark.column + 1) from None
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        msg = f"YAML syntax error: {_syntax(e.context, e.problem)}"
        raise InputError.at(
            msg, path, mark.line + 1 if mark else None, mark.column + 1 if mark else None
        ) from None
    except yaml.YAMLError as e:
        raise InputError.at(f"YAML error: {e}", path) from None
    except RecursionError:  # not expected below MAX_DEPTH; kept as a last resort
        mark = loader.get_mark()  # where the reader had got to
        raise InputError.at(
            "YAML is nested too deeply", path, mark.line + 1, mark.column + 1
        ) from None
    finally:
        loader.dispose()
    doc = YamlDoc(path, None)
    if node is None:
        return doc
    builder = _Builder(doc, loader)
    try:
        builder.check_size(node)
        data = builder.build(node, ())
    except RecursionError:
        raise InputError.at("YAML is nested too deeply", path, *_pos(node)) from None
    return YamlDoc(path, data, doc.values, doc.keys)


def _syntax(context: str | None, problem: str | None) -> str:
    """PyYAML's problem, whole: 'but found another document' needs what was expected."""
    if problem and "'\\t'" in problem:
        return "a tab character; YAML needs spaces here, not tabs"
    if context and problem and context.startswith("expected"):
        return f"{context}, {problem}"
    return problem or context or "unreadable YAML"


def _line_col(text: str, index: int) -> Pos:
    return text.count("\n", 0, index) + 1, index - text.rfind("\n", 0, index)


def _pos(node: yaml.Node) -> Pos:
    return node.start_mark.line + 1, node.start_mark.column + 1


class _Builder:
    def __init__(self, doc: YamlDoc, loader: yaml.SafeLoader) -> None:
        self.doc = doc
        self.loader = loader

    def _fail(self, message: str, node: yaml.Node) -> InputError:
        return InputError.at(message, self.doc.file, *_pos(node))

    def check_size(self, root: yaml.Node) -> None:
        """Count nodes as they would be after alias expansion, without expanding."""
        sizes: dict[int, int] = {}
        active: set[int] = set()
        seen: set[int] = set()
        shared = 0

        def size(n: yaml.Node) -> int:
            nonlocal shared
            key = id(n)
            if key in sizes:
                shared += 1
                if shared > MAX_ALIASES:
                    raise self._fail(f"YAML uses more than {MAX_ALIASES} aliases", n)
                return sizes[key]
            if key in active:
                raise self._fail("recursive YAML alias", n)
            if n.tag not in _ALLOWED_TAGS:
                raise self._fail(
                    f"YAML tag '{n.tag.replace(_STD, '!!')}' is not allowed; "
                    "only plain maps, lists, strings, numbers, booleans and null",
                    n,
                )
            active.add(key)
            total = 1
            if isinstance(n, yaml.MappingNode):
                try:
                    self.loader.flatten_mapping(n)  # resolve '<<' merge keys in place
                except yaml.MarkedYAMLError as e:
                    merge = next((k for k, _ in n.value if k.tag == _STD + "merge"), n)
                    raise self._fail(f"YAML merge key '<<': {e.problem}", merge) from None
                total += sum(size(k) + size(v) for k, v in n.value)
            elif isinstance(n, yaml.SequenceNode):
                total += sum(size(v) for v in n.value)
            active.discard(key)
            seen.add(key)
            sizes[key] = total
            if total > MAX_NODES:
                raise self._fail(
                    f"YAML expands to more than {MAX_NODES} values (an alias bomb?)", n
                )
            return total

        size(root)

    def build(self, node: yaml.Node, loc: Loc) -> Any:
        self.doc.values.setdefault(loc, _pos(node))
        if isinstance(node, yaml.MappingNode):
            out: dict[str, Any] = {}
            first: dict[str, yaml.Node] = {}
            for k, v in node.value:
                if not isinstance(k, yaml.ScalarNode):
                    raise self._fail("mapping keys must be plain names", k)
                name = str(k.value)
                self._check_text(name, k)
                if name in first:
                    line = _pos(first[name])[0]
                    raise self._fail(f"duplicate key '{name}' (first given at line {line})", k)
                first[name] = k
                self.doc.keys.setdefault((*loc, name), _pos(k))
                out[name] = self.build(v, (*loc, name))
            return out
        if isinstance(node, yaml.SequenceNode):
            return [self.build(v, (*loc, i)) for i, v in enumerate(node.value)]
        try:
            value = self.loader.construct_object(node, deep=True)
        except yaml.YAMLError as e:
            raise self._fail(f"bad YAML value: {e}", node) from None
        except _BadScalar as e:
            raise self._fail(f"bad YAML value: {e}", node) from None
        except ValueError:  # an integer of thousands of digits
            raise self._fail(
                f"bad YAML value: the number {_shown(node.value)} is too long", node
            ) from None
        if isinstance(value, str):
            self._check_text(value, node)
        return value

    def _check_text(self, text: str, node: yaml.Node) -> None:
        """A \\u escape can give half a surrogate pair: no character, and unprintable."""
        if _SURROGATE.search(text):
            raise self._fail(
                "bad YAML value: a \\u escape gives an unpaired surrogate (D800-DFFF), "
                "which is not a character",
                node,
            )


_SURROGATE = re.compile(r"[\ud800-\udfff]")


def _shown(text: str) -> str:
    return text if len(text) <= 40 else text[:37] + "..."
