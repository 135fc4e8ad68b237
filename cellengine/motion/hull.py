"""Convex hulls as ``coal.Convex``, computed by the qhull built into coal (no scipy)."""

from __future__ import annotations

from typing import Any

import coal
import numpy as np

from cellengine.arrays import Vec

# Qt: triangulated facets (coal needs it to keep triangles). Pp: no precision warnings, which
# coal's qhull would print through a null stream and crash.
_QHULL = "Qt Pp"
FLAT = 1e-9  # thickness over size below which points are flat; qhull copes down to ~1e-13
# coal's qhull crashes the process on far points with little spread (1e-5 m at 1e11 m): the
# loaders bound what they read far below this; here, the last guard before qhull
MAX_COORDINATE = 1e4  # m


def convex_hull(points: Vec) -> Any | None:
    """The hull of ``points`` (n, 3) as a coal.Convex of outward-wound triangles; None if the
    points are flat (see :func:`is_flat`) and enclose no volume."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if not np.isfinite(points).all():
        raise ValueError("coordinates must be finite")
    if len(points) and np.abs(points).max() > MAX_COORDINATE:
        raise ValueError(f"coordinates beyond {MAX_COORDINATE:g} m of the origin")
    if is_flat(points):  # qhull would fail, and coal's qhull crashes as it reports why
        return None
    centre = (points.min(axis=0) + points.max(axis=0)) / 2.0  # qhull's precision is absolute
    todo = coal.StdVec_Vec3s()
    for p in points - centre:
        todo.append(p)
    hull = coal.Convex.convexHull(todo, True, _QHULL)  # its triangles wind outwards
    out = coal.StdVec_Vec3s()  # the same hull moved back
    for v in np.asarray(hull.points()) + centre:
        out.append(v)
    triangles = coal.StdVec_Triangle()
    for t in map(hull.polygons, range(hull.num_polygons)):
        triangles.append(coal.Triangle(t[0], t[1], t[2]))
    return coal.Convex(out, triangles)


def is_flat(points: Vec) -> bool:
    """All points on one plane (or line, or point), to :data:`FLAT` of their size."""
    if len(points) < 4:
        return True
    sv = np.linalg.svd(points - points.mean(axis=0), compute_uv=False)
    return bool(sv[-1] <= FLAT * max(float(sv[0]), 1e-300))
