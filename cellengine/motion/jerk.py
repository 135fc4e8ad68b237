"""On-path smoothing of a time-optimal speed profile into a C2, jerk-limited trajectory.

The TOPP profile is bang-bang: its path acceleration sddot jumps, so joint accelerations
jump, which no driver can follow and which a Trajectory (C2 quintic pieces) cannot even
represent. We smooth the path parameter only, never the joints, so every sample stays on
the geometric path (which is what the planner collision-checked):

    s_f(t) = (1/W) * integral of s_ref over [t - W, t]

a moving average (an FIR filter, Biagiotti & Melchiorri's jerk-limiting filter) of the
reference s_ref(t). Its derivatives are differences of the reference's:
sdot_f(t) = (s_ref(t) - s_ref(t - W)) / W, sddot_f = (sdot_ref(t) - sdot_ref(t - W)) / W,
and the path jerk is (sddot_ref(t) - sddot_ref(t - W)) / W, so a window W = 2 a / j
turns an acceleration step from +a to -a into a ramp at jerk j. Rest-to-rest stays
rest-to-rest (zero velocity and acceleration at both ends); the motion takes W longer.

Averaging is not the optimum: near a slow point of the path (a tight curve), the averaged
speed is above the reference's there, and the path's own curvature adds jerk
(3 q'' sdot sddot + q''' sdot^3) that no filter removes. So the result is checked, segment
by segment, with bounds that hold between samples (Trajectory.peaks); where a limit is
exceeded the reference is capped around the spot (sdot^2 lowered by the ratio found), the
profile recomputed and filtered again; where only jerk is (the acceleration swings by more
than the window assumed), the window is widened instead. A few rounds settle it; if they do
not, the whole trajectory is slowed in time by the worst ratio (exact for a path-following
motion: velocities scale by 1/k, accelerations by 1/k^2, jerks by 1/k^3), so what leaves
here is within the limits.

Why not ruckig for this: ruckig Community has no path following (intermediate waypoints
are a Pro feature); ruckig between dense waypoints or tracking the reference moves the
joints independently, off the collision-checked path, and its time-synchronised profiles
put full-jerk pulses in every segment. ruckig is used where joint space is free
(point-to-point moves, online re-targeting: otg.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cellengine.arrays import FloatArray
from cellengine.motion.topp import GeometricPath, SpeedPlanner, SpeedProfile, row_max, row_min
from cellengine.motion.trajectory import Trajectory

# Knots are placed where the filtered motion has a kink in jerk (reference grid times,
# their shifts by W, path knots crossed), and no further apart than this, so the quintic
# pieces reproduce the motion: at 50 ms their accelerations overshot the filtered motion's by
# 4 % on a 0.7 s move, and each overshoot is paid for by slowing down; at 20 ms, 1 %.
MAX_KNOT_GAP = 0.02
MIN_KNOT_GAP = 5e-4
# A slow-down lowers sdot^2 a little more than the ratio asks, so rounds converge.
SLOWDOWN_MARGIN = 0.99
# TCP speed is checked at knots from |dp/ds| interpolated on the TOPP grid: keep this
# fraction of the limit in hand for what happens between them.
TCP_MARGIN = 0.995
MAX_ROUNDS = 12
# An excess this small (as a time stretch) is fixed by slowing the whole motion uniformly
# instead of another round: cheaper, and it costs at most this share of the duration.
SCALE_TOLERANCE = 5e-3


@dataclass(frozen=True)
class PathLimits:
    """What the smoothed trajectory must respect. `tcp_ds` is |dp/ds| at the planner's grid
    points (the largest over the tool points), with `tcp_speed` the limit (m/s)."""

    velocity: FloatArray
    acceleration: FloatArray
    jerk: FloatArray | None = None
    tcp_speed: float | None = None
    tcp_ds: FloatArray | None = None


class _Reference:
    """A speed profile as a function of time: s, sdot, sddot and the running integral of s,
    extended by rest before the start and after the end."""

    def __init__(self, profile: SpeedProfile) -> None:
        self.t = profile.t
        self.s = profile.s
        self.v = profile.sdot
        self.u = profile.u
        h = np.diff(self.t)
        pieces = self.s[:-1] * h + self.v[:-1] * h**2 / 2 + self.u * h**3 / 6
        self.integral = np.concatenate([[0.0], np.cumsum(pieces)])

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    def at(self, times: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Integral of s from 0, s, sdot and sddot at `times`."""
        end = self.duration
        length = float(self.s[-1])
        tc = np.clip(times, 0.0, end)
        i = np.clip(np.searchsorted(self.t, tc, side="right") - 1, 0, self.t.size - 2)
        tau = tc - self.t[i]
        s0, v0, u = self.s[i], self.v[i], self.u[i]
        pos = s0 + tau * (v0 + 0.5 * u * tau)
        vel = v0 + u * tau
        acc = u.copy()
        area = self.integral[i] + tau * (s0 + tau * (v0 / 2 + u * tau / 6))
        outside = (times < 0.0) | (times > end)
        vel[outside] = 0.0
        acc[outside] = 0.0
        pos[times < 0.0] = 0.0
        area[times < 0.0] = 0.0
        area = np.where(times > end, area + length * (times - end), area)
        return area, pos, vel, acc


