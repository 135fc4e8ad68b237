"""What each gripper holds, as collision objects riding on its TCP.

A gripper event's ``holds`` names what the gripper holds from then on. The executor keeps the
collision checker's held objects in step: the previous one is detached, the new one attached.

Shapes: a connector (``cable1.connector``) or a container (``vial1``) as the world describes
it (:func:`~cellengine.motion.scene.held_from_world`); anything else, a cable or a piece of
it, is a cube of the cable's diameter at the fingertips (the cable beyond the fingers is slack
and deformable: the executor does not model it). Names are ``<object>@<arm>``, since both hands
can hold one cable.

A held object may touch the platform elements (combs, guides, the connector guide): putting
the cable or the connector into them is the task, with the clearances of a few millimetres the
guides are made with. The arms themselves are still checked against every element.
"""

from __future__ import annotations

import numpy as np

from cellengine.motion.collision import CollisionChecker
from cellengine.motion.scene import HeldObject, held_box, held_from_world
from cellengine.world import RefError, World

DEFAULT_SIZE = 0.01  # m: the cube for an object the world gives no size for


def held_name(arm: str, obj: str) -> str:
    return f"{obj}@{arm}"


def held_object(world: World, checker: CollisionChecker, arm: str, obj: str) -> HeldObject:
    """The collision object for ``obj`` in ``arm``'s gripper, centred at its TCP."""
    allowed = _platform_elements(world, checker)
    name = held_name(arm, obj)
    try:
        shaped = held_from_world(world, obj, arm, np.eye(4), allowed)
        return HeldObject(name, arm, shaped.shape, shaped.T_tcp_object, shaped.allowed)
    except (RefError, ValueError):
        pass  # not a connector or a container: a piece of cable, or an unknown name
    cable = obj.split(".", 1)[0]
    size = DEFAULT_SIZE
    if cable in world.objects.cables:
        size = float(world.objects.cables[cable].diameter)
    return held_box(name, arm, (size, size, size), np.eye(4), allowed)


def _platform_elements(world: World, checker: CollisionChecker) -> frozenset[str]:
    return frozenset(
        s.name for s in checker.scene.statics if s.name.split(".", 1)[0] in world.platforms
    )


class Holding:
    """Each arm's held object, kept in step with a checker's scene."""

    def __init__(self, world: World, checker: CollisionChecker) -> None:
        self.world = world
        self.checker = checker
        self.by_arm: dict[str, str] = {}

    def set(self, arm: str, obj: str | None) -> None:
        """``arm`` holds ``obj`` from now on (None: nothing). ValueError when the object
        cannot ride on the gripper (it intersects the wrist)."""
        if self.by_arm.get(arm) == obj:
            return
        previous = self.by_arm.pop(arm, None)
        if previous is not None:
            self.checker.detach(held_name(arm, previous))
        if obj is not None:
            self.checker.attach(held_object(self.world, self.checker, arm, obj))
            self.by_arm[arm] = obj
