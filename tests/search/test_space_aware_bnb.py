"""Space-aware infotaxis by branch and bound: the decision is the exhaustive arg max of ``space_aware_gain``, and
every bound lies above the value it bounds (along seeded episodes in the embedded house and in a large generated
home, and on randomly drawn posteriors)."""

import numpy as np
import pytest

from psgsl_pgm.search import SearchConfig, run_closed_loop
from psgsl_pgm.search import _policies as P
from psgsl_pgm.search._choose import choose


def _check(sit):
    """Assert the branch-and-bound decision is the exhaustive one and the bounds hold; the share of candidates
    whose bound could beat the winner."""
    dec = choose("space-aware-infotaxis", sit)
    cells, drive, pred, tau = P._candidates(sit)
    gain = P.space_aware_gain(sit, cells)
    ref = P._best(P._score(sit, gain, tau), cells, pred, drive, sit)
    assert (dec.cell, dec.headings, dec.drive, dec.score) == (ref.cell, ref.headings, ref.drive, ref.score)
    np.testing.assert_array_equal(dec.path, ref.path)
    sa = P._SpaceAware(sit)
    p_f, rows = P._found_mass(sit, cells)
    bound = P._space_aware_bound(sit, sa, cells, p_f, rows, drive, P._view_bits(sit, sa, cells))
    assert bound.shape == gain.shape and (bound >= gain).all()
    return float(np.mean(P._score(sit, bound, tau).max(axis=1) >= ref.score))


def _along(monkeypatch, runs):
    from psgsl_pgm.search import _stepper

    shares, sits = [], []

    def exhaustive_too(policy, sit):
        shares.append(_check(sit))
        sits.append(sit)
        return choose(policy, sit)

    monkeypatch.setattr(_stepper, "choose", exhaustive_too)  # the loop's per-stop code
    for args, kwargs in runs:
        run_closed_loop(*args, **kwargs)
    return shares, sits


def test_branch_and_bound_is_the_exhaustive_arg_max_in_short_episodes_of_each_belief(monkeypatch):
    """The default run's check along episodes: one or more decisions under each belief (olfaction alone, and
    semantics alone with the PMFS estimator and a detector that misses); semantics+rooms is checked along the
    episode of :func:`test_branch_and_bound_on_random_posteriors`, the longer episodes are the slow test below."""
    runs = [(("oven", 4, "space-aware-infotaxis", "olfaction"),
             {"search": SearchConfig(found_radius=1e-3, time_budget=12.0)}),
            (("bed", 5, "space-aware-infotaxis", "semantics", "analytic-plume"),
             {"search": SearchConfig(time_budget=12.0, miss_probability=0.3)})]
    _, sits = _along(monkeypatch, runs)
    assert {s.variant for s in sits} == {"olfaction", "semantics"}
    assert all(s.detection is not None for s in sits if s.variant == "semantics")  # the detector that misses


@pytest.mark.slow
def test_branch_and_bound_is_the_exhaustive_arg_max_along_episodes(monkeypatch):
    runs = [(("bed", 3, "space-aware-infotaxis", "semantics+rooms"),
             {"search": SearchConfig(found_radius=1e-3, time_budget=40.0)}),
            (("oven", 4, "space-aware-infotaxis", "olfaction"),
             {"search": SearchConfig(found_radius=1e-3, time_budget=40.0)}),
            (("bed", 5, "space-aware-infotaxis", "semantics", "analytic-plume"),
             {"search": SearchConfig(time_budget=40.0, miss_probability=0.3)})]
    shares, sits = _along(monkeypatch, runs)
    assert len(shares) >= 15
    assert {s.variant for s in sits} == {"semantics+rooms", "olfaction", "semantics"}
    assert np.mean(shares) < 0.9  # the bounds prune: most candidates are never scored exactly


