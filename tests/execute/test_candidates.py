"""The compiler's search over a family's candidates (execute/candidates.py), on the reference
cell: the next candidate where one cannot run, back to an earlier choice when a later one has
nothing that runs, and the error of the attempt that got furthest when nothing does."""

from __future__ import annotations

from collections.abc import Callable, Iterator

import numpy as np
import pytest

from cellengine import geometry as g
from cellengine.errors import InputError, Problem, StepError
from cellengine.execute import Compiler
from cellengine.execute.candidates import compile_candidates
from cellengine.execute.growing import Growing, Taken
from cellengine.family import Candidate
from cellengine.program import ArmPath, Segment
from tests.execute.scenes import cable_cell, home, line, pose

NEAR = (0.40, 0.15, 0.20)  # the left arm reaches it
ALSO = (0.35, 0.20, 0.25)
FAR = (1.50, 0.15, 0.20)  # 1.5 m: out of the left arm's reach


def hop(step: int, where: tuple[float, float, float]) -> Segment:
    return Segment(step, f"to {where}", (ArmPath("left", "transit", pose(where)[None]),))


def choice(*options: Candidate) -> Iterator[Candidate]:
    yield from options


def failing(step: int) -> Iterator[Candidate]:
    raise StepError(Problem(f"steps[{step}]: no way"), step)
    yield  # a generator


def compiler() -> Compiler:
    world, cell, checker = cable_cell()
    return Compiler(world, cell, checker, home(cell))


def labels(c: Compiler) -> list[str]:
    return [s.segment.label for s in c.program().segments]


def test_one_candidate_per_choice_compiles_them_in_order() -> None:
    c = compiler()
    second = Candidate((hop(1, ALSO),))
    taken = compile_candidates(c, choice(Candidate((hop(0, NEAR),), then=lambda: choice(second))))
    assert labels(c) == [f"to {NEAR}", f"to {ALSO}"]
    assert taken[1] is second


def test_the_next_candidate_where_the_first_cannot_run() -> None:
    c = compiler()
    compile_candidates(c, choice(Candidate((hop(0, FAR),)), Candidate((hop(0, NEAR),))))
    assert labels(c) == [f"to {NEAR}"]


def test_back_to_an_earlier_choice_when_a_later_one_has_nothing() -> None:
    """Choice 0's first candidate leads to a choice whose only candidate cannot run, its
    second to one that can; what choice 0's second candidate compiled is kept."""
    c = compiler()
    seen: list[str] = []
    dead_end = Candidate((hop(0, NEAR),), then=lambda: choice(Candidate((hop(1, FAR),))))
    way = Candidate((hop(0, ALSO),), then=lambda: choice(Candidate((hop(1, NEAR),))))
    compile_candidates(c, choice(dead_end, way), lambda s: seen.append(s.label))
    assert labels(c) == [f"to {ALSO}", f"to {NEAR}"]
    # the first candidates (the unreachable hop retried by the transit search), then the
    # second candidate of choice 0 and what follows it, once each
    assert seen[:2] == [f"to {NEAR}", f"to {FAR}"] and set(seen[2:-2]) == {f"to {FAR}"}
    assert seen[-2:] == [f"to {ALSO}", f"to {NEAR}"]


def test_a_family_that_cannot_plan_a_choice_sends_the_search_back() -> None:
    c = compiler()
    stuck = Candidate((hop(0, NEAR),), then=lambda: failing(1))
    way = Candidate((hop(0, ALSO),))
    compile_candidates(c, choice(stuck, way))
    assert labels(c) == [f"to {ALSO}"]


def test_nothing_runs_the_first_of_the_furthest_errors_is_raised() -> None:
    c = compiler()
    with pytest.raises(StepError) as e:
        compile_candidates(
            c, choice(Candidate((hop(0, FAR),)), Candidate((hop(0, (1.6, 0.15, 0.2)),)))
        )
    assert e.value.step == 0
    assert str(e.value).startswith(f"step 1 (to {FAR}): ")
    assert labels(c) == []


def test_nothing_runs_the_error_of_the_attempt_that_got_furthest_is_raised() -> None:
    """The first candidate stops at its first hop; the second gets past it and stops at the
    next choice's: that is what stops the plan, not the first error."""
    c = compiler()
    beyond = (1.6, 0.15, 0.2)
    further = Candidate((hop(0, NEAR),), then=lambda: choice(Candidate((hop(1, beyond),))))
    with pytest.raises(StepError) as e:
        compile_candidates(c, choice(Candidate((hop(0, FAR),)), further))
    assert str(e.value).startswith(f"step 2 (to {beyond}): ")


