"""cellengine: a declarative engine for programming dual-arm robot cells from files."""

__version__ = "0.1.0"
