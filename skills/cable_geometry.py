"""Geometry of the published cable-routing method (paper 003, section III-B and Fig. 4).

TCP frame convention (every pose here is ``T_cell_tcp``, the fingertip centre of the tool's
``tcp`` in the cell frame):

- ``z_tcp`` points out of the fingertips, the approach direction: down (``-up``) for the top
  grasps every cable skill uses;
- ``y_tcp`` is the jaw axis, along which the fingers close: across the cable;
- ``x_tcp`` runs along the held cable, towards increasing ``s`` (away from the connector, to
  the free end). So ``x = cable direction``, ``z = -up``, ``y = z x x``. A hand that holds
  only the cable may instead face the other way (x towards decreasing ``s``, the gripper being
  symmetric about its tool axis) when that turns its wrist less (:func:`nearer_turn`); the
  connector hand never does;
- then each hand's tool is tipped by :data:`LEAN` (15 deg) so its flange moves away from the
  other hand: the hand behind on the cable (smaller ``s``) tips its flange back along the
  cable, the hand ahead forward; in RouteCable each also tips towards its own arm's base.
  ``z_tcp`` is then 15 deg off straight down; the jaw axis ``y_tcp`` stays normal to the
  cable, so the fingers still close across it. Without the tip the two UR5e wrists collide
  at the hand spacings the method uses.

A keypoint whose x runs along the cable and whose z is up (a guide's ``slot``, a comb's
``slot``) gives the top grasp there, before the tip, as ``T_cell_keypoint @ Rx(pi)`` when its x
already points to increasing ``s``.

The gripper as the method sees it (:class:`Hand`): ``W_gripper`` is the tool's
``finger_width``, its extent across the cable (DESIGN 3.1 names it so); along the cable the
fingers are ``finger_thickness`` thick (the paper's pull_distance uses "the fingers
thickness" with "the guides thickness", both along the cable). Clearances along the cable use
what the executor will check: the tool's finger boxes (``fingers.size`` along x) when the
tool declares them, else the motion layer's stand-in, a box ``finger_width`` square
(motion/robot.py), so half the larger of the two.

Symbols of the published formulas, with where each value comes from:

- ``L`` guide length along the cable, ``W_guide`` its width across it:
  ``world.dimensions(guide)`` (``length``, ``width``); ``H`` how far the guide's top stands
  over the cable held at its slot (:func:`rise`, from the element's bounds; its ``height``
  dimension when it has none);
- ``W_gripper``: the tool's ``finger_width``;
- ``A``: the gap between the routing gripper's front and the guide's near face when it stops
  before the guide (Fig. 4(a)); :data:`APPROACH_GAP`;
- ``X_offset``: the distance from a guide face to the fingertip centre of a hand holding the
  cable beside it: ``A`` plus the hand's half-length along the cable. The other hand grasps
  the cable there (``X_offset`` before the near face: the pivot of the circular moves) and the
  routing hand ends ``X_offset`` (at least) past the far face;
- ``Z_offset``: clearance of the lifted cable over the guide's top; :data:`Z_OFFSET`.

Then ``R_lift = sqrt((L + X_offset)^2 + (H + Z_offset)^2)``, ``R_insert = L + 2 X_offset``,
``R_cable = max(R_lift, R_insert)`` and the sliding angle ``theta > atan((W_gripper +
W_guide) / (2 A))``. The paper calls ``H`` the guide's height; what the lift must clear is
the part of the guide above the cable, and the hands hold the cable at the slot. (Taken as
the full height, a 60 mm guide whose slot is near its top would send the routing hand 30-40
mm farther past the guide, onto the next one on a dense board.)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from cellengine import geometry as g
from cellengine.arrays import Mat, Poses, Vec
from cellengine.errors import InputError, Problem
from cellengine.info.cell import Tool
from cellengine.info.platform import Element
from cellengine.motion import interpolate as ip
from cellengine.world import World

# Offsets of the method (m, rad). Constants of the skills, not of a cell: the paper gives no
# values; these fit a 6 mm cable and 20 mm fingers with room for a few mm of error.
APPROACH_GAP = 0.025  # A: gripper front to guide face when the routing hand stops before it
Z_OFFSET = 0.010  # Z_offset: lifted cable over the guide's top
APPROACH_HEIGHT = 0.060  # a hand comes down onto a grasp or an insert from this high
RETRACT_HEIGHT = 0.100  # and leaves upwards this far (a comb's slot is 18 mm deep)
STAND_BACK = 0.100  # the pivot hand, released, then backs off this far along the route
THETA_MARGIN = math.radians(5.0)  # the sliding angle is this much over its published minimum
THETA_MAX = math.radians(90.0)  # straight across the guide: beyond, it would slide back
# PickCable: the sliding hand first goes this far down on its circle about the other hand
# (enough for the cable to hang back through its fingers), by at most SLIDE_DOWN_ANGLE: a fixed
# angle would drop it 225 mm between the REMODEL sample's combs, 450 mm apart.
SLIDE_DROP = 0.060
SLIDE_DOWN_ANGLE = math.radians(30.0)
# Each hand tips its tool by this much so that its flange moves away from the other hand: with
# 200 mm tools straight down, two UR5e wrists and forearms collide when the fingertips are
# closer than about 100 mm (measured with motion.collision on the cable_routing cell), and the
# method holds the cable with the hands 46-85 mm apart. Tipped 15 deg apart along the cable,
# about half of the IK branch pairs are free at 46-57 mm in open space. Where the two arms
# come from the sides (a route across the cell) RouteCable also tips each flange towards its
# own arm's base, away from the other arm's forearm (twice the free pairs on plan_one_turn's
# guide4). A hand holding the connector tips only along the cable and always the same way,
# so the connector, grasped already tipped, stays level.
LEAN = math.radians(15.0)
# RouteCable's other hand, holding the pivot while the routing arm reaches past it, tips its
# flange further towards its own base: after a turn the routing arm's forearm sweeps over the
# pivot hand's wrist (plan_one_turn's guide4: 0.9 mm at 15 and 20 deg; free from 25 deg to at
# least 40 deg on the three reference plans, measured with every execution strategy).
PIVOT_LEAN = math.radians(30.0)
# The other values a RouteCable way may take, after the defaults above (guide_ways): the
# sliding angle in steps up to THETA_MAX, and other tips of the two hands.
THETA_STEP = math.radians(5.0)
# PlaceConnector's other hand, holding the cable behind the connector while the pair is
# carried: (roll about the cable, m farther along it) than as published. Where the guide's
# cable runs back towards the connector arm's base, the other hand stands under that arm's
# forearm; turned about the cable its wrist moves aside (cable.py ranks them by room).
PLACE_HOLDS = tuple(
    (math.radians(roll), farther) for farther in (0.0, 0.040) for roll in (0, 30, -30, 45, -45)
)
LEANS = (LEAN, math.radians(25.0), math.radians(5.0))
# PickCable: where the hands meet before the far hand slides to the connector hand: (how far
# along the level span to the far hand the connector hand first carries its end, how far the
# far hand then comes round it, turning the chord about the vertical); (0, 0): where the
# connector was picked, as published. Combs far apart leave the sliding arm reaching across
# the other's; meeting between them, the pair across the robots' line of sight, does not.
# A swing of ACROSS: the hands end as far apart ((1 - fraction) of the span), centred on
# the bisector of the two bases where the combs' midpoint projects onto it, each on its own
# arm's side, the chord from the connector arm's base to the far arm's (combs on one arm's
# side or near the bases leave that arm's forearm over the other hand wherever along the
# combs they meet). Not an angle: no turn of the chord puts the hands there.
ACROSS = math.inf
PICK_MEETS = tuple(
    (fraction, math.radians(swing))
    for fraction, swing in ((0, 0), (0.5, 0), (0.5, 90), (0.5, -90), (0.5, ACROSS))
)
# between guides a short span apart, a leaning pivot hand's closed fingers reach back over
# the guide before: upright ones stay between the two
PIVOT_LEANS = (PIVOT_LEAN, math.radians(20.0), math.radians(40.0), math.radians(10.0), 0.0)
STAND_BACKS = (STAND_BACK, 0.050, 0.150)
# The released pivot hand also rises only this high, its fingertips just clear of the cable,
# then backs off STAND_BACK along the route or to either side: under a routing arm that
# reaches over it, rising RETRACT_HEIGHT takes its forearm into that arm. (lift m, turn rad
# about the vertical from back along the route, positive to the left)
STAND_LOW = 0.030
STAND_LOWS = ((STAND_LOW, 0.0), (STAND_LOW, -math.pi / 2.0), (STAND_LOW, math.pi / 2.0))
# Or it only rises RETRACT_HEIGHT, straight up off the cable: backing off along the route or
# to a side, the open fingers sweep whatever stands beside the pivot (a connector guide the
# route turns back past).
STAND_UP = (0.0, RETRACT_HEIGHT, 0.0)
# A, the routing hand's stop before a guide, smaller where guides stand close together (the
# slide then starts nearer the guide, and must be steeper: theta > atan((W + W_g) / 2A))
APPROACH_GAPS = (APPROACH_GAP, 0.015, 0.010)
# how far past a guide's far face the routing hand may end its insert besides those: farther
# out, the slide's radius is longer and the hands stand farther apart while it slides
INSERT_PASTS = (0.040,)
# How much of the sliding angle the routing hand turns as it slides (the swing turns it back):
# all of it holds the cable straight through the fingers, as published; less keeps the
# fingers' across extent out of a short gap between two guides (the cable then bends at the
# fingers, as it does at the other hand)
SLIDE_TURNS = (1.0, 0.5, 0.0)
# Pull that puts the cable in tension, per metre between the hands: the sag of a loosely held
# span. The paper makes it "a function of the distance between grippers and the cable
# properties"; objects.yaml gives no stiffness, so only the distance is used.
TENSION_STRAIN = 0.02
TINY_ANGLE = 1e-6  # rad: a reorientation smaller than this is no segment
# A hand holding only the cable turns the other way round (nearer_turn) rather than leave its
# TCP turned more than this about the vertical since home: a UR wrist 3 turns 2 pi either way
# from home, and within a guide the slide turns the hand by up to THETA_MAX more and the
# shoulder's pan adds its own turn.
WIND_LIMIT = math.pi
# RouteCable turns the routing hand in place to face the next guide when its heading changes
# by more than this; a smaller change (the tip towards the base differs a little from guide
# to guide) is spread over the approach line.
REORIENT_MIN = math.radians(10.0)


# --------------------------------------------------------------------------- frames


def horizontal(v: ArrayLike, up: Vec) -> Vec:
    """``v`` projected on the plane normal to ``up``, unit length."""
    a = np.asarray(v, dtype=float)
    return g.unit(a - up * float(a @ up))


def tcp_frame(
    position: ArrayLike,
    x_axis: ArrayLike,
    up: Vec,
    flange_towards: ArrayLike | None = None,
    lean: float = 0.0,
) -> Mat:
    """T_cell_tcp of a top grasp at ``position`` holding a cable along ``x_axis``: z = -up
    tipped by ``lean`` so that the flange (behind the fingertips, on -z) moves towards
    ``flange_towards`` (made horizontal); y = z x x kept normal to the cable, so the
    fingers still close across it; x = y x z. See :data:`LEAN`."""
    c = horizontal(x_axis, up)
    z = -up
    if flange_towards is not None and lean != 0.0:
        z = -math.cos(lean) * up - math.sin(lean) * horizontal(flange_towards, up)
    y = g.unit(g.cross(z, c))
    return g.transform(g.frame_yz(y, z), position)


def at(T: Mat, position: ArrayLike) -> Mat:
    """``T`` moved to ``position``, orientation kept."""
    out = np.array(T, dtype=float)
    out[:3, 3] = position
    return out


def lifted(T: Mat, up: Vec, height: float) -> Mat:
    return at(T, T[:3, 3] + height * up)


# --------------------------------------------------------------------------- paths


def line(T0: Mat, T1: Mat) -> Poses:
    """A straight TCP line within the default steps (5 mm, 2 deg)."""
    return ip.line(T0, T1)


def turn_in_place(T0: Mat, T_target: Mat) -> Poses:
    """The TCP turned in place to ``T_target``'s orientation."""
    return ip.line(T0, at(T_target, T0[:3, 3]))


