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
