"""FreeSpace.cover: the candidate lattice gains finder cells, so that a stop can find every findable source."""

import numpy as np
import pytest

from psgsl_pgm.search import DetectionModel
from psgsl_pgm.search._space import FreeSpace
from psgsl_pgm.sim import Camera, generate_house, load_world


@pytest.fixture(scope="module")
def home(tmp_path_factory):
    """Generated home 48: its oven stands where no 0.5-m lattice cell comes within 0.5 m of its footprint."""
    path = generate_house(48).write(tmp_path_factory.mktemp("h48"))
    world = load_world(path)
    return path, world, world.house(0)


def _space(world, house):
    return FreeSpace(house, Camera(), clearance=world.clearance)


def _uncovered(space, detection, lattice, *, floor=True):
    """Hypotheses (footprint cells, and free cells with ``floor``) some drivable cell finds and no cell of
    ``lattice`` does."""
    nav = np.flatnonzero(space.nav.ravel())
    findable = detection.rows(space.centres[nav]).getnnz(axis=0) > 0
    covered = detection.rows(space.centres[np.flatnonzero(lattice.ravel())]).getnnz(axis=0) > 0
    hypotheses = (detection.owner >= 0) | (space.free if floor else False)
    return hypotheses & findable & ~covered


@pytest.mark.parametrize("radius", [0.5, 0.36])
def test_after_cover_a_lattice_stop_finds_every_findable_hypothesis(home, radius):
    _, world, house = home
    space = _space(world, house)
    detection = DetectionModel.from_house(house, radius)
    base = space.lattice.copy()
    assert _uncovered(space, detection, base).sum() > 0  # the lattice alone misses some (else the test is moot)
    finders = space.cover(detection)
    assert not _uncovered(space, detection, space.lattice).any()
    assert space.nav.ravel()[finders].all()  # drivable
    assert np.array_equal(space.lattice.ravel(), base.ravel() | np.isin(np.arange(base.size), finders))
    assert np.array_equal(space.cover(detection), finders)  # idempotent
    # each finder is needed by a hypothesis that no base-lattice cell finds
    alone = detection.rows(space.centres[finders])
    base_found = detection.rows(space.centres[np.flatnonzero(base.ravel())]).getnnz(axis=0) > 0
    assert all((~base_found[alone[k].indices]).any() for k in range(finders.size))


def test_the_oven_of_home_48_is_found_only_through_a_finder_cell(home):
    _, world, house = home
    space = _space(world, house)
    detection = DetectionModel.from_house(house, 0.5)
    oven = next(o for o in house.objects if o.name == "oven_4")
    hypothesis = detection.source_cell(oven.center, oven, house)
    lattice_points = space.centres[np.flatnonzero(space.lattice.ravel())]
    assert not detection.found(lattice_points, hypothesis).any()
    finders = space.cover(detection)
    assert detection.found(space.centres[finders], hypothesis).any()


def test_below_half_the_lattice_diagonal_only_footprints_get_finder_cells(home):
    """r = 0.3 m < 0.5 m / √2: open floor is beyond the lattice's reach anyway; footprints are still covered."""
    _, world, house = home
    space = _space(world, house)
    detection = DetectionModel.from_house(house, 0.3)
    base = space.lattice.copy()
    assert _uncovered(space, detection, base, floor=False).sum() > 0
    finders = space.cover(detection)
    assert not _uncovered(space, detection, space.lattice, floor=False).any()
    assert _uncovered(space, detection, space.lattice).any()  # floor cells the 0.5-m lattice cannot reach
    assert (detection.rows(space.centres[finders]).getnnz(axis=1) > 0).all()


def test_a_tiny_found_radius_adds_no_finder_cell(home):
    """1 mm: no drivable cell comes that close to a footprint, and floor cells are the lattice's."""
    _, world, house = home
    space = _space(world, house)
    base = space.lattice.copy()
    assert space.cover(DetectionModel.from_house(house, 1e-3)).size == 0
    assert np.array_equal(space.lattice, base)


def test_cover_with_another_radius_gives_that_radius_candidates(home):
    _, world, house = home
    fresh = _space(world, house)
    fresh.cover(DetectionModel.from_house(house, 0.5))
    space = _space(world, house)
    cell = space.snap(world.start_for(house))
    space.cover(DetectionModel.from_house(house, 0.3))
    before = space.candidates(cell, 2.0)[0].copy()
    space.cover(DetectionModel.from_house(house, 0.5))
    assert np.array_equal(space.lattice, fresh.lattice)
    after = space.candidates(cell, 2.0)[0]  # the cached set of the old lattice is not reused
    assert np.array_equal(after, fresh.candidates(cell, 2.0)[0])
    assert not np.array_equal(before, after) or np.array_equal(fresh.lattice, space.lattice)


