"""The detection model: one rule for "found", for the "not found here" update and for P_f."""

import numpy as np
import pytest

from psgsl_pgm.search import DetectionModel, SearchConfig, run_closed_loop


def _object_masks(house):
    """Each object's footprint mask on the house grid, flattened (rasterised once per check, not once per cell)."""
    return [o.mask(house.grid).ravel() for o in house.objects]


def _brute_region(house, cell, masks=None):
    """Found region of hypothesis ``cell`` written out: the footprint of the last object holding it, else it."""
    for mask in reversed(_object_masks(house) if masks is None else masks):
        if mask[cell]:
            return np.flatnonzero(mask)
    return np.array([cell])


def _brute_found(house, points, cell, r, masks=None):
    centres = house.grid.cell_centres().reshape(-1, 2)[_brute_region(house, cell, masks)]
    d = np.sqrt(((points[:, None, :] - centres[None]) ** 2).sum(-1)).min(axis=1)
    return d <= r


@pytest.fixture(scope="module")
def probe(house_space):
    """Robot positions: random points and drivable cell centres around the oven, the bed and a floor cell."""
    house, space = house_space
    rng = np.random.default_rng(7)
    nav = space.centres[space.nav.ravel()]
    oven = next(o for o in house.objects if o.class_name == "oven")
    near = nav[np.linalg.norm(nav - oven.center, axis=1) < 1.2]
    pts = np.concatenate([rng.uniform((0.3, 0.3), (9.7, 11.7), size=(40, 2)), nav[rng.choice(len(nav), 20)],
                          near[:: max(1, len(near) // 10)]])
    return house, space, pts, oven


def test_success_rule_and_p_f_agree_on_every_cell_with_the_written_out_rule(probe):
    """For every hypothesis c and robot position x: rows (P_f, the update) = found (the success rule) = the rule
    written out (object footprint grown by r, else a disc about c's centre)."""
    house, _, pts, _ = probe
    model = DetectionModel.from_house(house, 0.5)
    rows = model.rows(pts).toarray()
    n = rows.shape[1]
    centres = house.grid.cell_centres().reshape(-1, 2)
    close = np.flatnonzero(np.sqrt(((centres[:, None] - pts[None]) ** 2).sum(-1)).min(axis=1) <= 0.6)
    far = np.setdiff1d(np.arange(n), close)
    others = np.random.default_rng(3).choice(far, 400, replace=False)
    # the rows' far cells hold no hypothesis but object cells (a footprint may reach far)
    assert not rows[:, far][:, model.owner[far] < 0].any()
    by_object, by_disc = 0, 0
    masks = _object_masks(house)
    for c in np.unique(np.concatenate([close, others, np.flatnonzero(model.owner >= 0)])):  # (test only)
        expect = _brute_found(house, pts, c, 0.5, masks)
        np.testing.assert_array_equal(rows[:, c], expect)
        np.testing.assert_array_equal(model.found(pts, c), expect)
        if expect.any():
            by_object += model.owner[c] >= 0
            by_disc += model.owner[c] < 0
    assert by_object > 100 and by_disc > 100  # both kinds of found region were exercised


def test_an_object_source_is_found_near_its_footprint_not_only_near_its_centre(probe):
    house, space, _, oven = probe
    model = DetectionModel.from_house(house, 0.5)
    truth = model.source_cell(oven.center, oven, house)
    from psgsl_pgm.sim import SceneObject

    again = SceneObject(oven.class_name, oven.footprint.copy(), oven.z_range, oven.name)
    assert model.source_cell(oven.center, again, house) == truth
    moved = SceneObject(oven.class_name, oven.footprint + 0.3, oven.z_range, oven.name)
    with pytest.raises(ValueError, match="source_object must be one of the house's objects"):
        model.source_cell(oven.center, moved, house)
    fp = np.flatnonzero(oven.mask(house.grid).ravel() & house.grid.free.ravel())
    np.testing.assert_array_equal(np.sort(_brute_region(house, truth)), fp)
    nav = space.centres[space.nav.ravel()]
    found = model.found(nav, truth)
    d_centre = np.linalg.norm(nav - oven.center, axis=1)
    assert found.any() and d_centre[found].min() > 0.5  # no drivable cell within 0.5 m of the oven's centre
    # a point source in a free floor cell: a disc about that cell's centre
    cell = model.source_cell((5.0, 6.0))
    assert model.owner[cell] == -1
    centre = model.centres[cell]
    np.testing.assert_array_equal(model.found(nav, cell), ((nav - centre) ** 2).sum(-1) <= 0.25)


@pytest.mark.parametrize("miss", [0.0, 0.3])
def test_not_found_likelihood_and_p_f(probe, miss):
    house, _, pts, _ = probe
    model = DetectionModel.from_house(house, 0.5, miss_probability=miss)
    union = model.rows(pts[:5]).toarray().any(axis=0)
    w = model.not_found_likelihood(pts[:5])
    np.testing.assert_array_equal(w, np.where(union, miss, 1.0))
    np.testing.assert_array_equal(np.isneginf(model.not_found_log_likelihood(pts[:5])), union & (miss == 0))
    # the hypotheses found along a path are kept per path: the same path again, then others
    np.testing.assert_array_equal(model.not_found_likelihood(pts[:5].copy()), w)
    for path in (pts[1:6], pts[:4], pts[:5][::-1]):
        along = model.rows(path).toarray().any(axis=0)
        np.testing.assert_array_equal(model.not_found_likelihood(path), np.where(along, miss, 1.0))
    post = np.random.default_rng(1).random(union.size)
    post /= post.sum()
    cells = [model.source_cell(p) for p in pts[:8]]
    rows = model.cell_rows(cells, model.centres[cells])
    expect = [(1 - miss) * post[model.rows(model.centres[[c]]).toarray()[0]].sum() for c in cells]
    np.testing.assert_allclose(model.found_probability(post, rows), expect, rtol=1e-12)


@pytest.mark.parametrize("estimator", ["infotaxis", "analytic-plume"])
@pytest.mark.parametrize("miss", [0.0, 0.25])
def test_the_update_leaves_exactly_the_modelled_mass_in_every_variant(estimator, miss):
    """p(s | g) conditioned on "not found" along a path: the found hypotheses keep m p(R) / (m p(R) + 1 − p(R))
    of the mass, in p(s | g) and in every fused variant; the factor survives the next gas reading."""
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors, visit
    from psgsl_pgm.sim import make_world

    config = ExperimentConfig()
    world = make_world(seed=3, source="oven", warm_up=config.warm_up)
    b = VariantPosteriors(world, estimator, config)
    stop = np.array([3.05, 6.05])
    first = visit(world, stop, (0.0,), config)
    b.observe(stop, *first)
    model = DetectionModel.from_house(world.house, 0.5, miss_probability=miss)
    from psgsl_pgm.search import FreeSpace

    space = FreeSpace(world.house, world.camera)
    nav = space.centres[space.nav.ravel()]
    path = nav[np.argsort(np.linalg.norm(nav - world.source, axis=1))[:3]]  # beside the oven
    region = model.rows(path).toarray().any(axis=0).reshape(world.house.shape)
    before = b.posteriors()
    b.condition(model.not_found_log_likelihood(path))
    after = b.posteriors()
    for v in range(len(before)):
        p_r = before[v][region].sum()
        assert 0.01 < p_r < 0.99
        np.testing.assert_allclose(after[v][region].sum(), miss * p_r / (miss * p_r + 1 - p_r), rtol=1e-12,
                                   atol=1e-15)
        np.testing.assert_allclose(after[v][~region], before[v][~region] / (miss * p_r + 1 - p_r), rtol=1e-10,
                                   atol=1e-300)
    plain = VariantPosteriors(world, estimator, config)  # the same readings without the update
    plain.observe(stop, *first)
    stop2 = np.array([5.05, 6.05])
    reading = world.sense_gas(stop2)
    wind = world.sense_wind(stop2)
    b.observe(stop2, reading, wind, [])
    plain.observe(stop2, reading, wind, [])
    p, q = b.estimator.posterior, plain.estimator.posterior
    expect = q * np.where(region, miss, 1.0)
    np.testing.assert_allclose(p, expect / expect.sum(), rtol=1e-10, atol=1e-300)


def test_condition_rejects_bad_likelihoods():
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors
    from psgsl_pgm.sim import make_world

    config = ExperimentConfig()
    world = make_world(seed=0, source="oven", warm_up=config.warm_up)
    est = VariantPosteriors(world, "infotaxis", config).estimator
    shape = world.house.shape
    with pytest.raises(ValueError, match="log_likelihood must have the map's shape"):
        est.condition(np.zeros(7))
    with pytest.raises(ValueError, match="no NaN"):
        est.condition(np.full(shape, np.nan))
    with pytest.raises(ValueError, match="zero likelihood"):
        est.condition(np.full(shape, -np.inf))
    with pytest.raises(TypeError):
        est.condition("x")
    np.testing.assert_array_equal(est.posterior, est.prior)  # nothing applied


def test_detection_model_validates_its_arguments(house_space):
    house, _ = house_space
    with pytest.raises(ValueError, match="miss_probability must lie in"):
        DetectionModel.from_house(house, 0.5, miss_probability=1.0)
    with pytest.raises(ValueError, match="found_radius"):
        DetectionModel.from_house(house, -0.1)
    with pytest.raises(ValueError, match="points must have shape"):
        DetectionModel.from_house(house, 0.5).rows(np.zeros(3))


# --- the success rule of the house loop ----------------------------------------------------------------------

def test_the_oven_is_found_within_found_radius_of_its_footprint(house_space):
    """A found rule that used the oven's centre only could never find it (no drivable cell within 0.5 m)."""
    run = run_closed_loop("oven", 100, "infotaxis", "olfaction", search=SearchConfig(time_budget=300.0))
    assert run.found
    from psgsl_pgm.sim import make_world
    from psgsl_pgm.experiment import ExperimentConfig

    world = make_world(seed=100, source="oven", warm_up=ExperimentConfig().warm_up)
    fp = world.house.grid.cell_to_world(np.argwhere(world.source_object.mask(world.house.grid)))
    d_fp = np.sqrt(((run.path[:, None, :] - fp[None]) ** 2).sum(-1)).min(axis=1)
    assert d_fp[-1] <= 0.5 < d_fp[:-1].min()  # the path ends where it first comes within 0.5 m of the footprint
    assert np.linalg.norm(run.path - run.source_xy, axis=1).min() > 0.5


def test_a_find_exactly_at_the_budget_counts_and_one_past_it_does_not(house_space):
    _, space = house_space
    run = run_closed_loop("2.3,6.05", 0, "greedy", "olfaction", search=SearchConfig(time_budget=200.0), space=space)
    assert run.found
    t = run.time_to_find
    at = run_closed_loop("2.3,6.05", 0, "greedy", "olfaction", search=SearchConfig(time_budget=t), space=space)
    assert at.found and at.time_to_find == t
    before = run_closed_loop("2.3,6.05", 0, "greedy", "olfaction",
                             search=SearchConfig(time_budget=float(np.nextafter(t, 0))), space=space)
    assert not before.found and before.time_to_find == np.nextafter(t, 0)


def test_a_seeded_episode_is_bit_reproducible(house_space):
    _, space = house_space
    search = SearchConfig(time_budget=60.0, miss_probability=0.2)
    a = run_closed_loop("bed", 5, "space-aware-infotaxis", "semantics+rooms", search=search, space=space)
    b = run_closed_loop("bed", 5, "space-aware-infotaxis", "semantics+rooms", search=search, space=space)
    for name in ("time", "position", "heading", "hit", "error", "path", "final_posterior"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert (a.found, a.time_to_find) == (b.found, b.time_to_find)


def test_found_rule_memory_is_bounded_by_blocks_not_by_cells_times_footprint(monkeypatch):
    """A 1-cm map: 60 000 robot positions against a 3 600-cell footprint would need 3.5 GB compared at once; the
    rule compares them in blocks (32 MiB) and gives the same answers as one block does."""
    import tracemalloc

    from psgsl_pgm import GridMap
    from psgsl_pgm.search import _detection

    grid = GridMap(np.zeros((300, 200), dtype=bool), 0.01)  # 3 m x 2 m at 1 cm: 60 000 cells
    footprint = np.zeros(grid.shape, dtype=bool)
    footprint[120:180, 70:130] = True  # a 0.6 m x 0.6 m oven: 3 600 cells
    model = DetectionModel(grid, 0.5, footprints=[footprint])
    points = grid.cell_centres().reshape(-1, 2)
    oven = int(np.flatnonzero(footprint.ravel())[0])
    tracemalloc.start()
    try:
        found = model.found(points, oven)
        near = model.near_footprints(points[::7])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 200 * 2**20, f"peak {peak / 2**20:.0f} MiB"
    # the same answers in blocks of one point: block size does not change a comparison
    monkeypatch.setattr(_detection, "_PAIRS_AT_ONCE", 1)
    np.testing.assert_array_equal(model.found(points[::97], oven), found[::97])
    np.testing.assert_array_equal(model.near_footprints(points[::7][::13]), near[::13])
    x = np.array([[1.0, 1.5], [0.2, 0.2], [1.6, 2.9]])  # distance to the oven's nearest cell centre, brute force
    d = np.sqrt(((x[:, None] - points[footprint.ravel()][None]) ** 2).sum(-1)).min(axis=1)
    np.testing.assert_array_equal(model.found(x, oven), d <= 0.5)


def test_found_is_the_brute_force_rule_for_points_in_and_out_of_the_footprints_box():
    """The points outside a footprint's box widened by r are never compared with its cells: the answers are those
    of every point against every cell, also at exactly r from the nearest centre."""
    from psgsl_pgm import GridMap

    grid = GridMap(np.zeros((40, 50), dtype=bool), 0.1)
    footprint = np.zeros(grid.shape, dtype=bool)
    footprint[10:14, 20:27] = True
    r = 0.5
    model = DetectionModel(grid, r, footprints=[footprint])
    centres = grid.cell_centres().reshape(-1, 2)[footprint.ravel()]
    rng = np.random.default_rng(3)
    pts = np.concatenate([rng.uniform(0.0, 5.0, (4000, 2)),
                          centres[:5] + [[r, 0.0], [0.0, -r], [-r, 0.0], [0.0, r], [r * 0.6, r * 0.8]]])
    d2 = ((pts[:, None] - centres[None]) ** 2).sum(-1).min(axis=1)
    got = model.found(pts, int(np.flatnonzero(footprint.ravel())[3]))
    np.testing.assert_array_equal(got, d2 <= r**2)
    assert 50 < got.sum() < 3000


def test_rows_in_blocks_equal_rows_at_once(monkeypatch, house):
    from psgsl_pgm.search import _detection

    model = DetectionModel.from_house(house, 0.6)
    pts = house.grid.cell_centres().reshape(-1, 2)[::37]
    whole = model.rows(pts)
    monkeypatch.setattr(_detection, "_PAIRS_AT_ONCE", 50)  # blocks of one point
    blocks = DetectionModel.from_house(house, 0.6).rows(pts)
    assert (whole != blocks).nnz == 0 and whole.nnz > 0
