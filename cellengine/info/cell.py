"""cell.yaml (DESIGN 3.1): robots, tools, platforms, obstacles, driver."""

from __future__ import annotations

from collections.abc import Sequence
from ipaddress import IPv4Address
from typing import Annotated, Literal

from pydantic import Field, StringConstraints, field_validator, model_validator

from cellengine.arrays import Mat
from cellengine.info.camera import Camera
from cellengine.info.pose import Pose
from cellengine.info.speed import SpeedSpec
from cellengine.info.units import Angle, Frozen, Length, Mass, Units, Vec3Angle, Vec3Length

# Names become parts of dotted references (platform.element.keypoint): no dots, no spaces.
Name = Annotated[str, StringConstraints(pattern=r"^[A-Za-z_][A-Za-z0-9_-]*$")]

BUILTIN_ROBOTS = ("ur3e", "ur5", "ur5e", "ur10e")
# Robots in one cell. Its tasks take one or two arms, and the collision model checks every
# link of every arm against every other, with each pair's motion per joint of the cell: that
# grows with the cube of the count (40 robots: 10 s and 1 GB before a plan is looked at).
# Refused at loading, before any of it is built.
MAX_ROBOTS = 8
# m: the least distance between the arms, and from an arm to what it is not meant to touch
DEFAULT_CLEARANCE = 0.010
DEFAULT_WORK_CLEARANCE = 0.005


class UrdfModel(Frozen):
    urdf: str  # path inside the cell folder
    tip: str  # the flange link


class Robot(Frozen):
    model: str | UrdfModel
    base: Pose = Pose()  # controller base frame in the cell frame
    tool: str | None = None
    # angle units here; build_cell_model rescales prismatic axes to the length unit
    home: tuple[Angle, ...] | None = None
    srdf: str | None = None  # an SRDF whose <disable_collisions> pairs are never checked


class Cylinder(Frozen):
    radius: Length = Field(gt=0)
    length: Length = Field(gt=0)


class ToolPart(Frozen):
    """One solid of a tool, in the flange frame: a box or a cylinder (its axis along the
    part's z), centred at ``pose``."""

    name: Name | None = None
    box: Vec3Length | None = None
    cylinder: Cylinder | None = None
    pose: Pose = Pose()

    @model_validator(mode="after")
    def _one_shape(self) -> ToolPart:
        given = [k for k in ("box", "cylinder") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "give exactly one shape of box, cylinder" + (" (got both)" if given else "")
            )
        if self.box is not None and min(self.box) <= 0:
            raise ValueError("box sizes must be greater than 0")
        return self


class Fingers(Frozen):
    """Two boxes ``size`` = (thickness along x, width along y, length along z) whose inner
    faces are jaw[mode]/2 either side of the TCP along its y (the jaw axis), ending at the
    TCP along its z."""

    size: Vec3Length

    @model_validator(mode="after")
    def _positive(self) -> Fingers:
        if min(self.size) <= 0:
            raise ValueError("finger sizes must be greater than 0")
        return self


FINGER_NAMES = ("finger_left", "finger_right")  # +y, -y of the TCP


class ToolSlot(Frozen):
    """Where a tool waits in an automatic tool changer (ATC) while no arm carries it.

    ``at``: the flange's pose when the tool is seated and locked in its slot, as a keypoint
    (platform.element[.keypoint]: that element is the station) or a pose in the cell frame.
    ``exit``: offsets in the slot frame, in order, that a seated tool leaves its slot
    through on the arm (reversed to put it back). ``retreat``: the offsets the bare flange
    leaves a seated tool through (reversed to take it)."""

    at: str | Pose
    exit: tuple[Vec3Length, ...] = Field(min_length=1)
    retreat: tuple[Vec3Length, ...] = Field(min_length=1)