def _filtered(
    ref: _Reference, window: float, times: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """s, sdot, sddot of the moving average of the reference over [t - window, t]."""
    now = ref.at(times)
    before = ref.at(times - window)
    return (
        (now[0] - before[0]) / window,
        (now[1] - before[1]) / window,
        (now[2] - before[2]) / window,
    )


def _knot_times(ref: _Reference, window: float, breakpoints: FloatArray) -> FloatArray:
    """Times where the filtered motion's jerk may jump, with gaps split to MAX_KNOT_GAP.

    The filtered s is a cubic in t between the reference's grid times and their shifts by
    the window; the path's third derivative jumps where s crosses a breakpoint.
    """
    end = ref.duration + window
    kinks = np.unique(np.clip(np.concatenate([ref.t, ref.t + window]), 0.0, end))
    if breakpoints.size:
        s_kinks = _filtered(ref, window, kinks)[0]
        crossings = np.interp(breakpoints, s_kinks, kinks)
        # one Newton step: s is smooth between kinks, the linear guess is off by ~1e-3 s
        pos, vel, _ = _filtered(ref, window, crossings)
        crossings = np.clip(crossings - (pos - breakpoints) / np.maximum(vel, 1e-9), 0.0, end)
        kinks = np.unique(np.concatenate([kinks, crossings]))
    kinks = _spaced(kinks, end)
    gaps = np.diff(kinks)
    parts = np.maximum(1, np.ceil(gaps / MAX_KNOT_GAP - 1e-9).astype(np.intp))
    # every gap split into `parts` equal pieces: a start plus a fraction of the gap
    owner = np.repeat(np.arange(gaps.size), parts)
    first = np.repeat(np.cumsum(parts) - parts, parts)
    frac = (np.arange(owner.size) - first) / parts[owner]
    return np.append(kinks[owner] + frac * gaps[owner], end)


def _spaced(times: FloatArray, end: float) -> FloatArray:
    """`times` (sorted, from 0) thinned so that knots are at least MIN_KNOT_GAP apart, and
    ending at `end`. The filtered s is a difference of two running integrals, exact to
    about 1e-13: over a 5 us segment that noise alone made a quintic jerk of 2e4.

    A time is dropped when it follows the previous time (kept or not) too closely; every
    kept time is then at least the gap after the previous kept one."""
    keep = np.concatenate([[True], np.diff(times) >= MIN_KNOT_GAP])
    keep &= times <= end - MIN_KNOT_GAP
    kept = times[keep]
    return np.append(kept, end) if kept.size else np.array([0.0, end])


@dataclass(frozen=True)
class _Built:
    trajectory: Trajectory
    s: FloatArray  # path parameter at each knot
    sdot: FloatArray


def _build(path: GeometricPath, ref: _Reference, window: float, names: tuple[str, ...]) -> _Built:
    times = _knot_times(ref, window, path.breakpoints)
    s, sd, sdd = _filtered(ref, window, times)
    s = np.clip(s, 0.0, path.length)
    q, d1, d2 = path.derivatives(s)
    dof = q.shape[1]
    speed = np.repeat(sd, dof).reshape(q.shape)  # full shape: faster than (M, 1) columns
    qd = d1 * speed
    qdd = d1 * np.repeat(sdd, dof).reshape(q.shape) + d2 * (speed * speed)
    # rest at both ends exactly, not to rounding
    qd[[0, -1]] = 0.0
    qdd[[0, -1]] = 0.0
    return _Built(Trajectory(names, times, q, qd, qdd), s, sd)


def _segment_ratios(built: _Built, limits: PathLimits, grid: FloatArray) -> FloatArray:
    """Per segment, by how much each limit is exceeded: columns velocity, acceleration,
    jerk, TCP speed as ratios to the limit (<= 1 is fine)."""
    peaks = built.trajectory.peaks()
    count = peaks.velocity.shape[0]
    ratios = np.zeros((count, 4))
    ratios[:, 0] = row_max(peaks.velocity / limits.velocity)
    ratios[:, 1] = row_max(peaks.acceleration / limits.acceleration)
    if limits.jerk is not None:
        ratios[:, 2] = row_max(peaks.jerk / limits.jerk)
    if limits.tcp_speed is not None and limits.tcp_ds is not None:
        speed = np.interp(built.s, grid, limits.tcp_ds) * built.sdot
        at_knots = speed / (limits.tcp_speed * TCP_MARGIN)
        ratios[:, 3] = np.maximum(at_knots[:-1], at_knots[1:])
    return ratios


def _slowdown(ratios: FloatArray) -> FloatArray:
    """The factor on sdot^2 that each ratio asks for: velocity and TCP speed scale with
    sdot, accelerations roughly with sdot^2, jerks with sdot^3."""
    r = np.maximum(ratios, 1.0)
    need = np.minimum.reduce([r[:, 0] ** -2, r[:, 1] ** -1, r[:, 2] ** (-2 / 3), r[:, 3] ** -2])
    return np.asarray(np.minimum(need * SLOWDOWN_MARGIN, SLOWDOWN_MARGIN))


def _range_min(grid: FloatArray, lo: FloatArray, hi: FloatArray, value: FloatArray) -> FloatArray:
    """Per grid point, the least `value` among the intervals [lo, hi] covering it (1.0 when
    none does). Few intervals: a loop of slice minimums."""
    out = np.ones(grid.size)
    first = np.searchsorted(grid, lo, side="left")
    last = np.searchsorted(grid, hi, side="right")
    for a, b, v in zip(first.tolist(), last.tolist(), value.tolist(), strict=True):
        block = out[max(a - 1, 0) : b + 1]  # one grid point beyond: the cap acts on steps
        np.minimum(block, v, out=block)
    return out


def _jerk_cap(path: GeometricPath, grid: FloatArray, jerk: FloatArray) -> FloatArray:
    """At constant speed the joint jerk is q''' sdot^3, so sdot^2 <= (j / |q'''|)^(2/3) is
    needed wherever the profile cruises: a first cap that saves rounds."""
    d3 = path.derivatives3(grid)[3]
    # q''' is constant per spline piece and jumps at its knots: take both sides
    d3 = np.maximum(np.abs(d3), np.abs(path.derivatives3(np.maximum(grid - 1e-9, 0.0))[3]))
    with np.errstate(divide="ignore"):
        return np.asarray(row_min(jerk / d3) ** (2.0 / 3.0))


def smooth(
    path: GeometricPath,
    planner: SpeedPlanner,
    limits: PathLimits,
    window: float,
    joint_names: tuple[str, ...],
) -> Trajectory:
    """The time-optimal profile of `planner`, filtered over `window` seconds and slowed
    where needed until the trajectory is within `limits` (see the module doc)."""
    grid = planner.s
    cap = np.full(grid.size, np.inf)
    if limits.jerk is not None:
        cap = np.minimum(cap, _jerk_cap(path, grid, limits.jerk))
    if limits.tcp_speed is not None and limits.tcp_ds is not None:
        with np.errstate(divide="ignore"):
            cap = np.minimum(cap, (limits.tcp_speed * TCP_MARGIN**2 / limits.tcp_ds) ** 2)
    profile, cap = planner.solve_within(cap)
    for _ in range(MAX_ROUNDS):
        ref = _Reference(profile)
        built = _build(path, ref, window, joint_names)
        ratios = _segment_ratios(built, limits, grid)
        worst = ratios.max(axis=0)
        stretch = _stretch(worst)
        if stretch <= 1.0 + SCALE_TOLERANCE:
            return _time_scaled(built.trajectory, stretch)
        if worst[2] > 1.0 and max(worst[0], worst[1], worst[3]) <= 1.0:
            # Only jerk is over: the profile's acceleration swings (TOPP-RA's sddot is
            # piecewise constant and swings by more than 2 a where q'' sdot^2 helps), not
            # its speed. Path jerk is that swing over the window: widen the window, which
            # costs its growth in duration once, instead of capping sdot all along.
            window *= worst[2] / SLOWDOWN_MARGIN
            continue
        # segment k depends on the reference over [t_k - W, t_k+1]
        bad = np.flatnonzero(row_max(ratios) > 1.0)
        t = built.trajectory.t
        lo = ref.at(t[bad] - window)[1]
        hi = ref.at(t[bad + 1])[1]
        factor = _range_min(grid, lo, hi, _slowdown(ratios[bad]))
        cap = np.minimum(cap, np.where(factor < 1.0, profile.x * factor, np.inf))
        profile, cap = planner.solve_within(cap)
    return _time_scaled(built.trajectory, stretch)


def _stretch(worst: FloatArray) -> float:
    """The uniform time scaling k that brings the worst ratios (velocity, acceleration,
    jerk, TCP speed) to 1: they scale as 1/k, 1/k^2, 1/k^3, 1/k."""
    return float(max(1.0, worst[0], worst[1] ** 0.5, worst[2] ** (1 / 3), worst[3]))


def _time_scaled(traj: Trajectory, k: float) -> Trajectory:
    """The same motion slowed uniformly by k (exact for the quintic pieces: their shapes in
    normalised time do not change)."""
    if k <= 1.0:
        return traj
    return traj.time_scaled(k * (1.0 + 1e-12))  # rounding must not leave a ratio above 1
