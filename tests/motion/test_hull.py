"""convex_hull: coal's qhull on points, without scipy; flat input gives None, not a crash."""

from __future__ import annotations

import coal
import numpy as np
import pytest

from cellengine.info.mesh import Mesh
from cellengine.motion.hull import convex_hull, is_flat

CUBE = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])


def _mesh(hull: coal.Convex) -> Mesh:
    faces = [[t[0], t[1], t[2]] for t in map(hull.polygons, range(hull.num_polygons))]
    return Mesh(np.asarray(hull.points()), faces)


@pytest.mark.parametrize("offset", [0.0, 1000.0])
def test_hull_of_a_cube_with_inner_points(offset: float) -> None:
    rng = np.random.default_rng(0)
    points = np.vstack([CUBE, rng.uniform(0.1, 0.9, (50, 3))]) * 0.01 + offset
    hull = convex_hull(points)
    assert isinstance(hull, coal.Convex)
    mesh = _mesh(hull)
    assert len(mesh.vertices) == 8 and len(mesh.faces) == 12
    np.testing.assert_allclose(mesh.bounds, [[offset] * 3, [offset + 0.01] * 3], atol=1e-9)
    assert mesh.is_watertight
    assert mesh.volume == pytest.approx(1e-6, rel=1e-6)  # > 0: the triangles wind outwards
    assert hull.computeVolume() == pytest.approx(1e-6, rel=1e-6)


def test_flat_points_have_no_hull() -> None:
    square = CUBE[CUBE[:, 2] == 0]
    assert convex_hull(square) is None and is_flat(square)
    assert convex_hull(CUBE[:3]) is None  # fewer than four points
    near = np.vstack([square, [0.5, 0.5, 1e-10]])  # flat to rounding: coal's qhull would crash
    assert convex_hull(near) is None
    thin = np.vstack([square, [0.5, 0.5, 1e-7]])  # thin but solid
    hull = convex_hull(thin)
    assert hull is not None and hull.computeVolume() == pytest.approx(1e-7 / 3)


def test_non_finite_points_are_refused() -> None:
    with pytest.raises(ValueError, match="finite"):
        convex_hull(np.vstack([CUBE, [np.nan, 0, 0]]))


def test_far_points_never_reach_qhull() -> None:
    # a 10 um cloud 1e11 m out: qhull would crash the process (a signal, not an exception)
    far = CUBE * 1e-5 + 1e11
    with pytest.raises(ValueError, match="coordinates beyond 10000 m of the origin"):
        convex_hull(far)