def test_cover_refuses_a_model_of_another_grid(home):
    _, world, house = home
    space = _space(world, house)
    from psgsl_pgm import GridMap

    other = DetectionModel(GridMap(np.zeros((4, 5), bool), 0.1), 0.5)
    with pytest.raises(ValueError, match="detection must be on this space's grid"):
        space.cover(other)


def test_infotaxis_finds_a_source_that_only_a_finder_cell_reaches(home):
    """The closed loop calls cover(): without finder cells this seeded search ends at the budget, cycling near
    the oven (every lattice stop is farther than the found radius from its footprint)."""
    from psgsl_pgm.runs._key import digest, world_key
    from psgsl_pgm.search._grid import closed_loop_in_world

    path, _, house = home
    oven = next(o for o in house.objects if o.name == "oven_4")
    run = closed_loop_in_world(tuple(oven.center), 0, "infotaxis", "olfaction", "infotaxis", world=str(path),
                               world_digest=digest(world_key(path)))
    assert run.found and run.time_to_find < 1000.0


def test_finder_cells_beyond_the_horizon_are_candidates(home):
    """A far target carries the P_f of the stop that finds what lies there: the far candidates are the 1-m
    lattice and every reachable finder cell beyond the horizon."""
    from scipy.sparse.csgraph import dijkstra

    _, world, house = home
    space = _space(world, house)
    finders = space.cover(DetectionModel.from_house(house, 0.5))
    cell = space.snap(world.start_for(house))
    near, _, _ = space.candidates(cell, 2.0)
    cells, drive, _ = space.candidates(cell, 2.0, 1.0)
    full = dijkstra(space.graph, indices=cell)
    beyond = finders[np.isfinite(full[finders]) & (full[finders] > 2.0)]
    assert beyond.size > 0  # else the test is moot
    assert np.isin(beyond, cells[len(near):]).all()
    targets = space.far_lattice(1.0).ravel().copy()
    targets[finders] = True
    expect = np.flatnonzero(targets & np.isfinite(full) & (full > 2.0))
    np.testing.assert_array_equal(cells[len(near):], expect)  # lattice order
    np.testing.assert_allclose(drive, full[cells], rtol=1e-12)


def test_findable_hypotheses_match_distances_to_the_reachable_drivable_cells(home):
    """FreeSpace.findable against a distance transform: a point hypothesis is findable iff a reachable drivable
    cell lies within r of it, an object's footprint cell iff one lies within r of the footprint."""
    from scipy import ndimage as ndi
    from scipy.sparse.csgraph import dijkstra

    _, world, house = home
    r = 0.5
    space = _space(world, house)
    detection = DetectionModel.from_house(house, r)
    cell = space.snap(world.start_for(house))
    got = space.findable(detection, cell)
    reach = (space.nav.ravel() & np.isfinite(dijkstra(space.graph, indices=cell))).reshape(space.nav.shape)
    gap = (ndi.distance_transform_edt(~reach) * space.resolution).ravel()  # to the nearest reachable drivable cell
    expect = gap <= r + 1e-9
    for j in np.unique(detection.owner[detection.owner >= 0]).tolist():
        mask = detection.owner == j
        expect[mask] = gap[detection.footprints[j]].min() <= r + 1e-9
    hypotheses = (detection.owner >= 0) | space.free
    np.testing.assert_array_equal(got[hypotheses], expect[hypotheses])
    assert (space.free & ~got).any()  # some free cells no stop can rule out (else the test is moot)
    assert space.findable(detection, cell) is got  # cached


def test_the_closed_loop_belief_holds_no_mass_where_no_stop_finds(home):
    """The robot searches for a source it can find: from the first record on, every variant's posterior is 0
    on the hypotheses no reachable drivable cell finds (the factor p(s) ∝ p(s) [s findable])."""
    from psgsl_pgm.runs._key import digest, world_key
    from psgsl_pgm.search import SearchConfig
    from psgsl_pgm.search._grid import closed_loop_in_world

    path, world, house = home
    oven = next(o for o in house.objects if o.name == "oven_4")
    run = closed_loop_in_world(tuple(oven.center), 0, "tour", "semantics+rooms", "infotaxis", world=str(path),
                               world_digest=digest(world_key(path)), search=SearchConfig(time_budget=30.0))
    space = _space(world, house)
    unfindable = ~space.findable(DetectionModel.from_house(house, 0.5), space.snap(world.start_for(house)))
    post = run.final_posterior.ravel()
    assert (post[unfindable & space.free] == 0).all()
    assert post.sum() == pytest.approx(1.0, rel=1e-6)
