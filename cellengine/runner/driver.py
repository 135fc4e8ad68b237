"""The driver a run plays on, and the user's word before it moves real arms."""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from cellengine.errors import UsageError

if TYPE_CHECKING:  # the drivers and the motion stack are imported when a run starts
    from cellengine.drivers.base import Driver
    from cellengine.drivers.lab import JointSpec
    from cellengine.motion.robot import CellModel
    from cellengine.pipeline import Compiled


@dataclass(frozen=True)
class DriverOptions:
    """``kind``: a driver instead of the cell's (e.g. "sim"); ``realtime``: the simulated
    cell plays in real time."""

    kind: str | None = None
    realtime: bool = False


def open_driver(
    compiled: Compiled,
    options: DriverOptions,
    q0: Any = None,
    grippers: dict[str, Any] | None = None,
    tares: dict[str, float] | None = None,
    at: int = 0,
) -> Driver:
    """The cell's driver (or ``options.kind``'s), unconfigured. The simulated cell starts
    where the program does, or at ``q0`` with ``grippers`` (where a journal left it); the
    lab bench's load cells keep the zeros ``tares`` (the run's start took them). The arms
    carry the tools the program has them carry at its segment ``at``."""
    from cellengine.drivers.registry import make_driver

    world, cell = compiled.world, compiled.cell
    joints = {name: arm.joint_names for name, arm in cell.arms.items()}
    extra: dict[str, Any] = {}  # the driver class's own options
    program = compiled.program
    if program.changes:  # only a cell with a tool changer: other drivers take no tools
        at = min(at, len(program.segments) - 1)
        extra["tools"] = program.tools_at(program.segments[at].trajectory.start_time)
    if (options.kind or world.cell.driver.kind) == "lab":  # settings checked against these
        extra.update(specs=joint_specs(cell), tares=tares or {})
    if (options.kind or world.cell.driver.kind) == "sim":
        start = compiled.program.segments[0].trajectory.q[0] if q0 is None else q0
        extra.update(realtime=options.realtime, q0=start)
        if grippers is not None:
            extra["grippers"] = grippers
    return make_driver(world.cell, joints, objects=world.objects, kind=options.kind, **extra)


def joint_specs(cell: CellModel) -> dict[str, JointSpec]:
    """Each joint's kind, range and timing limits, by the cell's joint name."""
    from cellengine.drivers.lab import JointSpec

    lim = cell.timing_limits()
    out: dict[str, JointSpec] = {}
    for arm in cell.arms.values():
        for j, joint in enumerate(list(arm.model.joints)[1:]):
            name = arm.joint_names[j]
            i = cell.joint_names.index(name)
            out[name] = JointSpec(
                joint.shortname().startswith("JointModelP"),
                float(lim.lower[i]),
                float(lim.upper[i]),
                float(lim.velocity[i]),
                float(lim.acceleration[i]),
            )
    return out


def confirm(driver: Driver, yes: bool, about: Callable[[], str], quiet: bool = False) -> None:
    """Real arms move only when the user says so: ``yes``, or 'yes' typed at a terminal,
    asked with what the run will do (``about()``: its duration and speeds; said too, unless
    ``quiet``, when ``yes`` was given)."""
    if driver.kind == "sim":
        return
    where = ", ".join(f"{arm} at {ip}" for arm, ip in getattr(driver, "addresses", {}).items())
    if yes:
        if not quiet:
            print(f"moving real arms ({where}): {about()}", file=sys.stderr)
        return
    if not sys.stdin.isatty():
        raise UsageError.at(
            f"refusing to move real arms ({where}) without --yes: no terminal to ask", None
        )
    answer = input(f"This moves real arms: {where}; {about()}. Type 'yes' to go on: ")
    if answer.strip().lower() != "yes":
        raise UsageError.at("not confirmed: nothing moved", None)
