"""The planning context: what every skill family and the compiler plan over, built once per
compile and passed explicitly (no module-level caches keyed by the world).

It holds the loaded world, the robots as pinocchio models, the collision scene of the cell
with its containers where they stand and a checker on it, each arm's inverse kinematics, the
one home configuration, the cell's clearance, a probe of the tools against the environment
(a skill screens its candidate poses with it), and the masses measured so far (a runtime
choice such as ``heavier_of`` picks by them).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

from cellengine.arrays import Mat
from cellengine.info.cell import DEFAULT_CLEARANCE
from cellengine.motion.collision import CollisionChecker
from cellengine.motion.ik import ArmIK, arm_ik
from cellengine.motion.probe import ToolProbe
from cellengine.motion.robot import CellModel, build_cell_model, home_configuration
from cellengine.motion.scene import CollisionScene, build_scene
from cellengine.motion.speed import Speed, resolve
from cellengine.world import World


@dataclass(frozen=True)
class PlanningContext:
    world: World
    cell: CellModel
    scene: CollisionScene  # every container where objects.yaml stands it
    checker: CollisionChecker  # on ``scene``; the compiler attaches held objects to its own
    iks: Mapping[str, ArmIK]  # by arm
    masses: Mapping[str, float] = field(default_factory=lambda: MappingProxyType({}))
    # cell.yaml's clearance (m): the gate's least distance between the arms and from the
    # environment, and the async schedule's between two arms moving on their own
    clearance: float = DEFAULT_CLEARANCE
    # the plan's execution: "sequential" keeps a family's robots to one at a time
    execution: str = "split"
    probe: ToolProbe = field(init=False)  # on ``scene``
    # every tool assignment built so far (world, robot models untimed, scene, checker, IK),
    # by the tool of each arm: shared by the contexts derived from this one
    tooling: dict[tuple[tuple[str, str | None], ...], Tooling] = field(
        default_factory=dict, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "probe", ToolProbe(self.cell, self.scene))

    @property
    def home(self) -> Mat:
        """Every arm at its cell.yaml ``home`` (InputError naming an arm without one)."""
        return home_configuration(self.cell, self.world.cell_file)

    def tcp_home(self, arm: str) -> Mat:
        """T_cell_tcp of ``arm`` at home."""
        return self.cell.arms[arm].fk(self.home[self.cell.slices[arm]])

    def with_masses(self, masses: Mapping[str, float]) -> PlanningContext:
        """The same cell with other measured masses (a replan after a weighing)."""
        return replace(self, masses=MappingProxyType(dict(masses)))

    def with_execution(self, execution: str) -> PlanningContext:
        return self if execution == self.execution else replace(self, execution=execution)

    def tooled(self, tools: Mapping[str, str | None]) -> PlanningContext:
        """The same cell with the arms named in ``tools`` carrying those tools (None: a bare
        flange) and the others theirs: its robot models, scene, checker and IK, built once
        per assignment; timed, weighed and executed as this one."""
        assignment = {**self.world.tools, **tools}
        key = tuple(sorted(assignment.items()))
        if assignment == self.world.tools:
            return self
        if key not in self.tooling:
            self.tooling[key] = _tooling(self.world.with_tools(assignment))
        t = self.tooling[key]
        cell = t.cell.with_speed(self.speed)
        return replace(self, world=t.world, cell=cell, scene=t.scene, checker=t.checker, iks=t.iks)

    def tooled_parts(
        self, tools: Mapping[str, str | None]
    ) -> tuple[World, CellModel, CollisionScene]:
        """:meth:`tooled`'s world, robot models and scene (what a compiler switches to at
        a tool change)."""
        c = self.tooled(tools)
        return c.world, c.cell, c.scene

    @property
    def speed(self) -> Speed:
        """How fast trajectories are timed (the cell model's)."""
        return self.cell.speed

    def with_speed(self, speed: Speed) -> PlanningContext:
        """The same cell timed at ``speed`` (a plan's own, the command line's)."""
        return self if speed == self.speed else replace(self, cell=self.cell.with_speed(speed))


@dataclass(frozen=True)
class Tooling:
    """The parts of a context that depend on the tools the arms carry."""

    world: World
    cell: CellModel
    scene: CollisionScene
    checker: CollisionChecker
    iks: Mapping[str, ArmIK]


def _tooling(world: World) -> Tooling:
    cell = build_cell_model(world)
    scene = build_scene(cell, world)
    iks = MappingProxyType({name: arm_ik(arm) for name, arm in cell.arms.items()})
    return Tooling(world, cell, scene, CollisionChecker(scene), iks)


def build_context(world: World, masses: Mapping[str, float] | None = None) -> PlanningContext:
    """Build the robots, the scene, its checker and the IK of every arm of ``world``."""
    t = _tooling(world)
    ctx = PlanningContext(
        world,
        t.cell.with_speed(resolve(world.cell)),
        t.scene,
        t.checker,
        t.iks,
        MappingProxyType(dict(masses or {})),
        world.cell.clearance,
    )
    ctx.tooling[tuple(sorted(world.tools.items()))] = t
    return ctx
