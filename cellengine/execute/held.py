"""What each gripper holds, as collision objects riding on its TCP.

A gripper event's ``holds`` names what the gripper holds from then on. The executor keeps the
collision checker's held objects in step: the previous one is detached, the new one attached.

Shapes: a connector (``cable1.connector``) or a container (``vial1``) as the world describes
it (:func:`~cellengine.motion.scene.held_from_world`); anything else, a cable or a piece of
it, is a cube of the cable's diameter at the fingertips (the cable beyond the fingers is slack
and deformable: the executor does not model it). Names are ``<object>@<arm>``, since both hands
can hold one cable.

Each gripper's fingers are placed at the opening of its last jaw mode (part of :class:`Held`,
so a scene is kept per opening too).

A held object may touch the platform elements (combs, guides, the connector guide): putting
the cable or the connector into them is the task, with the clearances of a few millimetres the
guides are made with. The arms themselves are still checked against every element.
"""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace

import coal
import numpy as np

from cellengine import geometry as g
from cellengine.arrays import Mat
from cellengine.execute.laid import Point, Stretch
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.robot import contact_parts
from cellengine.motion.scene import (
    CollisionScene,
    HeldObject,
    Pair,
    StaticShape,
    assemble,
    held_box,
    held_from_world,
    pair_key,
    standing_container,
)
from cellengine.world import RefError, World

DEFAULT_SIZE = 0.01  # m: the cube for an object the world gives no size for
# Held states whose checker (and scene) are kept, the latest used: a grasp-release cycle
# comes back to the same few states, while every state a long plan passes through (each
# checker with its margin and clearance models is tens of MB) would make a compile's memory
# grow with its steps (issue 19: 68 MB per Weigh step).
KEPT_STATES = 8


def held_name(arm: str, obj: str) -> str:
    return f"{obj}@{arm}"


def held_object(world: World, scene: CollisionScene, arm: str, obj: str) -> HeldObject:
    """The collision object for ``obj`` in ``arm``'s gripper, centred at its TCP."""
    allowed = _platform_elements(world, scene)
    name = held_name(arm, obj)
    try:
        shaped = held_from_world(world, obj, arm, np.eye(4), allowed)
        return HeldObject(name, arm, shaped.shape, shaped.T_tcp_object, shaped.allowed)
    except (RefError, ValueError):
        pass  # not a connector or a container: a piece of cable, or an unknown name
    cable = obj.split(".", 1)[0]
    size = DEFAULT_SIZE
    found = world.objects.cable(cable)
    if found is not None:
        size = float(found.diameter)
    return held_box(name, arm, (size, size, size), np.eye(4), allowed)


def _platform_elements(world: World, scene: CollisionScene) -> frozenset[str]:
    return frozenset(s.name for s in scene.statics if s.name.split(".", 1)[0] in world.platforms)


@dataclass(frozen=True)
class Held:
    """What the grippers hold and where the containers stand, at one moment of a program.

    ``by_arm``: arm -> the object it holds. ``grips``: arm -> T_tcp_object of a held
    container (its centre in the fingertip frame, where it was grasped). ``standing``:
    container -> T_cell_base of each container standing somewhere. ``contacts``: (arm,
    object) pairs whose contact the current segment expects (a gripper closing on, or
    letting go of, a container): that arm's tool is not checked against that object.
    ``jaw``: arm -> its fingers' opening (m) in its last mode; an arm not named (no mode set
    yet, or a tool without fingers) has them at the widest."""

    by_arm: Mapping[str, str]
    grips: Mapping[str, tuple[tuple[float, ...], ...]]
    standing: Mapping[str, tuple[tuple[float, ...], ...]]
    contacts: frozenset[tuple[str, str]] = frozenset()
    jaw: Mapping[str, float] = field(default_factory=dict)
    # cables laid on the board that the hands keep clear of (execute/laid.py)
    laid: tuple[Stretch, ...] = ()

    def key(self) -> tuple[object, ...]:
        return (
            self.laid,
            tuple(sorted(self.by_arm.items())),
            tuple(sorted(self.grips.items())),
            tuple(sorted(self.standing.items())),
            tuple(sorted(self.contacts)),
            tuple(sorted(self.jaw.items())),
        )


def _rows(T: Mat) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(round(float(v), 12) for v in row) for row in np.asarray(T))


def _mat(rows: tuple[tuple[float, ...], ...]) -> Mat:
    return np.array(rows, dtype=float)


