"""The development/test split of the closed-loop evaluations (``psgsl search`` and ``psgsl benchmark``).

**Development** (``dev``) is everything used so far to build, tune, calibrate and look at the searches: the embedded
house (or a world file) at any seed outside the test range — the published runs use seeds 0–9, 100–119, 200–219,
300–319, 1000–1019 and 5000–5003, the robot's detector model the reference houses 10000–10009 — and generated
homes 0–9999 (the published benchmark: homes 0–49) with episode seeds 0, 1, ….

**Test** (``test``) is kept for the evaluation of a release, run once and never inspected run by run:

* generated homes :data:`TEST_HOMES` = 10000–10099 (``psgsl benchmark --split test``), none of them a reference
  house of the generated ontology (1000000–1000019);
* episode seeds :data:`TEST_SEEDS` = 20000–20019, disjoint from every seed range above: the seeds of
  ``psgsl search --split test`` in the embedded house or a world file, and the per-home seeds of
  ``psgsl benchmark --split test`` (in the test homes, or in a world file).

A count (``--seeds S``, ``--houses H``) takes the first S seeds or H homes of the test set (default: all of the
house's 20 seeds, all 100 homes, and the benchmark's 5 seeds per home); the test set has no ``--first-seed`` or
``--first-house``. A development run may not reach into the test set.

Examples
--------
>>> list(house_seeds("test", seeds=3))
[20000, 20001, 20002]
>>> list(house_seeds("dev", seeds=2, first_seed=100))
[100, 101]
>>> split_of_seeds([20000, 20001])
'test'
"""

from __future__ import annotations

from .._shared._validate import one_of

__all__ = ["BENCHMARK_TEST_SEEDS", "SPLITS", "TEST_HOMES", "TEST_SEEDS", "benchmark_sample", "check_split",
           "house_seeds", "split_of_seeds"]

#: The splits (module docstring).
SPLITS = ("dev", "test")
#: Generated homes of the test split (seeds of :func:`psgsl_pgm.sim.generate_house`).
TEST_HOMES = range(10_000, 10_100)
#: Episode seeds of the test split: the house's, and each test home's (the benchmark takes the first 5 by default).
TEST_SEEDS = range(20_000, 20_020)
#: Seeds per home of ``psgsl benchmark --split test`` when no count is given.
BENCHMARK_TEST_SEEDS = 5


def check_split(split) -> str:
    """``split`` if it is one of :data:`SPLITS`; ValueError (TypeError) naming them otherwise."""
    return one_of(split, "split", SPLITS)


def _count(value, name: str, default: int, maximum: int | None = None) -> int:
    if value is None:
        return default
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name} must be at most {maximum} with the test split (its size), got {value}")
    return value


def _overlap(ids, test, what: str, option: str) -> None:
    lo, hi = max(ids.start, test.start), min(ids.stop, test.stop)
    if lo < hi:
        raise ValueError(f"{what} {test.start}-{test.stop - 1} are the test split's; a development run may not "
                         f"use them (got {option} reaching {lo}); run them with --split test")


def house_seeds(split: str, *, seeds: int | None = None, first_seed: int | None = None) -> range:
    """The seeds of a grid in one house (``psgsl search``).

    Parameters
    ----------
    split : {"dev", "test"}
    seeds : int, optional, keyword-only
        How many: dev default 10 (seeds ``first_seed`` …); test default all of :data:`TEST_SEEDS`, at most 20.
    first_seed : int, optional, keyword-only
        The first seed (dev only, default 0); with ``"test"`` a ValueError.

    Returns
    -------
    range
    """
    check_split(split)
    if split == "test":
        if first_seed is not None:
            raise ValueError(f"the test split has its own seeds ({TEST_SEEDS.start}-{TEST_SEEDS.stop - 1}); "
                             f"--first-seed does not apply with --split test (got {first_seed})")
        return TEST_SEEDS[:_count(seeds, "seeds", len(TEST_SEEDS), len(TEST_SEEDS))]
    first = 0 if first_seed is None else first_seed
    if isinstance(first, bool) or not isinstance(first, int) or first < 0:
        raise ValueError(f"first_seed must be an integer >= 0, got {first!r}")
    out = range(first, first + _count(seeds, "seeds", 10))
    _overlap(out, TEST_SEEDS, "seeds", "--first-seed/--seeds")
    return out


def benchmark_sample(split: str, *, houses: int | None = None, seeds: int | None = None,
                     first_house: int | None = None, world: bool = False) -> tuple:
    """The homes and per-home seeds of ``psgsl benchmark``: ``(house_ids, seed_ids)``, two ranges.

    Parameters
    ----------
    split : {"dev", "test"}
    houses : int, optional, keyword-only
        How many generated homes (0 or None with ``world``): dev ``first_house`` …; test the first of
        :data:`TEST_HOMES` (default all 100).
    seeds : int, optional, keyword-only
        Episodes per home: dev seeds 0 … seeds − 1 (default 5); test the first of :data:`TEST_SEEDS` (default
        :data:`BENCHMARK_TEST_SEEDS`, at most 20).
    first_house : int, optional, keyword-only
        Dev only (default 0); with ``"test"`` a ValueError.
    world : bool, keyword-only
        A world file instead of generated homes: ``house_ids`` is ``range(0, 1)`` (the world's only house).

    Returns
    -------
    tuple of range
    """
    check_split(split)
    if split == "test":
        if first_house is not None:
            raise ValueError(f"the test split has its own homes ({TEST_HOMES.start}-{TEST_HOMES.stop - 1}); "
                             f"--first-house does not apply with --split test (got {first_house})")
        seed_ids = TEST_SEEDS[:_count(seeds, "seeds", BENCHMARK_TEST_SEEDS, len(TEST_SEEDS))]
        if world:
            return range(0, 1), seed_ids
        return TEST_HOMES[:_count(houses or None, "houses", len(TEST_HOMES), len(TEST_HOMES))], seed_ids
    seed_ids = range(_count(seeds, "seeds", 5))
    if world:
        return range(0, 1), seed_ids
    first = 0 if first_house is None else first_house
    if isinstance(first, bool) or not isinstance(first, int) or first < 0:
        raise ValueError(f"first_house must be an integer >= 0, got {first!r}")
    house_ids = range(first, first + (houses or 0))
    _overlap(house_ids, TEST_HOMES, "generated homes", "--first-house/--houses")
    return house_ids, seed_ids


def split_of_seeds(seeds) -> str:
    """Which split a set of episode seeds belongs to: ``"test"`` when all lie in :data:`TEST_SEEDS`, ``"dev"``
    when none does, ``"mixed"`` otherwise (a folder holding runs of both)."""
    inside = [int(s) in TEST_SEEDS for s in seeds]
    return "test" if inside and all(inside) else ("mixed" if any(inside) else "dev")
