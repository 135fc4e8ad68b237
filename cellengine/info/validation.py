"""Pydantic validation of a loaded YAML file, with errors turned into problems at
file:line:col that name the path to the bad value and, where they can, the valid choices."""

from __future__ import annotations

import types
import typing
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError
from pydantic_core import ErrorDetails

from cellengine.errors import InputError, Problem, known
from cellengine.info.yamlio import Loc, YamlDoc

M = TypeVar("M", bound=BaseModel)


def validate(
    cls: type[M],
    doc: YamlDoc,
    context: dict[str, Any] | None = None,
    data: Any = None,
    prefix: Loc = (),
) -> M:
    """Validate ``data`` (default: the whole document) found at ``prefix`` in ``doc``."""
    value = doc.data if data is None else data
    if value is None:
        value = {}
    try:
        return cls.model_validate(value, context=context)
    except ValidationError as e:
        errors = _prune_unions(doc.data, prefix, e.errors())
        raise InputError([problem(doc, cls, err, prefix) for err in errors]) from None


def dotted(loc: Loc) -> str:
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def problem(doc: YamlDoc, cls: type[BaseModel], err: ErrorDetails, prefix: Loc = ()) -> Problem:
    """One pydantic error as a Problem at the place the value (or key) was written."""
    path, on_key = _data_path(doc.data, prefix, err["loc"])
    kind = err["type"]
    here = dotted(path)
    if kind == "missing" and err["loc"] and isinstance(err["loc"][-1], int):
        line, col = doc.where(path) or (None, None)  # a tuple with too few items
        return Problem(f"{here}: too few items", str(doc.file), line, col)
    if kind in ("missing", "extra_forbidden"):
        parent, name = path[:-1], path[-1] if path else "?"
        where = doc.where(parent if kind == "missing" else path, key=kind != "missing")
        if kind == "missing":
            msg = f"missing required key '{name}'"
        else:
            branch = _branch(doc.data, prefix, err)
            fields = _fields_at(cls, path[len(prefix) : -1], branch[1] if branch else None)
            msg = f"unknown key '{name}'" + (known(fields) if fields is not None else "")
        loc_text = dotted(parent)
        message = f"{loc_text}: {msg}" if loc_text else msg
    else:
        if kind == "union_tag_invalid":  # point at the tag's value, not the mapping
            tag_key = str((err.get("ctx") or {}).get("discriminator", "")).strip("'")
            if (*path, tag_key) in doc.values:
                path = (*path, tag_key)
                here = dotted(path)
        where = doc.where(path, key=on_key)
        message = f"{here}: {_describe(err, on_key)}" if here else _describe(err, on_key)
    line, col = where or (None, None)
    return Problem(message, str(doc.file), line, col)


def _describe(err: ErrorDetails, on_key: bool) -> str:
    kind, ctx, value = err["type"], err.get("ctx") or {}, err.get("input")
    if kind == "union_tag_invalid":
        tags = [t.strip(" '") for t in str(ctx.get("expected_tags", "")).split(",")]
        return f"unknown {str(ctx.get('discriminator')).strip(chr(39))} '{ctx.get('tag')}'" + known(
            tags
        )
    if kind == "union_tag_not_found":
        return f"missing required key {ctx.get('discriminator')}"
    if kind == "string_pattern_mismatch":
        what = f"'{value}' is not a valid name" if isinstance(value, str) else "not a valid name"
        return f"{what}: use letters, digits, '_' and '-', starting with a letter or '_'"
    if kind == "union_kinds":
        return f"must be {' or '.join(ctx['kinds'])}, got {_show(value)}"
    if kind == "too_short":
        least = ctx.get("min_length", 1)
        return f"must have at least {least} item{'s' if least != 1 else ''}, got {_count(value)}"
    msg = err["msg"].removeprefix("Value error, ")
    msg = msg.replace("Input should be", "must be").replace("Input is ", "")
    if kind in _KINDS:  # name the YAML kind, not the Python type
        msg = f"must be {_KINDS[kind]}"
    if (
        kind in ("literal_error", "enum")
        or kind.endswith("_type")
        or kind.endswith("_parsing")
        or (isinstance(value, str | int | float) and "got" not in msg)
    ):
        msg += f", got {_show(value)}"
    return msg


_KINDS = {
    "dict_type": "a mapping",
    "model_type": "a mapping",
    "model_attributes_type": "a mapping",
    "list_type": "a list",
    "tuple_type": "a list",
    "string_type": "a string",
    "float_type": "a number",
    "int_type": "an integer",
    "bool_type": "true or false",
}


def _kind(error_type: str) -> str:
    return _KINDS.get(error_type) or error_type.removesuffix("_type")


def _count(value: Any) -> str:
    return str(len(value)) if isinstance(value, list | dict | tuple) else "fewer"


def _show(value: Any) -> str:
    if isinstance(value, dict):
        return "a mapping"
    if isinstance(value, list):
        return "a list"
    if isinstance(value, bool) or value is None:  # as YAML writes them
        return {True: "true", False: "false", None: "null"}[value]
    return repr(value) if isinstance(value, str) else str(value)


