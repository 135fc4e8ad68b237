"""The executor: segments to timed, validated dual-arm programs (split, sync, async).

``compile_segments(world, cell, checker, segments, q_start, strategy)`` -> Program, or the
:class:`Compiler` to add segments one at a time. See compile.py for the order of work,
strategies.py, merge.py and schedule.py for the choices.
"""

from cellengine.execute.compile import Compiler, compile_segments
from cellengine.execute.merge import MERGES, Merge
from cellengine.execute.strategies import STRATEGIES, Strategy
from cellengine.execute.timeline import program_trajectory
from cellengine.motion.robot import home_configuration

__all__ = [
    "MERGES",
    "STRATEGIES",
    "Compiler",
    "Merge",
    "Strategy",
    "compile_segments",
    "home_configuration",
    "program_trajectory",
]