def nearer_turn(T_from: Mat, T_to: Mat, wound: float = 0.0) -> Mat:
    """``T_to`` or ``T_to`` turned half a turn about its z, whichever is the smaller rotation
    from ``T_from``. The parallel gripper is symmetric about its tool axis, so a hand holding
    only a cable (never one holding the connector, which turns with it) may face either way
    along it; taking the nearer keeps the wrist from winding up over a route (plan_two_turns
    turned the routing hand's wrist past its 2 pi limit). The first wins a tie. But when the
    hand has ``wound`` (rad, about the vertical since home) so far that the nearer would
    leave it wound more than WIND_LIMIT, the other, if it unwinds it."""
    flipped = np.array(T_to, dtype=float)
    flipped[:3, :2] *= -1.0  # Rz(pi): x and y reversed, z kept
    near, far = (
        (flipped, T_to)
        if g.rotation_angle(T_from, flipped) < g.rotation_angle(T_from, T_to) - 1e-9
        else (T_to, flipped)
    )
    after_near = abs(wound + turn_about_vertical(T_from, near))
    if after_near > WIND_LIMIT and abs(wound + turn_about_vertical(T_from, far)) < after_near:
        return far
    return near


def turn_about_vertical(T0: Mat, T1: Mat) -> float:
    """The signed turn (rad, in (-pi, pi]) about the cell's z from T0's TCP x to T1's, seen
    from above: the shorter way round."""
    a0 = math.atan2(T0[1, 0], T0[0, 0])
    a1 = math.atan2(T1[1, 0], T1[0, 0])
    d = (a1 - a0 + math.pi) % (2.0 * math.pi) - math.pi
    return math.pi if d == -math.pi else d


