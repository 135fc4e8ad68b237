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
            out += _rows(owner, step.cable, routed, at)
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


def _rows(harness: Harness, branch: str, routed: set[str], at: Loc) -> list[Finding]:
    """The branch's cables are not routed yet and lie on top of those still to be routed
    at the connector (cable_group takes a group from the top)."""
    group = harness.branches[branch].cables
    taken = [n for n in harness.in_order(group) if n in routed]
    if taken:
        return [(at, f"{', '.join(taken)} of {branch} are routed already")]
    rows = {n: harness.cables[n].pin for n in harness.cables if n not in routed}
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
            "separating those needs a separation guide to lay them aside in (REMODEL's J<n>S), "
            f"which this engine does not have yet; route {' or '.join(tops)} before {branch}"
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
    d = packed_diameter([_diameter(world, n) for n in [*laid, *group]])
    try:
        gap = world.dimensions(ref)["gap"]
    except (RefError, KeyError):
        return []  # the plan's own checks say what is wrong with the guide
    if gap > d:
        return []
    msg = (
        f"guide '{ref}' has a {_mm(gap)} mm slot (its gap); {', '.join(laid)} lie in it "
        f"already, and with {name} ({', '.join(group)}) the bundle is {_mm(d)} mm thick: it "
        "does not fit"
    )
    return [(at, msg)]


def _diameter(world: World, cable: str) -> float:
    found = world.objects.single(cable)
    assert found is not None  # cables_of names only the objects' cables
    return float(found.diameter)
