"""The lab skills' motion primitives: pick, place, weigh, unscrew, pour, as segments.

Each primitive takes the :class:`LabState` the previous one left and returns its segments
and the state after them; the arms it uses are given (the allocator chose them). Moves
through free space are transits (the executor plans them); moves next to a container are
Cartesian lines and turns (the executor follows them exactly). Every key pose is checked
for an inverse kinematics solution first, so an impossible grasp is reported in plan terms
before any planning.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import replace
from types import MappingProxyType
from typing import Any, Protocol

import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat
from cellengine.errors import InputError, Problem
from cellengine.motion import interpolate as ip
from cellengine.program import Annotation, ArmPath, GripperEvent, Measure, Segment
from cellengine.skills import lab_geometry as lg
from cellengine.skills.lab_state import LabState
from cellengine.world import World

OPEN, GRASP = "open", "grasp"
# Unscrewing turns the cap in strokes of at most this much: a wrist with a limited range
# lets go, turns back and grasps again between strokes.
STROKE = math.radians(180.0)
# A container set down is turned about its axis by the first of these (deg) that the arm
# reaches: the hand's own heading first.
SET_DOWN_TURNS_DEG = (0, *(s * d for d in range(15, 181, 15) for s in (1, -1)))
CAP_DROP = 0.01  # m: a cap may be let go of this high over where it lands
POUR_CLEARANCE = 0.03  # m: the container's mouth above the target's rim while pouring


class Solver(Protocol):
    """Whether ``arm`` reaches ``T_cell_tcp`` in a configuration free of collisions, the
    containers named in ``ignore`` (the one grasped or set down) left out."""

    def __call__(self, arm: str, T_cell_tcp: Mat, ignore: Sequence[str] = ()) -> bool: ...


class Builder:
    """Appends segments for one step and keeps the state in step with them."""

    def __init__(self, state: LabState) -> None:
        self.state = state
        self.segments: list[Segment] = []
        self.tag: Mapping[str, Any] = {}  # facts every segment added gets (the mission part)

    def add(
        self,
        label: str,
        paths: Iterable[ArmPath],
        *,
        before: Iterable[GripperEvent] = (),
        after: Iterable[GripperEvent] = (),
        closed_chain: tuple[str, str] | None = None,
        contacts: Iterable[tuple[str, str]] = (),
        facts: Mapping[str, Any] | None = None,
        annotations: Iterable[Annotation] = (),
    ) -> None:
        seg = Segment(
            step=self.state.step,
            label=label,
            paths=tuple(paths),
            before=tuple(before),
            after=tuple(after),
            closed_chain=closed_chain,
            contacts=tuple(contacts),
            facts=MappingProxyType({**self.tag, **(facts or {})}),
            annotations=tuple(annotations),
        )
        for path in seg.paths:
            self.state = self.state.moved(path.arm, path.poses[-1])
        self.segments.append(seg)


def error(message: str) -> InputError:
    return InputError(Problem(message))


def _mm(p: Sequence[float] | Mat) -> str:
    return "(" + ", ".join(f"{1000.0 * float(v):.1f}" for v in p) + ") mm"


def transit(arm: str, T: Mat) -> ArmPath:
    return ArmPath(arm, "transit", np.asarray(T, dtype=float)[None])


def line(arm: str, T0: Mat, T1: Mat) -> ArmPath:
    return ArmPath(arm, "cartesian", ip.line(T0, T1))


# ------------------------------------------------------------------------- pick and place


def choose_grasp(
    reach: Solver, arm: str, candidates: Sequence[Mat], where: str, what: str, name: str
) -> Mat:
    """The first candidate whose grasp, approach and lifted poses the arm reaches (container
    ``name`` itself left out: the fingers close on it)."""
    for T in candidates:
        if all(reach(arm, P, (name,)) for P in (T, lg.approach_of(T), lg.lifted(T))):
            return T
    raise error(
        f"{where}: arm '{arm}' cannot grasp {what}: none of {len(candidates)} grasps round "
        f"{_mm(candidates[0][:3, 3])} has an inverse kinematics solution (with its approach "
        "and lift) within the joint limits and free of collisions"
    )


def pick(
    b: Builder, reach: Solver, world: World, arm: str, name: str, grasp: lg.Grasp, where: str
) -> None:
    """``arm`` comes in, closes on container ``name`` where it stands, and lifts it."""
    state = b.state
    if name not in state.where:
        holder = state.holder(name)
        raise error(f"{where}: '{name}' is held by arm '{holder}', not standing anywhere")
    base = world.cell.robots[arm].base.matrix()[:3, 3]
    body = lg.Body.of(world.container(name))
    T = choose_grasp(
        reach,
        arm,
        lg.grasp_candidates(grasp, state.where[name], body, base),
        where,
        f"'{name}'",
        name,
    )
    b.add(
        f"{where}: to {name}", [transit(arm, lg.approach_of(T))], before=[GripperEvent(arm, OPEN)]
    )
    b.add(
        f"{where}: grasp {name}",
        [line(arm, lg.approach_of(T), T)],
        after=[GripperEvent(arm, GRASP, name)],
        contacts=[(arm, name)],
    )
    b.state = b.state.grasped(arm, name)
    b.add(f"{where}: lift {name}", [line(arm, T, lg.lifted(T))])


def place(
    b: Builder, reach: Solver, arm: str, T_cell_base: Mat, where: str, label: str = "put down"
) -> None:
    """``arm`` puts what it holds down standing at ``T_cell_base``, opens and backs off
    upwards."""
    name, T = set_down(b, reach, arm, T_cell_base, where, label)
    b.segments[-1] = replace(b.segments[-1], after=(GripperEvent(arm, OPEN),))
    b.state = b.state.released(arm)
    # open, the fingers clear the container upwards whichever way they came in; going up
    # keeps the hand away from what stands beside it at the same height
    b.add(f"{where}: back off", [line(arm, T, lg.lifted(T))], contacts=[(arm, name)])


def hold(b: Builder, reach: Solver, arm: str, T_cell_base: Mat, where: str) -> None:
    """``arm`` sets what it holds down at ``T_cell_base`` and keeps holding it (for another
    arm to work on it)."""
    set_down(b, reach, arm, T_cell_base, where, "hold")


def set_down(
    b: Builder, reach: Solver, arm: str, T_cell_base: Mat, where: str, label: str
) -> tuple[str, Mat]:
    """Carry what ``arm`` holds over ``T_cell_base`` and lower it there: the container turned
    about its axis as little as lets the arm reach (it is round); the object's name and the
    hand's pose at the end."""
    held = b.state.held.get(arm)
    if held is None:
        raise error(f"{where}: arm '{arm}' holds nothing to put down")
    T_now_base = b.state.tcp[arm] @ g.inverse(held.T_base_tcp)
    target = np.asarray(T_cell_base)[:3, 3]
    for deg in SET_DOWN_TURNS_DEG:
        R = g.rot_z(math.radians(deg)) @ T_now_base[:3, :3]
        T = g.transform(R, target) @ held.T_base_tcp
        if all(reach(arm, P, (held.name,)) for P in (T, lg.lifted(T), lg.approach_of(T))):
            break
    else:
        raise error(
            f"{where}: out of reach of arm '{arm}': it cannot set '{held.name}' down at "
            f"{_mm(target)} (no inverse kinematics solution free of collisions for any turn)"
        )
    b.add(f"{where}: carry {held.name}", [transit(arm, lg.lifted(T))])
    b.add(f"{where}: {label} {held.name}", [line(arm, lg.lifted(T), T)])
    return held.name, T


