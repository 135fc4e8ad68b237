"""TCP pose interpolation: lines and circular arcs in the cell frame, orientation by slerp,
sampled so that no step exceeds a maximum translation and a maximum rotation.

Every function returns the poses as an (N, 4, 4) array of ``T_cell_tcp``, the first and the
last included, at equal steps of one parameter: position and orientation advance together, so
a segment's steps are all the same length and the same angle. The step count is the smallest
that keeps both under their maximum: ``max(ceil(length / max_translation), ceil(angle /
max_rotation), 1)`` steps, N = steps + 1 poses.

This is the problem-building half of a Cartesian path; :mod:`cellengine.motion.cartesian`
solves it. The rotations (log, batched exp, slerp, angles) are :mod:`cellengine.geometry`'s.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from cellengine import geometry as g
from cellengine.arrays import Mat, Poses, Vec

MAX_TRANSLATION = 0.005  # m per step: 1 mm of chord sag between steps on a 5 cm radius arc
MAX_ROTATION = math.radians(2.0)  # rad per step
# Three points closer than this to one line have no circle through them.
COLLINEAR = 1e-9
# The length of one radian of TCP rotation when rotation and translation are measured together
# (path length, fraction of a path achieved): a point 10 cm from the TCP moves 10 cm per rad.
ROTATION_LENGTH = 0.1  # m / rad


# ----------------------------------------------------------------------------- lengths


def step_lengths(Ts: Poses) -> Vec:
    """Length of each step of a pose path, (N-1,): translation and rotation together,
    ``hypot(|dp|, ROTATION_LENGTH * angle)``, so a pure reorientation has a length too."""
    P = np.asarray(Ts)[:, :3, 3]
    dp = np.linalg.norm(np.diff(P, axis=0), axis=1)
    out: Vec = np.hypot(dp, ROTATION_LENGTH * g.rotation_angles(Ts))
    return out


# ----------------------------------------------------------------------------- step counts


def steps(length: float, angle: float, max_translation: float, max_rotation: float) -> int:
    """The fewest equal steps that keep each under both maxima (at least one)."""
    if not max_translation > 0 or not max_rotation > 0:
        raise ValueError("max_translation and max_rotation must be positive")
    # A hair of slack: 1 m in 1 mm steps is 1000 steps, not 1001 from round-off.
    n = max(math.ceil(length / max_translation - 1e-9), math.ceil(abs(angle) / max_rotation - 1e-9))
    return max(int(n), 1)


# ----------------------------------------------------------------------------- lines


def line(
    T_start: Mat,
    T_end: Mat,
    max_translation: float = MAX_TRANSLATION,
    max_rotation: float = MAX_ROTATION,
) -> Poses:
    """A straight line of the TCP from ``T_start`` to ``T_end``, orientation by slerp."""
    T0, T1 = _pose(T_start, "T_start"), _pose(T_end, "T_end")
    dp = T1[:3, 3] - T0[:3, 3]
    w = g.log3(T0[:3, :3].T @ T1[:3, :3])
    n = steps(float(np.linalg.norm(dp)), float(np.linalg.norm(w)), max_translation, max_rotation)
    t = np.arange(n + 1) / n
    out = _poses(T0[:3, :3] @ g.exp3_batch(t[:, None] * w), T0[:3, 3] + t[:, None] * dp)
    out[-1] = T1  # exact end, whatever the round-off
    return out


def polyline(
    waypoints: Sequence[Mat] | Poses,
    max_translation: float = MAX_TRANSLATION,
    max_rotation: float = MAX_ROTATION,
) -> Poses:
    """Lines through the poses one after the other (MoveIt's computeCartesianPath input):
    each segment sampled on its own, shared ends kept once."""
    Ts = np.asarray(waypoints, dtype=float)
    if Ts.ndim != 3 or Ts.shape[1:] != (4, 4) or len(Ts) < 1:
        raise ValueError(f"waypoints must be (N, 4, 4) with N >= 1, got {Ts.shape}")
    if len(Ts) == 1:
        return Ts.copy()
    parts = [line(a, b, max_translation, max_rotation) for a, b in itertools.pairwise(Ts)]
    return concatenate(parts)


def concatenate(parts: Sequence[Poses]) -> Poses:
    """Pose paths joined end to start; each join (the end of one = the start of the next,
    within 1e-9) kept once."""
    out = [np.asarray(parts[0], dtype=float)]
    for p in parts[1:]:
        p = np.asarray(p, dtype=float)
        if not np.allclose(out[-1][-1], p[0], rtol=0.0, atol=1e-9):
            raise ValueError("concatenate: a part does not start where the previous one ends")
        out.append(p[1:])
    return np.concatenate(out)


# ----------------------------------------------------------------------------- arcs


@dataclass(frozen=True)
class Circle:
    """A circle in the cell frame: centre, unit normal (the axis; positive angles turn
    counter-clockwise about it) and radius; ``x`` is the unit vector from the centre to the
    point at angle 0."""

    centre: Vec
    axis: Vec
    radius: float
    x: Vec

    def points(self, angles: ArrayLike) -> Vec:
        """Points at the given angles (rad) from ``x`` about ``axis``: (len, 3)."""
        a = np.atleast_1d(np.asarray(angles, dtype=float))[:, None]
        y = np.cross(self.axis, self.x)
        out: Vec = self.centre + self.radius * (np.cos(a) * self.x + np.sin(a) * y)
        return out


def circle_through(p0: ArrayLike, p1: ArrayLike, p2: ArrayLike) -> tuple[Circle, float, float]:
    """The circle through three points, oriented so that p0 -> p1 -> p2 turns positively,
    with the angles of p1 and p2 from p0 (0 < angle(p1) < angle(p2) < 2 pi)."""
    a, b, c = (np.asarray(p, dtype=float).reshape(3) for p in (p0, p1, p2))
    u, v = b - a, c - a
    n = np.cross(u, v)
    nn = float(n @ n)
    scale = float(np.linalg.norm(u) * np.linalg.norm(v))
    if scale == 0.0 or math.sqrt(nn) <= COLLINEAR * scale:
        raise ValueError("circle_through: the three points are on one line (or repeated)")
    # The circumcentre of a triangle from its edge vectors (no linear solve).
    centre = a + (float(u @ u) * np.cross(v, n) + float(v @ v) * np.cross(n, u)) / (2.0 * nn)
    axis = n / math.sqrt(nn)
    radius = float(np.linalg.norm(a - centre))
    circle = Circle(centre, axis, radius, (a - centre) / radius)
    return circle, _angle_on(circle, b), _angle_on(circle, c)


def arc_through(
    T_start: Mat,
    p_via: ArrayLike,
    T_end: Mat,
    max_translation: float = MAX_TRANSLATION,
    max_rotation: float = MAX_ROTATION,
) -> Poses:
    """The TCP along the circle from T_start's position through ``p_via`` to T_end's,
    orientation by slerp from T_start's to T_end's in step with the arc angle."""
    T0, T1 = _pose(T_start, "T_start"), _pose(T_end, "T_end")
    circle, _, sweep = circle_through(T0[:3, 3], p_via, T1[:3, 3])
    w = g.log3(T0[:3, :3].T @ T1[:3, :3])
    angle = float(np.linalg.norm(w))
    n = steps(circle.radius * sweep, angle, max_translation, max_rotation)
    t = np.arange(n + 1) / n
    out = _poses(T0[:3, :3] @ g.exp3_batch(t[:, None] * w), circle.points(t * sweep))
    out[0], out[-1] = T0, T1
    return out


def arc_about(
    T_start: Mat,
    centre: ArrayLike,
    axis: ArrayLike,
    angle: float,
    *,
    turn: bool | float = True,
    max_translation: float = MAX_TRANSLATION,
    max_rotation: float = MAX_ROTATION,
) -> Poses:
    """The TCP turned by ``angle`` (rad, any size, right-handed) about the axis through
    ``centre`` along ``axis``; the radius is the start's distance from that axis (0: the TCP
    turns in place). With ``turn`` the orientation turns with the arc (the TCP moves as if
    fixed to a wheel on the axis: the slerp about that axis), else it stays as at the start;
    a number turns it by that fraction of ``angle`` as it goes."""
    T0 = _pose(T_start, "T_start")
    k = np.asarray(axis, dtype=float).reshape(3)
    norm = float(np.linalg.norm(k))
    if norm < 1e-12:
        raise ValueError("arc_about: the axis is zero")
    k = k / norm
    c = np.asarray(centre, dtype=float).reshape(3)
    r_vec = T0[:3, 3] - c
    radius = float(np.linalg.norm(r_vec - k * float(k @ r_vec)))
    share = float(turn)
    n = steps(radius * abs(angle), abs(angle * share), max_translation, max_rotation)
    t = np.arange(n + 1) / n
    R = g.exp3_batch((t * angle)[:, None] * k)  # (n + 1, 3, 3) about the axis
    positions = c + R @ r_vec
    R_turn = R if share == 1.0 else g.exp3_batch((t * angle * share)[:, None] * k)
    orientations = R_turn @ T0[:3, :3]
    out = _poses(orientations, positions)
    out[0] = T0
    return out


def arc_circle(T_start: Mat, centre: ArrayLike, axis: ArrayLike) -> Circle:
    """The circle :func:`arc_about` moves T_start's position on (its centre is the foot of
    the start on the axis)."""
    T0 = _pose(T_start, "T_start")
    k = np.asarray(axis, dtype=float).reshape(3)
    k = k / np.linalg.norm(k)
    c = np.asarray(centre, dtype=float).reshape(3)
    r_vec = T0[:3, 3] - c
    foot = c + k * float(k @ r_vec)
    radial = T0[:3, 3] - foot
    radius = float(np.linalg.norm(radial))
    x = radial / radius if radius > 0 else g.any_perpendicular(k)
    return Circle(foot, k, radius, x)


# ----------------------------------------------------------------------------- helpers


def _angle_on(circle: Circle, p: Vec) -> float:
    """Angle of ``p`` (on the circle) from ``circle.x`` about its axis, in (0, 2 pi]."""
    d = p - circle.centre
    y = np.cross(circle.axis, circle.x)
    a = math.atan2(float(d @ y), float(d @ circle.x))
    return a if a > 0 else a + 2.0 * math.pi


def _pose(T: ArrayLike, name: str) -> Mat:
    a = np.asarray(T, dtype=float)
    if a.shape != (4, 4):
        raise ValueError(f"{name} must be 4x4, got {a.shape}")
    return a


def _poses(R: Poses, p: Vec) -> Poses:
    out = np.zeros((len(R), 4, 4))
    out[:, :3, :3] = R
    out[:, :3, 3] = p
    out[:, 3, 3] = 1.0
    return out
