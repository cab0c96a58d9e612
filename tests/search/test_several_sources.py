"""Several sources per episode: the stopping probability, the scoring of declarations, the settings' checks, the
stored runs (old ones load as one source), and a seeded search that declares two sources one by one."""

import numpy as np
import pytest

from psgsl_pgm.search import SearchConfig
from psgsl_pgm.search._benchmark import check_sources_per_episode
from psgsl_pgm.search._settings import SearchRun
from psgsl_pgm.search._several import match_declarations, more_sources_probability
from psgsl_pgm.search._store import load_search_run, save_search_run


def test_more_sources_probability_is_bayes_rule_on_the_count():
    prior = [0.5, 0.3, 0.2]
    # nothing searched (Z = 1): the prior's P(N > k | N >= k)
    assert more_sources_probability(prior, 1, 1.0) == pytest.approx(0.5)
    assert more_sources_probability(prior, 2, 1.0) == pytest.approx(0.2 / 0.5)
    # everywhere searched without a detection (Z = 0): no further source
    assert more_sources_probability(prior, 1, 0.0) == 0.0
    # by hand: a = 0.5, Z = 0.1 -> 0.05 / (0.05 + 0.5)
    assert more_sources_probability(prior, 1, 0.1) == pytest.approx(0.05 / 0.55)
    # the prior's largest count reached: none further
    assert more_sources_probability(prior, 3, 1.0) == 0.0
    assert more_sources_probability([0.5, 0.5, 0.0], 2, 1.0) == 0.0
    z = np.linspace(0, 1, 11)
    p = [more_sources_probability(prior, 1, v) for v in z]
    assert np.all(np.diff(p) > 0)  # the less searched, the more the robot believes in another source
    with pytest.raises(ValueError, match="prior"):
        more_sources_probability([0.5, 0.5], 1, 0.5)
    with pytest.raises(ValueError, match="k must"):
        more_sources_probability(prior, 0, 0.5)
    with pytest.raises(ValueError, match="escape"):
        more_sources_probability(prior, 1, 1.5)


def test_declarations_name_each_source_once_in_order():
    sources = [[1.0, 1.0], [8.0, 1.0]]
    got = match_declarations([[1.2, 1.0], [1.0, 1.3], [8.5, 1.0], [4.0, 4.0]], sources, radius=1.0)
    assert got.tolist() == [0, -1, 1, -1]  # the second near source 0 is a false declaration: 0 was named
    # an object source is scored on its footprint
    region = [np.array([[5.0, 5.0], [5.0, 6.5]]), None]
    assert match_declarations([[5.2, 7.0]], [[5.0, 5.5], [0.0, 0.0]], radius=1.0, regions=region).tolist() == [0]
    assert match_declarations(np.zeros((0, 2)), sources, radius=1.0).tolist() == []