def weigh(b: Builder, arm: str, name: str, where: str) -> None:
    """Read the held container's mass: the segment's Measure tells the runner to read the
    arm's load cell once the arm stands still after it."""
    held = b.state.held.get(arm)
    if held is None or held.name != name:
        raise error(f"{where}: arm '{arm}' must hold '{name}' to weigh it")
    T = b.state.tcp[arm]
    b.add(
        f"{where}: weigh {name}",
        [line(arm, T, lg.lifted(T, 0.01))],
        facts={"measure": "mass", "object": name, "arm": arm},
        annotations=[Measure(arm, name)],
    )


# ------------------------------------------------------------------------------- unscrew


def unscrew_strokes(turns: float, stroke: float = STROKE) -> list[float]:
    """The turn (rad) of each stroke: as many full strokes as fit, then the rest."""
    total = 2.0 * math.pi * turns
    n = max(1, math.ceil(total / stroke - 1e-9))
    return [total / n] * n


def unscrew(
    b: Builder,
    reach: Solver,
    world: World,
    turner: str,
    name: str,
    where: str,
    turns: float | None = None,
) -> None:
    """``turner`` grips the cap of container ``name`` (held still by the other arm) from
    above and turns it off counter-clockwise by ``turns`` (default: the cap's), rising by
    the pitch per turn, in strokes it releases and re-grasps between; then lifts the cap
    away, holding it (put it down with :func:`put_cap_down` once the other arm has gone)."""
    c = world.container(name)
    if c.cap is None or name not in b.state.capped:
        raise error(f"{where}: '{name}' has no cap on to unscrew")
    body = lg.Body.of(c)
    T_base = b.state.base_of(name)
    p = T_base[:3, 3] + (body.height - body.cap_height / 2.0) * lg.UP
    base = world.cell.robots[turner].base.matrix()[:3, 3]
    heading = math.atan2(float((p - base)[1]), float((p - base)[0])) + math.pi / 2.0
    candidates = [lg.top_grasp(p, heading + k * math.pi / 8) for k in range(8)]
    T0 = choose_grasp(reach, turner, candidates, where, f"the cap of '{name}'", name)
    b.add(
        f"{where}: to the cap",
        [transit(turner, lg.approach_of(T0))],
        before=[GripperEvent(turner, OPEN)],
    )
    touch = [(turner, name)]
    b.add(f"{where}: grip the cap", [line(turner, lg.approach_of(T0), T0)], contacts=touch)
    rise_per_rad = c.cap.pitch / (2.0 * math.pi)
    cap = f"{name}.cap"
    strokes = unscrew_strokes(c.cap.turns if turns is None else turns)
    T = T0
    for k, angle in enumerate(strokes):
        last = k == len(strokes) - 1
        # counter-clockwise seen from above (a right-hand thread comes off): +z of the cell
        turned = _turned(T, angle, rise_per_rad * angle)
        if not reach(turner, turned, (name,)):
            raise error(
                f"{where}: arm '{turner}' cannot turn the cap of '{name}' by "
                f"{math.degrees(angle):.0f} deg"
            )
        b.add(
            f"{where}: turn the cap ({k + 1}/{len(strokes)})",
            [ArmPath(turner, "cartesian", _screw_path(T, angle, rise_per_rad * angle))],
            # the last stroke frees the cap: from then on the hand holds it
            before=[GripperEvent(turner, GRASP, cap if last else None)],
            after=[] if last else [GripperEvent(turner, OPEN)],
            contacts=touch,
        )
        T = turned
        if not last:
            b.add(
                f"{where}: turn back ({k + 1}/{len(strokes)})",
                [ArmPath(turner, "cartesian", _screw_path(T, -angle, 0.0))],
                contacts=touch,
            )
            T = _turned(T, -angle, 0.0)
    T_up = lg.lifted(T)
    b.add(f"{where}: lift the cap away", [line(turner, T, T_up)], contacts=touch)
    b.state = b.state.uncapped(name, T_up)  # in the turner's hand: see put_cap_down


