"""The development/test split: which homes and seeds each split holds, the refusals (explicit seeds with the test
split, development runs reaching into the test set), and the test set disjoint from every seed range the project
has used (published runs, calibration, the detector model's and the generated ontology's reference houses)."""

import pytest

from psgsl_pgm.search._split import (
    BENCHMARK_TEST_SEEDS,
    TEST_HOMES,
    TEST_SEEDS,
    benchmark_sample,
    check_split,
    house_seeds,
    split_of_seeds,
)


def test_dev_is_todays_seeds_and_homes():
    assert house_seeds("dev") == range(10)
    assert house_seeds("dev", seeds=20, first_seed=100) == range(100, 120)
    assert benchmark_sample("dev", houses=50, seeds=5) == (range(0, 50), range(5))
    assert benchmark_sample("dev", houses=3, seeds=2, first_house=7) == (range(7, 10), range(2))
    assert benchmark_sample("dev", seeds=4, world=True) == (range(0, 1), range(4))


def test_test_split_is_its_own_homes_and_seeds():
    assert list(house_seeds("test")) == list(range(20_000, 20_020))
    assert list(house_seeds("test", seeds=3)) == [20_000, 20_001, 20_002]
    homes, seeds = benchmark_sample("test")
    assert list(homes) == list(range(10_000, 10_100)) and list(seeds) == list(range(20_000, 20_000 + BENCHMARK_TEST_SEEDS))
    assert benchmark_sample("test", houses=20, seeds=2) == (range(10_000, 10_020), range(20_000, 20_002))
    assert benchmark_sample("test", world=True) == (range(0, 1), range(20_000, 20_005))


@pytest.mark.parametrize("call, needle", [
    (lambda: house_seeds("test", first_seed=0), "--first-seed does not apply with --split test"),
    (lambda: house_seeds("test", seeds=21), "at most 20"),
    (lambda: benchmark_sample("test", houses=5, first_house=0), "--first-house does not apply with --split test"),
    (lambda: benchmark_sample("test", houses=101), "at most 100"),
    (lambda: benchmark_sample("test", seeds=21), "at most 20"),
    (lambda: house_seeds("dev", seeds=5, first_seed=19_998), "are the test split's"),
    (lambda: benchmark_sample("dev", houses=2, first_house=9_999), "are the test split's"),
    (lambda: check_split("holdout"), "split must be one of ('dev', 'test'), got 'holdout'"),
])
def test_refusals_name_the_option(call, needle):
    with pytest.raises(ValueError) as exc:
        call()
    assert needle in str(exc.value)


def test_test_set_is_disjoint_from_every_range_used_so_far():
    from psgsl_pgm.sim import GENERATOR_REFERENCE_SEEDS
    from psgsl_pgm.sim._house_ontology import REFERENCE_SEEDS

    used = [range(0, 10), range(100, 120), range(200, 220), range(300, 320), range(1000, 1020), range(5000, 5004),
            range(10_000, 10_010)]  # published runs, calibration and tuning seeds, the detector's reference houses
    assert not set(TEST_SEEDS) & set().union(*map(set, used)) and not set(TEST_SEEDS) & set(REFERENCE_SEEDS)
    assert not set(TEST_HOMES) & set(GENERATOR_REFERENCE_SEEDS) and min(TEST_HOMES) >= 10_000  # dev: 0-9999
    assert split_of_seeds(range(100, 120)) == "dev" and split_of_seeds(TEST_SEEDS) == "test"
    assert split_of_seeds([3, 20_001]) == "mixed"
