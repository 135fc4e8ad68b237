"""The timed joint trajectory that the motion layer, the executor and the drivers share.

A `Trajectory` is a list of knots (time, positions, velocities, accelerations) with a
quintic Hermite polynomial per segment between consecutive knots: the interpolation that
ROS's joint_trajectory_controller uses when a point carries positions, velocities and
accelerations, so `sample` here and a ROS controller playing `to_json()` move alike.

The quintic matches position, velocity and acceleration at both ends of a segment, so a
producer must store derivatives that belong to one C2 motion: a trajectory whose
acceleration jumps at a knot (a bang-bang profile) cannot be represented without the
polynomial overshooting next to that knot. Jerk-limited producers (timing.py) satisfy this.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from cellengine.arrays import FloatArray

# Junctions of concatenated trajectories must agree to this (rad or m, and per second).
JOIN_TOLERANCE = 1e-6
# Samples per segment behind Trajectory.peaks' bounds on velocity and acceleration.
PEAK_SUBDIVISIONS = 4
# Times sampled per block (keeps every temporary array small; see _quintic_coefficients).
_BLOCK = 1024


class Peaks(NamedTuple):
    """Per segment and joint (N-1, n): bounds on |velocity|, |acceleration|, |jerk|."""

    velocity: FloatArray
    acceleration: FloatArray
    jerk: FloatArray


def _frozen(value: ArrayLike, name: str, ndim: int) -> FloatArray:
    try:
        arr = np.array(value, dtype=np.float64)  # a copy: the caller's array stays theirs
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be numeric: {exc}") from None
    if arr.ndim != ndim:
        raise ValueError(f"{name} must have {ndim} dimension(s), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ValueError(f"{name} holds a non-finite value at index {tuple(int(i) for i in bad)}")
    arr.flags.writeable = False
    return arr


def _quintic_coefficients(
    t: FloatArray, q: FloatArray, qd: FloatArray, qdd: FloatArray
) -> tuple[FloatArray, ...]:
    """Per segment, the coefficients c0..c5 of p(tau) = sum c_k tau^k, tau in [0, 1]: six
    (N-1, n) arrays (separate, not one (N-1, 6, n) block: arrays past ~100 kB cost a page
    fault per page on every allocation on the benchmark machine).

    Matching q, qd, qdd at both ends fixes c0..c2 from the start and c3..c5 from the three
    end-point residuals (the closed form of the 3x3 solve).
    """
    # full-shape h: broadcasting an (N-1, 1) column is several times slower
    h = np.repeat(np.diff(t), q.shape[1]).reshape(q.shape[0] - 1, q.shape[1])
    hh = h * h
    q0, q1, v0, v1, a0, a1 = q[:-1], q[1:], qd[:-1], qd[1:], qdd[:-1], qdd[1:]
    c2 = 0.5 * a0 * hh
    dq = q1 - q0 - v0 * h - c2
    dv = (v1 - v0 - a0 * h) * h
    da = (a1 - a0) * hh
    c3 = 10.0 * dq - 4.0 * dv + 0.5 * da
    c4 = -15.0 * dq + 7.0 * dv - da
    c5 = 6.0 * dq - 3.0 * dv + 0.5 * da
    coef = (np.ascontiguousarray(q0), v0 * h, c2, c3, c4, c5)
    for c in coef:
        c.flags.writeable = False
    return coef


@dataclass(frozen=True, eq=False)
class Trajectory:
    """An immutable timed joint trajectory: knots at strictly increasing times `t` (s), with
    positions `q`, velocities `qd` and accelerations `qdd` (N knots x n joints, SI units).

    Arrays are copied and made read-only at construction; shapes, finiteness and the strict
    increase of `t` are checked there (ValueError naming what is wrong).
    """

    joint_names: tuple[str, ...]
    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    _coef: tuple[FloatArray, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        names = tuple(self.joint_names)
        if not names or not all(isinstance(n, str) and n for n in names):
            raise ValueError("joint_names must be a non-empty sequence of non-empty strings")
        if len(set(names)) != len(names):
            dup = sorted({n for n in names if names.count(n) > 1})
            raise ValueError(f"joint_names repeats {', '.join(dup)}")
        t = _frozen(self.t, "t", 1)
        arrays = {k: _frozen(getattr(self, k), k, 2) for k in ("q", "qd", "qdd")}
        if t.size == 0:
            raise ValueError("a trajectory needs at least one point; t is empty")
        for key, arr in arrays.items():
            if arr.shape != (t.size, len(names)):
                raise ValueError(
                    f"{key} has shape {arr.shape}; expected ({t.size}, {len(names)}) "
                    f"for {t.size} times and {len(names)} joints"
                )
        steps = np.diff(t)
        if np.any(steps <= 0.0):
            k = int(np.argmax(steps <= 0.0))
            raise ValueError(
                f"t must strictly increase; t[{k + 1}] = {float(t[k + 1])!r} "
                f"follows t[{k}] = {float(t[k])!r}"
            )
        for key, value in (("joint_names", names), ("t", t), *arrays.items()):
            object.__setattr__(self, key, value)
        coef = _quintic_coefficients(t, arrays["q"], arrays["qd"], arrays["qdd"])
        object.__setattr__(self, "_coef", coef)

    # -- basic properties -------------------------------------------------------------

    @property
    def dof(self) -> int:
        return len(self.joint_names)

    @property
    def start_time(self) -> float:
        return float(self.t[0])

    @property
    def end_time(self) -> float:
        return float(self.t[-1])

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0])

    def __len__(self) -> int:
        return int(self.t.size)

    def __repr__(self) -> str:
        return (
            f"Trajectory({self.dof} joints, {len(self)} points, "
            f"t = {self.start_time:g}..{self.end_time:g} s)"
        )

    # -- sampling ---------------------------------------------------------------------

    def _locate(self, t: ArrayLike) -> tuple[NDArray[np.intp], FloatArray, FloatArray]:
        """Segment index, normalised time tau in [0, 1] and segment length for each time;
        times outside [start, end] are clamped to the ends."""
        ts = np.clip(np.asarray(t, dtype=np.float64), self.t[0], self.t[-1])
        seg = np.clip(np.searchsorted(self.t, ts, side="right") - 1, 0, self.t.size - 2)
        h = self.t[seg + 1] - self.t[seg]
        return seg, (ts - self.t[seg]) / h, h

    def sample(self, t: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Positions, velocities and accelerations at time(s) `t`.

        A scalar gives arrays of shape (n,), an array of M times gives (M, n). Times before
        the start or after the end are clamped: the end point's stored state is returned.
        """
        scalar = np.ndim(t) == 0
        ts = np.atleast_1d(np.asarray(t, dtype=np.float64)).ravel()
        if self.t.size == 1:
            out = tuple(np.repeat(a, ts.size, axis=0) for a in (self.q, self.qd, self.qdd))
        else:
            parts = [self._sample_block(ts[i : i + _BLOCK]) for i in range(0, ts.size, _BLOCK)]
            out = tuple(np.concatenate(p) for p in zip(*parts, strict=True))
        if scalar:
            return out[0][0], out[1][0], out[2][0]
        return out[0], out[1], out[2]

    def _sample_block(self, ts: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        seg, tau, h = self._locate(ts)
        c0, c1, c2, c3, c4, c5 = (np.take(c, seg, axis=0) for c in self._coef)
        tt = np.repeat(tau, self.dof).reshape(c0.shape)  # full shape: faster than (M, 1)
        hh = np.repeat(h, self.dof).reshape(c0.shape)
        pos = c0 + tt * (c1 + tt * (c2 + tt * (c3 + tt * (c4 + tt * c5))))
        vel = c1 + tt * (2 * c2 + tt * (3 * c3 + tt * (4 * c4 + tt * 5 * c5)))
        acc = 2 * c2 + tt * (6 * c3 + tt * (12 * c4 + tt * 20 * c5))
        return pos, vel / hh, acc / (hh * hh)

    def jerk(self, t: ArrayLike) -> FloatArray:
        """Jerk (third derivative) of the interpolation at time(s) `t`; zero outside."""
        scalar = np.ndim(t) == 0
        ts = np.atleast_1d(np.asarray(t, dtype=np.float64)).ravel()
        if self.t.size == 1:
            out = np.zeros((ts.size, self.dof))
        else:
            seg, tau, h = self._locate(ts)
            c3, c4, c5 = (np.take(c, seg, axis=0) for c in self._coef[3:])
            tt = tau[:, None]
            out = (6 * c3 + tt * (24 * c4 + tt * 60 * c5)) / (h[:, None] ** 3)
            out[(ts < self.t[0]) | (ts > self.t[-1])] = 0.0
        return out[0] if scalar else out

    def peaks(self) -> Peaks:
        """Upper bounds on |velocity|, |acceleration| and |jerk| over each segment, per joint,
        shape (N-1, n) each: what a check at any sampling rate can find, at once.

        Jerk is a quadratic per segment, its peak exact (ends and vertex). Acceleration and
        velocity are evaluated at the ends and at PEAK_SUBDIVISIONS - 1 inner points, plus
        the remainder bound for a function between two samples delta apart,
        max|f''| delta^2 / 8, with max|f''| the segment's exact peak snap or jerk. The bound
        exceeds the true peak by at most that remainder (about 1e-5 of the limits for
        segments of a few ms to tens of ms).
        """
        if self.t.size == 1:
            zero = np.zeros((0, self.dof))
            return Peaks(zero, zero, zero)
        _, c1, c2, c3, c4, c5 = self._coef
        # full-shape h: broadcasting an (N-1, 1) column is several times slower
        h = np.repeat(np.diff(self.t), self.dof).reshape(c1.shape)
        jerk_end = np.maximum(np.abs(6 * c3), np.abs(6 * c3 + 24 * c4 + 60 * c5))
        with np.errstate(divide="ignore", invalid="ignore"):
            vertex = np.clip(np.where(c5 != 0.0, -c4 / (5.0 * c5), 0.0), 0.0, 1.0)
        jerk_mid = np.abs(6 * c3 + vertex * (24 * c4 + vertex * 60 * c5))
        jerk = np.maximum(jerk_end, jerk_mid) / h**3
        snap = np.maximum(np.abs(24 * c4), np.abs(24 * c4 + 120 * c5)) / h**4
        # the velocity and acceleration polynomials' coefficients, once
        v1, v2, v3, v4, v5 = c1, 2 * c2, 3 * c3, 4 * c4, 5 * c5
        a0, a1, a2, a3 = 2 * c2, 6 * c3, 12 * c4, 20 * c5
        vel = np.abs(v1)
        acc = np.abs(a0)
        for tau in (np.arange(1, PEAK_SUBDIVISIONS + 1) / PEAK_SUBDIVISIONS).tolist():
            np.maximum(vel, np.abs(v1 + tau * (v2 + tau * (v3 + tau * (v4 + tau * v5)))), out=vel)
            np.maximum(acc, np.abs(a0 + tau * (a1 + tau * (a2 + tau * a3))), out=acc)
        gap = (h / PEAK_SUBDIVISIONS) ** 2 / 8.0
        return Peaks(vel / h + jerk * gap, acc / (h * h) + snap * gap, jerk)

    def time_scaled(self, factor: float) -> Trajectory:
        """The same motion `factor` times slower (factor > 1) or faster: times stretched,
        velocities divided by factor, accelerations by factor^2. The quintic pieces keep
        their shapes in normalised time, so nothing is re-fitted."""
        if not (np.isfinite(factor) and factor > 0.0):
            raise ValueError(f"factor must be a positive number, got {factor!r}")
        out = object.__new__(Trajectory)
        fields = {
            "joint_names": self.joint_names,
            "t": self.t * factor,
            "q": self.q,
            "qd": self.qd / factor,
            "qdd": self.qdd / (factor * factor),
            "_coef": self._coef,
        }
        for key, value in fields.items():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            object.__setattr__(out, key, value)
        return out

    def resample(self, dt: float) -> Trajectory:
        """The trajectory sampled every `dt` seconds from its start; the end point is kept
        (the last step is shorter when the duration is not a multiple of dt)."""
        if not (np.isfinite(dt) and dt > 0.0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        count = int(np.floor(self.duration / dt + 1e-9))
        times = self.t[0] + dt * np.arange(count + 1)
        if self.end_time - times[-1] > 1e-9 * max(1.0, dt):
            times = np.append(times, self.end_time)
        else:
            times[-1] = self.end_time
        q, qd, qdd = self.sample(times)
        return Trajectory(self.joint_names, times, q, qd, qdd)

    def refined(self, t: FloatArray) -> tuple[FloatArray, ...]:
        """The coefficients (as ``_coef``) of this trajectory's own polynomials on the knots
        ``t`` (increasing, within its span): the same motion, exactly, however close two
        knots come. Hermite data at the ends of a 10 us interval, each rounded on its own,
        would give accelerations off by 1e-6 of a limit there."""
        if self.t.size == 1:
            const = np.repeat(self.q, t.size - 1, axis=0)
            return (const, *(np.zeros_like(const) for _ in range(5)))
        mid = 0.5 * (t[:-1] + t[1:])
        j = np.clip(np.searchsorted(self.t, mid, side="right") - 1, 0, self.t.size - 2)
        h = self.t[j + 1] - self.t[j]
        alpha = ((t[:-1] - self.t[j]) / h)[:, None]
        beta = (np.diff(t) / h)[:, None]
        c = [np.take(ck, j, axis=0) for ck in self._coef]
        # p(alpha + beta s) expanded in powers of s
        return tuple(
            sum(math.comb(k, m) * c[k] * alpha ** (k - m) for k in range(m, 6)) * beta**m
            for m in range(6)
        )

    @classmethod
    def with_coefficients(
        cls,
        joint_names: Sequence[str],
        t: FloatArray,
        q: FloatArray,
        qd: FloatArray,
        qdd: FloatArray,
        coef: Sequence[FloatArray],
    ) -> Trajectory:
        """A trajectory whose polynomials are ``coef`` (from :meth:`refined`), its knots'
        values ``q, qd, qdd`` (what they give there)."""
        out = cls(tuple(joint_names), t, q, qd, qdd)
        frozen = tuple(np.ascontiguousarray(c, dtype=np.float64) for c in coef)
        if len(frozen) != 6 or any(c.shape != (t.size - 1, len(joint_names)) for c in frozen):
            raise ValueError("coef must be 6 arrays of (knots - 1, joints)")
        for c in frozen:
            c.flags.writeable = False
        object.__setattr__(out, "_coef", frozen)
        return out

    def shifted(self, offset: float) -> Trajectory:
        """The same motion with every time moved by `offset` seconds."""
        return Trajectory(self.joint_names, self.t + offset, self.q, self.qd, self.qdd)

    # -- ROS JointTrajectory ----------------------------------------------------------

    def to_json(self, decimals: int | None = None) -> dict[str, Any]:
        """DESIGN 3.5's trajectory.json body (ROS JointTrajectory semantics): joint names and
        one point per knot with positions, velocities, accelerations and time_from_start,
        rounded to ``decimals`` when given (shorter numbers: a file written and read faster).
        Events are not the trajectory's business; the writer adds them."""
        return {"joint_names": list(self.joint_names), "points": self.points_json(decimals)}

    def points_json(
        self, decimals: int | None = None, start: int = 0, stop: int | None = None
    ) -> list[dict[str, Any]]:
        """:meth:`to_json`'s points of the knots ``start:stop`` (a writer can take a long
        trajectory a slice at a time: as Python lists it is ~7 times its text)."""
        part = slice(start, stop)

        def out(a: FloatArray) -> list[Any]:
            a = a[part]
            return (a if decimals is None else np.round(a, decimals)).tolist()  # type: ignore[no-any-return]

        return [
            {"positions": q, "velocities": qd, "accelerations": qdd, "time_from_start": t}
            for t, q, qd, qdd in zip(
                out(self.t), out(self.q), out(self.qd), out(self.qdd), strict=True
            )
        ]

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Trajectory:
        """Inverse of `to_json` (every point must carry all three vectors)."""
        try:
            names = tuple(data["joint_names"])
            points: Sequence[Mapping[str, Any]] = data["points"]
            t = [p["time_from_start"] for p in points]
            q = [p["positions"] for p in points]
            qd = [p["velocities"] for p in points]
            qdd = [p["accelerations"] for p in points]
        except (KeyError, TypeError) as exc:
            raise ValueError(f"not a trajectory: missing or malformed {exc}") from None
        return cls(
            names, np.asarray(t, dtype=np.float64), np.asarray(q), np.asarray(qd), np.asarray(qdd)
        )


def concatenate(parts: Sequence[Trajectory]) -> Trajectory:
    """One trajectory playing `parts` one after another on a single time axis.

    Each part is shifted to begin where the previous one ends; its first point must equal the
    previous part's last point (positions, velocities, accelerations within JOIN_TOLERANCE),
    and the two coincide in one knot.
    """
    if not parts:
        raise ValueError("concatenate needs at least one trajectory")
    first = parts[0]
    times, qs, qds, qdds = [first.t], [first.q], [first.qd], [first.qdd]
    end = first.end_time
    for k, part in enumerate(parts[1:], start=1):
        if part.joint_names != first.joint_names:
            raise ValueError(
                f"part {k} has joints {list(part.joint_names)}; part 0 has "
                f"{list(first.joint_names)}"
            )
        prev = parts[k - 1]  # its last point is the last appended (a one-point part adds none)
        _check_junction(k, prev.q[-1], prev.qd[-1], prev.qdd[-1], part)
        times.append(part.t[1:] - part.t[0] + end)
        qs.append(part.q[1:])
        qds.append(part.qd[1:])
        qdds.append(part.qdd[1:])
        end += part.duration
    return Trajectory(
        first.joint_names,
        np.concatenate(times),
        np.concatenate(qs),
        np.concatenate(qds),
        np.concatenate(qdds),
    )


def joined(parts: Sequence[Trajectory]) -> Trajectory:
    """Trajectories that follow one another on one time axis (each begins where and when
    the one before ends) as one, their polynomials kept as they are (not rebuilt from
    the knots: see :meth:`Trajectory.refined`)."""
    if not parts:
        raise ValueError("joined needs at least one trajectory")
    many = [p for p in parts if p.t.size > 1]
    if len(many) <= 1:
        return many[0] if many else parts[0]
    for a, b in itertools.pairwise(many):
        if abs(a.end_time - b.start_time) > 1e-9 or a.joint_names != b.joint_names:
            raise ValueError(
                f"joined: a part ends at {a.end_time!r} s, the next begins at {b.start_time!r}"
            )
    first = many[0]
    t = np.concatenate([first.t, *(p.t[1:] for p in many[1:])])
    q, qd, qdd = (
        np.concatenate([getattr(first, k), *(getattr(p, k)[1:] for p in many[1:])])
        for k in ("q", "qd", "qdd")
    )
    coef = [np.concatenate([p._coef[m] for p in many]) for m in range(6)]
    return Trajectory.with_coefficients(first.joint_names, t, q, qd, qdd, coef)


def _check_junction(
    k: int, q: FloatArray, qd: FloatArray, qdd: FloatArray, part: Trajectory
) -> None:
    for what, prev, nxt in (
        ("position", q, part.q[0]),
        ("velocity", qd, part.qd[0]),
        ("acceleration", qdd, part.qdd[0]),
    ):
        gap = np.abs(nxt - prev)
        if np.any(gap > JOIN_TOLERANCE):
            j = int(np.argmax(gap))
            raise ValueError(
                f"part {k} does not start where part {k - 1} ends: {what} of "
                f"{part.joint_names[j]} jumps from {prev[j]:.9g} to {nxt[j]:.9g}"
            )