def put_cap_down(
    b: Builder, reach: Solver, world: World, turner: str, name: str, T_place: Mat, where: str
) -> None:
    """The turner puts the cap of ``name`` it holds (after :func:`unscrew`) down at
    ``T_place`` (the cap's base there) and backs off upwards."""
    body = lg.Body.of(world.container(name))
    T_put = np.array(b.state.tcp[turner], dtype=float)
    # on the surface, or let go of it up to CAP_DROP above where the arm reaches no lower
    for drop in np.linspace(0.0, CAP_DROP, 5):
        T_put[:3, 3] = np.asarray(T_place)[:3, 3] + (body.cap_height / 2.0 + drop) * lg.UP
        if reach(turner, T_put, (name,)) and reach(turner, lg.lifted(T_put), (name,)):
            break
    else:
        raise error(f"{where}: arm '{turner}' cannot put the cap down at {_mm(T_put[:3, 3])}")
    b.add(f"{where}: carry the cap", [transit(turner, lg.lifted(T_put))])
    b.add(
        f"{where}: put the cap down",
        [line(turner, lg.lifted(T_put), T_put)],
        after=[GripperEvent(turner, OPEN)],
    )
    b.add(f"{where}: back off", [line(turner, T_put, lg.lifted(T_put))])
    b.state = b.state.uncapped(name, T_put)


