"""Runtime choices: a step's object named by what is measured (``heavier_of``,
``lighter_of``), resolved with the masses known. Any skill whose field is an ``ObjectRef``
gets them; the runner compares what they pick before and after a measurement to know
whether the rest of the plan must be planned again."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from cellengine.errors import InputError, Problem
from cellengine.skill import HeavierOf, LighterOf, ObjectRef, Skill
from cellengine.world import World


def candidates(ref: ObjectRef) -> tuple[str, ...]:
    """The objects a reference may stand for (one for a name)."""
    if isinstance(ref, HeavierOf):
        return ref.heavier_of
    if isinstance(ref, LighterOf):
        return ref.lighter_of
    return (ref,)


def known_masses(world: World, measured: Mapping[str, float] | None = None) -> dict[str, float]:
    """objects.yaml's masses, with ``measured`` over them."""
    known = {n: float(c.mass) for n, c in world.objects.containers.items() if c.mass is not None}
    known.update(measured or {})
    return known


def resolve(ref: ObjectRef, masses: Mapping[str, float]) -> str:
    """The object ``ref`` picks with ``masses``; InputError when one it needs is unknown."""
    if isinstance(ref, str):
        return ref
    names = candidates(ref)
    missing = [n for n in names if n not in masses]
    if missing:
        raise InputError(
            Problem(
                f"the mass of {', '.join(missing)} is not known: weigh it first or give it "
                "in objects.yaml"
            )
        )
    pick = max if isinstance(ref, HeavierOf) else min
    return pick(names, key=lambda n: masses[n])


def choices(
    world: World,
    steps: Sequence[Skill],
    masses: Mapping[str, float] | None = None,
    measured_only: bool = False,
) -> dict[str, str]:
    """The objects the runtime choices pick, by ``steps[i].field``, with ``masses`` over
    objects.yaml's (with ``measured_only``, with ``masses`` alone); a choice whose masses are
    not all known is left out."""
    known = dict(masses or {}) if measured_only else known_masses(world, masses)
    out: dict[str, str] = {}
    for i, step in enumerate(steps):
        for field in type(step).model_fields:
            ref = getattr(step, field)
            if isinstance(ref, HeavierOf | LighterOf) and all(n in known for n in candidates(ref)):
                out[f"steps[{i}].{field}"] = resolve(ref, known)
    return out