def pair_line(T_leader0: Mat, T_leader1: Mat, T_leader_follower: Mat) -> tuple[Poses, Poses]:
    """Both hands moving one object rigidly (a closed chain): the leader on a line, the
    follower fixed to it. Steps are halved and the rotation step scaled by the follower's
    lever so the follower too moves at most 5 mm and 2 deg per step."""
    lever = float(np.linalg.norm(T_leader_follower[:3, 3]))
    max_t = ip.MAX_TRANSLATION / 2.0
    max_r = min(ip.MAX_ROTATION, max_t / lever) if lever > 0 else ip.MAX_ROTATION
    leader = ip.line(T_leader0, T_leader1, max_translation=max_t, max_rotation=max_r)
    return leader, leader @ T_leader_follower


def arc(T0: Mat, centre: ArrayLike, axis: ArrayLike, angle: float, *, turn: bool | float) -> Poses:
    """The TCP on a circle about the axis through ``centre``: its distance to ``centre``
    stays constant (the cable length between the hands, when the other hand is there)."""
    return ip.arc_about(T0, centre, axis, angle, turn=turn)


# --------------------------------------------------------------------------- the gripper


@dataclass(frozen=True)
class Hand:
    """The gripper as the method sees it (m)."""

    width: float  # W_gripper: across the cable (finger_width)
    thickness: float  # the fingers along the cable (finger_thickness)
    half_length: float  # half the extent along the cable that collision checks see
    keep: float  # from the fixtures it works beside (the cell's work_clearance)

    @classmethod
    def from_tool(cls, tool: Tool, tool_name: str, keep: float) -> Hand:
        if tool.finger_width is None or tool.finger_thickness is None:
            missing = "finger_width" if tool.finger_width is None else "finger_thickness"
            raise InputError(
                Problem(f"tool '{tool_name}' has no {missing}: the cable skills need both")
            )
        # The fingers' own boxes when the tool has them; else the motion layer's stand-in, a
        # box finger_width square.
        if tool.fingers is not None:
            half = tool.fingers.size[0] / 2.0
        else:
            half = max(tool.finger_width, tool.finger_thickness) / 2.0
        return cls(tool.finger_width, tool.finger_thickness, half, keep)

    @property
    def x_offset(self) -> float:
        """X_offset: guide face to fingertip centre of a hand beside the guide."""
        return APPROACH_GAP + self.half_length

    @property
    def end_margin(self) -> float:
        """Cable a hand needs beyond its fingertip centre to hold it."""
        return self.half_length + self.keep


