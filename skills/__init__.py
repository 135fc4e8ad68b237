"""The built-in skill library. Importing it registers every built-in skill."""

from cellengine.skills import cable, lab

__all__ = ["cable", "lab"]
