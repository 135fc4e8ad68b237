"""Cartesian paths: TCP waypoints in the cell frame -> a joint path that follows them, or the
part of it that can be followed and exactly why it stops there.

What MoveIt's computeCartesianPath does, with these differences:

- **It never stops short silently.** A result either reaches every waypoint or carries a
  :class:`Stop`: the kind (``unreachable``, ``limit``, ``joint_jump``, ``collision``), the first
  waypoint not reached, the arm, and the particulars (the joint and by how much it jumped or
  how far beyond its limit it would go; the two objects in contact).
- **The IK branch is kept.** For a UR arm every waypoint is solved at once, all eight branches
  in one numpy pass; the path takes the branch of the start configuration (``4 * shoulder + 2 *
  wrist + elbow``, chosen as the branch whose solution at the first waypoint is nearest the
  start) and unwraps each angle against the previous waypoint so that it moves continuously
  (no 2 pi steps). A pose that branch cannot reach is ``unreachable`` even if another branch
  could: changing branch is a reconfiguration, never a Cartesian motion. A joint that would
  pass its limit while following the path continuously is a ``limit`` stop (the other
  representative of the angle is a full turn away). Other arms follow the path with the
  numerical solver warm-started at the previous waypoint, without random restarts (a restart
  lands anywhere: a jump by construction); it keeps every joint within its limits, so a pose
  needing more is ``unreachable``, and the message names the joints against their limits.
- **Two jump tests, both on by default** (:class:`JumpThreshold`):
  *absolute*: no joint may move more than ``revolute`` rad (``prismatic`` m) between two
  consecutive waypoints. This is what catches branch flips and wrist flips (pi), whatever the
  rest of the path does, and it bounds how far joint-space interpolation between waypoints can
  stray from the Cartesian path.
  *relative*: MoveIt compares each step's joint distance with ``factor`` times the MEAN step
  of the path; one big jump raises the mean it is compared with, and steps of different lengths
  (a dense arc then a sparse line) look like jumps. Here each step's joint motion is divided by
  its Cartesian length (joint motion per metre of path: the local inverse-Jacobian gain, which
  does not depend on how finely the path is sampled) and compared with ``relative`` times the
  MEDIAN gain of the path, which a few jumps do not move. It stops the path where joint speeds
  would explode relative to the rest of the path, e.g. close to a singularity, and on the way
  to the workspace's edge, where a path leaving the workspace stops a few millimetres early
  as a jump (its message then says the next poses are out of reach). The motion of a step is
  its largest joint's (rad or m alike).
  A step whose TCP does not move but whose joints do (more than 1e-6) is a jump too.
- **Fraction** is of the path length, as in MoveIt: the length from the first waypoint to the
  last one reached over the length to the last waypoint; a step's length counts rotation too
  (``hypot(|dp|, ROTATION_LENGTH * angle)``, see interpolate), so a pure reorientation has one.
- **Collisions: every step is proved free, not sampled.** The checker's ``check_segment``
  proves a joint-space segment free (cellengine.motion.collision: conservative advancement
  with margins from each joint's reach, no point of any object can move further than the pair
  was apart); in free space one check covers a step of a dense path, ends included. So each
  step (start -> waypoint 0, waypoint i -> i + 1) goes to check_segment, in path order, and
  the first contact stops the path: a collision thinner than a step cannot hide between two
  waypoints, and a state check of the waypoints would add nothing. A per-state batch
  (``check_batch`` of every waypoint, about a third of the cost) is there for callers that
  re-check later anyway (``segments=False``): it can miss what passes between waypoints.
- **Dual-arm paths are checked together**: both arms' paths are resampled onto one common
  parameter (each arm's fraction of its own path length; the grid is the union of both arms'
  waypoints), so every state checked has BOTH arms where they actually are at that moment,
  each arm checked against the other arm's motion and never against it standing still.
- **Closed chain**: a follower's TCP keeps a constant pose relative to the leader's
  (``T_cell_follower = T_cell_leader @ T_leader_follower``) at every waypoint; the two paths
  share the leader's waypoints as their grid.

The start configuration (``seed``) is where the arm is when the path begins: the first
waypoint is normally its own TCP pose. The step from it to the first waypoint is checked like
any other (a seed far from the first waypoint is a joint jump at waypoint 0), and the path's
rows are the configurations at the waypoints reached, one per waypoint.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Literal, Protocol

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from cellengine import geometry as g
from cellengine.arrays import BoolArray, Poses, Vec
from cellengine.motion.ik import ArmIK, arm_ik, wrap
from cellengine.motion.interpolate import step_lengths
from cellengine.motion.robot import Arm, CellModel

StopKind = Literal["unreachable", "branch", "limit", "joint_jump", "collision"]

TWO_PI = 2.0 * math.pi
# A joint beyond its limit by less than this is on it (round-off of the unwrapping).
LIMIT_SLACK = 1e-10
# A step shorter than this (m, with rotation, see interpolate.step_lengths) has no length:
# its joints may move only by round-off, ZERO_STEP_MOTION.
ZERO_STEP = 1e-12
ZERO_STEP_MOTION = 1e-6
# A jump this close (m of path) before an unreachable waypoint is put down to the edge of the
# workspace in its message.
EDGE_DISTANCE = 0.01
# Resampling: grid parameters closer than this are one.
SAME_PARAMETER = 1e-12


# ------------------------------------------------------------------------------ interfaces


class Checker(Protocol):
    """A collision checker over configurations ``q`` (the whole cell's, for the one of
    cellengine.motion.collision; see :class:`ArmInCell` to check one arm's q)."""

    def check(self, q: Vec) -> Any | None:
        """A contact naming the two objects, or None."""
        ...

    def check_batch(self, Q: Vec) -> NDArray[np.bool_]:
        """(k,) True where the state (row of Q) is in collision."""
        ...

    def check_segment(self, q0: Vec, q1: Vec) -> Any | None:
        """A contact somewhere on the joint-space segment q0 -> q1, or None."""
        ...


@dataclass(frozen=True)
class JumpThreshold:
    """The joint-jump tests (see the module docstring); None turns a test off.

    ``revolute`` (rad) and ``prismatic`` (m): the largest motion of any one joint between two
    consecutive waypoints. The defaults suit waypoints a few millimetres apart (interpolate's
    defaults: 5 mm, 2 deg), where joints move hundredths of a radian per step; a branch or
    wrist flip moves a joint by about pi. ``relative``: the largest joint motion per metre of
    path of any step, as a multiple of the path's median.
    """

    revolute: float | None = 0.3
    prismatic: float | None = 0.05
    relative: float | None = 10.0


@dataclass(frozen=True)
class Stop:
    """Why a path stops short. ``waypoint``: the first waypoint (row of the path's grid) not
    reached. ``waypoints``: each moving arm's own first waypoint not reached (its index in the
    waypoints it was given). ``arm``: the arm that could not go on (None for a collision
    between two arms, see ``pair``). ``joint``/``value``/``bound``: the joint that jumped or
    hit its limit, by how much (rad or m; the joint's value for a limit) and the bound it
    broke. ``pair``/``contact``: the two objects in collision and the checker's contact."""

    kind: StopKind
    waypoint: int
    message: str
    arm: str | None = None
    waypoints: Mapping[str, int] = field(default_factory=lambda: MappingProxyType({}))
    joint: str | None = None
    value: float = math.nan
    bound: float = math.nan
    pair: tuple[str, str] | None = None
    contact: Any = None

    def __str__(self) -> str:
        return self.message


@dataclass(frozen=True)
class CartesianResult:
    """A joint path along TCP waypoints. ``q`` (k, n): the configuration at each waypoint
    reached (the whole cell's for dual-arm paths); ``s`` (k,): each row's place on the path
    (fraction of its length); ``fraction``: of the path length achieved; ``stop``: why it
    stops short, None only when every waypoint is reached."""

    q: Vec
    s: Vec
    fraction: float
    stop: Stop | None
    n_waypoints: int  # how many there were (rows of the grid)

    def __post_init__(self) -> None:
        complete = len(self.q) == self.n_waypoints
        if complete != (self.stop is None):  # never short without a reason, nor vice versa
            raise ValueError(
                f"a path with {len(self.q)} of {self.n_waypoints} waypoints must "
                + ("not have a stop" if complete else "say why it stops")
            )
        for name in ("q", "s"):
            getattr(self, name).setflags(write=False)

    @property
    def ok(self) -> bool:
        return self.stop is None


# ------------------------------------------------------------------------------ one arm


def cartesian_path(
    arm: Arm,
    waypoints: ArrayLike,
    seed: ArrayLike,
    *,
    check: Checker | None = None,
    jump: JumpThreshold | None = None,
    segments: bool = True,
) -> CartesianResult:
    """The arm's joint path through TCP ``waypoints`` (N, 4, 4) in the cell frame, starting
    from the configuration ``seed``. ``check`` sees the arm's q (wrap a whole-cell checker
    with :class:`ArmInCell`)."""
    Ts = _waypoints(waypoints, arm.name)
    q0 = _configuration(seed, arm.nq, arm.name)
    run = solve_arm(arm_ik(arm), Ts, q0, jump or JumpThreshold())
    lengths = step_lengths(Ts)
    rows, stop = len(run.q), run.stop
    if check is not None:
        hit = first_collision(np.vstack([q0, run.q]), check, segments=segments)
        if hit is not None:  # always before the IK's stop: only reached waypoints are checked
            rows, stop = hit.waypoint, _collision_stop(hit, {arm.name: hit.waypoint})
    s = _parameter(lengths)
    return CartesianResult(
        run.q[:rows], s[:rows], _fraction(s, rows), _with_waypoints(stop, arm.name), len(Ts)
    )


@dataclass(frozen=True)
class ArmRun:
    """One arm's IK along its waypoints: the rows solved before the first stop."""

    q: Vec  # (m, n)
    stop: Stop | None  # kind unreachable | limit | joint_jump; waypoint = m


def solve_arm(ik: ArmIK, Ts: Poses, seed: Vec, jump: JumpThreshold) -> ArmRun:
    """IK of every waypoint on the seed's branch (closed form) or warm-started (numerical),
    then limits and jumps: the rows before the first waypoint that fails."""
    if ik.closed_form is not None:
        q, stop = _closed_form_rows(ik, Ts, seed)
    else:
        q, stop = _numeric_rows(ik, Ts, seed)
    jumped = _first_jump(ik, q, seed, Ts, jump)
    if jumped is not None and (stop is None or jumped.waypoint <= stop.waypoint):
        stop = _edge_note(jumped, stop, Ts)
    m = len(Ts) if stop is None else stop.waypoint
    return ArmRun(q[:m], stop)


def _edge_note(jumped: Stop, ik_stop: Stop | None, Ts: Poses) -> Stop:
    """Joint speeds explode on the way to the workspace's edge (the elbow stretching, the
    wrist point nearing the shoulder axis), so the jump tests often stop a path just before
    the pose that is out of reach: say so."""
    if ik_stop is None or ik_stop.kind != "unreachable":
        return jumped
    i, k = jumped.waypoint, ik_stop.waypoint
    if k <= i or float(step_lengths(Ts[i : k + 1]).sum()) > EDGE_DISTANCE:
        return jumped
    note = f"; waypoint {k} is out of reach (the arm nears its workspace's edge)"
    return replace(jumped, message=jumped.message + note)


# ------------------------------------------------------------------------------ closed form


def _closed_form_rows(ik: ArmIK, Ts: Poses, seed: Vec) -> tuple[Vec, Stop | None]:
    """All waypoints on one branch, unwrapped, up to the first unreachable or beyond-limit
    one."""
    kin = ik.closed_form
    assert kin is not None
    T_bf = ik.base_flange(Ts)
    sols, valid = kin.solve(T_bf, seed[5])  # (N, 8, 6): all branches at once
    branch = _start_branch(sols, valid, seed)
    reached = valid[:, branch]
    m = len(Ts) if reached.all() else int(np.argmin(reached))
    q = sols[:m, branch]
    q = _unwrap(_fix_singular_wrists(kin, T_bf[:m], q, seed, branch), seed)
    stop = _unreachable_on_branch(ik, m, branch, valid[m]) if m < len(Ts) else None
    limit = _first_beyond_limit(ik, q)
    if limit is not None:
        return q[: limit.waypoint], limit
    return q, stop


def _start_branch(sols: Vec, valid: BoolArray, seed: Vec) -> int:
    """The seed's branch: the one whose solution at the first waypoint is nearest the seed
    (angles compared modulo 2 pi). A tie (the seed at a singularity, where branches coincide)
    is broken at the second waypoint."""
    d0 = _branch_distance(sols[0], valid[0], seed)
    if len(sols) > 1 and np.isfinite(d0.min()):
        tied = d0 <= d0.min() + 1e-9
        d1 = _branch_distance(sols[1], valid[1] & tied, seed)
        if np.isfinite(d1.min()):
            return int(np.argmin(d1))
    return int(np.argmin(d0))


def _branch_distance(sols: Vec, valid: BoolArray, seed: Vec) -> Vec:
    d: Vec = np.sqrt((wrap(sols - seed) ** 2).sum(axis=1))
    d[~valid] = np.inf
    return d


def _fix_singular_wrists(kin: Any, T_bf: Poses, q: Vec, seed: Vec, branch: int) -> Vec:
    """At a wrist singularity the closed form takes q6 from its seed (q6 of the start for
    the whole batch); there q6 is re-solved from the previous waypoint's, so that it does not
    jump back to the start's. Exact singularities are rare: one pose at a time."""
    singular = np.flatnonzero(np.abs(np.sin(q[:, 4])) < 1e-10)
    for i in singular:
        prev = seed if i == 0 else q[i - 1]
        sols, _ = kin.solve(T_bf[i : i + 1], prev[5])
        q[i] = sols[0, branch]
    return q


def _unwrap(q: Vec, seed: Vec) -> Vec:
    """Each angle moved by multiples of 2 pi to follow the previous waypoint's continuously
    from the seed. The values are the solver's plus whole turns (no accumulated round-off)."""
    if len(q) == 0:
        return q
    steps = wrap(np.diff(np.vstack([seed, q]), axis=0))
    estimate = seed + np.cumsum(steps, axis=0)
    turns = np.floor((estimate - q) / TWO_PI + 0.5)
    out: Vec = q + TWO_PI * turns
    return out


def _unreachable_on_branch(ik: ArmIK, i: int, branch: int, valid_i: BoolArray) -> Stop:
    others = [int(b) for b in np.flatnonzero(valid_i)]
    if others:
        why = (
            f"branch {branch} ({_branch_name(branch)}) cannot reach it; branches {others} "
            "could, but changing branch is a reconfiguration, not a Cartesian motion"
        )
    else:
        why = "no IK branch reaches it (outside the workspace)"
    kind: StopKind = "branch" if others else "unreachable"  # "branch": others reach it
    return Stop(kind, i, f"waypoint {i}: {why}", arm=ik.arm.name)


def _branch_name(b: int) -> str:
    return f"shoulder {b >> 2}, wrist {(b >> 1) & 1}, elbow {b & 1}"


def _first_beyond_limit(ik: ArmIK, q: Vec) -> Stop | None:
    lo, hi = ik.lower - LIMIT_SLACK, ik.upper + LIMIT_SLACK
    bad = (q < lo) | (q > hi)
    if not bad.any():
        return None
    i = int(np.argmax(bad.any(axis=1)))
    j = int(np.argmax(bad[i]))
    value = float(q[i, j])
    bound = float(ik.upper[j] if value > hi[j] else ik.lower[j])
    name = ik.arm.joint_names[j]
    return Stop(
        "limit",
        i,
        f"waypoint {i}: joint '{name}' would reach {value:.4f}, beyond its limit {bound:.4f} "
        "(following the path continuously)",
        arm=ik.arm.name,
        joint=name,
        value=value,
        bound=bound,
    )


# ------------------------------------------------------------------------------ numerical


def _numeric_rows(ik: ArmIK, Ts: Poses, seed: Vec) -> tuple[Vec, Stop | None]:
    """Waypoint by waypoint from the previous solution; stop at the first that fails."""
    solver = ik.path_solver()
    out = np.empty((len(Ts), ik.n))
    prev = seed
    for i, T in enumerate(Ts):
        r = solver.solve(T, prev)
        if not r.success:
            at = _at_limits(ik, r.q)
            msg = (
                f"waypoint {i}: no IK solution near the previous waypoint's (residual "
                f"{r.pos_err:.2e} m, {r.rot_err:.2e} rad{at})"
            )
            return out[:i], Stop("unreachable", i, msg, arm=ik.arm.name)
        out[i] = prev = r.q
    return out, None


def _at_limits(ik: ArmIK, q: Vec) -> str:
    solver = ik.path_solver()
    lo, hi = solver.lower, solver.upper
    names = [
        ik.arm.joint_names[k]
        for k, j in enumerate(list(ik.arm.model.joints)[1:])
        if j.nq == 1 and (q[j.idx_q] <= lo[j.idx_q] + 1e-9 or q[j.idx_q] >= hi[j.idx_q] - 1e-9)
    ]
    return f"; against the limit: {', '.join(names)}" if names else ""


# ------------------------------------------------------------------------------ jumps


def _joint_steps(ik: ArmIK, q: Vec, seed: Vec) -> Vec:
    """(m, nv) joint motion of each step (seed -> waypoint 0 first), in the tangent space
    (a continuous joint's angle, not its cos and sin)."""
    rows = np.vstack([seed, q])
    model = ik.arm.model
    if model.nq == model.nv:
        return np.diff(rows, axis=0)
    return np.array([pin.difference(model, a, b) for a, b in itertools.pairwise(rows)])


def _prismatic(ik: ArmIK) -> BoolArray:
    """(nv,) which velocity coordinates are prismatic."""
    out = np.zeros(ik.arm.model.nv, dtype=bool)
    for j in list(ik.arm.model.joints)[1:]:
        name = j.shortname()
        out[j.idx_v] = name.startswith("JointModelP") and not name.startswith("JointModelPlanar")
    return out


def _first_jump(ik: ArmIK, q: Vec, seed: Vec, Ts: Poses, jump: JumpThreshold) -> Stop | None:
    """The first step (into waypoint i) that breaks a jump test, or None."""
    if len(q) == 0:
        return None
    dq = np.abs(_joint_steps(ik, q, seed))
    lengths = _lengths_from(ik, seed, Ts[: len(q)])
    prismatic = _prismatic(ik)
    bound = np.where(
        prismatic,
        np.inf if jump.prismatic is None else jump.prismatic,
        np.inf if jump.revolute is None else jump.revolute,
    )
    absolute: BoolArray = np.asarray((dq > bound).any(axis=1))
    biggest = dq.max(axis=1)
    zero = lengths <= ZERO_STEP
    still: BoolArray = np.asarray(zero & (biggest > ZERO_STEP_MOTION))
    gain = np.where(zero, 0.0, biggest / np.where(zero, 1.0, lengths))
    median = float(np.median(gain[~zero])) if (~zero).any() else 0.0
    relative = np.zeros(len(dq), dtype=bool)
    if jump.relative is not None and median > 0.0:
        relative = gain > jump.relative * median
    bad = absolute | still | relative
    if not bad.any():
        return None
    i = int(np.argmax(bad))
    if absolute[i]:
        j = int(np.argmax(dq[i] / bound))
        return _jump_stop(
            ik,
            i,
            j,
            dq[i, j],
            bound[j],
            prismatic[j],
            f"more than the {bound[j]:g} {{unit}} allowed per step",
        )
    j = int(np.argmax(dq[i]))
    if still[i]:
        return _jump_stop(
            ik,
            i,
            j,
            dq[i, j],
            ZERO_STEP_MOTION,
            prismatic[j],
            "while the TCP stays put (a reconfiguration)",
        )
    assert jump.relative is not None
    why = (
        f"over {lengths[i] * 1e3:.3g} mm of path: {gain[i]:.3g} {{unit}}/m, "
        f"{gain[i] / median:.3g} x the path's median {median:.3g} {{unit}}/m "
        f"(at most {jump.relative:g} x)"
    )
    stop = _jump_stop(ik, i, j, dq[i, j], jump.relative * median, prismatic[j], why)
    return replace(stop, value=float(gain[i]))


def _jump_stop(
    ik: ArmIK, i: int, j: int, value: float, bound: float, prismatic: bool, why: str
) -> Stop:
    """A joint_jump stop of joint j (velocity index) on the step into waypoint i. ``value``
    and ``bound`` are the step and its bound (the relative test: gain and bound, rad/m)."""
    name = _velocity_name(ik, j)
    unit = "m" if prismatic else "rad"
    where = "from the start configuration to waypoint 0" if i == 0 else f"into waypoint {i}"
    msg = f"waypoint {i}: joint '{name}' moves {value:.4g} {unit} {where}, " + why.format(unit=unit)
    return Stop(
        "joint_jump", i, msg, arm=ik.arm.name, joint=name, value=float(value), bound=float(bound)
    )


def _lengths_from(ik: ArmIK, seed: Vec, Ts: Poses) -> Vec:
    """Length of each step, the first from the seed's own TCP pose to waypoint 0."""
    T_start = ik.arm.fk(seed)
    return step_lengths(np.concatenate([T_start[None], Ts]))


def _velocity_name(ik: ArmIK, v: int) -> str:
    for k, j in enumerate(list(ik.arm.model.joints)[1:]):
        if j.idx_v <= v < j.idx_v + j.nv:
            return ik.arm.joint_names[k]
    return f"#{v}"


# ------------------------------------------------------------------------------ collisions


@dataclass(frozen=True)
class Hit:
    """A collision along a path: the first waypoint not reached, the checker's contact, and
    where: at the start configuration, at the waypoint, or on the step into it."""

    waypoint: int
    contact: Any
    where: Literal["start", "waypoint", "step"]


def first_collision(states: Vec, check: Checker, *, segments: bool = True) -> Hit | None:
    """The first collision along ``states`` (row 0 the start, row i + 1 waypoint i), or None.

    ``segments``: each step goes to ``check_segment`` in path order (a proof for a checker
    whose segment check is one, as cellengine.motion.collision's); else only the states, in
    one ``check_batch``."""
    if isinstance(check, ArmInCell):  # whole-cell states once, not per call
        states, check = check.lift(states), check.checker
    if not segments:
        hit = np.flatnonzero(check.check_batch(states))
        if len(hit) == 0:
            return None
        k = int(hit[0])
        return Hit(max(k - 1, 0), check.check(states[k]), "start" if k == 0 else "waypoint")
    if len(states) == 1:
        contact = check.check(states[0])
        return None if contact is None else Hit(0, contact, "start")
    for k in range(len(states) - 1):
        contact = check.check_segment(states[k], states[k + 1])
        if contact is not None:
            return Hit(k, contact, _where_on_step(contact, k))
    return None


def _where_on_step(contact: Any, k: int) -> Literal["start", "waypoint", "step"]:
    """Where on step k a segment contact is, from its ``t`` (fraction along the step)."""
    t = getattr(contact, "t", None)
    if t is None:
        return "step"
    if t <= 0.0 and k == 0:
        return "start"
    return "waypoint" if t >= 1.0 else "step"


def _collision_stop(hit: Hit, waypoints: Mapping[str, int]) -> Stop:
    pair = _pair(hit.contact)
    what = f"'{pair[0]}' and '{pair[1]}'" if pair else f"({hit.contact})"
    distance = getattr(hit.contact, "distance", None)
    if isinstance(distance, float) and distance > 0.0:  # a segment check's near miss
        what += f" (within {distance * 1e3:.2f} mm, under the checker's clearance)"
    i = hit.waypoint
    where = {
        "start": "at the start configuration",
        "waypoint": "there",
        "step": "on the way there from " + ("the start" if i == 0 else f"waypoint {i - 1}"),
    }[hit.where]
    return Stop(
        "collision",
        i,
        f"waypoint {i}: collision between {what} {where}",
        arm=_arm_of(pair, waypoints),
        waypoints=MappingProxyType(dict(waypoints)),
        pair=pair,
        contact=hit.contact,
    )


def _pair(contact: Any) -> tuple[str, str] | None:
    """The two object names of a contact: its ``pair``, or ``a``/``b``, or
    ``object1``/``object2``."""
    if contact is None:
        return None
    pair = getattr(contact, "pair", None)
    if pair is not None and len(pair) == 2:
        return str(pair[0]), str(pair[1])
    for a, b in (("a", "b"), ("object1", "object2"), ("first", "second")):
        if hasattr(contact, a) and hasattr(contact, b):
            return str(getattr(contact, a)), str(getattr(contact, b))
    return None


def _arm_of(pair: tuple[str, str] | None, arms: Mapping[str, int]) -> str | None:
    """The one moving arm named by the pair (objects are '<robot>/<link>'); None when both
    objects belong to moving arms, or neither does."""
    if pair is None:
        return None
    named = {n.split("/", 1)[0] for n in pair} & set(arms)
    return next(iter(named)) if len(named) == 1 else None


# ------------------------------------------------------------------------------ both arms


@dataclass(frozen=True)
class ArmInCell:
    """A whole-cell checker seen from one arm: the arm's q placed into ``q_cell`` (the other
    arms standing where ``q_cell`` has them)."""

    checker: Checker
    cell: CellModel
    arm: str
    q_cell: Vec

    def lift(self, q: Vec) -> Vec:
        """The cell's q (..., nq) of the arm's q (..., n)."""
        Q = np.array(np.broadcast_to(self.q_cell, (*np.shape(q)[:-1], self.cell.nq)))
        Q[..., self.cell.slices[self.arm]] = q
        return Q

    def check(self, q: Vec) -> Any | None:
        return self.checker.check(self.lift(q))

    def check_batch(self, Q: Vec) -> NDArray[np.bool_]:
        return self.checker.check_batch(self.lift(Q))

    def check_segment(self, q0: Vec, q1: Vec) -> Any | None:
        return self.checker.check_segment(self.lift(q0), self.lift(q1))


def dual_cartesian_path(
    cell: CellModel,
    waypoints: Mapping[str, ArrayLike],
    seeds: Mapping[str, ArrayLike] | ArrayLike,
    *,
    check: Checker | None = None,
    jump: JumpThreshold | None = None,
    segments: bool = True,
) -> CartesianResult:
    """Several arms along their own TCP waypoints at once, the whole cell's q per row.

    Each arm's path is parametrised by its fraction of its own length; both are resampled
    (positions linearly, orientations by slerp between an arm's waypoints) at the union of
    their waypoints' parameters, and every row of the grid is one moment of the motion with
    every arm where it is then. Arms without waypoints stand at their seed. The path stops at
    the first row where any arm stops or the cell collides; ``fraction`` is the common one."""
    seed = _cell_seed(cell, seeds)
    paths = {name: _waypoints(W, name) for name, W in waypoints.items()}
    _known_arms(cell, paths)
    params = {name: _parameter(step_lengths(Ts)) for name, Ts in paths.items()}
    grid = _union(list(params.values()))
    on_grid = {name: resample(paths[name], params[name], grid) for name in paths}
    own = {name: _own_index(params[name], grid) for name in paths}
    return _solve_on_grid(
        cell, on_grid, own, grid, seed, _Checks(check, jump or JumpThreshold(), segments)
    )


def closed_chain_path(
    cell: CellModel,
    leader: str,
    follower: str,
    waypoints: ArrayLike,
    seeds: Mapping[str, ArrayLike] | ArrayLike,
    T_leader_follower: ArrayLike | None = None,
    *,
    check: Checker | None = None,
    jump: JumpThreshold | None = None,
    segments: bool = True,
) -> CartesianResult:
    """Both hands on one object: the leader's TCP along ``waypoints``, the follower's at
    ``T_cell_leader @ T_leader_follower`` at every waypoint (default: the relative pose of
    the two TCPs at the seeds). Both arms share the leader's waypoints as grid."""
    seed = _cell_seed(cell, seeds)
    _known_arms(cell, {leader: None, follower: None})
    if leader == follower:
        raise ValueError("closed_chain_path: the leader and the follower must be two arms")
    Ts = _waypoints(waypoints, leader)
    q = cell.split(seed)
    if T_leader_follower is None:
        T_lf = g.inverse(cell.arms[leader].fk(q[leader])) @ cell.arms[follower].fk(q[follower])
    else:
        T_lf = np.asarray(T_leader_follower, dtype=float).reshape(4, 4)
    grid = _parameter(step_lengths(Ts))
    index = np.arange(len(Ts))
    on_grid = {leader: Ts, follower: Ts @ T_lf}
    own = {leader: index, follower: index}
    return _solve_on_grid(
        cell, on_grid, own, grid, seed, _Checks(check, jump or JumpThreshold(), segments)
    )


@dataclass(frozen=True)
class _Checks:
    """What a path is checked for besides reach and limits."""

    check: Checker | None
    jump: JumpThreshold
    segments: bool


def _solve_on_grid(
    cell: CellModel,
    on_grid: Mapping[str, Poses],
    own: Mapping[str, NDArray[np.intp]],
    grid: Vec,
    seed: Vec,
    checks: _Checks,
) -> CartesianResult:
    """Every arm's IK along the shared grid; the rows before the first stop of any arm,
    then the cell's collisions on those rows."""
    seeds = cell.split(seed)
    n = len(grid)
    rows, stop = n, None
    runs: dict[str, ArmRun] = {}
    for name in cell.arms:  # cell order: ties go to the first arm
        if name not in on_grid:
            continue
        runs[name] = run = solve_arm(
            arm_ik(cell.arms[name]), on_grid[name], seeds[name], checks.jump
        )
        if run.stop is not None and run.stop.waypoint < rows:
            rows, stop = run.stop.waypoint, run.stop
    Q = np.repeat(seed[None, :], rows, axis=0)
    for name, run in runs.items():
        Q[:, cell.slices[name]] = run.q[:rows]
    if checks.check is not None:
        hit = first_collision(np.vstack([seed, Q]), checks.check, segments=checks.segments)
        if hit is not None:
            rows = hit.waypoint
            stop = _collision_stop(hit, _own_at(own, rows))
    if stop is not None and stop.kind != "collision":
        stop = _replace_waypoints(stop, _own_at(own, stop.waypoint))
    return CartesianResult(Q[:rows], grid[:rows], _fraction(grid, rows), stop, n)


# ------------------------------------------------------------------------------ resampling


def resample(Ts: Poses, s: Vec, grid: Vec) -> Poses:
    """Poses of a path whose waypoints are at parameters ``s`` (non-decreasing, 0 to 1), at
    the parameters ``grid``: positions linearly, orientations by slerp between the two
    waypoints around each grid value (a waypoint itself where the grid has it)."""
    if len(Ts) == 1 or s[-1] <= 0.0:
        return np.repeat(Ts[:1], len(grid), axis=0)
    k = np.clip(np.searchsorted(s, grid, side="right") - 1, 0, len(s) - 2)  # segment k..k+1
    span = s[k + 1] - s[k]
    t = np.where(span > 0, (grid - s[k]) / np.where(span > 0, span, 1.0), 0.0)
    t = np.clip(t, 0.0, 1.0)
    A, B = Ts[k], Ts[k + 1]
    out = np.array(A)
    out[:, :3, 3] += t[:, None] * (B[:, :3, 3] - A[:, :3, 3])
    inner = (t > 0.0) & (t < 1.0)
    at_end = t >= 1.0
    out[at_end] = B[at_end]
    if inner.any():
        w = g.log3_batch(np.swapaxes(A[inner, :3, :3], 1, 2) @ B[inner, :3, :3])
        out[inner, :3, :3] = A[inner, :3, :3] @ g.exp3_batch(t[inner, None] * w)
    return out


def _union(params: Sequence[Vec]) -> Vec:
    """The sorted union of parameter grids, values within SAME_PARAMETER merged."""
    allp = np.sort(np.concatenate(params))
    keep = np.concatenate([[True], np.diff(allp) > SAME_PARAMETER])
    out: Vec = allp[keep]
    return out


def _own_index(s: Vec, grid: Vec) -> NDArray[np.intp]:
    """For each grid row, the arm's own waypoint at or just after it (the one that row is on
    the way to)."""
    out: NDArray[np.intp] = np.minimum(
        np.searchsorted(s, grid - SAME_PARAMETER, side="left"), len(s) - 1
    )
    return out


def _own_at(own: Mapping[str, NDArray[np.intp]], row: int) -> dict[str, int]:
    return {name: int(ix[min(row, len(ix) - 1)]) for name, ix in own.items()}


# ------------------------------------------------------------------------------ helpers


def _parameter(lengths: Vec) -> Vec:
    """Each waypoint's fraction of the path length (0 .. 1); by index when the path has
    no length at all."""
    total = float(lengths.sum())
    if total <= ZERO_STEP:
        n = len(lengths) + 1
        return np.linspace(0.0, 1.0, n) if n > 1 else np.zeros(1)
    out: Vec = np.concatenate([[0.0], np.cumsum(lengths) / total])
    out[-1] = 1.0
    return out


def _fraction(s: Vec, rows: int) -> float:
    """Reaching ``rows`` waypoints: the parameter of the last one reached (0 for none)."""
    if rows >= len(s):
        return 1.0
    return float(s[rows - 1]) if rows > 0 else 0.0


def _with_waypoints(stop: Stop | None, arm: str) -> Stop | None:
    if stop is None or stop.waypoints:
        return stop
    return _replace_waypoints(stop, {arm: stop.waypoint})


def _replace_waypoints(stop: Stop, waypoints: Mapping[str, int]) -> Stop:
    return replace(stop, waypoints=MappingProxyType(dict(waypoints)))


def _waypoints(W: ArrayLike, name: str) -> Poses:
    Ts = np.asarray(W, dtype=float)
    if Ts.ndim != 3 or Ts.shape[1:] != (4, 4) or len(Ts) == 0:
        raise ValueError(f"arm '{name}': waypoints must be (N, 4, 4) with N >= 1, got {Ts.shape}")
    if not np.isfinite(Ts).all():
        raise ValueError(f"arm '{name}': waypoints must be finite")
    return Ts


def _configuration(q: ArrayLike, n: int, name: str) -> Vec:
    qa = np.asarray(q, dtype=float)
    if qa.shape != (n,) or not np.isfinite(qa).all():
        raise ValueError(f"arm '{name}': the seed must be {n} finite values, got shape {qa.shape}")
    return qa


def _cell_seed(cell: CellModel, seeds: Mapping[str, ArrayLike] | ArrayLike) -> Vec:
    if isinstance(seeds, Mapping):
        return cell.join(seeds)
    return _configuration(seeds, cell.nq, "cell")


def _known_arms(cell: CellModel, paths: Mapping[str, object]) -> None:
    unknown = sorted(set(paths) - set(cell.arms))
    if unknown:
        raise ValueError(f"unknown arm(s) {unknown}; the cell has {sorted(cell.arms)}")
    if not paths:
        raise ValueError("no arm has waypoints")