class Tool(Frozen):
    kind: Literal["parallel_gripper", "taping_gun"]
    tcp: Pose = Pose()  # fingertip centre in the flange frame
    finger_width: Length | None = Field(None, gt=0)
    finger_thickness: Length | None = Field(None, gt=0)
    jaw: dict[Name, Annotated[Length, Field(ge=0)]] = {}
    # The collision shape: a mesh (path inside the cell folder; its convex hull, its
    # coordinates in the file's length unit, in the flange frame), parts and fingers, in that
    # order. None of them: a box from the flange to the TCP, finger_width square.
    mesh: str | None = None
    shape: tuple[ToolPart, ...] | None = None
    fingers: Fingers | None = None
    mass: Mass | None = Field(None, ge=0)
    # How the fingers meet an upright object: from above (the tool's z down) or from the
    # side (the tool's z horizontal). Lab skills choose grasps by it.
    grasp: Literal["top", "side"] = "top"
    load_cell: bool = False  # the tool weighs what it holds (gives the Weigh skill)
    slot: ToolSlot | None = None  # its place in the tool changer: arms change to and from it
    # a taping gun's working time per trigger (s): the arms stand still while it tapes
    dwell: float | None = Field(None, gt=0, le=600)

    @model_validator(mode="after")
    def _parts(self) -> Tool:
        if self.shape == ():
            raise ValueError("shape: give at least one part, or leave shape out")
        if self.fingers is not None and not self.jaw:
            raise ValueError("fingers need the jaw's openings (jaw: {open: ..., ...})")
        if (self.kind == "taping_gun") != (self.dwell is not None):
            raise ValueError(
                "a taping_gun needs dwell (s it tapes for)"
                if self.kind == "taping_gun"
                else f"dwell is a taping_gun's; a {self.kind} has none"
            )
        names = [p.name or f"part{k + 1}" for k, p in enumerate(self.shape or ())]
        names += list(FINGER_NAMES) if self.fingers is not None else []
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ValueError(f"shape: part name '{twice[0]}' is used twice")
        return self


class ElementPose(Frozen):
    """An element's pose over what the CAD says: a guide moved on the real board, a layout
    being compared. ``xyz``, ``rpy``: in its platform's frame; ``move``: a shift in the
    cell's frame (the frame `cellengine show` prints keypoints in), after those. What is
    not given is the CAD's."""

    xyz: Vec3Length | None = None
    rpy: Vec3Angle | None = None
    move: Vec3Length | None = None


class PlatformSpec(Frozen):
    pose: Pose = Pose()
    format: Literal["x3d", "remodel"] = "x3d"
    cad: str
    models: str
    map: str | None = None  # x3d: the mapping CSV
    ids: str | None = None  # remodel: the *_ids.wri file
    up: Literal["y", "z"] = "y"
    elements: dict[Name, ElementPose] = {}

    @model_validator(mode="after")
    def _files_for_format(self) -> PlatformSpec:
        need, other = ("map", "ids") if self.format == "x3d" else ("ids", "map")
        if getattr(self, need) is None:
            raise ValueError(f"format '{self.format}' needs '{need}'")
        if getattr(self, other) is not None:
            raise ValueError(f"'{other}' is not used by format '{self.format}'; remove it")
        return self


class Sphere(Frozen):
    radius: Length = Field(gt=0)