def _turned(T: Mat, angle: float, rise: float) -> Mat:
    out = np.array(T, dtype=float)
    out[:3, :3] = g.rot_z(angle)[:3, :3] @ T[:3, :3]
    out[:3, 3] += rise * lg.UP
    return out


def _screw_path(T: Mat, angle: float, rise: float, step: float = math.radians(5.0)) -> Any:
    n = max(2, math.ceil(abs(angle) / step) + 1)
    return np.stack([_turned(T, angle * s, rise * s) for s in np.linspace(0.0, 1.0, n)])


# ---------------------------------------------------------------------------------- pour


def pour(
    b: Builder,
    reach: Solver,
    world: World,
    arm: str,
    name: str,
    into: str,
    angle: float,
    where: str,
) -> None:
    """The arm holding open container ``name`` brings it beside and above ``into``, tilts it
    by ``angle`` about a horizontal axis through the fingertips, so that its mouth swings
    over the target's axis, and turns it back. Held that high, no part of it goes below
    the target's rim plus :data:`POUR_CLEARANCE` at any tilt."""
    held = b.state.held.get(arm)
    if held is None or held.name != name:
        raise error(f"{where}: arm '{arm}' must hold '{name}' to pour it")
    if name in b.state.capped:
        raise error(f"{where}: '{name}' is capped: unscrew it before pouring")
    body = lg.Body.of(world.container(name))
    target = lg.Body.of(world.container(into))
    T_target = b.state.base_of(into)
    T_hand = b.state.tcp[arm]
    # tilt about the horizontal axis across the approach: the tool's x for a top grasp
    # (x is horizontal), the tool's z for a side grasp (z is horizontal)
    axis = T_hand[:3, 2] if abs(float(T_hand[:3, 2] @ lg.UP)) < 0.5 else T_hand[:3, 0]
    axis = lg.horizontal(axis)
    # the fingertips are on the container's axis, `grip` above its base
    grip = float(held.T_base_tcp[2, 3])
    above = body.height - grip  # from the fingertips to the mouth
    # tilting by +angle about `axis` swings the mouth along axis x up, by above * sin(angle)
    swing = np.cross(axis, lg.UP) * above * math.sin(angle)
    reach_down = max(grip, above) + body.diameter / 2.0  # the farthest point from the pivot
    T_over = np.array(T_hand, dtype=float)
    T_over[:3, 3] = T_target[:3, 3] - swing + (target.height + POUR_CLEARANCE + reach_down) * lg.UP
    tilt = [_tilted(T_over, axis, angle * s) for s in np.linspace(0.0, 1.0, 19)]
    for P in (T_over, tilt[-1]):
        if not reach(arm, P, (name, into)):
            raise error(
                f"{where}: arm '{arm}' cannot pour '{name}' over '{into}': the pose at "
                f"{_mm(P[:3, 3])} has no inverse kinematics solution within its joint limits"
            )
    b.add(f"{where}: over {into}", [transit(arm, T_over)])
    b.add(
        f"{where}: pour {name}",
        [ArmPath(arm, "cartesian", np.stack(tilt))],
        facts={"pour": name, "into": into},
    )
    b.add(f"{where}: upright", [ArmPath(arm, "cartesian", np.stack(tilt[::-1]))])


def _tilted(T: Mat, axis: Any, angle: float) -> Mat:
    out = np.array(T, dtype=float)
    R = g.axis_angle_to_matrix(axis, angle)
    out[:3, :3] = R @ T[:3, :3]
    return out


# ---------------------------------------------------------------------------- carry together