class Holding:
    """What the grippers hold and where containers stand (:class:`Held`), and a checker whose
    scene has them (``checker``: another whenever that changes; the base scene is never
    changed). Containers start where objects.yaml stands them (the base scene has them
    there); one grasped rides on the gripper, one let go stands where the hand put it."""

    def __init__(self, world: World, scene: CollisionScene, keep: int = KEPT_STATES) -> None:
        self.world = world
        self.base = scene
        self.keep = keep  # checkers kept
        containers = world.objects.containers
        self.state = Held(
            {},
            {},
            {n: _rows(world.standing(c)) for n, c in containers.items() if c.at is not None},
        )
        self.checker = CollisionChecker(scene)
        # the checkers of the latest KEPT_STATES held states, the latest last (a checker is
        # never changed after it is built; its scene is checker.scene)
        self.kept: OrderedDict[tuple[object, ...], CollisionChecker] = OrderedDict(
            [(self.state.key(), self.checker)]
        )

    @property
    def by_arm(self) -> Mapping[str, str]:
        return self.state.by_arm

    def restore(self, state: Held) -> None:
        """Back to ``state`` (a compiler's mark): its checker again, built again if it was
        dropped."""
        self._use(state)

    def set(
        self, arm: str, obj: str | None, T_cell_tcp: Mat | None = None, mode: str | None = None
    ) -> None:
        """``arm`` holds ``obj`` from now on (None: nothing), its fingertips at
        ``T_cell_tcp`` (needed when a container is grasped or let go), its jaw in ``mode``
        (None: as it was). ValueError when the object cannot ride on the gripper (it
        intersects the wrist)."""
        s = self.state
        jaw = self._jaw(arm, mode)
        if s.by_arm.get(arm) == obj:
            if jaw != s.jaw:
                self._use(replace(s, jaw=jaw))
            return
        by_arm, grips, standing = dict(s.by_arm), dict(s.grips), dict(s.standing)
        was = by_arm.pop(arm, None)
        if was is not None and arm in grips:
            # a container let go stands where the hand put it
            grip = _mat(grips.pop(arm))
            T_centre = _need(T_cell_tcp, arm, was) @ grip
            standing[was] = _rows(T_centre @ _half_height(self.world, was, -1.0))
        if obj is not None:
            by_arm[arm] = obj
            if obj in standing:
                T_centre = _mat(standing.pop(obj)) @ _half_height(self.world, obj, 1.0)
                grips[arm] = _rows(g.inverse(_need(T_cell_tcp, arm, obj)) @ T_centre)
        self._use(Held(by_arm, grips, standing, s.contacts, jaw))

    def _jaw(self, arm: str, mode: str | None) -> Mapping[str, float]:
        fingers = self.base.cell.arms[arm].fingers
        if mode is None or fingers is None:
            return self.state.jaw
        return {**self.state.jaw, arm: fingers.opening(mode)}

    def lay(self, laid: Sequence[Stretch]) -> None:
        """The cables laid that the hands keep clear of from now on."""
        if tuple(laid) != self.state.laid:
            self._use(replace(self.state, laid=tuple(laid)))

    def touch(self, contacts: Iterable[tuple[str, str]]) -> None:
        """The contacts the next segment expects (see :class:`Held`)."""
        self._use(replace(self.state, contacts=frozenset(contacts)))

    def _use(self, state: Held) -> None:
        key = state.key()
        checker = self.kept.pop(key, None)
        if checker is None:
            checker = CollisionChecker(self._scene(state))
        self.kept[key] = checker
        while len(self.kept) > self.keep:
            self.kept.popitem(last=False)
        self.state, self.checker = state, checker

    def _scene(self, state: Held) -> CollisionScene:
        """The base scene with ``state``'s jaw, held objects and standing containers, built
        in one go (each change one at a time built a scene for each: ~10 ms apiece)."""
        base = self.base
        jaw = {**base.jaw, **state.jaw}
        plain = not state.grips and not state.contacts and not state.laid
        if plain and self._standing_as_built(state):
            if not state.by_arm and not state.jaw:
                return base
            riding = [held_object(self.world, base, a, o) for a, o in sorted(state.by_arm.items())]
            by_name = {h.name: h for h in riding}
            return assemble(base.cell, base.statics, by_name, base.fixed_reasons, base.notes, jaw)
        containers = self.world.objects.containers
        statics = [s for s in self.base.statics if s.name not in containers]
        statics += [
            standing_container(self.world, n, _mat(T)) for n, T in sorted(state.standing.items())
        ]
        statics += [_stretch(*s) for s in state.laid]
        held: dict[str, HeldObject] = {}
        for arm, obj in sorted(state.by_arm.items()):
            h = held_object(self.world, self.base, arm, obj)
            if arm in state.grips:
                h = replace(h, T_tcp_object=_mat(state.grips[arm]))
            held[h.name] = h
        allowed: dict[Pair, str] = {}
        for arm, obj in state.contacts:
            # the arm's tool, and what it holds (a cap coming off), against the object
            # standing or in either hand
            mine = list(contact_parts(self.base.cell.arms[arm]))
            if arm in state.by_arm:
                mine.append(held_name(arm, state.by_arm[arm]))
            for name in (obj, *(held_name(a, obj) for a in state.by_arm)):
                for m in mine:
                    if m != name:
                        allowed[pair_key(m, name)] = "contact"
        fixed = {**base.fixed_reasons, **allowed}
        return assemble(base.cell, statics, held, fixed, base.notes, jaw)

    def _standing_as_built(self, state: Held) -> bool:
        containers = self.world.objects.containers
        built = {
            s.name: _rows(s.T_cell_shape @ _half_height(self.world, s.name, -1.0))
            for s in self.base.statics
            if s.name in containers
        }
        return built == dict(state.standing)


def _stretch(name: str, a: Point, b: Point, radius: float) -> StaticShape:
    """A stretch of laid cable: a capsule from ``a`` to ``b``."""
    p, q = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    length = float(np.linalg.norm(q - p))
    shape = coal.Capsule(radius, length)
    T = g.transform(g.z_along((q - p) / length), (p + q) / 2.0)
    return StaticShape(name, T, shape, shape, True)


def _half_height(world: World, name: str, sign: float) -> Mat:
    c = world.container(name)
    h = float(c.full_height or 0.0)
    T = np.eye(4)
    T[2, 3] = sign * h / 2.0
    return T


def _need(T: Mat | None, arm: str, obj: str) -> Mat:
    if T is None:
        raise ValueError(f"where the {arm} gripper is must be known to grasp or let go '{obj}'")
    return T