def test_a_family_error_before_anything_compiles_is_raised_as_it_is() -> None:
    with pytest.raises(InputError, match=r"steps\[0\]: no way"):
        compile_candidates(compiler(), failing(0))


def test_what_comes_before_the_choice_changed_is_not_compiled_again() -> None:
    c = compiler()
    seen: list[str] = []
    stuck = Candidate((hop(1, ALSO),), then=lambda: choice(Candidate((hop(2, FAR),))))
    way = Candidate((hop(1, NEAR),), then=lambda: choice(Candidate((hop(2, ALSO),))))
    first = Candidate((hop(0, NEAR),), then=lambda: choice(stuck, way))
    compile_candidates(c, choice(first), lambda s: seen.append(f"{s.step} {s.label}"))
    assert labels(c) == [f"to {NEAR}", f"to {NEAR}", f"to {ALSO}"]
    assert seen.count(f"0 to {NEAR}") == 1


def blamed(step: int, blames: str) -> Iterator[Candidate]:
    e = StepError(Problem(f"steps[{step}]: out of reach"), step)
    e.blames = blames
    raise e
    yield  # a generator


def test_an_error_that_blames_a_decision_goes_back_to_the_choice_that_made_it() -> None:
    """Choice 0 decides the arms; choice 1 has two ways, after each of which choice 2 fails
    blaming the arms. The search skips choice 1's second way and choice 0's candidate that
    decides the arms as the first did, straight to the one that decides them otherwise."""
    c = compiler()
    seen: list[str] = []

    def middle(label: tuple[float, float, float]) -> Iterator[Candidate]:
        return choice(
            Candidate((hop(1, label),), then=lambda: blamed(2, "arms")),
            Candidate((hop(1, FAR),), then=lambda: blamed(2, "arms")),
        )

    same = {"arms": "left holds the connector"}
    first = Candidate((hop(0, NEAR),), then=lambda: middle(ALSO), decides=same)
    again = Candidate((hop(0, ALSO),), then=lambda: middle(ALSO), decides=same)
    other = Candidate((hop(0, ALSO),), decides={"arms": "right holds the connector"})
    taken = compile_candidates(c, choice(first, again, other), lambda s: seen.append(s.label))
    assert taken == [other]
    assert labels(c) == [f"to {ALSO}"]
    # choice 1's FAR way was never compiled
    assert f"to {FAR}" not in seen


def test_a_blame_no_choice_decided_backtracks_as_usual() -> None:
    c = compiler()
    stuck = Candidate((hop(0, NEAR),), then=lambda: blamed(1, "arms"))
    way = Candidate((hop(0, ALSO),))
    compile_candidates(c, choice(stuck, way))
    assert labels(c) == [f"to {ALSO}"]


def test_the_candidates_a_blame_passes_are_tried_when_none_decides_otherwise() -> None:
    """Choice 1 fails blaming the arms after choice 0's first candidate; no candidate of choice
    0 decides the arms otherwise. The search goes on as without the blame: the candidates the
    blame passed over are still tried, in their order, and the second one compiles."""
    c = compiler()
    same = {"arms": "right holds the connector"}
    stuck = Candidate((hop(0, NEAR),), then=lambda: blamed(1, "arms"), decides=same)
    way = Candidate((hop(0, ALSO),), decides=same)
    later = Candidate((hop(0, FAR),), decides=same)
    assert compile_candidates(c, choice(stuck, way, later)) == [way]
    assert labels(c) == [f"to {ALSO}"]


def test_the_candidates_a_blame_passes_come_after_the_one_it_jumped_to() -> None:
    """The blame jumps over ``again`` to ``other``, which fails too: ``again`` is tried next."""
    c = compiler()
    same = {"arms": "right holds the connector"}
    stuck = Candidate((hop(0, NEAR),), then=lambda: blamed(1, "arms"), decides=same)
    again = Candidate((hop(0, ALSO),), decides=same)
    other = Candidate(
        (hop(0, FAR),), then=lambda: failing(1), decides={"arms": "left holds the connector"}
    )
    assert compile_candidates(c, choice(stuck, again, other)) == [again]
    assert labels(c) == [f"to {ALSO}"]


def slide(step: int, a: tuple[float, float, float], b: tuple[float, float, float]) -> Segment:
    return Segment(step, f"along to {b}", (ArmPath("left", "cartesian", line(a, b)),))


