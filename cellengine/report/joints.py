"""Each joint's kind for the page's units: a prismatic joint's value is a length (shown in
mm, mm/s), a revolute one's an angle (deg, deg/s)."""

from __future__ import annotations

from cellengine.motion.robot import CellModel


def joint_kinds(cell: CellModel) -> list[str]:
    """``prismatic`` or ``revolute`` per joint, in ``cell.joint_names``' order (pinocchio's
    joint types: PX, PY, PZ and PrismaticUnaligned are prismatic)."""
    model = cell.model
    out = []
    for name in cell.joint_names:
        short = model.joints[model.getJointId(name)].shortname()
        prismatic = "Prismatic" in short or short.startswith("JointModelP")
        out.append("prismatic" if prismatic else "revolute")
    return out
