"""The skill-family contract: how a family of skills plugs into the compiler.

A family (the built-in cable and lab skills, or another package's) is an object registered
under the ``cellengine.skills`` entry point group. It names its skill models (``skills``:
the plan parser validates steps against them) and plans a plan's steps over a
:class:`~cellengine.context.PlanningContext`.

Planning is a search tree the family grows lazily. ``plan`` yields the candidates for its
first choice, best first; a :class:`Candidate` carries segments (with their typed
annotations) and ``then``, the candidates of the next choice given this one. The compiler
takes the first candidate at every choice and compiles the segments; when a segment cannot
run, it asks the choice that produced it for its next candidate, then the choices before
it (:mod:`cellengine.execute.candidates`). A family with one way per step yields one
candidate per choice; a family that sees several (another grasp, another sliding angle)
yields them in order of preference, and the compiler takes the first that compiles.

A family may also have ``check(world, steps)``: what the steps mean in the loaded world,
checked when the plan is loaded (``validate --no-compile`` too) and before any motion is
planned. It returns ``(path, message)`` pairs, the path into the plan file (``("steps", 2,
"guides", 1)``); the loader puts each at its file:line.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from cellengine.concurrency import Overlap
from cellengine.errors import InputError, Problem
from cellengine.program import Program, Segment
from cellengine.skill import Skill

if TYPE_CHECKING:  # planning needs the motion stack; parsing a plan does not
    from cellengine.context import PlanningContext

GROUP = "cellengine.skills"


@dataclass(frozen=True)
class Candidate:
    """One way to do the next part of a plan: its segments, then what comes after it
    (``then()``: the candidates of the next choice, best first; None: the plan ends here).
    ``report``: entries for report.json once the program is compiled (e.g. a mission with
    the actual times of its parts), from the compiled program. ``decides``: what this
    candidate fixes for the rest of the plan, by name (e.g. ``{"arms": "left holds the
    connector"}``): an error that blames one of these names sends the search straight back
    to the latest choice that decided it, to a candidate that decides it otherwise.
    ``failed_at(j)``: called when the compiler could not compile the candidate's segment
    ``j``, so the family can leave out, before building them, the candidates it has not
    offered yet that would fail there too (the compiler passes over those it is given).
    ``overlap``: the rules under which the arms' segments may run at once (unless the plan's
    execution is ``sequential``)."""

    segments: tuple[Segment, ...]
    then: Callable[[], Iterator[Candidate]] | None = None
    report: Callable[[Program], Mapping[str, Any]] | None = None
    decides: Mapping[str, str] = field(default_factory=dict)
    failed_at: Callable[[int], None] | None = None
    # what lets the arms' segments run at once (execute/streams.py); None: one after another
    overlap: Overlap | None = None


@runtime_checkable
class SkillFamily(Protocol):
    """What a package registers under the ``cellengine.skills`` entry point group."""

    name: str  # e.g. "cable"; errors and reports name the family by it
    skills: tuple[type[Skill], ...]  # each model's ``skill`` field is a Literal of its name

    def plan(self, ctx: PlanningContext, steps: Sequence[Skill]) -> Iterator[Candidate]:
        """The candidates for the first choice of ``steps`` (all of this family; the index
        of a step in ``steps`` is its index in the plan), best first. A step that cannot be
        done raises :class:`~cellengine.errors.StepError` with its index."""
        ...


@dataclass(frozen=True)
class Families:
    """Every installed family, and which family each skill name belongs to."""

    by_name: Mapping[str, SkillFamily]
    of_skill: Mapping[str, SkillFamily]

    @property
    def skills(self) -> Mapping[str, type[Skill]]:
        """Skill name -> its parameter model."""
        return MappingProxyType(
            {name: m for f in self.by_name.values() for m in f.skills for name in [skill_name(m)]}
        )


def skill_name(model: type[Skill]) -> str:
    """A skill model's name in plans: its class name (``skill: Literal["PickCable"]``)."""
    return model.__name__


@functools.cache  # installed package metadata: read once per process, never changes in it
def families() -> Families:
    """The families registered under ``cellengine.skills`` (the built-ins among them). A
    registration that is not a family, or two families claiming one skill name, is an
    error naming the entry point."""
    by_name: dict[str, SkillFamily] = {}
    of_skill: dict[str, SkillFamily] = {}
    for ep in sorted(entry_points(group=GROUP), key=lambda e: e.name):
        family = ep.load()
        if not isinstance(family, SkillFamily):
            raise InputError(
                Problem(
                    f"entry point '{ep.name} = {ep.value}' in group '{GROUP}' is not a skill "
                    "family (it needs 'name', 'skills' and 'plan(ctx, steps)')"
                )
            )
        by_name[family.name] = family
        for model in family.skills:
            name = skill_name(model)
            if name in of_skill and of_skill[name] is not family:
                raise InputError(
                    Problem(
                        f"skill '{name}' is claimed by two families: "
                        f"'{of_skill[name].name}' and '{family.name}' ({ep.value})"
                    )
                )
            of_skill[name] = family
    return Families(MappingProxyType(by_name), MappingProxyType(of_skill))