@pytest.mark.parametrize("kwargs, match", [
    ({"source_count_prior": (0.5, 0.5)}, "source_count_prior"),
    ({"source_count_prior": (0.5, 0.4, 0.2)}, "source_count_prior"),
    ({"source_count_prior": (1.0, 0.0, 0.0)}, "source_count_prior"),
    ({"source_count_prior": (-0.1, 0.6, 0.5)}, "source_count_prior"),
    ({"source_count_prior": "1/3"}, "source_count_prior"),
    ({"source_count_prior": (1 / 3, 1 / 3, 1 / 3), "end": "reach"}, "source_count_prior"),
    ({"more_sources_level": 0.0}, "more_sources_level"),
    ({"more_sources_level": 1.0}, "more_sources_level"),
])
def test_bad_settings_name_the_argument(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SearchConfig(**kwargs)


def test_a_one_source_robot_keeps_the_stored_settings():
    d = SearchConfig().to_dict()
    assert "source_count_prior" not in d and "more_sources_level" not in d
    d = SearchConfig(source_count_prior=(0.2, 0.3, 0.5)).to_dict()
    assert d["source_count_prior"] == [0.2, 0.3, 0.5] and d["more_sources_level"] == 0.1


@pytest.mark.parametrize("value, expected", [(1, 1), (3, 3), ("2", 2), ("1-3", (1, 3)), ("2-3", (2, 3)),
                                             ((1, 2), (1, 2)), ("3-3", 3)])
def test_sources_per_episode_accepts_n_or_a_range(value, expected):
    assert check_sources_per_episode(value) == expected


@pytest.mark.parametrize("value", [0, 4, "0", "4", "1-4", "3-1", "a-b", "1-2-3", "", (0, 2), (1, 2, 3)])
def test_sources_per_episode_outside_1_to_3_is_a_value_error_naming_it(value):
    with pytest.raises(ValueError, match="sources_per_episode"):
        check_sources_per_episode(value)
    with pytest.raises(TypeError, match="sources_per_episode"):
        check_sources_per_episode(2.5)


@pytest.mark.parametrize("value", ["4", "1-5", "x"])
def test_the_benchmark_command_refuses_a_bad_count_in_one_line(tmp_path, capsys, value):
    from psgsl_pgm.cli._main import main

    code = main(["benchmark", "--houses", "1", "--seeds", "1", "--sources-per-episode", value,
                 "--out", str(tmp_path / "b")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "--sources-per-episode" in err[0]
    assert not (tmp_path / "b").exists()


def _run(**extra):
    n = 3
    return SearchRun("oven", 0, "infotaxis", "olfaction", "infotaxis", np.array([7.7, 0.5]), True, 12.0, 3.0,
                     4.0, np.arange(n, dtype=float) * 10, np.zeros((n, 2)), np.zeros(n), np.zeros(n, bool),
                     np.arange(n, dtype=float), np.ones(n), np.ones(n), np.ones(n), np.ones(n),
                     np.zeros(n, bool), np.zeros((4, 2)), np.zeros((2, 3), np.float32),
                     {"search": SearchConfig(time_budget=100.0).to_dict() | {"start": [0.8, 6.0]}},
                     np.zeros(n), declared=True, declared_xy=np.array([7.7, 0.5]), time_to_declare=20.0,
                     declared_error=0.0, declared_correct=True, declared_mass=0.95, **extra)


def test_a_one_source_run_round_trips_without_the_several_fields(tmp_path):
    run = _run()
    assert not run.several and run.n_sources == 1
    path = save_search_run(run, tmp_path / "one.npz")
    with np.load(path) as z:
        assert "declarations" not in z.files  # the file a one-source run always wrote
    back = load_search_run(path)
    assert not back.several and back.declarations.shape == (0, 4) and back.sources_xy.shape == (0, 2)
    t, ok = back.source_times()
    assert t.tolist() == [20.0] and ok.tolist() == [True]
    assert back.time_to_all() == (20.0, True) and back.n_false_declarations == 0


def test_a_several_source_run_round_trips(tmp_path):
    run = _run(sources_xy=np.array([[7.7, 0.5], [0.75, 2.3]]),
               declarations=np.array([[7.7, 0.5, 20.0, 0.95], [3.0, 3.0, 40.0, 0.91], [0.8, 2.2, 70.0, 0.97]]),
               declared_source=np.array([0, -1, 1]), more_probability=np.array([np.nan, 0.5, 0.05]))
    back = load_search_run(save_search_run(run, tmp_path / "two.npz"))
    assert back.several and back.n_sources == 2
    np.testing.assert_array_equal(back.declarations, run.declarations)
    np.testing.assert_array_equal(back.declared_source, run.declared_source)
    np.testing.assert_array_equal(back.more_probability, run.more_probability)
    t, ok = back.source_times()
    assert t.tolist() == [20.0, 70.0] and ok.all()
    assert back.time_to_all() == (70.0, True) and back.n_false_declarations == 1
    half = _run(sources_xy=np.array([[7.7, 0.5], [0.75, 2.3]]), declarations=np.array([[7.7, 0.5, 20.0, 0.95]]),
                declared_source=np.array([0]), more_probability=np.array([np.nan, 0.5, 0.5]))
    assert half.time_to_all() == (100.0, False)  # censored at the budget


@pytest.mark.slow
def test_two_sources_far_apart_are_declared_one_after_the_other():
    """The oven and the couch, 7 m apart: the robot declares one, the declared region leaves its belief, it
    finds the other, and it stops once p(another source) is low — well before the budget."""
    from psgsl_pgm.search import run_closed_loop

    run = run_closed_loop("oven", 0, "infotaxis", "semantics+rooms", extra_sources=("couch",),
                          search=SearchConfig(time_budget=1000.0, source_count_prior=(1 / 3, 1 / 3, 1 / 3)))
    assert run.n_sources == 2
    assert sorted(run.declared_source.tolist()) == [0, 1] and run.n_false_declarations == 0
    t, ok = run.source_times()
    assert ok.all() and run.time_to_all()[1]
    k = int(np.searchsorted(run.time, run.declarations[0, 2]))  # the stop of the first declaration
    assert np.isnan(run.more_probability[:k]).all()
    assert run.more_probability[-1] < 0.1 <= np.nanmax(run.more_probability)
    assert run.time[-1] < 1000.0  # it stopped itself


@pytest.mark.slow
def test_a_several_source_benchmark_reports_per_source_and_all_found(tmp_path):
    import json

    from psgsl_pgm.search import run_benchmark

    out = tmp_path / "b"
    s = run_benchmark(out=out, houses=1, seeds=2, policies=("infotaxis",), variants=("semantics+rooms",),
                      conditions=("right-ontology",), search=SearchConfig(time_budget=120.0), workers=1,
                      progress=False, figures=False, sources_per_episode=(2, 3))
    episodes = json.loads((out / "episodes.json").read_text())
    assert all(e["n_sources"] in (2, 3) and len(e["extra"]) == e["n_sources"] - 1 for e in episodes.values())
    for e in episodes.values():  # the first source is the one-source benchmark's draw, the others apart from it
        xy = np.array([e["xy"]] + [x["xy"] for x in e["extra"]])
        d = np.linalg.norm(xy[:, None] - xy[None], axis=-1)
        assert d[np.triu_indices(len(xy), 1)].min() >= 2.0
    arm = s["arms"]["right-ontology"]["infotaxis/semantics+rooms"]["several_sources"]
    assert arm["n"] == 2 and arm["sources"] == sum(e["n_sources"] for e in episodes.values())
    assert 0.0 <= arm["source_success"]["value"] <= 1.0 and arm["all_found_rmst"]["tau"] == 120.0
    assert "Several sources per episode" in (out / "report.md").read_text()
    from psgsl_pgm.search import load_search_run  # a run's CPU seconds, once, under its benchmark label

    configs = [load_search_run(p).config for p in sorted((out / "runs").iterdir())]
    assert all("cpu_seconds" not in c and c["benchmark"]["cpu_seconds"] > 0 for c in configs)
    with pytest.raises(ValueError, match="sources_per_episode"):
        run_benchmark(out=tmp_path / "c", houses=1, seeds=1, sources_per_episode=4)


def test_an_unknown_gas_episode_gives_each_source_its_gas_and_only_the_world_knows():
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.search._stepper import ClosedLoopEpisode

    ep = ClosedLoopEpisode("oven", 0, "infotaxis", "semantics+rooms", config=ExperimentConfig(gas="unknown"),
                           gas_type="smoke", extra_sources=("toilet",), extra_gas_types=("ammonia",),
                           search=SearchConfig(time_budget=40.0, source_count_prior=(0.5, 0.5, 0.0)))
    assert ep.world.gas_types == ("smoke", "ammonia") and ep.world.n_sources == 2
    while not ep.done:
        ep.take(ep.planned_move())
    run = ep.result()
    assert run.gas == "smoke" and run.n_sources == 2 and len(run.more_probability) == len(run.time)
    with pytest.raises(ValueError, match="estimator must be one of"):
        ClosedLoopEpisode("oven", 0, "infotaxis", "olfaction", "particle-filter",
                          search=SearchConfig(source_count_prior=(0.5, 0.5, 0.0)))