class Obstacle(Frozen):
    box: Vec3Length | None = None
    cylinder: Cylinder | None = None
    sphere: Sphere | None = None
    pose: Pose = Pose()

    @model_validator(mode="after")
    def _one_shape(self) -> Obstacle:
        given = [k for k in ("box", "cylinder", "sphere") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ValueError(
                "give exactly one shape of box, cylinder, sphere"
                + (f" (got {', '.join(given)})" if given else "")
            )
        if self.box is not None and min(self.box) <= 0:
            raise ValueError("box sizes must be greater than 0")
        return self


class Zone(Frozen):
    """A box of the cell frame where only ``robots`` may work: one robot's private zone, or
    a zone shared by several, which one robot at a time enters unless they cooperate."""

    min: Vec3Length
    max: Vec3Length
    robots: tuple[Name, ...] = Field(min_length=1)
    # keypoints (platform.element[.keypoint]) of a shared zone: where one robot puts an
    # object down for another (handover, cooperation mode 1), and where two robots meet to
    # work on one object together (cooperation mode 2)
    handovers: tuple[str, ...] = ()
    cooperation: tuple[str, ...] = ()
    # keypoints where anything may be put down out of the way: a cap screwed off, an object
    # moved so that another can be grasped
    free: tuple[str, ...] = ()

    @model_validator(mode="after")
    def _ordered(self) -> Zone:
        if not all(lo < hi for lo, hi in zip(self.min, self.max, strict=True)):
            raise ValueError("each of min's x, y, z must be below max's")
        if len(set(self.robots)) != len(self.robots):
            raise ValueError("robots: a robot is named twice")
        return self

    def contains(self, p: Sequence[float] | Mat) -> bool:
        """Whether the point ``p`` (cell frame, m) is inside, faces included."""
        return all(lo <= float(v) <= hi for lo, v, hi in zip(self.min, p, self.max, strict=True))


class SimDriver(Frozen):
    kind: Literal["sim"]
    # the simulated load cell's standard deviation (the cell's stated noise)
    mass_noise: Mass = Field(0.0, ge=0)


class Servo(Frozen):
    """servoJ's smoothing, within the ranges the UR controller accepts."""

    gain: float = Field(300.0, ge=100.0, le=2000.0)
    lookahead: float = Field(0.1, ge=0.03, le=0.2)  # s


class UrRtdeDriver(Frozen):
    kind: Literal["ur_rtde"]
    arms: dict[Name, IPv4Address]
    servo: Servo = Servo()
    # largest deviation (angle unit) of a measured joint from its command before both arms stop
    tracking_tolerance: Angle = Field(0.05, gt=0)
    # largest distance (angle unit) of a joint from the plan's first point at the start
    start_tolerance: Angle = Field(0.01, gt=0)
    # the run moves the arms to the plan's start (or, resumed, to the next segment's) on its
    # own only when no joint is farther than this (angle unit) from it; else it is refused
    start_move_limit: Angle = Field(0.5, gt=0)
    # a segment may take this many times its duration, plus overrun_margin s, before it is
    # stopped as overrun (a controller slows the arms with its speed slider)
    overrun_scale: float = Field(1.5, ge=1.0)
    overrun_margin: float = Field(1.0, ge=0.0)
    # the grippers: the standard digital outputs high in each jaw mode (the others listed
    # for any mode are set low)
    gripper_io: dict[Name, tuple[Annotated[int, Field(ge=0, le=7)], ...]] = {}
    # the tool changer: the standard digital output that, high, releases its lock (low
    # locks it; REMODEL sets its IO 10026 to 1 to release)
    changer_release: Annotated[int, Field(ge=0, le=7)] | None = None
    # the tools that work on a trigger (a taping gun): the standard digital output high
    # while the tool works, by tool
    trigger_io: dict[Name, Annotated[int, Field(ge=0, le=7)]] = {}


class GrblAxis(Frozen):
    """One joint of a cartesian robot as one GRBL axis: GRBL's machine position (mm; a
    rotary axis in degrees) = ``offset`` + ``sign`` x the joint's value (mm or deg)."""

    letter: Literal["X", "Y", "Z", "A"]
    sign: Literal[-1, 1] = 1
    offset: float = Field(0.0, allow_inf_nan=False)  # GRBL's units (mm, deg)


MAX_XM430_MA = 3209.0  # the XM430-W350's current limit (1193 x 2.69 mA)


class DynamixelGripper(Frozen):
    """A gripper turned by a Dynamixel XL430 (Protocol 2.0, a U2D2 on USB)."""

    port: str = Field(min_length=1)  # grippers on one bus share it
    baud: int = Field(57600, gt=0)
    id: int = Field(ge=0, le=252)
    positions: dict[Name, int] = Field(min_length=1)  # jaw mode -> goal position (ticks)
    holding: tuple[Name, ...] = ("grasp",)  # modes that close on something
    load: int = Field(200, ge=0, le=1000)  # 0.1 %: what a holding mode holds with at least
    timeout: float = Field(2.0, gt=0)  # s for a mode to take
    model: Literal["xl430", "xm430"] = "xl430"  # XL430-W250, or XM430-W350 (current sensing)
    # jaw mode -> the most current it squeezes with (mA): an XM430 in current-based position
    # control (its grasp confirmed by pressing with 80 % of it)
    currents: dict[Name, float] = {}

    @model_validator(mode="after")
    def _currents(self) -> DynamixelGripper:
        if self.currents and self.model != "xm430":
            raise ValueError("currents need a servo that senses current: model: xm430")
        unknown = sorted(set(self.currents) - set(self.positions))
        if unknown:
            raise ValueError(f"currents for mode(s) {', '.join(unknown)} without a position")
        bad = [m for m, v in self.currents.items() if not 0 < v <= MAX_XM430_MA]
        if bad:
            raise ValueError(f"currents.{bad[0]} must be more than 0 and at most {MAX_XM430_MA} mA")
        return self


class DynamixelJoint(Frozen):
    """A rotation joint turned by a Dynamixel XL430 (Protocol 2.0) instead of a GRBL axis:
    the servo's position (ticks) = ``zero`` + ``sign`` x the joint's angle x 4096 / turn."""

    port: str = Field(min_length=1)  # servos and grippers on one bus share it
    baud: int = Field(57600, gt=0)
    id: int = Field(ge=0, le=252)
    sign: Literal[-1, 1] = 1
    zero: int = Field(2048, ge=-(2**20), le=2**20)


class SerialLoadCell(Frozen):
    """A load cell whose Arduino prints one reading a line on USB serial."""

    port: str = Field(min_length=1)
    baud: int = Field(9600, gt=0)
    unit: Literal["mg", "g", "kg"] = "g"  # of the readings without one
    readings: int = Field(5, ge=1, le=100)  # a weighing is their median
    settle: float = Field(0.5, ge=0)  # s after the arm stops before reading
    timeout: float = Field(2.0, gt=0)  # s without a reading is a fault


class GrblRobot(Frozen):
    """A cartesian robot's GRBL controller (an Arduino on USB serial), its gripper and its
    load cell."""

    port: str = Field(min_length=1)  # e.g. /dev/ttyACM0
    baud: int = Field(115200, gt=0)
    axes: dict[Name, GrblAxis] = Field(min_length=1)  # the robot's joints (URDF names)
    # joints turned by Dynamixel servos instead (a gripper's roll or turn)
    servos: dict[Name, DynamixelJoint] = {}
    # activate runs GRBL's homing cycle ($H); else an alarm at activation is refused unless
    # unlock says to clear it ($X)
    home: bool = False
    unlock: bool = False
    gripper: DynamixelGripper | None = None
    load_cell: SerialLoadCell | None = None

    @model_validator(mode="after")
    def _one_drive_each(self) -> GrblRobot:
        both = sorted(set(self.axes) & set(self.servos))
        if both:
            raise ValueError(f"joint(s) {', '.join(both)} both in axes and in servos: give one")
        ids = [s.id for s in self.servos.values()] + ([self.gripper.id] if self.gripper else [])
        if len(set(ids)) != len(ids):
            raise ValueError("two servos (joints or gripper) share a Dynamixel id")
        return self


class LabDriver(Frozen):
    """The lab bench's hardware: each cartesian robot's axes on its own GRBL controller."""

    kind: Literal["lab"]
    robots: dict[Name, GrblRobot] = Field(min_length=1)
    # largest distance (length unit) of an axis from the plan (at any moment within 0.25 s)
    # before both robots stop; a rotary axis' (angle unit). GRBL reports where it has
    # stepped to, not an encoder's reading: this catches a controller off the plan's time
    # (a feed override, a hold), not a stalled motor
    tracking_tolerance: Length = Field(0.01, gt=0)
    tracking_tolerance_rotary: Angle = Field(0.1, gt=0)
    # largest distance of an axis from a segment's first point at its start
    start_tolerance: Length = Field(0.0005, gt=0)
    # the run moves the robots to the plan's start on its own only from this near
    start_move_limit: Length = Field(0.05, gt=0)
    status_hz: float = Field(20.0, ge=10.0, le=100.0)  # status reports asked for per second


DriverSpec = Annotated[SimDriver | UrRtdeDriver | LabDriver, Field(discriminator="kind")]


class Cell(Frozen):
    name: Name
    units: Units = Units()
    robots: dict[Name, Robot] = Field(min_length=1, json_schema_extra={"maxProperties": MAX_ROBOTS})
    tools: dict[Name, Tool] = {}
    platforms: dict[Name, PlatformSpec] = {}
    obstacles: dict[Name, Obstacle] = {}
    zones: dict[Name, Zone] = {}
    driver: DriverSpec = SimDriver(kind="sim")
    camera: Camera | None = None  # locates objects by their ArUco markers
    # every compiled segment keeps the arms this far apart, and from what they do not touch
    # on purpose (the gate refuses a segment passing closer); 0: measured and reported only
    clearance: Length = Field(DEFAULT_CLEARANCE, ge=0)
    # the cable skills' hands keep this far from the fixtures they work beside on purpose
    # (the guide a hand routes, the one the cable leaves, the plate under the cable): the
    # cell's clearance is kept from everything else
    work_clearance: Length = Field(DEFAULT_WORK_CLEARANCE, gt=0)
    # fractions of the joints' velocity and acceleration limits the trajectories are timed
    # with (one number: both); a plan's own replaces it
    speed: SpeedSpec = 1.0
    # the tools' (TCPs') speed cap, length unit per second; a plan's own may lower it
    tcp_speed: Length | None = Field(None, gt=0)

    @field_validator("robots")
    @classmethod
    def _plannable(cls, robots: dict[str, Robot]) -> dict[str, Robot]:
        if len(robots) > MAX_ROBOTS:
            raise ValueError(
                f"{len(robots)} robots, more than the {MAX_ROBOTS} this engine plans for: its "
                "tasks take one or two arms, and checking every arm against every other grows "
                "with the cube of the count"
            )
        return robots