def compiled_after_near(*ways: Candidate) -> list[str]:
    """The labels compiled (in order, again when the search comes back) for a hop to NEAR
    then a choice of ``ways``, the last of which must be the one taken."""
    seen: list[str] = []
    start = Candidate((hop(0, NEAR),), then=lambda: choice(*ways))
    taken = compile_candidates(compiler(), choice(start), lambda s: seen.append(s.label))
    assert taken == [start, ways[-1]]
    return seen


def test_a_candidate_beginning_as_the_one_that_failed_is_passed_over() -> None:
    """Choice 1's first way fails in its first segment, a Cartesian line out of reach; its
    second way begins with the same line (then goes on): compiled from the same place it would
    fail the same way, and is not compiled. The third way compiles."""
    out = (0.40, 0.15, 1.40)  # 1.2 m straight up from NEAR: out of reach
    failed = Candidate((slide(1, NEAR, out),))
    same = Candidate((slide(1, NEAR, out), slide(1, out, NEAR)))
    other = Candidate((slide(1, NEAR, ALSO),))

    # the failing line is compiled (the compiler going back to the transit before it, too) as
    # often with ``same`` among the ways as without it
    assert compiled_after_near(failed, same, other) == compiled_after_near(failed, other)
    assert compiled_after_near(failed, other)[-1] == f"along to {ALSO}"


class _Scripted:
    """A compiler whose segments fail as scripted (by label), marked and restored as the real
    one is: a mark is how many segments are compiled."""

    def __init__(self, fails: Callable[[str, int, dict[str, int]], bool]) -> None:
        self.done: list[str] = []
        self.fails = fails
        self.last: dict[str, int] = {}  # the choice each label was last compiled with

    def mark(self) -> int:
        return len(self.done)

    def restore(self, mark: int) -> None:
        assert mark <= len(self.done), "restored to a mark ahead of what is compiled"
        del self.done[mark:]

    def add(self, segment: Segment, rest: object, choice: int) -> None:
        if self.fails(segment.label, choice, self.last):
            raise InputError(Problem(f"{segment.label} fails"))
        self.last[segment.label] = choice
        self.done.append(segment.label)


def test_a_choice_is_restored_to_where_it_began_on_the_attempt_kept() -> None:
    """Choice 0 is a transit, then a line; choice 1's first way fails. The compiler goes back
    to the transit and takes its other goals, from which the line fails: choice 1 was begun
    only on the first attempt. Its second way is compiled after choice 0 compiled again, not
    after what the attempts left (the transit alone: the line would be missing)."""
    a0 = Segment(0, "a0", (ArmPath("left", "transit", pose(NEAR)[None]),))
    a1 = slide(0, NEAR, ALSO)
    b_fails = Segment(1, "b fails", (ArmPath("left", "cartesian", line(ALSO, NEAR)),))
    b_runs = Segment(1, "b runs", (ArmPath("left", "cartesian", line(ALSO, NEAR)),))

    def fails(label: str, choice: int, last: dict[str, int]) -> bool:
        return label == "b fails" or (label == a1.label and last.get("a0", 0) > 0)

    c = _Scripted(fails)
    first = Candidate((a0, a1), then=lambda: choice(Candidate((b_fails,)), Candidate((b_runs,))))
    compile_candidates(c, choice(first))  # type: ignore[arg-type]
    assert c.done == ["a0", a1.label, "b runs"]


def test_the_compiler_refuses_a_mark_ahead_of_what_it_compiled() -> None:
    c = compiler()
    start = c.mark()
    c.add(hop(0, NEAR), (), 0)
    ahead = c.mark()
    c.restore(start)
    with pytest.raises(ValueError, match="the mark is ahead of what is compiled"):
        c.restore(ahead)


def test_a_candidate_beginning_as_any_that_failed_before_is_passed_over() -> None:
    """Two ways fail in their first segments, each out of reach; the third begins as the first
    did: it is passed over though another way failed after the first (ways that differ only
    after a shared first segment come in any order)."""
    out = (0.40, 0.15, 1.40)
    away = (0.40, 1.35, 0.20)  # 1.2 m sideways from NEAR: out of reach too
    first, second = Candidate((slide(1, NEAR, out),)), Candidate((slide(1, NEAR, away),))
    same = Candidate((slide(1, NEAR, out), slide(1, out, NEAR)))
    other = Candidate((slide(1, NEAR, ALSO),))

    assert compiled_after_near(first, second, same, other) == compiled_after_near(
        first, second, other
    )


