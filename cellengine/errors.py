"""User-facing errors: each names a file and a place in it, and maps to an exit code.

A user's mistake never shows a traceback; the CLI prints the problems and exits with
the code of the error class (DESIGN section 4).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Self

if TYPE_CHECKING:  # types only: errors are the bottom layer
    from cellengine.execute.failure import Failure

EXIT_OK = 0
EXIT_INVALID = 1
EXIT_USAGE = 2
EXIT_DRIVER = 3


def display_path(path: str | Path) -> str:
    """A path as users typed it: relative to the working directory when inside it."""
    p = Path(path)
    try:
        rel = os.path.relpath(p)
    except ValueError:  # another drive (Windows)
        return str(p)
    return str(p) if rel.startswith("..") else rel


# C0 and C1 controls (ESC, CSI, newlines), DEL, line and paragraph separators, bidi
# overrides and isolates, and lone surrogates (which no terminal can be sent)
_UNPRINTABLE = re.compile(
    r"[\x00-\x1f\x7f-\x9f\u2028\u2029\u200e\u200f\u202a-\u202e\u2066-\u2069\ud800-\udfff]"
)
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def printable(text: str) -> str:
    """``text`` with every control character escaped as Python writes it (``\\n``,
    ``\\x1b``, ``\\u202e``): a name from an input file must not colour or clear a terminal,
    start a new line (a GitHub workflow command such as ``::error::`` in a CI log) or
    reorder what is shown. Escaped text has none left, so escaping twice changes nothing."""
    return _UNPRINTABLE.sub(_escaped, text)


def _escaped(m: re.Match[str]) -> str:
    c = m.group()
    n = ord(c)
    return _NAMED.get(c) or (f"\\x{n:02x}" if n < 0x100 else f"\\u{n:04x}")


@dataclass(frozen=True)
class Problem:
    """One thing wrong with one input: where (file, line, col; CSV uses line = row) and what."""

    message: str
    file: str | None = None
    line: int | None = None
    col: int | None = None

    def location(self) -> str:
        """``file:line:col`` as far as known; empty for a problem of no file (a refusal,
        a driver's fault), which is then printed as its message alone."""
        if not self.file:
            return ""
        parts = [display_path(self.file)]
        if self.line is not None:
            parts.append(str(self.line))
            if self.col is not None:
                parts.append(str(self.col))
        return ":".join(parts)

    def __str__(self) -> str:
        """The problem on one line, as printed: names from files are escaped there."""
        where = self.location()
        return printable(f"{where}: {self.message}" if where else self.message)

    def warning(self) -> str:
        """As :meth:`__str__`, for what the files allow but a user should know."""
        where = self.location()
        return printable(
            f"{where}: warning: {self.message}" if where else f"warning: {self.message}"
        )


class CellError(Exception):
    """Base of every error meant for a user. Carries one or more problems."""

    exit_code = EXIT_INVALID

    def __init__(self, problems: Problem | Iterable[Problem]) -> None:
        self.problems: tuple[Problem, ...] = (
            (problems,) if isinstance(problems, Problem) else tuple(problems)
        )
        super().__init__("\n".join(str(p) for p in self.problems))

    @classmethod
    def at(
        cls, message: str, file: str | Path | None, line: int | None = None, col: int | None = None
    ) -> Self:
        return cls(Problem(message, str(file) if file is not None else None, line, col))


class InputError(CellError):
    """Invalid input, or a plan that cannot run (exit 1). ``blames``: what a search over
    candidates should change first to avoid it (a key of :attr:`Candidate.decides
    <cellengine.family.Candidate.decides>`, e.g. which arm does what), or None."""

    blames: str | None = None
    # a compile that stopped here: where, as data, for the report of the failed plan
    failure: Failure | None = None


class StepError(InputError):
    """A plan step that cannot be done. Carries the step's index (0-based, into the plan's
    ``steps``); whoever knows the plan file puts the problems at that step's place in it
    (:meth:`located`), so no message is parsed back for the step and no file read again."""

    def __init__(self, problems: Problem | Iterable[Problem], step: int | None = None) -> None:
        super().__init__(problems)
        self.step = step  # None: not known (an error made without a plan)

    @classmethod
    def wrap(cls, step: int, error: CellError) -> StepError:
        """``error`` as a StepError of ``step`` (kept as it is if it knows its step)."""
        if isinstance(error, StepError) and error.step is not None:
            return error
        wrapped = cls(error.problems, step)
        wrapped.blames = getattr(error, "blames", None)
        wrapped.failure = getattr(error, "failure", None)
        return wrapped

    def located(self, file: str | Path, line: int | None, col: int | None) -> InputError:
        """The problems placed at the step in its plan file (a problem placed already keeps
        its place)."""
        out = InputError(
            p if p.file else Problem(p.message, str(file), line, col) for p in self.problems
        )
        out.failure = self.failure
        return out


@contextmanager
def at_step(step: int) -> Iterator[None]:
    """Input errors raised inside are errors of plan step ``step`` (a StepError)."""
    try:
        yield
    except InputError as e:
        raise StepError.wrap(step, e) from None


class UsageError(CellError):
    """Bad command-line usage (exit 2)."""

    exit_code = EXIT_USAGE


class DriverError(CellError):
    """A driver or hardware fault (exit 3)."""

    exit_code = EXIT_DRIVER


def known(names: Iterable[str]) -> str:
    """The '; known: a, b, c' suffix of an unknown-name message."""
    names = sorted(names)
    return "; known: " + ", ".join(names) if names else "; none are defined"
