"""The candidates the compiler's search has taken, and their segments as a sequence that takes
the next choices' first candidates only when a segment past those taken is asked for.

Taking a candidate means the family plans it (a cable guide's ways are screened against the
cell: seconds), and a transit looks ahead only up to each arm's next transit
(:mod:`~cellengine.execute.preview`, :func:`~cellengine.execute.winding.ahead`,
:func:`~cellengine.execute.following.required`): taking every choice's first candidate to the
plan's end before compiling the first spends that planning again after each failure, on
candidates the failure throws away. Taken as they are asked for, the program is the same
(each segment sees the same segments after it); a choice that has no candidate is found
once the segments before it are compiled, not before.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, overload

from cellengine.errors import InputError
from cellengine.program import Segment

if TYPE_CHECKING:
    from cellengine.family import Candidate


@dataclass
class Choice:
    options: Iterator[Candidate]  # the ones not tried yet
    taken: Candidate
    # what the candidates taken here compiled up to the segment that failed
    # (candidates._prefix), when it may be skipped in others
    failed: set[tuple[object, ...]] = field(default_factory=set)


class NoCandidate(Exception):
    """The next choice offered no candidate (``error``: the family's reason, if it gave one).
    Not an InputError: it ends the compile's attempt, not one segment's."""

    def __init__(self, error: InputError | None) -> None:
        self.error = error


@dataclass
class Taken:
    """The candidate taken at each choice so far, and the next choice's candidates
    (``pending``; None: the plan ends after the last one taken)."""

    chosen: list[Choice]
    pending: Iterator[Candidate] | None

    def grow(self) -> bool:
        """Take the next choice's first candidate; False at the plan's end, NoCandidate when
        the choice has none."""
        if self.pending is None:
            return False
        try:
            taken = next(self.pending)
        except StopIteration:
            raise NoCandidate(None) from None
        except InputError as e:  # the family cannot do this choice
            raise NoCandidate(e) from None
        self.chosen.append(Choice(self.pending, taken))
        self.pending = taken.then() if taken.then is not None else None
        return True

    def grow_all(self) -> None:
        while self.grow():
            pass


class _Lazy(Sequence[Segment]):
    """A sequence whose slices are windows on it, as lazy as it is (forward slices only, as
    the compiler takes them)."""

    def _at(self, i: int) -> Segment:  # IndexError past the end
        raise NotImplementedError

    @overload
    def __getitem__(self, i: int) -> Segment: ...
    @overload
    def __getitem__(self, i: slice) -> Sequence[Segment]: ...
    def __getitem__(self, i: int | slice) -> Segment | Sequence[Segment]:
        if isinstance(i, slice):
            start, stop = i.start or 0, i.stop
            if i.step not in (None, 1) or start < 0 or (stop is not None and stop < 0):
                raise ValueError(f"unsupported slice {i}")
            return _Window(self, start, stop)
        if i < 0:
            raise IndexError(i)
        return self._at(i)


class Growing(_Lazy):
    """The segments of the choices from ``start`` on, in order; asking for one past those
    taken takes the next choices' candidates (:class:`Taken`). ``owner`` of a segment (by
    id): its place here, its choice, its place in that choice's; ``begins``: the choice
    whose first segment it is."""

    def __init__(self, taken: Taken, start: int) -> None:
        self.taken = taken
        self.segments: list[Segment] = []
        self.owner: dict[int, tuple[int, int, int]] = {}
        self.begins: dict[int, int] = {}
        self._next = start  # the first choice whose segments are not listed yet
        self._list()

    def _list(self) -> None:
        chosen = self.taken.chosen
        while self._next < len(chosen):
            k, segments = self._next, chosen[self._next].taken.segments
            if segments:
                self.begins[id(segments[0])] = k
            at = len(self.segments)
            self.owner.update((id(s), (at + j, k, j)) for j, s in enumerate(segments))
            self.segments += segments
            self._next += 1

    def has(self, i: int) -> bool:
        """Whether there is an i-th segment (taking candidates until there is, or the plan
        ends)."""
        while i >= len(self.segments):
            if not self.taken.grow():
                return False
            self._list()
        return True

    def _at(self, i: int) -> Segment:
        if not self.has(i):
            raise IndexError(i)
        return self.segments[i]

    def __len__(self) -> int:  # every choice taken to the plan's end
        self.taken.grow_all()
        self._list()
        return len(self.segments)


class _Window(_Lazy):
    """``source[start:stop]``."""

    def __init__(self, source: Sequence[Segment], start: int, stop: int | None) -> None:
        self.source, self.start, self.stop = source, start, stop

    def _at(self, i: int) -> Segment:
        if self.stop is not None and self.start + i >= self.stop:
            raise IndexError(i)
        return self.source[self.start + i]

    def __len__(self) -> int:
        n = max(0, len(self.source) - self.start)
        return n if self.stop is None else min(n, self.stop - self.start)


class UntilChange(_Lazy):
    """``source`` up to its first segment that changes tools, that one included, as lazy as
    ``source`` (the segments after it run on other robot models: a transit does not look
    ahead at them)."""

    def __init__(self, source: Sequence[Segment]) -> None:
        self.source = source

    def _at(self, i: int) -> Segment:
        if any(self.source[j].changes for j in range(i)):
            raise IndexError(i)
        return self.source[i]

    def __len__(self) -> int:
        n = 0
        while True:
            try:
                self._at(n)
            except IndexError:
                return n
            n += 1
