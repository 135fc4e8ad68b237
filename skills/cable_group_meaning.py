"""What a plan's harness steps mean, checked before any motion (cable_meaning's companion for
issue #15): a branch is routed after its harness's connector is placed, on the top rows of
the cables still at the connector (the bottom ones would need a separation guide, which is
not built), once; a whole harness is routed as a bundle only before any of its branches; and
every slot takes a group beside the cables laid in it before. Each is a plan fact: the
pins, diameters and gaps of the files and the order of the steps.
"""

from __future__ import annotations

from collections.abc import Sequence

from cellengine.info.harness import Harness, packed_diameter
from cellengine.skill import Skill
from cellengine.skills.cable import PlaceConnector, RouteCable, _mm
from cellengine.world import RefError, World

Loc = tuple[str | int, ...]
Finding = tuple[Loc, str]


def group_findings(world: World, steps: Sequence[Skill]) -> list[Finding]:
    """Every mistake of the plan's harness and branch routes, in plan order."""
    objects = world.objects
    out: list[Finding] = []
    placed: set[str] = set()  # harnesses (and cables) whose connector is placed
    routed: set[str] = set()  # the single cables whose route has begun
    laid: dict[str, list[str]] = {}  # guide -> the single cables in its slot
    aside: dict[str, str] = {}  # single cable -> the separation guide it lies aside in
    current = ""  # what the last RouteCable routed: the next one of it goes on
    for i, step in enumerate(steps):
        if isinstance(step, PlaceConnector):
            placed.add(step.cable)
        if not isinstance(step, RouteCable):
            continue
        at: Loc = ("steps", i, "cable")
        found = objects.branch_of(step.cable)
        harness = objects.harnesses.get(step.cable)
        if harness is not None and step.cable != current:
            out += _whole(harness, routed, at)
        if found is not None and step.cable != current:
            name, owner = found
            if name not in placed:
                msg = (
                    f"{step.cable} is a branch of harness {name}, whose connector is not placed "
                    f"before it: plan PlaceConnector (cable: {name}) first"
                )
                out.append((at, msg))
            out += _rows(owner, step.cable, routed, aside, step.separate_into, at)
            out += _aside(world, owner, step, routed, aside, ("steps", i))
        elif step.separate_into is not None:
            at_sep: Loc = ("steps", i, "separate_into")
            out.append((at_sep, f"{step.cable} is no branch of a harness: nothing to lay aside"))
        group = objects.cables_of(step.cable)
        for j, ref in enumerate(step.guides):
            here: Loc = ("steps", i, "guides", j)
            out += _slot(world, ref, laid.get(ref, []), step.cable, group, here)
            laid.setdefault(ref, []).extend(group)
        routed |= set(group)
        current = step.cable
    return out


def _whole(harness: Harness, routed: set[str], at: Loc) -> list[Finding]:
    """A whole harness is routed as one bundle only while none of its branches has been."""
    done = [b for b, br in harness.branches.items() if set(br.cables) & routed]
    if not done:
        return []
    rest = [b for b in harness.branches if b not in done]
    msg = f"its branch {', '.join(done)} is routed already; route the others by name"
    return [(at, msg + (f" ({', '.join(rest)})" if rest else ""))]


def _aside(
    world: World,
    harness: Harness,
    step: RouteCable,
    routed: set[str],
    aside: dict[str, str],
    at: Loc,
) -> list[Finding]:
    """``separate_into``: the cables above the branch still at the connector go into that
    guide (once per harness, as REMODEL does), which takes them."""
    group = harness.branches[step.cable].cables
    mine = [n for n in harness.cables if n in aside]
    if step.separate_into is None:
        return []
    here: Loc = (*at, "separate_into")
    low = min(harness.cables[n].pin for n in group)
    above = [
        n
        for n in harness.in_order(list(harness.cables))
        if n not in routed and n not in aside and n not in group and harness.cables[n].pin > low
    ]
    if not above:
        return [
            (here, f"no cable still to be routed lies above {step.cable}: nothing to lay aside")
        ]
    if mine:
        return [(here, f"{', '.join(mine)} lie aside already: a harness is laid aside once")]
    aside.update({n: step.separate_into for n in above})
    tight = _tight(world, step.separate_into, above)
    if tight is None:
        return []
    gap, d = tight
    msg = (
        f"guide '{step.separate_into}' has a {_mm(gap)} mm slot (its gap); {', '.join(above)} "
        f"to lay aside in it are a {_mm(d)} mm bundle: it does not fit"
    )
    return [(here, msg)]


