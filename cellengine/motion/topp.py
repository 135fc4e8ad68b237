"""Geometric paths through joint waypoints and their time-optimal speed profiles (TOPP-RA).

The path is a C2 cubic spline q(s) through the waypoints with s the cumulative joint-space
chord length (so |dq/ds| stays near 1 and a uniform grid in s is a uniform grid along the
motion). Chosen over MoveIt's TOTG (straight lines with circular blends) because:

- it passes through every waypoint, which a planner or a Cartesian path collision-checked;
  blends cut the corners, between waypoints nobody checked;
- it is C2, so the path acceleration q''(s) is continuous and a collocation grid resolves it
  without the switching-point special cases TOTG needs at blend ends;
- toppra uses the same kind of path, so the duration comparison is like for like.

Its cost: a cubic spline can bulge between waypoints that turn sharply; the trajectory gate
checks collisions on the timed trajectory anyway.

The speed profile follows TOPP-RA (Pham & Pham 2018): with x = sdot^2 and u = sddot,
joint velocity and acceleration limits are linear in (u, x) at every grid point. The
backward pass computes the controllable sets (the largest x at each grid point from which
the end can still be reached at rest), the forward pass then takes the largest admissible
u at each step while staying controllable. With box limits only, each set is an interval
whose end is a minimum of per-joint closed forms: the coefficients are computed for all
grid points and joints at once with numpy, and the two sequential passes run on plain
Python floats (a few joints per step), which is faster than numpy for short rows.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from cellengine.arrays import FloatArray

# A joint whose path derivative |dq_j/ds| is below this is treated as not moving along s
# there: its velocity limit cannot bind and its acceleration limit bounds x alone.
_STILL = 1e-9
# Spline systems up to this many rows are solved densely.
_DENSE_SOLVE = 300
# Stand-in for "no bound" in the per-joint closed forms (finite, so 0 * _HUGE is 0).
_HUGE = 1e300
# Points checked inside every grid step, and the share of the overshoot ratio taken off
# sdot^2 there (a hair more than the ratio, so that rounds converge).
STEP_SAMPLES = 3
STEP_MARGIN = 0.998


class GeometricPath(Protocol):
    """A path q(s), s in [0, length], in joint space, with its first three derivatives and
    the parameter values where the third one jumps (a spline's inner knots)."""

    @property
    def length(self) -> float: ...

    @property
    def breakpoints(self) -> FloatArray: ...

    def derivatives(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """q(s), dq/ds and d2q/ds2 at each s, each of shape (len(s), dof)."""
        ...

    def derivatives3(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """q(s) and its first three derivatives; the third from the right at breakpoints."""
        ...


class SplinePath:
    """A C2 cubic spline through joint waypoints, parameterised by chord length.

    `waypoints` is (N, n), N >= 2. Consecutive duplicates are dropped (they would give a
    zero-length interval). `knots` overrides the chord-length parameter values (strictly
    increasing, one per waypoint). End conditions are not-a-knot (N >= 4), as scipy's and
    toppra's default: the ends take the curvature the data suggest, instead of the
    zero curvature of a natural spline or the zero slope of a clamped one (a zero slope
    would make the path speed unbounded at the ends).
    """

    def __init__(self, waypoints: ArrayLike, knots: ArrayLike | None = None) -> None:
        wp = np.array(waypoints, dtype=np.float64)
        if wp.ndim != 2 or wp.shape[0] < 2 or wp.shape[1] < 1:
            raise ValueError(f"waypoints must be (N >= 2, n >= 1), got shape {wp.shape}")
        if not np.all(np.isfinite(wp)):
            raise ValueError("waypoints hold a non-finite value")
        if knots is None:
            step = np.linalg.norm(np.diff(wp, axis=0), axis=1)
            keep = np.concatenate([[True], step > 1e-12])
            wp = wp[keep]
            if wp.shape[0] < 2:
                raise ValueError("all waypoints are the same: there is no path to time")
            s = np.concatenate([[0.0], np.cumsum(step[keep[1:]])])
        else:
            s = np.array(knots, dtype=np.float64)
            if s.shape != (wp.shape[0],) or np.any(np.diff(s) <= 0):
                raise ValueError("knots must be strictly increasing, one per waypoint")
        self.knots: FloatArray = s
        self.waypoints: FloatArray = wp
        # per piece, q = c0 + c1 x + c2 x^2 + c3 x^3 with x = s - knot
        m = _second_derivatives(s, wp)
        h = np.diff(s)[:, None]
        slope = np.diff(wp, axis=0) / h - h * (2.0 * m[:-1] + m[1:]) / 6.0
        self._coef = tuple(
            np.ascontiguousarray(c)
            for c in (wp[:-1], slope, m[:-1] / 2.0, (m[1:] - m[:-1]) / (6.0 * h))
        )

    @property
    def length(self) -> float:
        return float(self.knots[-1] - self.knots[0])

    @property
    def dof(self) -> int:
        return int(self.waypoints.shape[1])

    @property
    def breakpoints(self) -> FloatArray:
        """Parameter values (from 0) of the inner waypoints, where d3q/ds3 jumps."""
        return np.asarray(self.knots[1:-1] - self.knots[0])

    def extremes(self) -> tuple[FloatArray, FloatArray]:
        """Least and greatest value of each joint over each cubic piece, (N-1, n) each:
        the ends and the roots of dq/ds inside the piece, exactly."""
        c0, c1, c2, c3 = self._coef
        width = np.repeat(np.diff(self.knots), self.dof).reshape(c0.shape)
        values = [c0, c0 + width * (c1 + width * (c2 + width * c3))]
        # dq/ds = c1 + 2 c2 x + 3 c3 x^2 = 0
        a, b = 3.0 * c3, 2.0 * c2
        with np.errstate(divide="ignore", invalid="ignore"):
            root = np.sqrt(np.maximum(b * b - 4.0 * a * c1, 0.0))
            for x in ((-b + root) / (2.0 * a), (-b - root) / (2.0 * a), -c1 / b):
                x = np.where(np.isfinite(x), np.clip(x, 0.0, width), 0.0)
                values.append(c0 + x * (c1 + x * (c2 + x * c3)))
        return np.minimum.reduce(values), np.maximum.reduce(values)

    def derivatives(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        q, d1, d2, _ = self.derivatives3(s)
        return q, d1, d2

    def derivatives3(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """q, dq/ds, d2q/ds2 and d3q/ds3 at path parameters s (measured from 0)."""
        knots = self.knots
        ss = np.clip(np.asarray(s, dtype=np.float64) + knots[0], knots[0], knots[-1])
        k = np.clip(np.searchsorted(knots, ss, side="right") - 1, 0, knots.size - 2)
        # np.take on contiguous arrays and a full-shape x: several times faster than fancy
        # indexing and (M, 1) broadcasting (measured: 64 vs 370 us for 7350 points)
        x = np.repeat(ss - knots[k], self.dof).reshape(k.size, self.dof)
        c0, c1, c2, c3 = (np.take(c, k, axis=0) for c in self._coef)
        q = c0 + x * (c1 + x * (c2 + x * c3))
        d1 = c1 + x * (2.0 * c2 + x * (3.0 * c3))
        d2 = 2.0 * c2 + x * (6.0 * c3)
        return q, d1, d2, 6.0 * c3


def _second_derivatives(s: FloatArray, y: FloatArray) -> FloatArray:
    """Second derivatives at the knots of the not-a-knot cubic spline through (s, y)."""
    count = s.size
    if count == 2:
        return np.zeros_like(y)
    h = np.diff(s)
    slopes = np.diff(y, axis=0) / h[:, None]
    if count == 3:  # not-a-knot with three points: the parabola through them
        curvature = 2.0 * (slopes[1] - slopes[0]) / (h[0] + h[1])
        return np.repeat(curvature[None, :], 3, axis=0)
    # Rows 1..N-2 of h[k-1] M[k-1] + 2(h[k-1]+h[k]) M[k] + h[k] M[k+1] = 6 (slope jump);
    # the not-a-knot conditions give M[0] and M[N-1] from their neighbours, which folds
    # them into the first and last rows and keeps the system tridiagonal.
    rhs = 6.0 * np.diff(slopes, axis=0)
    lower = h[:-1].copy()
    diag = 2.0 * (h[:-1] + h[1:])
    upper = h[1:].copy()
    diag[0] += h[0] + h[0] * h[0] / h[1]
    upper[0] -= h[0] * h[0] / h[1]
    diag[-1] += h[-1] + h[-1] * h[-1] / h[-2]
    lower[-1] -= h[-1] * h[-1] / h[-2]
    inner = _solve_tridiagonal(lower, diag, upper, rhs)
    first = ((h[0] + h[1]) * inner[0] - h[0] * inner[1]) / h[1]
    last = ((h[-2] + h[-1]) * inner[-1] - h[-1] * inner[-2]) / h[-2]
    return np.vstack([first, inner, last])


def _solve_tridiagonal(
    lower: FloatArray, diag: FloatArray, upper: FloatArray, rhs: FloatArray
) -> FloatArray:
    """lower[i] multiplies x[i-1] in row i (lower[0] unused), upper[i] multiplies x[i+1].
    A dense LAPACK solve up to a few hundred rows (one call, faster than a Python loop
    there), the Thomas algorithm beyond (one scalar factorisation for every column)."""
    size = diag.size
    if size <= _DENSE_SOLVE:
        matrix = np.diag(diag) + np.diag(lower[1:], -1) + np.diag(upper[:-1], 1)
        return np.asarray(np.linalg.solve(matrix, rhs))
    lo, up = lower.tolist(), upper.tolist()
    pivot = [float(diag[0])]
    factor = [0.0]
    for i in range(1, size):
        f = lo[i] / pivot[i - 1]
        factor.append(f)
        pivot.append(float(diag[i]) - f * up[i - 1])
    out = np.array(rhs, dtype=np.float64)
    for i in range(1, size):
        out[i] -= factor[i] * out[i - 1]
    out[-1] /= pivot[-1]
    for i in range(size - 2, -1, -1):
        out[i] = (out[i] - up[i] * out[i + 1]) / pivot[i]
    return out


@dataclass(frozen=True)
class SpeedProfile:
    """A speed profile along a path on a grid: `s` (K,), `x` = sdot^2 (K,), `u` = sddot
    per step (K-1,) (constant on [s_i, s_i+1]), `t` (K,) the time at each grid point."""

    s: FloatArray
    x: FloatArray
    u: FloatArray
    t: FloatArray

    @property
    def duration(self) -> float:
        return float(self.t[-1])

    @property
    def sdot(self) -> FloatArray:
        return np.sqrt(self.x)


@dataclass(frozen=True)
class _Constraints:
    """Joint acceleration limits on a grid as u in [-d - c x, d - c x] per joint."""

    c: FloatArray  # (K, n) ddq/dq
    d: FloatArray  # (K, n) a/|dq|
    x_max: FloatArray  # (K,) largest admissible x at each grid point on its own


def _constraints(
    slope: FloatArray,
    curve: FloatArray,
    limit: FloatArray,
    x_cap: FloatArray,
) -> _Constraints:
    """Rows |slope u + curve x| <= limit, (K, R) each, as u-intervals per row plus the
    largest x each grid point admits on its own (rows that do not involve u bound x)."""
    moving = np.abs(slope) > _STILL
    safe = np.where(moving, slope, 1.0)
    c = np.where(moving, curve / safe, 0.0)
    d = np.where(moving, limit / np.abs(safe), _HUGE)
    with np.errstate(divide="ignore"):
        # a row without u: |curve| x <= limit is all it says
        x_still = row_min(np.where(moving, np.inf, limit / np.abs(curve)))
    x_max = np.minimum(np.minimum(x_cap, x_still), _acceleration_mvc(c, d))
    return _Constraints(c, d, x_max)


def row_max(a: FloatArray) -> FloatArray:
    """a.max(axis=1) for a few columns: column by column is ten times faster than numpy's
    reduction along short rows (22 us for (491, 6) on the benchmark machine)."""
    out = a[:, 0].copy()
    for j in range(1, a.shape[1]):
        np.maximum(out, a[:, j], out=out)
    return out


def row_min(a: FloatArray) -> FloatArray:
    """a.min(axis=1), column by column (see row_max)."""
    out = a[:, 0].copy()
    for j in range(1, a.shape[1]):
        np.minimum(out, a[:, j], out=out)
    return out


def _acceleration_mvc(c: FloatArray, d: FloatArray) -> FloatArray:
    """Largest x at which some u satisfies every row's acceleration limit.

    The u-interval is nonempty iff every lower bound -d_j - c_j x is below every upper
    bound d_k - c_k x, i.e. (c_k - c_j) x <= d_j + d_k for every ordered pair; for each
    unordered pair one of the two orders binds: x <= (d_j + d_k) / |c_j - c_k|.
    """
    # rows as contiguous (R, K) arrays: minima over axis 0 are fast, over short rows not
    ct, dt = np.ascontiguousarray(c.T), np.ascontiguousarray(d.T)
    out = np.full(c.shape[0], np.inf)
    with np.errstate(divide="ignore", over="ignore"):  # inf is the right bound there
        for j in range(ct.shape[0] - 1):  # one row against the rest: small arrays
            bound = (dt[j] + dt[j + 1 :]) / np.abs(ct[j] - ct[j + 1 :])
            np.minimum(out, bound.min(axis=0), out=out)
    return out


def _grid(length: float, breakpoints: FloatArray, points: int) -> FloatArray:
    """About `points` grid points over [0, length], every breakpoint among them and the
    pieces between breakpoints split evenly, no step longer than length / (points - 1)."""
    edges = np.unique(
        np.concatenate([[0.0], breakpoints[(breakpoints > 0) & (breakpoints < length)], [length]])
    )
    widths = np.diff(edges)
    parts = np.maximum(1, np.ceil(widths / (length / (points - 1)) - 1e-9).astype(np.intp))
    owner = np.repeat(np.arange(widths.size), parts)
    first = np.repeat(np.cumsum(parts) - parts, parts)
    frac = (np.arange(owner.size) - first) / parts[owner]
    return np.append(edges[owner] + frac * widths[owner], length)


class SpeedPlanner:
    """TOPP-RA on one path, under symmetric joint velocity and acceleration limits. The
    per-row closed forms are computed once; `solve` runs the two passes, under an optional
    extra bound on sdot^2 per grid point (a TCP speed limit, the slow-downs that jerk
    limiting asks for).

    Grid: about `grid_points` points, every spline knot among them (`_grid`). A knot is
    where the path turns most, so the slowest point of a curve is on the grid, and no
    step straddles a change of cubic piece: duration 1 % shorter once checked, on the
    benchmark's paths, than with an even grid of as many points.

    Discretisation: TOPP-RA's "interpolation" scheme, extended. Each step's constant u
    must satisfy the acceleration limits at its start, its middle and its end (x there is
    x_i + 2 f ds u), not only at its start ("collocation"). Where a joint reverses along
    the path, dq_j/ds passes through zero and collocation pins u to a narrow band valid at
    one end only: jagged profiles, 30 % slow at 100 points. Rows at both ends brought
    that to 5 %; the middle rows cut the overshoot inside steps from 2.5 % to 0.5 %.

    Like toppra's, the profile meets the limits where it has rows only; `solve_within`
    checks STEP_SAMPLES points inside every step and lowers sdot^2 at both ends of a
    step that still overshoots, by the ratio found (x and u then both scale by it, and so
    does the joint acceleration inside the step).
    """

    def __init__(
        self,
        path: GeometricPath,
        velocity: ArrayLike,
        acceleration: ArrayLike,
        grid_points: int,
    ) -> None:
        if grid_points < 2:
            raise ValueError(f"grid_points must be at least 2, got {grid_points}")
        self.s = _grid(path.length, np.asarray(path.breakpoints), grid_points)
        self.steps = np.diff(self.s)
        self.q, self.dq, self.ddq, self._d3 = path.derivatives3(self.s)
        self.velocity = np.asarray(velocity, dtype=np.float64)
        self.acceleration = np.asarray(acceleration, dtype=np.float64)
        with np.errstate(divide="ignore"):
            x_vel = row_min(self.velocity / np.abs(self.dq)) ** 2
        # rows at the step's middle and end, where x = x_i + 2 f ds u (f = 1/2, 1). No
        # step straddles a breakpoint, so the middle's derivatives are a Taylor expansion
        # from the start, and the end's are the next grid point's (the path is C2). The
        # last grid point has no step: its own rows again (x is 0 there).
        half = 0.5 * self.steps[:, None]
        ddq_mid = self.ddq[:-1] + half * self._d3[:-1]
        dq_mid = self.dq[:-1] + half * (self.ddq[:-1] + 0.5 * half * self._d3[:-1])
        lift = 2.0 * self.steps[:, None]
        slopes = [
            self.dq,
            np.vstack([dq_mid + 2.0 * half * ddq_mid, self.dq[-1:]]),
            np.vstack([self.dq[1:] + lift * self.ddq[1:], self.dq[-1:]]),
        ]
        curves = [
            self.ddq,
            np.vstack([ddq_mid, self.ddq[-1:]]),
            np.vstack([self.ddq[1:], self.ddq[-1:]]),
        ]
        self._cons = _constraints(
            np.hstack(slopes),
            np.hstack(curves),
            np.tile(self.acceleration, len(slopes)),
            x_vel,
        )
        self._passes = _Passes.of(self._cons, self.steps)
        self._inside: list[tuple[FloatArray, FloatArray]] | None = None
        self._step_list: list[float] = self.steps.tolist()
        self._last: _Solution | None = None

    @property
    def x_max(self) -> FloatArray:
        """The largest sdot^2 each grid point admits on its own (the maximum velocity curve)."""
        return self._cons.x_max

    def solve(self, x_cap: FloatArray | None = None) -> SpeedProfile:
        """The time-optimal rest-to-rest profile, with sdot^2 <= x_cap (K,) if given.

        Each solve starts from the planner's previous one and recomputes only what the
        changed caps reach (a slow-down round changes a few grid points): the result is
        the same as from scratch."""
        caps = self._passes.x_max if x_cap is None else np.minimum(self._passes.x_max, x_cap)
        cap_list = caps.tolist()
        old = self._last
        upper, touched = _backward_pass(self._passes, cap_list, old)
        xs, us = _forward_pass(self._passes, upper, self._step_list, old, touched)
        self._last = _Solution(cap_list, upper, xs, us)
        x = np.array(xs)
        return SpeedProfile(self.s, x, np.array(us), _times(x, self.steps))

    def step_ratios(self, profile: SpeedProfile) -> FloatArray:
        """Per step, the worst |joint acceleration| / limit at the samples inside the step:
        the factor by which sdot^2 is too high there. (Velocity inside a step only strays
        by the curvature of |dq/ds| over one step; the final check covers it.)"""
        if self._inside is None:
            self._inside = self._inside_rows()
        dof = self.velocity.size
        u = np.repeat(profile.u, dof).reshape(-1, dof)
        x0 = np.repeat(profile.x[:-1], dof).reshape(u.shape)
        worst = np.zeros(u.shape)
        for acc_u, acc_x in self._inside:
            np.maximum(worst, np.abs(acc_u * u + acc_x * x0), out=worst)
        return row_max(worst)

    def _inside_rows(self) -> list[tuple[FloatArray, FloatArray]]:
        """At fraction f of a step, x = x_i + 2 f ds u, so a joint's acceleration over its
        limit is |(dq + 2 f ds ddq) u + ddq x_i| / a: fixed (K-1, n) coefficients times
        u and x_i, one pair per fraction (arrays past ~40 kB cost page faults on every
        allocation on the benchmark machine: no (K, S, n) blocks). No step straddles a
        breakpoint, so inside a step the path is one cubic: its derivatives there are a
        Taylor expansion from the step's start, exact."""
        dq, ddq, d3 = self.dq[:-1], self.ddq[:-1], self._d3[:-1]
        inv = 1.0 / self.acceleration
        rows: list[tuple[FloatArray, FloatArray]] = []
        for frac in (np.arange(1, STEP_SAMPLES + 1) / (STEP_SAMPLES + 1)).tolist():
            h = (frac * self.steps)[:, None]
            ddq_in = ddq + h * d3
            dq_in = dq + h * (ddq + 0.5 * h * d3)
            rows.append(((dq_in + 2.0 * h * ddq_in) * inv, ddq_in * inv))
        return rows

    def solve_within(
        self, x_cap: FloatArray | None = None, tolerance: float = 1e-2, rounds: int = 8
    ) -> tuple[SpeedProfile, FloatArray]:
        """`solve`, then lower sdot^2 around steps that overshoot inside by more than
        `tolerance` and solve again, at most `rounds` times. Returns the profile and the
        cap it ended with (for callers that lower it further)."""
        cap = np.full(self.s.size, np.inf) if x_cap is None else np.array(x_cap)
        profile = self.solve(cap)
        for _ in range(rounds):
            ratio = self.step_ratios(profile)
            bad = ratio > 1.0 + tolerance
            if not bad.any():
                break
            factor = np.ones(self.s.size)
            need = np.where(bad, STEP_MARGIN / ratio, 1.0)
            np.minimum(factor[:-1], need, out=factor[:-1])
            np.minimum(factor[1:], need, out=factor[1:])
            cap = np.minimum(cap, np.where(factor < 1.0, profile.x * factor, np.inf))
            profile = self.solve(cap)
        return profile, cap


def speed_profile(
    path: GeometricPath,
    velocity: ArrayLike,
    acceleration: ArrayLike,
    grid_points: int,
    x_cap: FloatArray | None = None,
) -> SpeedProfile:
    """The time-optimal rest-to-rest speed profile of `path` (see SpeedPlanner)."""
    return SpeedPlanner(path, velocity, acceleration, grid_points).solve(x_cap)


@dataclass(frozen=True)
class _Passes:
    """The rows of both passes, pruned once per planner.

    Backward: x_i is controllable iff some admissible u_i lands x_i + 2 ds u_i in
    K_i+1 = [0, k], i.e. for every row  x_i + 2 ds (-d - c x_i) <= k  (the lowest landing
    point is low enough) and  x_i + 2 ds (d - c x_i) >= 0  (the highest is not negative).
    With e = 1 - 2 ds c the first reads x_i <= k / e + 2 ds d / e when e > 0: a line in
    k. The second bounds x_i only when e < 0 (a coarse grid on a tight curve) and does not
    depend on k, so it joins x_max.

    Forward: the largest u is the least of d - c x_i over the rows: a line in x_i.

    Each pass only needs the rows that can be the least for some argument in its range;
    ranges only shrink under extra caps, so pruning against the uncapped ones holds for
    every solve.
    """

    x_max: FloatArray
    backward: _Rows
    forward: _Rows

    @staticmethod
    def of(cons: _Constraints, steps: FloatArray) -> _Passes:
        step = np.append(steps, steps[-1])[:, None]  # the last point has no step: any
        e = 1.0 - 2.0 * step * cons.c
        grows = e > 0.0
        safe_e = np.where(grows, e, 1.0)
        slope = np.where(grows, 1.0 / safe_e, 0.0)
        offset = np.where(grows, 2.0 * step * cons.d / safe_e, np.inf)
        coarse = np.where(grows, np.inf, 2.0 * step * cons.d / np.where(grows, 1.0, -e))
        x_max = np.minimum(cons.x_max, row_min(coarse))
        next_max = np.append(x_max[1:], 0.0)  # the range of k = K_i+1's top
        backward = _Rows.lower_envelope(slope, offset, next_max, x_max, x_max)
        never = np.full(x_max.size, np.inf)
        forward = _Rows.lower_envelope(-cons.c, cons.d, x_max, never, never)
        return _Passes(x_max, backward, forward)


@dataclass(frozen=True)
class _Solution:
    """A solve's inputs and results as plain lists, for the next solve to start from."""

    caps: list[float]
    upper: list[float]
    xs: list[float]
    us: list[float]


def _backward_pass(
    passes: _Passes, caps: list[float], old: _Solution | None
) -> tuple[list[float], list[int]]:
    """Upper ends of the controllable sets K_i under the per-point caps (their lower ends
    are 0: starting at x = 0 with u = 0 is always admissible), and the indices whose
    value differs from `old`'s.

    With `old`, only what the changed caps reach is recomputed: from each changed index
    downwards until a value comes out equal to the old one at an unchanged index, after
    which every value below is the old one (same inputs, same arithmetic).
    """
    slope, offset, start = passes.backward.slope, passes.backward.offset, passes.backward.start
    count = len(caps)
    if old is None:
        upper = [0.0] * count  # the end is reached at rest
        todo = [count - 2]
    else:
        upper = list(old.upper)
        todo = [i for i in range(count - 2, -1, -1) if caps[i] != old.caps[i]]
    changed = set(todo)
    touched = []
    k = 0
    while k < len(todo):
        i = todo[k]
        reach = upper[i + 1]
        while i >= 0:
            bound = caps[i]
            for r in range(start[i], start[i + 1]):
                v = slope[r] * reach + offset[r]
                if v < bound:
                    bound = v
            if bound < 0.0:
                bound = 0.0
            if bound == upper[i]:
                if old is not None and i not in changed:
                    break
            else:
                upper[i] = bound
                touched.append(i)
            reach = bound
            i -= 1
        while k < len(todo) and todo[k] >= i:
            k += 1
    upper[0] = 0.0  # the start is at rest too
    return upper, touched


def _forward_pass(
    passes: _Passes,
    upper: list[float],
    steps: list[float],
    old: _Solution | None,
    touched: list[int],
) -> tuple[list[float], list[float]]:
    """Greedy pass: at each step the largest u that the rows admit at x_i and that keeps
    x_i+1 inside the controllable set. With `old`, only from the steps whose target set
    changed (`touched` upper ends), each until x comes out equal to the old one."""
    slope, offset, start = passes.forward.slope, passes.forward.offset, passes.forward.start
    count = len(upper)
    if old is None:
        xs = [0.0] * count
        us = [0.0] * (count - 1)
        todo = [0]
    else:
        xs, us = list(old.xs), list(old.us)
        todo = sorted({max(i - 1, 0) for i in touched})
    pending = set(todo)
    k = 0
    while k < len(todo):
        i = todo[k]
        x = xs[i]
        while i < count - 1:
            two_step = 2.0 * steps[i]
            top = upper[i + 1]
            best = (top - x) / two_step
            for r in range(start[i], start[i + 1]):
                v = offset[r] + slope[r] * x
                if v < best:
                    best = v
            nxt = x + two_step * best
            # rounding can step a hair outside [0, K_i+1]; the sets say it must not
            if nxt < 0.0:
                nxt = 0.0
            elif nxt > top:
                nxt = top
            us[i] = (nxt - x) / two_step
            if old is not None and nxt == xs[i + 1] and i + 1 not in pending:
                break
            xs[i + 1] = nxt
            x = nxt
            i += 1
        while k < len(todo) and todo[k] <= i:
            k += 1
    return xs, us


@dataclass(frozen=True)
class _Rows:
    """Per grid point, the lines y = slope z + offset that can be the lowest for z in
    [0, z_max], flattened: grid point i owns rows start[i] .. start[i+1] - 1.

    Pruning with numpy first keeps the sequential passes to the two or three rows that can
    bind instead of every joint at both ends of the step.
    """

    slope: list[float]
    offset: list[float]
    start: list[int]

    @staticmethod
    def lower_envelope(
        slope: FloatArray,
        offset: FloatArray,
        z_max: FloatArray,
        ceiling_lo: FloatArray,
        ceiling_hi: FloatArray,
    ) -> _Rows:
        """Drop rows above another row at both z = 0 and z = z_max (lines: then above it
        throughout), and rows not below the ceiling (a line given by its values at z = 0
        and z_max) at either end.

        Sorted by the value at z = 0, a row is above an earlier one at both ends iff its
        value at z_max is not below the least value at z_max so far: a staircase, found
        with one sort and a running minimum per grid point. (Rows tied at z = 0 may keep
        a redundant member: harmless.)
        """
        lo = offset
        with np.errstate(invalid="ignore"):  # 0 * inf for rows that never bind
            hi = np.where(np.isfinite(offset), offset + slope * z_max[:, None], np.inf)
        order = np.argsort(lo, axis=1, kind="stable")
        hi_sorted = np.take_along_axis(hi, order, axis=1)
        least_before = np.minimum.accumulate(hi_sorted, axis=1)
        least_before = np.hstack([np.full((hi.shape[0], 1), np.inf), least_before[:, :-1]])
        staircase = np.zeros(hi.shape, dtype=bool)
        np.put_along_axis(staircase, order, hi_sorted < least_before, axis=1)
        useful = (lo < ceiling_lo[:, None]) | (hi < ceiling_hi[:, None])
        keep = staircase & useful
        start = np.concatenate([[0], np.cumsum(keep.sum(axis=1))])
        return _Rows(slope[keep].tolist(), offset[keep].tolist(), start.tolist())


def _times(x: FloatArray, steps: FloatArray) -> FloatArray:
    """Time at each grid point: sddot is constant per step, so sdot is linear in time and a
    step takes 2 ds / (sdot_i + sdot_i+1)."""
    sdot = np.sqrt(x)
    pace = sdot[:-1] + sdot[1:]
    if np.any(pace <= 0.0):
        i = int(np.argmax(pace <= 0.0))
        raise ValueError(f"the path cannot be traversed: the speed is zero around step {i}")
    return np.concatenate([[0.0], np.cumsum(2.0 * steps / pace)])
