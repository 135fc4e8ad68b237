"""The base of every skill's parameter model.

A plan step is validated against its skill's model. Fields that name things in the cell or
the objects are annotated with a :class:`Ref` so one generic check resolves them all. Skills
come in families (:mod:`cellengine.family`), registered through the ``cellengine.skills``
entry point group.
"""

from __future__ import annotations

import typing
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Annotated, Any

from pydantic import AfterValidator, BaseModel, ConfigDict, Field

from cellengine.info.units import Frozen


@dataclass(frozen=True)
class Ref:
    """Marks a string field as a reference to a ``kind`` of named thing."""

    kind: str  # keypoint | guide | cable | object | container | tool


KeypointRef = Annotated[str, Ref("keypoint")]  # platform.element[.keypoint]
GuideRef = Annotated[str, Ref("guide")]  # a keypoint reference whose element is a guide
CableRef = Annotated[str, Ref("cable")]
ObjectName = Annotated[str, Ref("object")]
ToolRef = Annotated[str, Ref("tool")]  # a tool of cell.yaml with a slot in the tool changer


def _distinct(names: tuple[str, ...]) -> tuple[str, ...]:
    """A choice between objects names each once: one named twice compares with itself."""
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ValueError(f"names '{twice[0]}' twice; a choice is between different objects")
    return names


Distinct = Annotated[
    tuple[ObjectName, ...],
    Field(min_length=2, json_schema_extra={"uniqueItems": True}),
    AfterValidator(_distinct),
]


class HeavierOf(Frozen):
    heavier_of: Distinct


class LighterOf(Frozen):
    lighter_of: Distinct


# An object named directly, or chosen at run time from results (no code in plans).
ObjectRef = ObjectName | HeavierOf | LighterOf

Loc = tuple[str | int, ...]


class Skill(BaseModel):
    """Parameters common to every step. Subclasses add theirs and fix ``skill``."""

    model_config = ConfigDict(extra="forbid", frozen=True, populate_by_name=True)

    skill: str
    id: str | None = None
    after: tuple[str, ...] = ()
    arm: str = "auto"  # a robot name, 'both', or 'auto' (the allocator decides)

    def refs(self) -> Iterator[tuple[Loc, str, str]]:
        """Every reference in this step: (path in the step, kind, name)."""
        yield from _refs(self, ())


def _refs(model: BaseModel, loc: Loc) -> Iterator[tuple[Loc, str, str]]:
    for name, field in type(model).model_fields.items():
        key = field.alias or name
        yield from _walk(getattr(model, name), field.annotation, field.metadata, (*loc, key))


def _walk(value: Any, tp: Any, meta: list[Any], loc: Loc) -> Iterator[tuple[Loc, str, str]]:
    if isinstance(value, BaseModel):
        yield from _refs(value, loc)
        return
    if typing.get_origin(tp) is Annotated:
        tp, *more = typing.get_args(tp)
        meta = [*meta, *more]
    ref = next((m for m in meta if isinstance(m, Ref)), None)
    if isinstance(value, str) and ref is not None:
        yield loc, ref.kind, value
    elif isinstance(value, tuple | list):
        args = typing.get_args(tp)
        for i, item in enumerate(value):
            item_tp = (
                args[0]
                if len(args) == 2 and args[1] is Ellipsis
                else (args[i] if i < len(args) else Any)
            )
            yield from _walk(item, item_tp, [], (*loc, i))
    elif isinstance(value, str):
        for arg in typing.get_args(tp):  # a union such as ObjectRef
            if typing.get_origin(arg) is Annotated:
                yield from _walk(value, arg, [], loc)
                return
