import numpy as np
import pytest

from cellengine.world import RefError
from tests.helpers import routing_world


def test_pose_composes_platform_element_keypoint() -> None:
    w = routing_world()
    # platform at (0.5, -0.1) turned +90 deg: element x 0.2 -> cell (0.5, 0.1); slot 55 mm up
    T = w.pose("routing.guide2.slot")
    np.testing.assert_allclose(T[:3, 3], [0.5, 0.1, 0.055], atol=1e-9)
    np.testing.assert_allclose(T[:3, 0], [0, 1, 0], atol=1e-9)
    # the element alone means its first keypoint
    np.testing.assert_allclose(w.pose("routing.guide2"), T)


def test_dimensions_and_objects() -> None:
    w = routing_world()
    assert w.dimensions("routing.guide2") == {"length": 0.01, "gap": 0.01}
    assert w.cable("cable1").diameter == 0.006
    assert sorted(w.keypoints("routing")) == [
        f"routing.guide{i}.{k}" for i in (1, 2, 3) for k in ("slot", "top")
    ]


@pytest.mark.parametrize(
    ("ref", "kind", "message"),
    [
        (
            "routing.guide9",
            "guide",
            "unknown guide 'routing.guide9'; known: guide1, guide2, guide3, plate",
        ),
        (
            "routing.guide9",
            "keypoint",
            "unknown element 'routing.guide9'; known: guide1, guide2, guide3, plate",
        ),
        ("board.J3.1", "keypoint", "unknown platform 'board' in 'board.J3.1'; known: routing"),
        (
            "routing.guide1.bottom",
            "keypoint",
            "unknown keypoint 'routing.guide1.bottom'; known: slot, top",
        ),
        (
            "routing",
            "keypoint",
            "'routing' is not a keypoint reference; write platform.element[.keypoint]",
        ),
        (
            "routing.plate",
            "keypoint",
            "element 'routing.plate' has no keypoints: model 'x' is not defined",
        ),
        ("cable9", "cable", "unknown cable 'cable9'; known: cable1"),
        ("vial9", "object", "unknown object 'vial9'; known: cable1, vial1"),
    ],
)
def test_unknown_names_list_known(ref: str, kind: str, message: str) -> None:
    with pytest.raises(RefError) as e:
        routing_world().check(kind, ref)
    assert str(e.value) == message
