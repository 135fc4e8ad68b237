import itertools
import random

from cellengine.skills.best_first import best_first


def _space(seed: int) -> tuple[list[list[list[int]]], list[int]]:
    """Groups of 1-4 dims of 0-4 small integer values (ties on purpose), a base per group."""
    rng = random.Random(seed)
    groups = [
        [[rng.randint(0, 3) for _ in range(rng.randint(0, 4))] for _ in range(rng.randint(1, 4))]
        for _ in range(rng.randint(1, 5))
    ]
    return groups, [rng.randint(0, 6) for _ in groups]


def test_best_first_lists_the_product_as_sorting_it_by_cost_then_position_would() -> None:
    for seed in range(200):
        groups, base = _space(seed)
        expected = sorted(
            (base[i] + sum(c), i, idx, c)
            for i, dims in enumerate(groups)
            for idx, c in zip(
                itertools.product(*(range(len(d)) for d in dims)),
                itertools.product(*dims),
                strict=True,
            )
        )
        got = list(best_first(groups, lambda i, c, b=base: b[i] + sum(c), lambda i, j, v: float(v)))
        assert got == [(i, c) for _, i, _, c in expected], seed


def test_best_first_builds_only_what_is_taken() -> None:
    costed = []

    def cost(i: int, c: tuple[int, ...]) -> float:
        costed.append(c)
        return float(sum(c))

    ways = best_first([[list(range(100))] * 4], cost, lambda i, j, v: float(v))
    assert [next(ways) for _ in range(3)] == [
        (0, (0, 0, 0, 0)),
        (0, (0, 0, 0, 1)),
        (0, (0, 0, 1, 0)),
    ]
    assert len(costed) < 20  # of 10^8


def _sorted(groups: list[list[list[int]]], base: list[int], ties: tuple[int, ...] | None) -> list:
    return sorted(
        (base[i] + sum(c), i, idx if ties is None else tuple(idx[j] for j in ties), c)
        for i, dims in enumerate(groups)
        for idx, c in zip(
            itertools.product(*(range(len(d)) for d in dims)),
            itertools.product(*dims),
            strict=True,
        )
    )


def test_ties_are_broken_in_the_order_of_dims_given() -> None:
    for seed in range(200):
        groups, base = _space(seed)
        width = min(len(dims) for dims in groups)
        ties = tuple(reversed(range(width)))
        if any(len(dims) != width for dims in groups):
            continue  # one order of the dims for every group
        got = best_first(
            groups, lambda i, c, b=base: b[i] + sum(c), lambda i, j, v: float(v), ties=ties
        )
        assert list(got) == [(i, c) for _, i, _, c in _sorted(groups, base, ties)], seed


def test_pruned_combinations_are_left_out_the_rest_in_order() -> None:
    for seed in range(200):
        groups, base = _space(seed)

        def prune(i: int, c: tuple[int, ...]) -> int | None:
            return 1 if len(c) >= 2 and c[0] + c[1] == 3 else None

        got = list(
            best_first(groups, lambda i, c, b=base: b[i] + sum(c), lambda i, j, v: float(v), prune)
        )
        alive = [(i, c) for _, i, _, c in _sorted(groups, base, None) if prune(i, c) is None]
        assert got == alive, seed


def test_what_agrees_with_a_dead_combination_up_to_the_named_coordinate_is_never_built() -> None:
    costed: list[tuple[int, ...]] = []

    def cost(i: int, c: tuple[int, ...]) -> float:
        costed.append(c)
        return float(sum(c))

    def prune(i: int, c: tuple[int, ...]) -> int | None:
        return 1 if c[0] + c[1] == 3 else None

    got = list(best_first([[list(range(10))] * 4], cost, lambda i, j, v: float(v), prune))
    assert len(got) == 10**4 - 4 * 10**2
    # of the 400 dead ones, only those whose last two coordinates are at their first values
    dead = [c for c in costed if c[0] + c[1] == 3]
    assert dead and all(c[2:] == (0, 0) for c in dead)
