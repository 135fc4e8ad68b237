import math

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.motion.tsr import TaskSpaceRegion, goal_configurations


def region() -> TaskSpaceRegion:
    # above a slot at (0.5, 0, 0.1): anywhere within +-2 cm in x, at 5-10 cm up, any yaw
    bounds = [[-0.02, 0.02], [0, 0], [0.05, 0.10], [0, 0], [0, 0], [-math.pi, math.pi]]
    return TaskSpaceRegion(g.pose([0.5, 0, 0.1]), g.pose([0, 0, 0], [math.pi, 0, 0]), bounds)


def test_samples_lie_in_the_region_and_are_seeded() -> None:
    tsr = region()
    poses = tsr.sample(np.random.default_rng(1), 50)
    assert poses.shape == (50, 4, 4)
    assert all(tsr.contains(T) for T in poses)
    xs, zs = poses[:, 0, 3], poses[:, 2, 3]
    assert xs.min() >= 0.48 - 1e-9 and xs.max() <= 0.52 + 1e-9
    assert zs.min() >= 0.15 - 1e-9 and zs.max() <= 0.20 + 1e-9
    np.testing.assert_allclose(poses[:, :3, 2] @ [0, 0, 1], -1.0)  # tool z points down
    np.testing.assert_array_equal(poses, tsr.sample(np.random.default_rng(1), 50))


def test_a_pose_outside_is_not_contained() -> None:
    assert not region().contains(g.pose([0.5, 0.05, 0.17], [math.pi, 0, 0]))
    assert not region().contains(g.pose([0.5, 0.0, 0.17], [math.pi / 2, 0, 0]))


def test_bad_bounds() -> None:
    with pytest.raises(ValueError, match="min <= max"):
        TaskSpaceRegion(np.eye(4), np.eye(4), [[1, 0]] * 6)


def test_goal_configurations_from_ik_and_validity() -> None:
    tsr = region()

    def ik(T: np.ndarray) -> list[np.ndarray]:  # a fake arm whose joints are x and z
        return [np.array([T[0, 3], T[2, 3]])]

    q = goal_configurations(tsr, ik, samples=20, seed=3, is_valid=lambda q: q[0] > 0.5)
    assert 0 < len(q) < 20 and np.all(q[:, 0] > 0.5)
