"""Names for people on the page: ``step 1 Weigh vial1`` and its segment ``to vial1`` rather
than the label ``steps[0] Weigh: to vial1``; ``robot1 gripper`` or ``left gripper`` (the
tool's name) rather than the collision objects ``robot1/gripper#2`` or ``left/tool``. The
labels and names in report.json stay as the engine writes them (messages quote them)."""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping

STEP_PREFIX = re.compile(r"^steps\[\d+\]\s*")


def step_title(step: int, label: str) -> str:
    """A plan step as the page names it: counted from 1, as people count."""
    return f"step {step + 1} {STEP_PREFIX.sub('', label)}".rstrip()


def segment_name(label: str, step_label: str) -> str:
    """A segment's label without its step's part: the ``steps[i]`` prefix, and the words
    before ':' when the step's label begins with them (the skill, or the whole step)."""
    rest = STEP_PREFIX.sub("", label)
    head, sep, tail = rest.partition(": ")
    if sep and tail.strip() and STEP_PREFIX.sub("", step_label).startswith(head.strip()):
        return tail
    return rest


def part_name(name: str, tools: Mapping[str, str]) -> str:
    """A collision object's name for people: ``<arm>/<link>[#k]`` as ``<arm> <link>`` (the
    k-th shape of a link is the link), ``<arm>/tool[/<part>]`` as the arm's tool by its
    cell.yaml name; a static object's name (``bench.rack1#2``) without its shape number."""
    base = re.sub(r"#\d+$", "", name)
    arm, sep, rest = base.partition("/")
    if not sep:
        return base
    parts = rest.split("/")
    if parts[0] == "tool":
        parts[0] = tools.get(arm, "tool")
    return " ".join([arm, *(p.replace("_", " ") for p in parts)])


def part_names(names: Iterable[str], tools: Mapping[str, str]) -> dict[str, str]:
    """Each of ``names`` (collision objects) by :func:`part_name`, where that differs."""
    return {n: shown for n in names if (shown := part_name(n, tools)) != n}
