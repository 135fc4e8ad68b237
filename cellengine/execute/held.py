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

from weakref import WeakKeyDictionary

import numpy as np

from cellengine.motion.collision import CollisionChecker
from cellengine.motion.scene import CollisionScene, HeldObject, attach, held_box, held_from_world
from cellengine.world import RefError, World

DEFAULT_SIZE = 0.01  # m: the cube for an object the world gives no size for


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
    if cable in world.objects.cables:
        size = float(world.objects.cables[cable].diameter)
    return held_box(name, arm, (size, size, size), np.eye(4), allowed)


def _platform_elements(world: World, scene: CollisionScene) -> frozenset[str]:
    return frozenset(s.name for s in scene.statics if s.name.split(".", 1)[0] in world.platforms)


# Scenes with held objects, per base scene and per set of held objects: a grasp-release cycle
# comes back to the same sets, and assembling a scene costs far more than a checker on it.
_SCENES: WeakKeyDictionary[CollisionScene, dict[tuple[tuple[str, str], ...], CollisionScene]] = (
    WeakKeyDictionary()
)


class Holding:
    """Each arm's held object, and a checker whose scene holds them (``checker``: a new one
    whenever what is held changes; the base scene is never changed)."""

    def __init__(self, world: World, scene: CollisionScene) -> None:
        self.world = world
        self.base = scene
        self.by_arm: dict[str, str] = {}
        self.checker = CollisionChecker(scene)

    def set(self, arm: str, obj: str | None) -> None:
        """``arm`` holds ``obj`` from now on (None: nothing). ValueError when the object
        cannot ride on the gripper (it intersects the wrist)."""
        if self.by_arm.get(arm) == obj:
            return
        held = dict(self.by_arm)
        held.pop(arm, None)
        if obj is not None:
            held[arm] = obj
        key = tuple(sorted(held.items()))
        scenes = _SCENES.setdefault(self.base, {})
        if key not in scenes:
            scenes[key] = self._scene(key)
        self.by_arm = held
        self.checker = CollisionChecker(scenes[key])

    def _scene(self, key: tuple[tuple[str, str], ...]) -> CollisionScene:
        scene = self.base
        for arm, obj in key:
            scene = attach(scene, held_object(self.world, scene, arm, obj))
        return scene