def _rows(
    harness: Harness,
    branch: str,
    routed: set[str],
    aside: dict[str, str],
    separate_into: str | None,
    at: Loc,
) -> list[Finding]:
    """The branch's cables are not routed yet and lie on top of those still to be routed
    at the connector (cable_group takes a group from the top), or all lie aside in a
    separation guide, or lie below the others and the step lays those aside."""
    group = harness.branches[branch].cables
    taken = [n for n in harness.in_order(group) if n in routed]
    if taken:
        return [(at, f"{', '.join(taken)} of {branch} are routed already")]
    if all(n in aside for n in group):
        for n in group:
            del aside[n]
        return []
    if any(n in aside for n in group):
        away = ", ".join(n for n in harness.in_order(group) if n in aside)
        return [(at, f"{away} of {branch} lie aside and the rest do not: no grasp takes them")]
    if separate_into is not None:
        return []  # _aside checks what is laid aside
    rows = {n: harness.cables[n].pin for n in harness.cables if n not in routed and n not in aside}
    others = [n for n in rows if n not in group]
    if all(rows[g] > rows[o] for g in group for o in others):
        return []
    mine = ", ".join(harness.in_order(group))
    low = min(rows[g] for g in group)
    above = ", ".join(n for n in harness.in_order(others) if rows[n] > low)
    if all(rows[g] < rows[o] for g in group for o in others):
        tops = [b for b, br in harness.branches.items() if set(br.cables) & set(others)]
        msg = (
            f"{branch}'s cables ({mine}) leave the connector below {above}, still to be routed: "
            f"route {' or '.join(tops)} before {branch}, or lay those aside in a separation "
            "guide first (separate_into: <guide>, REMODEL's J<n>S)"
        )
        return [(at, msg)]
    msg = (
        f"{branch}'s cables ({mine}) leave the connector in rows between those of {above}, "
        "still to be routed: no grasp takes them apart from the others"
    )
    return [(at, msg)]


def _slot(
    world: World, ref: str, laid: list[str], name: str, group: Sequence[str], at: Loc
) -> list[Finding]:
    """The guide's slot takes ``group`` beside the cables laid in it before."""
    if not laid:
        return []
    tight = _tight(world, ref, [*laid, *group])
    if tight is None:
        return []
    gap, d = tight
    msg = (
        f"guide '{ref}' has a {_mm(gap)} mm slot (its gap); {', '.join(laid)} lie in it "
        f"already, and with {name} ({', '.join(group)}) the bundle is {_mm(d)} mm thick: it "
        "does not fit"
    )
    return [(at, msg)]


def _tight(world: World, ref: str, cables: Sequence[str]) -> tuple[float, float] | None:
    """(gap, bundle diameter) when the guide's slot does not take ``cables`` packed; None
    when it does (or has no gap: the plan's own checks say what is wrong with the guide)."""
    d = packed_diameter([_diameter(world, n) for n in cables])
    try:
        gap = world.dimensions(ref)["gap"]
    except (RefError, KeyError):
        return None
    return None if gap > d else (gap, d)


def _diameter(world: World, cable: str) -> float:
    found = world.objects.single(cable)
    assert found is not None  # cables_of names only the objects' cables
    return float(found.diameter)