def turned(start: tuple[float, float, float], degrees: float) -> Segment:
    """The left tool turned about its own axis by ``degrees``, 2 deg a pose: the wrist's last
    joint turns with it (its limits: +-360 deg)."""
    T0 = pose(start)
    angles = np.radians(np.linspace(0.0, degrees, int(abs(degrees) / 2) + 1))
    poses = np.array([T0 @ g.transform(g.rot_z(a), np.zeros(3)) for a in angles])
    return Segment(1, f"turn {degrees:+.0f} deg", (ArmPath("left", "cartesian", poses),))


def test_an_arm_that_cannot_turn_on_from_an_earlier_transit_compiles_again_from_there() -> None:
    """The hop's transit chooses the wrist's turns looking ahead at the first candidates
    after it (a 400 deg turn one way, then a hop out of reach); once the search goes to the
    next candidate (400 deg the other way), the wrist is near the other limit: an error that
    blames the arm's configuration, not the path. The candidates are compiled again from the
    start, the hop now looking ahead at the turn it leads to."""
    c = compiler()
    seen: list[str] = []
    first = (turned(NEAR, 400.0), hop(1, FAR))
    other = (turned(NEAR, -400.0),)
    start = Candidate((hop(0, NEAR),), then=lambda: choice(Candidate(first), Candidate(other)))
    compile_candidates(c, choice(start), lambda s: seen.append(s.label))
    assert labels(c) == [f"to {NEAR}", "turn -400 deg"]
    assert seen[:2] == [f"to {NEAR}", "turn +400 deg"]
    assert seen[-3:] == ["turn -400 deg", f"to {NEAR}", "turn -400 deg"]


def test_a_candidate_is_told_which_of_its_segments_failed() -> None:
    """Choice 1's first way fails in its second segment (a line out of reach), and is told
    so (Candidate.failed_at), before the next way is drawn: a family can then leave out the
    ways it has not built yet that would fail there too. A way that compiles is told nothing."""
    out = (0.40, 0.15, 1.40)  # 1.2 m straight up from NEAR: out of reach
    told: list[tuple[str, int]] = []
    drawn: list[tuple[str, int]] = []  # each way, and how many were told when it was drawn

    def ways() -> Iterator[Candidate]:
        for name, segments in (
            ("fails", (slide(1, NEAR, ALSO), slide(1, ALSO, out))),
            ("runs", (slide(1, NEAR, ALSO),)),
        ):
            drawn.append((name, len(told)))
            yield Candidate(segments, failed_at=lambda j, name=name: told.append((name, j)))

    start = Candidate((hop(0, NEAR),), then=ways)
    compile_candidates(compiler(), choice(start))
    assert told == [("fails", 1)]
    assert drawn == [("fails", 0), ("runs", 1)]


def test_a_choice_is_taken_only_when_a_segment_past_it_is_asked_for() -> None:
    """Choice 0's first candidate cannot run; its hop looks ahead only to the left arm's next
    transit (choice 1's hop), so choice 2 is planned only after choice 0's second candidate,
    once: not once per candidate of choice 0."""
    c = compiler()
    planned: list[str] = []

    def third() -> Iterator[Candidate]:
        planned.append("choice 2")
        yield Candidate((hop(2, NEAR),))

    def second() -> Iterator[Candidate]:
        yield Candidate((hop(1, ALSO),), then=third)

    compile_candidates(
        c, choice(Candidate((hop(0, FAR),), then=second), Candidate((hop(0, NEAR),), then=second))
    )
    assert labels(c) == [f"to {NEAR}", f"to {ALSO}", f"to {NEAR}"]
    assert planned == ["choice 2"]


def test_a_window_on_the_segments_takes_only_what_it_is_asked_for() -> None:
    """growing.Growing sliced as the compiler slices it (after a segment, then the first few
    of those): iterating the window takes the choices up to its end, no further."""
    planned: list[int] = []

    def chain(k: int) -> Iterator[Candidate]:
        planned.append(k)
        then = (lambda: chain(k + 1)) if k < 5 else None
        yield Candidate((hop(k, NEAR), hop(k, ALSO)), then=then)

    segments = Growing(Taken([], chain(0)), 0)
    window = segments[1:][:4]  # segments 1-4: choices 0, 1 and 2
    assert [s.step for s in window] == [0, 1, 1, 2]
    assert planned == [0, 1, 2]
    assert len(segments) == 12 and planned == list(range(6))