@pytest.mark.slow
def test_branch_and_bound_is_the_exhaustive_arg_max_in_a_large_generated_home(monkeypatch):
    from psgsl_pgm.sim import generate_house

    g = generate_house(101, area=190.0)
    objects = list(g.house.objects)
    source = tuple(float(v) for v in objects[len(objects) // 2].center)
    runs = [((source, 0, "space-aware-infotaxis", "semantics+rooms"),
             {"world_spec": g.world(), "search": SearchConfig(found_radius=1e-3, time_budget=100.0)})]
    shares, _ = _along(monkeypatch, runs)
    assert len(shares) >= 5


def test_branch_and_bound_on_random_posteriors(monkeypatch):
    """Posteriors drawn at random (a few bumps, many empty cells, mass in unreachable cells) at random robot
    cells and headings, with a detector that misses and one that does not."""
    shares, sits = _along(monkeypatch, [(("bed", 6, "space-aware-infotaxis", "semantics+rooms"),
                                         {"search": SearchConfig(found_radius=1e-3, time_budget=15.0)})])
    base = sits[-1]
    space = base.space
    rng = np.random.default_rng(20)
    nav = np.flatnonzero(space.nav.ravel())
    centres = space.centres
    for trial in range(12):
        post = np.zeros(space.free.size)
        for _ in range(int(rng.integers(1, 4))):
            c = centres[int(rng.choice(np.flatnonzero(space.free)))]
            width = rng.uniform(0.2, 3.0)
            post += rng.uniform(0.1, 1.0) * np.exp(-0.5 * ((centres - c) ** 2).sum(axis=1) / width**2)
        post *= space.free * (rng.random(post.size) > rng.uniform(0.0, 0.7))
        post /= post.sum()
        sit = P.Situation(**{**base.__dict__, "posterior": post.reshape(space.nav.shape),
                             "cell": int(rng.choice(nav)), "heading": float(rng.uniform(-np.pi, np.pi)),
                             "score": ("per-time", "gain")[trial % 2],
                             "detection": base.detection if trial % 3 else None})
        shares.append(_check(sit))
    assert np.mean(shares) < 1.0


def test_tile_distance_floor_is_below_every_geodesic_distance_of_its_tile():
    from psgsl_pgm.search import FreeSpace
    from psgsl_pgm.sim import Camera, generate_house

    g = generate_house(102, area=120.0)
    space = FreeSpace(g.house, Camera())
    rng = np.random.default_rng(3)
    tight = []
    for cell in rng.choice(np.flatnonzero(space.nav.ravel()), 6, replace=False):
        d = space.distances(int(cell))
        d = np.where(np.isfinite(d), d, 0.0)
        exact = np.full(space.n_tiles + 1, np.inf)
        np.minimum.at(exact, space.tile, d)
        exact[-1] = 0.0
        floor, order = space.tile_distance_floor(int(cell))
        assert (np.diff(floor[order]) >= 0).all()
        assert floor.shape == (space.n_tiles + 1,) and floor[-1] == 0.0
        assert (floor <= exact).all()
        tight.append(np.median(floor[:-1][exact[:-1] > 0] / exact[:-1][exact[:-1] > 0]))
    assert min(tight) > 0.7  # the octile floor is not a trivial one


def test_views_are_shared_by_the_free_spaces_of_one_map_and_camera():
    from psgsl_pgm.search import FreeSpace
    from psgsl_pgm.sim import Camera, generate_house

    house = generate_house(104, area=60.0).house
    a, b = FreeSpace(house, Camera()), FreeSpace(house, Camera())
    narrow = FreeSpace(house, Camera(half_angle=0.3))
    other = FreeSpace(house, Camera(), n_headings=4)
    cell = int(np.flatnonzero(a.nav.ravel())[len(np.flatnonzero(a.nav.ravel())) // 2])
    flat, sectors = a.view(cell)
    assert b.view(cell)[0] is flat and b.view(cell)[1] is sectors  # computed once for both
    assert narrow.view(cell)[1].sum() < sectors.sum()  # another camera: its own views
    assert other.view(cell)[1].shape == (4, flat.size)
    fresh = FreeSpace.__new__(FreeSpace)
    fresh.__dict__.update(a.__dict__, _views={})  # the same geometry, nothing cached
    np.testing.assert_array_equal(fresh.view(cell)[0], flat)
    np.testing.assert_array_equal(fresh.view(cell)[1], sectors)
