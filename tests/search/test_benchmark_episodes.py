"""The benchmark's generative model of episodes and its ontology conditions (no closed-loop runs here)."""

import numpy as np
import pytest

from psgsl_pgm.search._benchmark import benchmark_arms
from psgsl_pgm.search._episodes import CONDITIONS, draw_episode, findable_sources, robot_ontology
from psgsl_pgm.sim import OTHER, generate_house


@pytest.fixture(scope="module")
def world():
    return generate_house(4).world()


@pytest.fixture(scope="module")
def sources(world):
    return findable_sources(world)


def test_right_and_no_rooms_ontologies(world):
    ont = world.ontology
    assert robot_ontology(ont, "right-ontology", house=4) is ont
    bare = robot_ontology(ont, "no-rooms", house=4)
    assert bare.rooms == () and bare.classes == ont.classes
    np.testing.assert_array_equal(bare.source_table, ont.source_table)
    np.testing.assert_array_equal(bare.class_prior, ont.class_prior)


def test_wrong_ontology_is_a_derangement_of_the_object_classes(world):
    ont = world.ontology
    objects = [i for i, c in enumerate(ont.classes) if c != OTHER]
    other = ont.classes.index(OTHER)
    perms = set()
    for house in range(6):
        wrong = robot_ontology(ont, "wrong-ontology", house=house)
        assert wrong == robot_ontology(ont, "wrong-ontology", house=house)  # seeded per house
        np.testing.assert_array_equal(wrong.source_table[:, other], ont.source_table[:, other])
        np.testing.assert_array_equal(wrong.room_table, ont.room_table)
        np.testing.assert_array_equal(wrong.class_prior, ont.class_prior)
        # each gas row: the same values over the object classes, moved; recover the permutation from the values
        row, new = ont.source_table[0, objects], wrong.source_table[0, objects]
        np.testing.assert_allclose(np.sort(new), np.sort(row), rtol=0, atol=0)
        oven = ont.class_index("oven")
        assert wrong.source_table[0, oven] != ont.source_table[0, oven]  # 0.40 moves to another class
        perms.add(tuple(np.round(new, 12)))
    assert len(perms) >= 5  # houses get different wrong tables


def test_draws_are_seeded_and_follow_the_table(world, sources):
    a = draw_episode(world, 4, 3, gases=("smoke",), off_rate=0.1, sources=sources)
    assert a == draw_episode(world, 4, 3, gases=("smoke",), off_rate=0.1, sources=sources)
    ont = world.ontology
    row = ont.source_likelihood("smoke")
    present = sorted({o.class_name for o in sources["objects"]} - {OTHER})
    p = np.array([row[ont.class_index(c)] for c in present])
    p = p / p.sum()
    n = 3000
    draws = [draw_episode(world, 4, s, gases=("smoke",), off_rate=0.0, sources=sources) for s in range(n)]
    assert all(d["kind"] == "object" for d in draws)
    counts = np.array([sum(d["class"] == c for d in draws) for c in present])
    sd = np.sqrt(n * p * (1 - p))
    assert np.all(np.abs(counts - n * p) <= 4 * sd + 1), dict(zip(present, counts))
    # instances of a class are drawn uniformly among its objects
    for d in draws[:50]:
        obj = next(o for o in world.house().objects if o.name == d["object"])
        np.testing.assert_allclose(d["xy"], obj.center, rtol=0, atol=1e-12)


def test_off_ontology_sources_are_findable_floor_cells_at_the_stated_rate(world, sources):
    from psgsl_pgm.search import check_findable

    n = 2000
    draws = [draw_episode(world, 4, s, gases=("smoke", "ethanol"), off_rate=0.25, sources=sources) for s in range(n)]
    off = [d for d in draws if d["kind"] == "off-ontology"]
    assert abs(len(off) - 0.25 * n) <= 4 * np.sqrt(n * 0.25 * 0.75)
    gases = [d["gas"] for d in draws]
    assert abs(gases.count("smoke") - n / 2) <= 4 * np.sqrt(n / 4)
    house = world.house()
    for d in off[:20]:
        r, c = house.grid.world_to_cell(np.array(d["xy"]))
        assert house.grid.free[r, c] and not house.furniture[r, c] and house.room_labels[r, c] >= 0
    res = check_findable(world, sources=[tuple(d["xy"]) for d in off[:20]])
    assert all(v["findable"] and v["object"] is None for v in res.values())


def test_arms_share_the_runs_that_do_not_read_the_ontology():
    pols, vars_ = ("tour", "greedy", "infotaxis", "semantic-modes"), ("olfaction", "semantics+rooms")
    right = benchmark_arms(pols, vars_, "right-ontology")
    assert right == [("tour", "olfaction"), ("greedy", "olfaction"), ("greedy", "semantics+rooms"),
                     ("infotaxis", "olfaction"), ("infotaxis", "semantics+rooms"), ("semantic-modes", "semantics+rooms")]
    for c in CONDITIONS[1:]:
        assert benchmark_arms(pols, vars_, c) == [("greedy", "semantics+rooms"), ("infotaxis", "semantics+rooms"),
                                                  ("semantic-modes", "semantics+rooms")]


def test_unknown_condition_names_the_choices(world):
    with pytest.raises(ValueError, match="condition must be one of"):
        robot_ontology(world.ontology, "wrong", house=0)


def test_wrong_ontology_moves_every_object_class_in_every_house():
    from psgsl_pgm.core._ontology import Ontology
    from psgsl_pgm.search._episodes import _derangement

    classes = ("oven", "bed", "sofa", "sink", "toilet", "table", "chair", "fridge", OTHER)
    table = np.arange(1.0, 10.0)[None, :] / 45.0  # distinct values: a class left in place keeps its own
    ont = Ontology(classes, ("smoke",), table, np.full(9, 1 / 9))
    for house in range(100):
        wrong = robot_ontology(ont, "wrong-ontology", house=house).source_table[0]
        assert wrong[-1] == table[0, -1]  # other keeps its own
        assert not np.any(wrong[:-1] == table[0, :-1]), (house, wrong)  # no object class keeps its probability
        assert sorted(wrong[:-1]) == sorted(table[0, :-1])
    rng = np.random.default_rng(0)
    for n in (2, 3, 5, 8):
        for _ in range(200):
            perm = _derangement(rng, n)
            assert sorted(perm) == list(range(n)) and not np.any(perm == np.arange(n))


def test_source_instances_are_drawn_uniformly_within_a_class(world, sources):
    by_class = {}
    for o in sources["objects"]:
        by_class.setdefault(o.class_name, []).append(o.name)
    many = {c: names for c, names in by_class.items() if len(names) > 1 and c != OTHER}
    assert many, "the test house must hold a class with several instances"
    n = 6000
    draws = [draw_episode(world, 4, s, gases=("smoke",), off_rate=0.0, sources=sources) for s in range(n)]
    for cls, names in many.items():
        got = [d["object"] for d in draws if d["class"] == cls]
        counts = np.array([got.count(name) for name in names])
        m, k = len(got), len(names)
        assert m >= 20, (cls, m)
        sd = np.sqrt(m * (1 / k) * (1 - 1 / k))
        assert np.all(np.abs(counts - m / k) <= 4 * sd), dict(zip(names, counts))