# --------------------------------------------------------------------------- the formulas


def r_lift(length: float, height: float, x_offset: float, z_offset: float) -> float:
    """R_lift = sqrt((L + X_offset)^2 + (H + Z_offset)^2): pivot to a point above the guide's
    far face, Z_offset over its top (Fig. 4(b))."""
    return math.hypot(length + x_offset, height + z_offset)


def r_insert(length: float, x_offset: float) -> float:
    """R_insert = L + 2 X_offset: X_offset before the guide to X_offset past it (Fig. 4(c))."""
    return length + 2.0 * x_offset


def theta_min(w_gripper: float, w_guide: float, a: float) -> float:
    """The published bound: theta > atan((W_gripper + W_guide) / (2 A)). Sliding from A
    before the guide at this angle, the gripper's side passes the guide's side: half the
    gripper plus half the guide, sideways, over the distance A."""
    return math.atan((w_gripper + w_guide) / (2.0 * a))


def slide_down_angle(radius: float) -> float:
    """The angle down the circle of ``radius`` that drops the hand SLIDE_DROP (at most
    SLIDE_DOWN_ANGLE)."""
    return min(SLIDE_DOWN_ANGLE, math.asin(min(1.0, SLIDE_DROP / radius)))


def tension_pull(distance: float) -> float:
    return TENSION_STRAIN * distance


