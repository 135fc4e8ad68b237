"""Mesh: read-only arrays, bounds, closedness, enclosed volume, transforms, concatenation."""

from __future__ import annotations

import numpy as np
import pytest

from cellengine.geometry import pose
from cellengine.info import primitives
from cellengine.info.mesh import Mesh


def test_unit_box() -> None:
    box = primitives.box((1, 1, 1))
    assert box.is_watertight
    assert box.volume == pytest.approx(1.0)
    np.testing.assert_allclose(box.bounds, [[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]])
    np.testing.assert_allclose(box.extents, [1, 1, 1])
    assert box.vertices.dtype == np.float64 and box.faces.dtype == np.int64


def test_arrays_are_read_only_copies() -> None:
    v = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0]])
    mesh = Mesh(v, [[0, 1, 2]])
    v[0, 0] = 5.0
    assert mesh.vertices[0, 0] == 0.0
    with pytest.raises(ValueError):
        mesh.vertices[0, 0] = 1.0
    with pytest.raises(ValueError):
        mesh.faces[0, 0] = 1
    with pytest.raises(ValueError, match=r"\(k, 3\) arrays, got \(4, 2\)"):
        Mesh(np.zeros((4, 2)), [[0, 1, 2]])


def test_open_meshes_are_not_watertight() -> None:
    box = primitives.box((1, 2, 3))
    open_box = Mesh(box.vertices, box.faces[:-1])  # one triangle missing
    assert not open_box.is_watertight
    assert not Mesh(box.vertices[:3], [[0, 1, 2]]).is_watertight
    assert not Mesh(np.zeros((0, 3)), np.zeros((0, 3), np.int64)).is_watertight
    # an edge shared by three faces (a fin on a closed box) is not closed either
    fin = Mesh(np.vstack([box.vertices, [[0.0, 0.0, 9.0]]]), np.vstack([box.faces, [[0, 1, 8]]]))
    assert not fin.is_watertight


def test_transformed_and_concatenated() -> None:
    T = pose([1.0, 2.0, 3.0], [0.0, 0.0, np.pi / 2])
    box = primitives.box((1, 2, 3)).transformed(T)
    np.testing.assert_allclose(box.bounds, [[0, 1.5, 1.5], [2, 2.5, 4.5]], atol=1e-9)
    assert box.volume == pytest.approx(6.0)
    mirrored = box.transformed(np.diag([-1.0, 1.0, 1.0, 1.0]))
    assert mirrored.volume == pytest.approx(6.0)  # faces flipped: still wound outwards
    both = Mesh.concatenate([box, primitives.box((1, 1, 1))])
    assert len(both.vertices) == 16 and len(both.faces) == 24
    assert both.is_watertight and both.volume == pytest.approx(7.0)
    assert both.faces.max() == 15


def test_read_only_arrays_are_shared_not_copied() -> None:
    box = primitives.box((1, 1, 1))
    again = Mesh(box.vertices, box.faces)
    assert again.vertices is box.vertices and again.faces is box.faces
    flipped = Mesh(box.vertices, box.faces[:, ::-1])  # a strided view: made contiguous
    assert flipped.faces.flags.c_contiguous and not flipped.faces.flags.writeable