def _branch(data: Any, prefix: Loc, err: ErrorDetails) -> tuple[Loc, str, int] | None:
    """The outermost union member an error is about: (data path of the union, the member's
    tag in pydantic's loc, the tag's index in loc), or None if the error is in no union."""
    path: list[str | int] = list(prefix)
    node = data
    for part in prefix:
        node = node[part]
    loc = err["loc"]
    for i, part in enumerate(loc):
        if part == "[key]":
            continue
        if _has(node, part):
            node = node[part]
            path.append(part)
        elif isinstance(part, str) and (i < len(loc) - 1 or err["type"] != "missing"):
            return tuple(path), part, i  # not in the data, and not a missing key
        else:
            return None
    return None


def _prune_unions(data: Any, prefix: Loc, errors: list[ErrorDetails]) -> list[ErrorDetails]:
    """Where a value fits none of a union's members, pydantic reports every member's
    errors. Keep one member's: not one whose kind the value is not (a string member for
    a mapping), preferring the member that knows every key given, then the fewest errors."""
    branches = [_branch(data, prefix, err) for err in errors]
    members: dict[Loc, dict[str, list[tuple[ErrorDetails, int]]]] = {}
    for err, b in zip(errors, branches, strict=True):
        if b is not None:
            members.setdefault(b[0], {}).setdefault(b[1], []).append((err, b[2]))
    keep: dict[Loc, str] = {}
    for at, by_member in members.items():
        if len(by_member) < 2:
            continue
        names = list(by_member)

        # a member whose only error is that the value is not even of its kind
        wrong_kind = {
            m
            for m, errs in by_member.items()
            if all(len(e["loc"]) == i + 1 and e["type"].endswith("_type") for e, i in errs)
        }
        if len(wrong_kind) == len(names):  # one problem: the kinds it could be
            kinds = [_kind(e["type"]) for m in names for e, _ in by_member[m]]
            first = by_member[names[0]][0][0]
            first["type"] = "union_kinds"
            first["ctx"] = {"kinds": list(dict.fromkeys(kinds))}
        fitting = [m for m in names if m not in wrong_kind] or names[:1]
        keep[at] = min(
            fitting,
            key=lambda m: (
                any(e["type"] == "extra_forbidden" for e, _ in by_member[m]),
                len(by_member[m]),
                names.index(m),
            ),
        )
    return [
        err
        for err, b in zip(errors, branches, strict=True)
        if b is None or b[0] not in keep or keep[b[0]] == b[1]
    ]


def _data_path(data: Any, prefix: Loc, loc: tuple[int | str, ...]) -> tuple[Loc, bool]:
    """Follow pydantic's loc through the data; skip parts that are not in the data
    (union tags, '[key]'). The second result says whether the error is about a key."""
    path: list[str | int] = list(prefix)
    node, on_key = data, False
    for part in prefix:
        node = node[part]
    for i, part in enumerate(loc):
        last = i == len(loc) - 1
        if part == "[key]":
            on_key = True
        elif _has(node, part):
            node = node[part]
            path.append(part)
        elif last and isinstance(node, dict) and isinstance(part, str):
            path.append(part)  # a missing key; anything else not in the data is a union tag
    return tuple(path), on_key


def _has(node: Any, part: str | int) -> bool:
    if isinstance(node, dict):
        return part in node
    return isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node)


def _fields_at(cls: Any, path: Loc, member: str | None = None) -> list[str] | None:
    """The keys a model accepts at ``path`` (relative to ``cls``; at a union, those of the
    member named ``member``), or None if unknown."""
    node: Any = cls
    for part in path:
        node = _step(node, part)
        if node is None:
            return None
    model = _model_in(node, name=member)
    return [f.alias or n for n, f in model.model_fields.items()] if model else None


def _step(tp: Any, part: str | int) -> Any:
    model = _model_in(tp, part)
    if model is not None and isinstance(part, str):
        for name, field in model.model_fields.items():
            if part in (name, field.alias):
                return field.annotation
        return None
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Annotated:
        return _step(args[0], part)
    if origin is dict:
        return args[1]
    if origin in (list, tuple) and args:
        return (
            args[0]
            if origin is list or args[-1] is Ellipsis
            else args[min(int(part), len(args) - 1)]
        )
    return None


def _model_in(
    tp: Any, field: str | int | None = None, name: str | None = None
) -> type[BaseModel] | None:
    """The model class ``tp`` is, or the union member model called ``name``, or the first
    with ``field``."""
    if isinstance(tp, type) and issubclass(tp, BaseModel):
        return tp
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin is typing.Annotated:
        return _model_in(args[0], field, name)
    if origin is typing.Union or origin is types.UnionType:
        models = [a for a in args if isinstance(a, type) and issubclass(a, BaseModel)]
        for m in models:
            if m.__name__ == name:
                return m
        for m in models:
            if field is None or field in m.model_fields:
                return m
        return models[0] if models else None
    return None