# --------------------------------------------------------------------------- the world


@dataclass(frozen=True)
class GuideDims:
    """A guide's dimensions (m): L along the cable, W across it, H its height, the slot gap."""

    length: float
    width: float
    height: float
    gap: float

    @classmethod
    def of(cls, world: World, ref: str, where: str) -> GuideDims:
        dims = world.dimensions(ref)
        width = _width(dims)
        missing = [k for k in ("length", "height", "gap") if k not in dims]
        if width is None:
            missing.append("width")
        if missing:
            raise InputError(
                Problem(
                    f"{where}: guide '{ref}' has no {', '.join(missing)} dimension; the "
                    "published method sizes its moves from length, width, height and gap"
                )
            )
        assert width is not None
        out = cls(dims["length"], width, dims["height"], dims["gap"])
        bad = [f"{k} {v * 1000:g} mm" for k, v in vars(out).items() if not v > 0.0]
        if bad:
            what = ", ".join(bad)
            raise InputError(
                Problem(f"{where}: guide '{ref}' has {what}; a guide's sizes are positive")
            )
        return out


def _width(dims: Mapping[str, float]) -> float | None:
    """``width``, or for a REMODEL guide the across-cable extent of its key's collision
    columns (``ycol2 - ycol1``)."""
    if "width" in dims:
        return dims["width"]
    if "ycol1" in dims and "ycol2" in dims:
        return abs(dims["ycol2"] - dims["ycol1"])
    return None


def platform_up(world: World, ref: str) -> Vec:
    """The z axis of the platform ``ref`` is on, in the cell frame: 'up' for its elements."""
    platform, _, _ = world.resolve(ref)
    return g.unit(platform.T_cell_platform[:3, 2])


def position(world: World, ref: str) -> Vec:
    out: Vec = np.array(world.pose(ref)[:3, 3], dtype=float)
    return out


def keypoint_x(world: World, ref: str) -> Vec:
    out: Vec = np.array(world.pose(ref)[:3, 0], dtype=float)
    return out


@dataclass(frozen=True)
class Footprint:
    """An element seen from above, with its top, for clearance checks of moves beside
    guides: ``outline`` is the convex outline (k, 3; cell frame, projected on the plane
    normal to up) of its bounding box."""

    name: str
    outline: Vec
    top: float  # highest point, along up

    @cached_property
    def points(self) -> Vec:
        """The outline's corners and points along its edges every 5 mm (k, 3)."""
        out: list[Vec] = []
        for a, c in zip(self.outline, np.roll(self.outline, -1, axis=0), strict=True):
            n = max(1, math.ceil(float(np.linalg.norm(c - a)) / 0.005))
            out += [a + (c - a) * (i / n) for i in range(n)]
        return np.array(out)

    def distance(self, a: Vec, b: Vec, up: Vec) -> float:
        """Horizontal distance from the segment ``a``-``b`` to the outline (0 when they
        overlap)."""
        return outline_distance(self.outline, a, b, up)

    @cached_property
    def circle(self) -> tuple[Vec, float]:
        """A circle (centre, radius) on the outline's plane that holds it."""
        centre: Vec = self.outline.mean(axis=0)
        return centre, float(np.linalg.norm(self.outline - centre, axis=1).max())

    def least_distance(self, a: Vec, reach: float, up: Vec) -> float:
        """At most :meth:`distance` from any segment that starts at ``a`` and is ``reach``
        long (its circle's, less 1 nm for rounding): a cheap bound to leave out the elements
        that stand far off."""
        centre, radius = self.circle
        off = a - centre
        off = off - (off @ up) * up
        return float(np.linalg.norm(off)) - radius - reach - 1e-9


