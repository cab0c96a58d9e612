"""PMFS's own navigation (``pmfs-nav``): its interest against a brute-force evaluation of the published formulas,
its two phases, and the estimator it needs."""

from types import SimpleNamespace

import numpy as np
import pytest

from psgsl_pgm import GridMap
from psgsl_pgm.olfaction import FilamentPMFS, PlumeModel
from psgsl_pgm.search import FreeSpace, SearchConfig, Situation, choose, run_closed_loop
from psgsl_pgm.search import _pmfs_nav
from psgsl_pgm.search._grid import run_search_grid
from psgsl_pgm.search._policies import check_estimator
from psgsl_pgm.sim import Camera


@pytest.fixture(scope="module")
def room():
    occ = np.zeros((30, 80), bool)
    occ[0, :] = occ[-1, :] = occ[:, 0] = occ[:, -1] = True
    grid = GridMap(occ, 0.1, (0.0, 0.0))
    return grid, FreeSpace(SimpleNamespace(grid=grid, robot_obstacles=occ), Camera())


@pytest.fixture(scope="module")
def pmfs(room):
    """PMFS after readings along the west half of the room, in a wind along +x: a hit near x = 2 m."""
    grid, _ = room
    est = FilamentPMFS(PlumeModel(grid.occupancy, resolution=0.1, wind=np.zeros((30, 80, 2))), seed=4)
    for x in (0.55, 1.05, 1.55, 2.05, 2.55, 3.05):
        for y in (0.85, 1.55, 2.25):
            est.update((x, y), abs(x - 2.05) < 0.1 and y == 1.55, wind=(0.3, 0.0))
    return est


def _situation(room, est, *, at=(2.05, 1.55), cache=None):
    grid, space = room
    return Situation(est.posterior, SimpleNamespace(estimator=est), "olfaction", space, space.snap(at), 0.0, 0.25,
                     1.0, 1.0, 2.0, 0.5, {} if cache is None else cache, score="gain", far_spacing=None)


def _exploration_brute_force(est, cell):
    """X(c) = Σ over free cells p of the window of half-side 5 ℓ of (1 − conf_p) exp(−‖p − c‖ / ℓ)."""
    geo = est.geometry
    ell = est.hit_block
    centres = geo.cell_centres().reshape(-1, 2)
    conf = est.confidence.ravel()
    free = geo.free.ravel()
    d = centres - centres[cell]
    inside = (np.abs(d) <= 5 * ell + 1e-9).all(axis=1) & free
    return float(((1 - conf[inside]) * np.exp(-np.hypot(d[inside, 0], d[inside, 1]) / ell)).sum())


def test_hit_variance_is_the_score_weighted_variance_of_the_simulated_hit_maps(pmfs):
    est = pmfs
    free = est.geometry.free.ravel()
    coarse = np.unique(est._coarse)  # a uniform prior: every first-level region was simulated
    sim = est._sim[coarse]
    score = est._score(sim, None, est._log_odds, est._omega)
    h = sim[:, est._block[free]]
    mean = np.average(h, axis=0, weights=np.exp(score - score.max()))
    var = np.average((h - mean) ** 2, axis=0, weights=np.exp(score - score.max()))
    got = est.hit_variance()
    np.testing.assert_allclose(got.ravel()[free], var, rtol=1e-10, atol=1e-15)
    assert (got.ravel()[~free] == 0).all() and var.max() > 0


def test_exploration_goes_to_the_least_confident_open_cell_by_the_published_sum(room, pmfs):
    grid, space = room
    sit = _situation(room, pmfs)
    decision = choose("pmfs-nav", sit)  # the first decision: exploration
    open_cells = np.array([c for c in sit.cache[_pmfs_nav._STATE]["open"] if c != sit.cell])
    brute = np.array([_exploration_brute_force(pmfs, c) for c in open_cells])
    np.testing.assert_allclose(_pmfs_nav.pmfs_interest(sit, open_cells, explore=True), brute, rtol=1e-10)
    assert decision.cell == open_cells[int(np.argmax(brute))]
    # the readings made the west confident: the robot explores eastwards, where nothing was measured
    assert space.position(decision.cell)[0] > 3.0


def test_after_the_exploration_moves_the_robot_goes_where_the_sources_disagree(room, pmfs, monkeypatch):
    monkeypatch.setattr(_pmfs_nav, "EXPLORATION_PROBABILITY", 0.0)
    cache = {}
    sit = _situation(room, pmfs, cache=cache)
    choose("pmfs-nav", sit)
    cache[_pmfs_nav._STATE]["decisions"] = _pmfs_nav.INITIAL_EXPLORATION  # the exploration moves are done
    decision = choose("pmfs-nav", _situation(room, pmfs, cache=cache))
    open_cells = np.array([c for c in cache[_pmfs_nav._STATE]["open"] if c != sit.cell])
    v = (pmfs.hit_variance() * (1 - pmfs.confidence)).ravel()[open_cells]
    assert v.max() > 0
    assert decision.cell == open_cells[int(np.argmax(v))]


def test_pmfs_nav_needs_the_pmfs_estimator(room):
    grid, _ = room
    other = SimpleNamespace(estimator=SimpleNamespace(posterior=np.full(grid.occupancy.shape, 1.0)))
    sit = Situation(other.estimator.posterior, other, "olfaction", room[1], room[1].snap((2.05, 1.55)), 0.0, 0.25,
                    1.0, 1.0, 2.0, 0.5, {})
    with pytest.raises(ValueError, match="needs the estimator 'pmfs'"):
        choose("pmfs-nav", sit)
    with pytest.raises(ValueError, match="runs with estimator 'pmfs' only, got 'infotaxis'"):
        check_estimator("pmfs-nav", "infotaxis")
    with pytest.raises(ValueError, match="estimator 'pmfs' only"):
        run_closed_loop("oven", 0, "pmfs-nav", "olfaction", "grgsl", search=SearchConfig(time_budget=30.0))


def test_a_grid_of_pmfs_nav_without_the_pmfs_estimator_is_refused_before_any_run(tmp_path):
    with pytest.raises(ValueError, match="policy 'pmfs-nav' runs with estimator 'pmfs' only, got 'grgsl'"):
        run_search_grid(policies=("pmfs-nav",), estimators=("grgsl",), seeds=(0,), out=tmp_path / "g")
    with pytest.raises(ValueError, match="grid entries: policy 'pmfs-nav' runs with estimator 'pmfs' only"):
        run_search_grid(grid=[("oven", "pmfs-nav", "olfaction", "infotaxis", 0)], out=tmp_path / "g")
    assert not (tmp_path / "g" / "runs").exists() or not any((tmp_path / "g" / "runs").iterdir())


@pytest.mark.slow
def test_a_pmfs_nav_episode_is_reproducible_and_fuses_with_semantics():
    search = SearchConfig(time_budget=120.0)
    a = run_closed_loop("oven", 1, "pmfs-nav", "semantics+rooms", "pmfs", search=search)
    b = run_closed_loop("oven", 1, "pmfs-nav", "semantics+rooms", "pmfs", search=search)
    assert a.n_steps > 3
    np.testing.assert_array_equal(a.position, b.position)
    np.testing.assert_array_equal(a.final_posterior, b.final_posterior)
