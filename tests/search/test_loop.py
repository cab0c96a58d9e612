"""The closed loop: the experiment's code path, the found rule, invariants of a run, storage and statistics."""

import numpy as np
import pytest

from psgsl_pgm.search import SearchConfig, credible_region, run_closed_loop, wilson_interval
from psgsl_pgm.search._store import load_search_run, save_search_run


def test_tour_in_the_closed_loop_is_the_validation_experiment_times_not_found(house_space):
    """Same world, same stops: the closed loop's posterior is the experiment's (the per-step code is shared)
    times the indicator of the hypotheses the robot can find and the "not found" likelihood of everywhere it
    drove, renormalised (fusion keeps the factors once)."""
    from psgsl_pgm.experiment import Tour, exploration_tour, run_search
    from psgsl_pgm.search import DetectionModel

    house, space = house_space
    run = run_closed_loop("oven", 0, "tour", "semantics+rooms", search=SearchConfig(time_budget=15.0), space=space)
    m = run.n_steps  # the closed loop's stops are the tour's first m stops
    assert m >= 3 and not run.found
    full = exploration_tour(house)
    short = Tour(full.stops[:m], full.headings[:m], full.path, full.distance[:m], full.waypoint[:m],
                 full.path_index[:m])
    ref = run_search("oven", 0, "infotaxis", tour=short, snapshot_at=(1.0,))
    np.testing.assert_array_equal(run.time, ref.time)
    np.testing.assert_array_equal(run.position[1:], ref.position[1:])
    np.testing.assert_array_equal(run.hit, ref.hit)
    model = DetectionModel.from_house(house, 0.5)
    visited = np.isneginf(model.not_found_log_likelihood(run.path)).reshape(house.shape)
    assert visited.sum() > 100
    findable = space.findable(model, space.snap(run.position[0])).reshape(house.shape)
    assert (~findable & house.grid.free).sum() > 10  # free cells no stop can rule out
    expected = np.where(visited | ~findable, 0.0, ref.snapshots[m][2])
    expected /= expected.sum()
    assert run.final_posterior[visited].max() == 0.0  # exactly the modelled mass: none
    np.testing.assert_allclose(run.final_posterior, expected, rtol=1e-5, atol=1e-12)  # float32 storage
    assert ((run.hpd_level > 0) & (run.hpd_level <= 1)).all()  # recorded at every stop


@pytest.mark.slow
def test_a_short_infotaxis_run_is_consistent(house_space):
    _, space = house_space
    search = SearchConfig(time_budget=25.0)
    run = run_closed_loop("oven", 1, "infotaxis", "semantics+rooms", search=search, space=space)
    n = run.n_steps + 1
    for a in (run.time, run.heading, run.hit, run.path_length, run.error, run.map_error, run.spread,
              run.region_area, run.region_hit, run.hpd_level):
        assert a.shape == (n,)
    assert np.all(np.diff(run.time) > 0) and np.all(np.diff(run.path_length) >= 0)
    steps = np.linalg.norm(np.diff(run.position[1:], axis=0), axis=1)
    assert np.all(steps > 0) and np.all(steps <= np.diff(run.path_length[1:]) + 1e-9)  # it moves, geodesically
    cells = [space.cell_of(p) for p in run.position[1:]]
    assert space.nav.ravel()[cells].all()
    assert not run.found and run.time_to_find == 25.0 and run.time[-2] < 25.0
    assert run.final_posterior.dtype == np.float32
    assert abs(float(run.final_posterior.sum(dtype=np.float64)) - 1) < 1e-5
    assert run.driven == pytest.approx(run.path_length[-1])


def test_found_on_the_way_within_the_radius(house_space):
    _, space = house_space
    run = run_closed_loop("2.0,6.05", 0, "greedy", "olfaction", search=SearchConfig(time_budget=200.0, end="reach"),
                          space=space)
    assert run.found
    centre = house_space[0].grid.cell_to_world(house_space[0].grid.world_to_cell(run.source_xy))  # its cell's
    d = np.linalg.norm(run.path - centre, axis=1)
    assert d[-1] <= 0.5 < d[:-1].min()  # the path stops where it first comes within the radius
    assert run.time_to_find > run.time[-1]  # found while driving after the last stop
    assert run.path_ratio >= 1.0 - 1e-9
    assert not run.declared and run.succeeded and run.time_to_success == run.time_to_find


def test_a_detection_stops_the_robot_where_it_fired_and_the_declaration_ends_the_run(house_space):
    _, space = house_space
    reach = run_closed_loop("2.0,6.05", 0, "greedy", "olfaction", search=SearchConfig(time_budget=200.0, end="reach"),
                            space=space)
    run = run_closed_loop("2.0,6.05", 0, "greedy", "olfaction", search=SearchConfig(time_budget=200.0), space=space)
    assert run.found and run.time_to_find == reach.time_to_find  # the same first pass within reach
    np.testing.assert_array_equal(run.path, reach.path)  # ... where the detection stopped the robot
    assert run.time[-1] > run.time_to_find  # then it looked (one reading and frame) and declared
    assert run.declared and run.time_to_declare == run.time[-1] and run.declared_mass >= 0.9
    assert run.declared_error == pytest.approx(np.linalg.norm(run.declared_xy - run.source_xy))
    assert run.declared_correct and run.succeeded and run.time_to_success == run.time_to_declare