def footprints(world: World, exclude: str, up: Vec) -> list[Footprint]:
    """Every platform element with geometry but the one ``exclude`` (a reference; "": none)
    is on.
    Its bounds come from its mesh, else its collision boxes, else its length, width and
    height (the native models' origin is the centre of the footprint on the plate)."""
    skip = world.resolve(exclude)[1] if exclude else None
    out: list[Footprint] = []
    for pname, platform in world.platforms.items():
        for element in platform.elements.values():
            corners = _corners(element)
            if element is skip or corners is None:
                continue
            T = platform.T_cell_platform @ element.T_platform_element
            P = g.transform_points(T, corners)
            heights = P @ up
            flat = P - np.outer(heights, up)
            name = f"{pname}.{element.name}"
            out.append(Footprint(name, _convex(flat, up), float(heights.max())))
    return out


def room_between(world: World, a: str, b: str, up: Vec) -> float | None:
    """How much of the straight cable from keypoint ``a`` to keypoint ``b`` (seen from
    above) lies between their elements' footprints: from where it leaves ``a``'s to where it
    enters ``b``'s (0 when they overlap on it); None when either has no geometry."""
    out = {f.name: f for f in footprints(world, "", up)}
    fa, fb = out.get(element_of(a)), out.get(element_of(b))
    if fa is None or fb is None:
        return None
    e1, e2 = _plane(up)
    p, q = position(world, a), position(world, b)
    length = float(np.linalg.norm((q - p) - float((q - p) @ up) * up))
    span_a = _clip(fa.outline, p, q, e1, e2)
    span_b = _clip(fb.outline, p, q, e1, e2)
    leaves = span_a[1] if span_a is not None else 0.0
    enters = span_b[0] if span_b is not None else 1.0
    return max(0.0, enters - leaves) * length


def _clip(outline: Vec, p: Vec, q: Vec, e1: Vec, e2: Vec) -> tuple[float, float] | None:
    """The part [t0, t1] of the segment p + t (q - p), t in [0, 1], inside a convex outline
    (seen from above: Cyrus-Beck); None when it misses it."""
    ring = [(float(v @ e1), float(v @ e2)) for v in outline]
    a = (float(p @ e1), float(p @ e2))
    d = (float(q @ e1) - a[0], float(q @ e2) - a[1])
    # orient the ring counter-clockwise, so each edge's inside is on its left
    edges = list(zip(ring, ring[1:] + ring[:1], strict=True))
    area = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in edges)
    if area < 0.0:
        ring.reverse()
        edges = list(zip(ring, ring[1:] + ring[:1], strict=True))
    t0, t1 = 0.0, 1.0
    for (x0, y0), (x1, y1) in edges:
        nx, ny = -(y1 - y0), x1 - x0  # inward normal
        num = nx * (a[0] - x0) + ny * (a[1] - y0)  # > 0: a inside this edge
        den = nx * d[0] + ny * d[1]
        if abs(den) < 1e-15:
            if num < 0.0:
                return None
            continue
        t = -num / den
        if den > 0.0:
            t0 = max(t0, t)
        else:
            t1 = min(t1, t)
        if t0 > t1:
            return None
    return t0, t1


def element_of(ref: str) -> str:
    """``platform.element`` of a keypoint reference (the scene's object)."""
    return ".".join(ref.split(".")[:2])


def _plane(up: Vec) -> tuple[Vec, Vec]:
    e1 = g.any_perpendicular(up)
    return e1, g.cross(up, e1)


def _convex(points: Vec, up: Vec) -> Vec:
    """The convex outline of points on the plane normal to ``up``, counter-clockwise about
    up (Andrew's monotone chain)."""
    e1, e2 = _plane(up)
    pts = sorted({(round(float(p @ e1), 12), round(float(p @ e2), 12)) for p in points})

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        h: list[tuple[float, float]] = []
        for p in seq:
            while len(h) >= 2 and _cross2(h[-2], h[-1], p) <= 0.0:
                h.pop()
            h.append(p)
        return h[:-1]

    ring = half(pts) + half(pts[::-1]) if len(pts) > 2 else pts
    return np.array([x * e1 + y * e2 for x, y in ring])