def carry_together(
    b: Builder,
    reach: Solver,
    world: World,
    leader: str,
    follower: str,
    name: str,
    T_to: Mat,
    where: str,
) -> None:
    """Both arms take container ``name`` (a box) by the middle of two opposite sides, the
    sides facing their bases, lift it, carry it over ``T_to``'s position, set it down there
    and let go: the follower keeps its pose relative to the leader throughout."""
    c = world.container(name)
    if c.size is None:
        raise error(f"{where}: '{name}' is not a box: BimanualCarry takes boxes (give 'size')")
    T_base = b.state.where.get(name)
    if T_base is None:
        raise error(f"{where}: '{name}' is in a hand, not standing anywhere")
    sx, sy, sz = c.size
    centre = T_base[:3, 3] + sz / 2.0 * lg.UP
    # the box's horizontal axis nearer the line from the leader's base to the follower's
    bases = [world.cell.robots[a].base.matrix()[:3, 3] for a in (leader, follower)]
    line_ab = lg.horizontal(bases[1] - bases[0])
    x_box, y_box = T_base[:3, 0], T_base[:3, 1]
    n, half = (
        (x_box, sx / 2.0) if abs(x_box @ line_ab) >= abs(y_box @ line_ab) else (y_box, sy / 2.0)
    )
    n = lg.horizontal(n if float(n @ line_ab) >= 0 else -n)  # from the leader towards the follower
    move = np.asarray(T_to)[:3, 3] - T_base[:3, 3]

    def route(T: Mat) -> list[Mat]:  # grasp, lifted, over the target, set down
        return [T, lg.lifted(T), _shifted(lg.lifted(T), move), _shifted(T, move)]

    def hold_way(arm: str, T: Mat) -> Mat:
        """The grasp either way round the tool's axis (the gripper is symmetric) that the
        arm holds all along the route."""
        missed = []
        for way in lg.both_ways(T):
            out = [P for P in route(way) if not reach(arm, P, (name,))]
            if not out:
                return way
            missed.append(out[0])
        raise error(
            f"{where}: arm '{arm}' cannot hold '{name}' by its side at {_mm(missed[0][:3, 3])} "
            f"on the way from {_mm(T_base[:3, 3])} to {_mm(np.asarray(T_to)[:3, 3])} (no "
            "inverse kinematics solution free of collisions, either way round its tool axis)"
        )

    T_lead = hold_way(leader, lg.side_grasp(centre - half * n, n))
    T_follow = hold_way(follower, lg.side_grasp(centre + half * n, -n))
    T_rel = g.inverse(T_lead) @ T_follow  # kept while both hold the box
    key_poses = route(T_lead)
    for arm, T in ((leader, T_lead), (follower, T_follow)):
        b.add(
            f"{where}: {arm} to {name}",
            [transit(arm, lg.approach_of(T))],
            before=[GripperEvent(arm, OPEN)],
        )
    # the leader holds the box, the follower a grip on its side (one rigid object, one owner)
    b.add(
        f"{where}: take {name}",
        [
            line(leader, lg.approach_of(T_lead), T_lead),
            line(follower, lg.approach_of(T_follow), T_follow),
        ],
        after=[GripperEvent(leader, GRASP, name), GripperEvent(follower, GRASP, f"{name}.side")],
        contacts=[(leader, name), (follower, name)],
    )
    b.state = b.state.grasped(leader, name)
    chain = (leader, follower)
    for label, P0, P1 in (
        ("lift", key_poses[0], key_poses[1]),
        ("carry", key_poses[1], key_poses[2]),
        ("set down", key_poses[2], key_poses[3]),
    ):
        lead_path = ip.line(P0, P1)
        follow_path = np.stack([P @ T_rel for P in lead_path])
        b.add(
            f"{where}: {label} {name} together",
            [ArmPath(leader, "cartesian", lead_path), ArmPath(follower, "cartesian", follow_path)],
            closed_chain=chain,
            contacts=[(follower, name)],
        )
    b.segments[-1] = replace(
        b.segments[-1], after=(GripperEvent(leader, OPEN), GripperEvent(follower, OPEN))
    )
    b.state = b.state.released(leader)
    T_end_f = key_poses[3] @ T_rel
    b.add(
        f"{where}: let go of {name}",
        [
            line(leader, key_poses[3], lg.approach_of(key_poses[3])),
            line(follower, T_end_f, lg.approach_of(T_end_f)),
        ],
        contacts=[(leader, name), (follower, name)],
    )


def _shifted(T: Mat, move: Any) -> Mat:
    out = np.array(T, dtype=float)
    out[:3, 3] += np.asarray(move, dtype=float)
    return out
