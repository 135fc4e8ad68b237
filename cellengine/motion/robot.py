"""The cell's robots as pinocchio models: each arm at its base pose with its tool's TCP, and
all arms together for one forward kinematics over the whole cell.

Building (:func:`build_arm`, :func:`build_cell_model`) is separate from using: an :class:`Arm`
or :class:`CellModel` is immutable data plus a few evaluation methods, so tests and other
layers can inspect what was built.

Frames: the universe of every model here is the CELL frame. An arm's URDF root link is its
controller base frame (for the built-in UR models, the frame the controller reports TCP poses
in), placed at ``T_cell_base``; ``tool0`` (or the user's ``tip`` link) is the flange; the TCP
frame is ``T_flange_tcp`` from the tool. Names inside the models are prefixed with the robot's
name (``left_shoulder_pan_joint``, ``left_tool0``, ``left_tcp``); collision objects are named
``<robot>/<link>`` (``left/forearm_link``, ``left/forearm_link#2``), the tool's solids
``<robot>/tool`` and ``<robot>/tool/<part>`` (:mod:`cellengine.motion.tool`; every code path
treats them alike through :func:`tool_parts` and :func:`is_tool`).

Limits (SI): position, velocity from the URDF. Acceleration: URDF has none. For the built-in
UR models it is :data:`UR_ACCELERATION`, 5 rad/s^2 on every joint, the value Universal Robots'
own MoveIt configuration (ur_moveit_config joint_limits.yaml) uses, "chosen conservatively";
the arms themselves are limited by torque, not by a published acceleration. For a user URDF
it is :data:`ACCELERATION_PER_VELOCITY` times the velocity limit (full speed in 0.5 s).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from types import MappingProxyType
from typing import Any, Literal

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from cellengine.arrays import Mat, Vec
from cellengine.errors import InputError, Problem, known
from cellengine.info.cell import Robot, Tool, UrdfModel
from cellengine.info.files import resolve_inside
from cellengine.info.units import Units
from cellengine.info.yamlio import load_yaml
from cellengine.motion.speed import Speed
from cellengine.motion.tool import DEFAULT_FINGER_WIDTH as DEFAULT_FINGER_WIDTH
from cellengine.motion.tool import TOOL_GEOMETRY as TOOL_GEOMETRY
from cellengine.motion.tool import Fingers, Solid, fingers_of, tool_solids
from cellengine.motion.tool import is_tool as is_tool
from cellengine.motion.ur_ik import DH, UR_DH
from cellengine.motion.urdf import (
    Urdf,
    build_geometry,
    build_model,
    check_chain,
    mesh_hull,
    read_urdf,
)
from cellengine.world import World

BUILTIN_DIR = Path(__file__).resolve().parent / "urdf"
BUILTIN_TIP = "tool0"
UR_ACCELERATION: dict[str, tuple[float, ...]] = {
    "ur3e": (5.0,) * 6,
    "ur5e": (5.0,) * 6,
    "ur10e": (5.0,) * 6,
    "ur5": (5.0,) * 6,
}
ACCELERATION_PER_VELOCITY = 2.0  # 1/s: a user URDF's joints reach full speed in 0.5 s
TCP_FRAME = "tcp"


def builtin_urdf(model: str) -> Path:
    """The shipped URDF of a built-in model (``ur5e``, ...)."""
    if model not in UR_DH:
        raise KeyError(f"unknown built-in robot model '{model}'" + known(UR_DH))
    return BUILTIN_DIR / f"{model}.urdf"


@dataclass(frozen=True)
class Limits:
    """Per-joint limits, SI (rad or m; /s; /s^2); read-only (n,) arrays."""

    lower: Vec
    upper: Vec
    velocity: Vec
    acceleration: Vec

    def __post_init__(self) -> None:
        n = len(self.lower)
        for name in ("lower", "upper", "velocity", "acceleration"):
            a = np.array(getattr(self, name), dtype=float)
            if a.shape != (n,):
                raise ValueError(f"limits: {name} has shape {a.shape}, expected ({n},)")
            a.setflags(write=False)
            object.__setattr__(self, name, a)

    @staticmethod
    def concatenate(parts: Sequence[Limits]) -> Limits:
        """The limits of several arms, one after the other (a cell's q)."""
        names = [f.name for f in fields(Limits)]
        return Limits(*(np.concatenate([getattr(p, k) for p in parts]) for k in names))


@dataclass(frozen=True, eq=False)
class Arm:
    """One robot of the cell. Evaluation methods share one pinocchio Data: not thread-safe."""

    name: str
    joint_names: tuple[str, ...]  # prefixed: 'left_shoulder_pan_joint'
    model: Any  # pin.Model of the arm alone; universe = the cell frame
    collision: Any  # pin.GeometryModel: the arm's links and its tool
    tool0: int  # frame id of the flange in `model`
    tcp: int  # frame id of the tool's TCP in `model`
    limits: Limits
    T_cell_base: Mat
    T_flange_tcp: Mat
    dh: DH | None  # the DH table of a built-in UR model (closed-form IK), else None
    home: Vec | None = None  # cell.yaml's home configuration, if given
    fingers: Fingers | None = None  # the tool's fingers, held in `collision` at their widest
    _data: Any = field(init=False, repr=False, compare=False)
    # its inverse kinematics, built on first use by motion.ik.arm_ik (which owns the type)
    solver: Any = field(init=False, default=None, repr=False, compare=False)

    def __post_init__(self) -> None:
        for name in ("T_cell_base", "T_flange_tcp"):
            a = np.array(getattr(self, name), dtype=float)
            a.setflags(write=False)
            object.__setattr__(self, name, a)
        object.__setattr__(self, "_data", self.model.createData())

    @property
    def nq(self) -> int:
        return int(self.model.nq)

    def fk(self, q: ArrayLike) -> Mat:
        """T_cell_tcp at ``q``."""
        return self._placement(q, self.tcp)

    def fk_flange(self, q: ArrayLike) -> Mat:
        """T_cell_flange at ``q``."""
        return self._placement(q, self.tool0)

    def jacobian(self, q: ArrayLike, frame: Literal["tcp", "flange"] = "tcp") -> Mat:
        """(6, n): rows 0-2 the frame origin's linear velocity, 3-5 its angular velocity, both
        in cell axes (pinocchio's LOCAL_WORLD_ALIGNED), per unit joint velocity."""
        frame_id = {"tcp": self.tcp, "flange": self.tool0}[frame]
        J = pin.computeFrameJacobian(
            self.model, self._data, self._q(q), frame_id, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        )
        return np.array(J).reshape(6, -1)  # pinocchio gives a one-joint arm's as 1-D

    def _placement(self, q: ArrayLike, frame_id: int) -> Mat:
        pin.forwardKinematics(self.model, self._data, self._q(q))
        return np.array(pin.updateFramePlacement(self.model, self._data, frame_id).homogeneous)

    def _q(self, q: ArrayLike) -> Vec:
        qa = np.asarray(q, dtype=float)
        if qa.shape != (self.nq,):
            raise ValueError(f"arm '{self.name}': q has shape {qa.shape}, expected ({self.nq},)")
        return qa


@dataclass(frozen=True, eq=False)
class CellModel:
    """Every arm of the cell in one model; q is the arms' q's in ``arms`` order."""

    arms: Mapping[str, Arm]
    model: Any  # pin.Model: all arms appended (pin.appendModel)
    collision: Any  # pin.GeometryModel: all arms' geometry, named '<robot>/<link>'
    joint_names: tuple[str, ...]
    slices: Mapping[str, slice]  # each arm's entries of the cell's q
    tool0: Mapping[str, int]  # each arm's flange frame id in `model`
    tcp: Mapping[str, int]  # each arm's TCP frame id in `model`
    # how fast trajectories are timed (the plan's speed); ``limits`` stay the arms' own
    speed: Speed = field(default_factory=Speed)

    @property
    def nq(self) -> int:
        return int(self.model.nq)

    @property
    def limits(self) -> Limits:
        """The arms' own limits: what the gate checks."""
        return Limits.concatenate([a.limits for a in self.arms.values()])

    def timing_limits(self, arm: str | None = None) -> Limits:
        """The limits trajectories are timed with, of ``arm`` (default: the whole cell):
        velocity and acceleration scaled by ``speed``."""
        own = self.limits if arm is None else self.arms[arm].limits
        if self.speed.velocity == 1.0 and self.speed.acceleration == 1.0:
            return own
        v, a = own.velocity * self.speed.velocity, own.acceleration * self.speed.acceleration
        return Limits(own.lower, own.upper, v, a)

    def with_speed(self, speed: Speed) -> CellModel:
        """The same arms timed at ``speed``."""
        return replace(self, speed=speed)

    def split(self, q: ArrayLike) -> dict[str, Vec]:
        qa = np.asarray(q, dtype=float)
        if qa.shape != (self.nq,):
            raise ValueError(f"q has shape {qa.shape}, expected ({self.nq},)")
        return {name: qa[s].copy() for name, s in self.slices.items()}

    def join(self, qs: Mapping[str, ArrayLike]) -> Vec:
        if set(qs) != set(self.arms):
            raise ValueError(f"join needs exactly the arms {sorted(self.arms)}, got {sorted(qs)}")
        out = np.empty(self.nq)
        for name, s in self.slices.items():
            part = np.asarray(qs[name], dtype=float)
            if part.shape != (s.stop - s.start,):
                raise ValueError(f"arm '{name}': q has shape {part.shape}")
            out[s] = part
        return out


def home_configuration(cell: CellModel, cell_file: Path | None = None) -> Vec:
    """Every arm at its cell.yaml ``home``: where a program starts, and the one configuration
    of the cell called home (reach tests, the arms' rests, a report without motion). An arm
    without one is an error at its robot in ``cell_file`` when given."""
    missing = [name for name, arm in cell.arms.items() if arm.home is None]
    if missing:
        message = (
            f"robots.{missing[0]}.home is not given: a program needs every arm's start "
            "configuration"
        )
        if cell_file is not None:
            raise _cell_error(cell_file, message, ("robots", missing[0]))
        raise InputError.at(message, None)
    return cell.join({name: np.asarray(arm.home) for name, arm in cell.arms.items()})


# ---------------------------------------------------------------------------------- building


def build_cell_model(world: World) -> CellModel:
    """Every robot of the world's cell; every problem of every robot reported together."""
    cell = world.cell
    arms: dict[str, Arm] = {}
    problems: list[Problem] = []
    for name, robot in cell.robots.items():
        tool = cell.tools.get(robot.tool) if robot.tool is not None else None
        try:
            arms[name] = build_arm(name, robot, tool, world.cell_file, cell.units)
        except InputError as e:
            problems.extend(e.problems)
    if problems:
        raise InputError(problems)
    return assemble(arms)


def assemble(arms: Mapping[str, Arm]) -> CellModel:
    """Append the arms (already in the cell frame) into one model and one geometry model."""
    model, geom = pin.Model(), pin.GeometryModel()
    for arm in arms.values():
        model, geom = pin.appendModel(model, arm.model, geom, arm.collision, 0, pin.SE3.Identity())
    slices: dict[str, slice] = {}
    for name, arm in arms.items():
        first = model.joints[model.getJointId(arm.joint_names[0])].idx_q
        last = model.joints[model.getJointId(arm.joint_names[-1])].idx_q
        slices[name] = slice(first, last + 1)
    return CellModel(
        MappingProxyType(dict(arms)),
        model,
        geom,
        tuple(str(n) for n in list(model.names)[1:]),
        MappingProxyType(slices),
        MappingProxyType({n: model.getFrameId(_frame_name(a, a.tool0)) for n, a in arms.items()}),
        MappingProxyType({n: model.getFrameId(_frame_name(a, a.tcp)) for n, a in arms.items()}),
    )


def _frame_name(arm: Arm, frame_id: int) -> str:
    return str(arm.model.frames[frame_id].name)


def parked_solids(world: World, tool: str, T_cell_flange: Mat) -> list[tuple[str, Mat, Any]]:
    """``tool``'s solids seated in its changer slot, (name, T_cell_solid, coal shape), the
    fingers at their widest; named ``<tool>@slot`` (``#2``, ``#3``... for its others)."""
    spec = world.cell.tools[tool]
    read = mesh_reader(world.cell_file, tool, world.cell.units)
    solids = tool_solids(spec, spec.tcp.matrix(), read)
    name = parked_name(tool)
    return [
        (name + (f"#{k + 1}" if k else ""), T_cell_flange @ s.T_flange_solid, s.shape)
        for k, s in enumerate(solids)
    ]


def parked_name(tool: str) -> str:
    """The scene's name of ``tool`` waiting in its slot."""
    return f"{tool}@slot"


def build_arm(
    name: str, robot: Robot, tool: Tool | None, cell_file: Path, units: Units | None = None
) -> Arm:
    """One robot of ``cell_file``'s cell: its URDF (built-in or the user's, resolved inside
    the cell folder), placed at its base pose, with its tool's TCP frame and collision solids."""
    prefix = f"{name}_"
    units = units or Units()
    if isinstance(robot.model, UrdfModel):
        try:
            path = resolve_inside(cell_file.parent, robot.model.urdf, cell_file)
        except InputError as e:  # load_cell checked it already; the file may have gone since
            loc = ("robots", name, "model", "urdf")
            raise _cell_error(cell_file, e.problems[0].message, loc) from None
        urdf, tip, dh = read_urdf(path, cell_file.parent), robot.model.tip, None
        if tip not in urdf.links:
            raise _cell_error(
                cell_file,
                f"robots.{name}.model.tip: unknown link '{tip}' in {robot.model.urdf}"
                + known(urdf.links),
                ("robots", name, "model", "tip"),
            )
    else:
        path = builtin_urdf(robot.model)
        urdf, tip, dh = read_urdf(path, BUILTIN_DIR), BUILTIN_TIP, UR_DH[robot.model]
    raw = build_model(urdf, tip, prefix)
    tool0 = raw.getFrameId(prefix + tip, pin.FrameType.BODY)
    T_flange_tcp = tool.tcp.matrix() if tool is not None else np.eye(4)
    _add_tcp_frame(raw, urdf, prefix, tool0, T_flange_tcp)
    geom = build_geometry(raw, urdf, prefix, name)
    fingers = None
    if tool is not None and robot.tool is not None:
        read = mesh_reader(cell_file, robot.tool, units)
        _add_tool_geometry(raw, geom, tool0, tool_solids(tool, T_flange_tcp, read), name)
        fingers = fingers_of(tool, T_flange_tcp)
    T_cell_base = robot.base.matrix()
    model, collision = pin.appendModel(
        pin.Model(), raw, pin.GeometryModel(), geom, 0, pin.SE3(T_cell_base)
    )
    joint_names = tuple(str(n) for n in list(model.names)[1:])
    limits = _limits(urdf, tip, robot)
    return Arm(
        name=name,
        joint_names=joint_names,
        model=model,
        collision=collision,
        tool0=model.getFrameId(prefix + tip, pin.FrameType.BODY),
        tcp=model.getFrameId(prefix + TCP_FRAME, pin.FrameType.OP_FRAME),
        limits=limits,
        T_cell_base=T_cell_base,
        T_flange_tcp=T_flange_tcp,
        dh=dh,
        home=_home(robot, name, joint_names, cell_file, model, units, limits),
        fingers=fingers,
    )


def _add_tcp_frame(model: Any, urdf: Urdf, prefix: str, tool0: int, T_flange_tcp: Mat) -> None:
    name = prefix + TCP_FRAME
    if TCP_FRAME in urdf.links or TCP_FRAME in urdf.joints:
        raise InputError.at(
            f"the URDF names a link or joint '{TCP_FRAME}', which cellengine keeps for the "
            "tool's TCP frame; rename it",
            urdf.file,
        )
    flange = model.frames[tool0]
    placement = flange.placement * pin.SE3(T_flange_tcp)
    model.addFrame(pin.Frame(name, flange.parentJoint, tool0, placement, pin.FrameType.OP_FRAME))


def _add_tool_geometry(
    model: Any, geom: Any, tool0: int, solids: Sequence[Solid], owner: str
) -> None:
    """The tool's solids on the flange's joint."""
    flange = model.frames[tool0]
    for s in solids:
        placement = flange.placement * pin.SE3(s.T_flange_solid)
        geom.addGeometryObject(
            pin.GeometryObject(f"{owner}/{s.name}", flange.parentJoint, tool0, placement, s.shape)
        )


def mesh_reader(cell_file: Path, tool_name: str, units: Units) -> Callable[[str], Any]:
    """Reads a tool's mesh (inside the cell folder, in the file's length unit) as its hull."""

    def read(ref: str) -> Any:
        loc = ("tools", tool_name, "mesh")
        try:
            path = resolve_inside(cell_file.parent, ref, cell_file)
        except InputError as e:
            raise _cell_error(cell_file, e.problems[0].message, loc) from None
        scale = (units.context()["length"],) * 3
        return mesh_hull(path, ref, scale, cell_file, _where(cell_file, loc)[0])

    return read


def tool_parts(arm: Arm) -> tuple[str, ...]:
    """The names of ``arm``'s tool's collision objects (``left/tool``, ``left/tool/...``)."""
    names = (str(o.name) for o in arm.collision.geometryObjects)
    return tuple(n for n in names if is_tool(n, arm.name))


def contact_parts(arm: Arm) -> tuple[str, ...]:
    """What of ``arm`` touches what it works on: its tool's collision objects, or, for a
    bare flange (an arm between two tools), the link objects the flange is on."""
    parts = tool_parts(arm)
    if parts:
        return parts
    joint = arm.model.frames[arm.tool0].parentJoint
    return tuple(str(o.name) for o in arm.collision.geometryObjects if o.parentJoint == joint)


def finger_placements(arm: Arm, opening: float) -> dict[str, Any]:
    """Object name -> placement (pin.SE3, in the flange's joint frame) of ``arm``'s fingers at
    ``opening``; empty for a tool without fingers."""
    if arm.fingers is None:
        return {}
    T_joint_flange = arm.model.frames[arm.tool0].placement
    return {
        f"{arm.name}/{name}": T_joint_flange * pin.SE3(T)
        for name, T in zip(arm.fingers.names, arm.fingers.placements(opening), strict=True)
    }


def _limits(urdf: Urdf, tip: str, robot: Robot) -> Limits:
    joints = check_chain(urdf, tip)
    lower = [-math.tau if j.type == "continuous" else float(j.lower or 0.0) for j in joints]
    upper = [math.tau if j.type == "continuous" else float(j.upper or 0.0) for j in joints]
    velocity = [float(j.velocity or 0.0) for j in joints]
    if isinstance(robot.model, str):
        acceleration = list(UR_ACCELERATION[robot.model])
    else:
        acceleration = [ACCELERATION_PER_VELOCITY * v for v in velocity]
    return Limits(np.array(lower), np.array(upper), np.array(velocity), np.array(acceleration))


def _home(
    robot: Robot,
    name: str,
    joints: Sequence[str],
    cell_file: Path,
    model: Any,
    units: Units,
    limits: Limits,
) -> Vec | None:
    if robot.home is None:
        return None
    n = len(joints)
    if len(robot.home) != n:
        raise _cell_error(
            cell_file,
            f"robots.{name}.home: the robot has {n} joints, got {len(robot.home)} values",
            ("robots", name, "home"),
        )
    home = np.array(robot.home, dtype=float)
    # cell.yaml converts home with the angle unit, before joint types are known; a prismatic
    # axis's value is a length: undo the angle factor and apply the length factor.
    ctx = units.context()
    factor = np.full(n, ctx["angle"])  # the file's unit -> rad or m, per joint
    for i, joint in enumerate(list(model.joints)[1:]):
        if "Prismatic" in joint.shortname() or joint.shortname().startswith("JointModelP"):
            home[i] *= ctx["length"] / ctx["angle"]
            factor[i] = ctx["length"]
    # an arm that starts outside its limits cannot move at all (radians in a degree file)
    out = np.flatnonzero((home < limits.lower - 1e-9) | (home > limits.upper + 1e-9))
    if len(out):
        i = int(out[0])
        lo, hi = limits.lower[i] / factor[i], limits.upper[i] / factor[i]
        raise _cell_error(
            cell_file,
            f"robots.{name}.home[{i}]: {joints[i]} at {home[i] / factor[i]:.6g} is outside "
            f"its limits [{lo:.6g}, {hi:.6g}] (in the file's units)",
            ("robots", name, "home", i),
        )
    home.setflags(write=False)
    return home


def _where(cell_file: Path, loc: tuple[str | int, ...]) -> tuple[int | None, int | None]:
    """Line and column of ``loc`` in the cell file: read again only when reporting."""
    try:
        pos = load_yaml(cell_file).where(loc)
    except InputError:
        return None, None
    return pos if pos else (None, None)


def _cell_error(cell_file: Path, message: str, loc: tuple[str | int, ...]) -> InputError:
    return InputError.at(message, cell_file, *_where(cell_file, loc))