def _cross2(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


def outline_distance(outline: Vec, a: Vec, b: Vec, up: Vec) -> float:
    """Horizontal distance from segment ``a``-``b`` to a convex outline; 0 when the segment
    enters it."""
    E = np.stack(_plane(up), axis=1)  # (3, 2): one product for every point, then floats
    ring: list[tuple[float, float]] = [(x, y) for x, y in (outline @ E).tolist()]
    (p, q) = [(x, y) for x, y in (np.stack([a, b]) @ E).tolist()]
    if _inside(ring, p) or _inside(ring, q):
        return 0.0
    best = math.inf
    for i, r in enumerate(ring):
        s = ring[(i + 1) % len(ring)]
        best = min(best, _segments_2d(p, q, r, s))
    return best


def _inside(ring: list[tuple[float, float]], p: tuple[float, float]) -> bool:
    return len(ring) > 2 and all(
        _cross2(ring[i], ring[(i + 1) % len(ring)], p) >= 0.0 for i in range(len(ring))
    )


def _segments_2d(
    p: tuple[float, float], q: tuple[float, float], r: tuple[float, float], s: tuple[float, float]
) -> float:
    """Distance between segments p-q and r-s in the plane (0 when they cross)."""
    d1, d2 = _cross2(r, s, p), _cross2(r, s, q)
    d3, d4 = _cross2(p, q, r), _cross2(p, q, s)
    if d1 * d2 < 0.0 and d3 * d4 < 0.0:
        return 0.0
    return min(_point_segment(p, r, s), _point_segment(q, r, s),
               _point_segment(r, p, q), _point_segment(s, p, q))  # fmt: skip


def _point_segment(p: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
    ab = (b[0] - a[0], b[1] - a[1])
    ap = (p[0] - a[0], p[1] - a[1])
    denom = ab[0] ** 2 + ab[1] ** 2
    t = 0.0 if denom == 0.0 else min(max((ap[0] * ab[0] + ap[1] * ab[1]) / denom, 0.0), 1.0)
    return math.hypot(ap[0] - t * ab[0], ap[1] - t * ab[1])


def _corners(element: Element) -> Vec | None:
    """The corners (k, 3) of the element's bounds in its own frame, or None if it has none."""
    unit_box = np.array(
        [[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)], dtype=float
    )
    if element.mesh is not None:
        lo, hi = np.asarray(element.mesh.bounds, dtype=float)
        out: Vec = (lo + hi) / 2.0 + unit_box * (hi - lo)
        return out
    if element.boxes:
        parts = [
            g.transform_points(b.T_element_box, unit_box * np.asarray(b.size))
            for b in element.boxes
        ]
        return np.concatenate(parts)
    dims = element.dimensions
    if all(k in dims for k in ("length", "width", "height")):
        size = np.array([dims["length"], dims["width"], dims["height"]])
        box: Vec = unit_box * size + np.array([0.0, 0.0, dims["height"] / 2.0])
        return box
    return None


def rise(world: World, ref: str, up: Vec) -> float | None:
    """How far the top of the element ``ref`` is on stands over the keypoint ``ref`` (along
    up): what a cable held at the keypoint is lifted over. None when it has no bounds."""
    platform, element, _ = world.resolve(ref)
    corners = _corners(element)
    if corners is None:
        return None
    T = platform.T_cell_platform @ element.T_platform_element
    top = float((g.transform_points(T, corners) @ up).max())
    return max(top - float(position(world, ref) @ up), 0.0)


def segment_distance(p: Vec, a: Vec, b: Vec, up: Vec) -> float:
    """Horizontal distance (normal to ``up``) from point ``p`` to segment ``a``-``b``."""

    def flat(v: Vec) -> Vec:
        out: Vec = v - up * float(v @ up)
        return out

    pa, ab = flat(p - a), flat(b - a)
    denom = float(ab @ ab)
    t = 0.0 if denom == 0.0 else min(max(float(pa @ ab) / denom, 0.0), 1.0)
    return float(np.linalg.norm(pa - t * ab))