def test_store_round_trip(tmp_path, house_space):
    _, space = house_space
    run = run_closed_loop("oven", 2, "greedy", "olfaction", search=SearchConfig(time_budget=8.0),
                          space=space)
    back = load_search_run(save_search_run(run, tmp_path / "r.npz"))
    for name in ("time", "position", "error", "region_hit", "hpd_level", "path", "final_posterior"):
        np.testing.assert_array_equal(getattr(back, name), getattr(run, name))
    assert (back.found, back.time_to_find, back.config, back.policy) == (run.found, run.time_to_find, run.config,
                                                                         run.policy)
    with pytest.raises(ValueError, match="not a search run"):
        load_search_run(tmp_path / "missing.npz")


def test_credible_region_is_the_smallest_set():
    rng = np.random.default_rng(0)
    for _ in range(20):
        p = rng.dirichlet(np.full(12, 0.3)).reshape(3, 4)
        region = credible_region(p, 0.9)
        assert p[region].sum() >= 0.9 - 1e-12
        srt = np.sort(p.ravel())[::-1]
        k = int(np.argmax(np.cumsum(srt) >= 0.9 - 1e-12)) + 1  # brute force: fewest cells reaching 0.9
        assert region.sum() == k
    with pytest.raises(ValueError):
        credible_region([0.5, 0.5], 1.0)


def test_wilson_interval():
    lo, hi = wilson_interval(8, 10)
    assert (round(lo, 4), round(hi, 4)) == (0.4902, 0.9433)
    assert wilson_interval(0, 10)[0] == 0.0 and wilson_interval(10, 10)[1] == 1.0


@pytest.mark.parametrize("kwargs, exc", [
    (dict(policy="random"), ValueError),
    (dict(variant="rooms"), ValueError),
    (dict(estimator="x"), ValueError),
    (dict(seed=1.5), TypeError),
])
def test_bad_arguments(kwargs, exc):
    args = dict(source="oven", seed=0, policy="tour", variant="olfaction", estimator="infotaxis") | kwargs
    with pytest.raises(exc):
        run_closed_loop(**args)


def test_search_config_is_validated():
    with pytest.raises(ValueError, match="found_radius"):
        SearchConfig(found_radius=0)
    with pytest.raises(TypeError, match="time_budget"):
        SearchConfig(time_budget="long")
    with pytest.raises(ValueError, match="start"):
        SearchConfig(start=(1.0,))
    with pytest.raises(TypeError, match="start must be an"):
        SearchConfig(start=[[1.0], [2.0, 3.0]])
    with pytest.raises(ValueError, match="time_budget must be a positive number in seconds, got an integer too large"):
        SearchConfig(time_budget=10**400)
    with pytest.raises(ValueError, match=r"credible must lie in \(0, 1\)"):
        SearchConfig(credible=1.0)
    with pytest.raises(ValueError, match="n_headings must be an int >= 1"):
        SearchConfig(n_headings=8.5)
    assert SearchConfig(time_budget=12).to_dict()["time_budget"] == 12.0
    with pytest.raises(ValueError, match=r"score must be one of \('per-time', 'gain'\), got 'fast'"):
        SearchConfig(score="fast")
    with pytest.raises(TypeError, match=r"score must be one of \('per-time', 'gain'\), got NoneType"):
        SearchConfig(score=None)


def test_the_default_score_is_left_out_of_stored_settings_so_older_runs_still_resume():
    assert "score" not in SearchConfig().to_dict()  # runs stored before the option existed match the default
    stored = SearchConfig(score="gain").to_dict()
    assert stored["score"] == "gain" and SearchConfig(**stored) == SearchConfig(score="gain")
    assert SearchConfig(**SearchConfig().to_dict()) == SearchConfig()
    # runs stored before the "not found" update and the far candidates searched differently: they never match
    old = {k: v for k, v in SearchConfig().to_dict().items() if k not in ("far_spacing", "miss_probability")}
    assert old != SearchConfig().to_dict()


def test_new_search_options_are_validated_and_stored():
    assert SearchConfig(far_spacing=None).far_spacing is None
    with pytest.raises(ValueError, match="far_spacing must be a positive"):
        SearchConfig(far_spacing=0)
    with pytest.raises(TypeError, match="far_spacing"):
        SearchConfig(far_spacing="far")
    with pytest.raises(ValueError, match=r"miss_probability must lie in \[0, 1\)"):
        SearchConfig(miss_probability=1.0)
    with pytest.raises(TypeError, match="miss_probability"):
        SearchConfig(miss_probability="often")
    assert SearchConfig(miss_probability=None).miss_probability is None  # the robot's estimate
    with pytest.raises(ValueError, match="end must be one of"):
        SearchConfig(end="found")
    with pytest.raises(ValueError, match="declare_mass must lie in"):
        SearchConfig(declare_mass=1.0)
    d = SearchConfig(miss_probability=0.1, far_spacing=None).to_dict()
    assert d["miss_probability"] == 0.1 and d["far_spacing"] is None
