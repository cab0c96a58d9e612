"""The pose-scoring rule, candidate poses, cached views and geodesics, and the policies' gains."""

import numpy as np
import pytest
from scipy.sparse.csgraph import dijkstra
from scipy.special import entr

from psgsl_pgm import view_information_gain
from psgsl_pgm.search import Situation, score_per_time, travel_time
from psgsl_pgm.search._policies import infotaxis_gain, space_aware_gain


def test_travel_time_counts_drive_turn_and_reading():
    tau = travel_time([0.5, 2.0], [np.pi, -np.pi / 2], speed=0.25, turn_time=1.0, sense_time=1.0)
    np.testing.assert_allclose(tau, [0.5 / 0.25 + 2.0 + 1.0, 2.0 / 0.25 + 1.0 + 1.0], rtol=1e-15)


def test_score_is_gain_per_unit_time():
    # a near pose with gain g (τ = 3 s) beats a far one with 2g (τ = 9 s); a loss is worse when it takes longer
    score = score_per_time([0.1, 0.2, -0.1, -0.1], [3.0, 9.0, 3.0, 9.0])
    np.testing.assert_allclose(score, [0.1 / 3, 0.2 / 9, -0.3, -0.9], rtol=1e-15)
    assert np.argmax(score) == 0
    with pytest.raises(ValueError, match="positive"):
        score_per_time([0.1], [0.0])


def test_candidates_are_lattice_cells_within_the_geodesic_horizon(house_space):
    _, space = house_space
    cell = space.snap((3.0, 6.0))
    cells, drive, pred = space.candidates(cell, 2.0)
    full = dijkstra(space.graph, indices=cell)
    expect = np.flatnonzero(space.lattice.ravel() & (full <= 2.0))
    np.testing.assert_array_equal(np.sort(cells), np.sort(expect[expect != cell]))
    np.testing.assert_allclose(drive, full[cells], rtol=1e-12)
    for c in cells[:5]:
        path = space.path(pred, c)
        assert path[0] == cell and path[-1] == c
        steps = np.linalg.norm(np.diff(space.position(path), axis=0), axis=1)
        assert steps.sum() == pytest.approx(full[c], rel=1e-12)
        assert space.nav.ravel()[path].all()


def test_geodesic_distances_match_dijkstra_on_drivable_cells(house_space):
    _, space = house_space
    cell = space.snap((6.0, 3.0))
    d = space.distances(cell)
    full = dijkstra(space.graph, indices=cell)
    nav = space.nav.ravel()
    np.testing.assert_allclose(d[nav], full[nav], rtol=1e-12)
    assert d is space.distances(cell)  # cached


def test_cached_views_are_the_cameras_field_of_view(house_space):
    house, space = house_space
    from psgsl_pgm.sim import Camera

    cam = Camera()
    for xy in ((3.05, 6.05), (7.05, 2.05)):
        cell = space.snap(xy)
        flat, sectors = space.view(cell)
        x, y = space.position(cell)
        for h, heading in enumerate(space.headings[:4]):
            seen = np.zeros(house.shape, bool).ravel()
            seen[flat[sectors[h]]] = True
            np.testing.assert_array_equal(seen.reshape(house.shape), cam.visible(house.grid, (x, y, heading)))


def test_view_gain_is_view_information_gain(house_space):
    house, space = house_space
    from psgsl_pgm.sim import Camera

    cam = Camera()
    gain = np.random.default_rng(0).random(house.shape) * house.grid.free  # the camera observes free cells
    cells = np.array([space.snap((3.05, 6.05)), space.snap((2.05, 9.05))])
    phi = space.view_gain(gain.ravel(), cells)
    for k, c in enumerate(cells):
        x, y = space.position(c)
        poses = np.array([(x, y, h) for h in space.headings])
        ref = view_information_gain(gain, house.grid.occupancy, poses, max_range=cam.max_range,
                                    half_angle=cam.half_angle, min_range=cam.min_range,
                                    resolution=house.grid.resolution, origin=house.grid.origin)
        np.testing.assert_allclose(phi[k], ref, rtol=1e-10)


@pytest.fixture(scope="module")
def situation(house_space):
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors, visit
    from psgsl_pgm.sim import make_world

    house, space = house_space
    config = ExperimentConfig(parameter_grid=None)  # the single-plume estimator: the scenes below were chosen with it
    world = make_world(house, seed=0, warm_up=20.0)
    beliefs = VariantPosteriors(world, "infotaxis", config)
    cell = space.snap((3.0, 6.0))
    stop = space.position(cell)
    reading, wind, frames = visit(world, stop, (0.0, np.pi), config)
    beliefs.observe(stop, reading, wind, frames)
    post = beliefs.posteriors(("semantics+rooms",))[0]
    return Situation(post, beliefs, "semantics+rooms", space, cell, np.pi, config.speed, config.turn_time, 1.0,
                     2.0, 0.5)


def test_infotaxis_gain_is_found_term_plus_phi_g_plus_phi_o(situation):
    from psgsl_pgm import semantic_information_gain

    sit = situation
    space, b = sit.space, sit.beliefs
    cells, _, _ = space.candidates(sit.cell, sit.horizon)
    cells = cells[:3]
    got = infotaxis_gain(sit, cells)
    xy = space.position(cells)
    # φ_G: I(S; hit) under the fused posterior, written out
    p_hit = b.estimator.hit_probability(xy).reshape(len(cells), -1)
    post = sit.posterior.ravel()
    p_bar = p_hit @ post
    phi_g = entr(p_bar) + entr(1 - p_bar) - (entr(p_hit) + entr(1 - p_hit)) @ post
    np.testing.assert_allclose(b.estimator.information_gain(xy, posterior=sit.posterior), phi_g, rtol=1e-10)
    info = semantic_information_gain(b.maps["semantics+rooms"].probs, b.likelihood, b.class_prior,
                                     olfactory=b.estimator.posterior, predictive="exact")
    g = space.grid
    cam = space.camera
    h_s = float(entr(post).sum())
    for k, c in enumerate(cells):
        d = np.linalg.norm(space.centres - xy[k], axis=1)
        p_f = post[d <= 0.5].sum()
        poses = np.array([(xy[k][0], xy[k][1], h) for h in space.headings])
        phi_o = view_information_gain(info * g.free, g.occupancy, poses, max_range=cam.max_range,
                                      half_angle=cam.half_angle, min_range=cam.min_range,
                                      resolution=g.resolution, origin=g.origin)
        np.testing.assert_allclose(got[k], p_f * h_s + (1 - p_f) * (phi_g[k] + phi_o), rtol=1e-9)


def test_olfaction_variant_has_no_view_term(situation):
    sit = situation
    cells, _, _ = sit.space.candidates(sit.cell, sit.horizon)
    olf = Situation(**{**sit.__dict__, "variant": "olfaction"})
    got = infotaxis_gain(olf, cells[:4])
    np.testing.assert_allclose(got, got[:, :1] * np.ones((1, got.shape[1])), rtol=0, atol=0)


def test_space_aware_gain_on_a_certain_belief_is_the_drive_saved(situation):
    """All the mass on one cell: H = 0, so V = log2(1 + D_r/ℓ) with D_r = max(D − r, 0) the distance past the
    found radius r = 0.5 m (ℓ = 1 m), and a nearer pose gains log2(1 + D_r,now) − log2(1 + D_r,p); a pose within the
    found radius gains all of V_now."""
    sit = situation
    space = sit.space
    target = space.snap((4.55, 6.05))
    post = np.zeros(sit.posterior.size)
    post[target] = 1.0
    olf = Situation(**{**sit.__dict__, "variant": "olfaction", "posterior": post.reshape(sit.posterior.shape)})
    cells, _, _ = space.candidates(sit.cell, sit.horizon)
    got = space_aware_gain(olf, cells)
    v_now = np.log2(1.0 + max(space.distances(sit.cell)[target] - 0.5, 0.0))
    assert v_now > 0
    for k, c in enumerate(cells):
        d = space.distances(c)[target]
        if np.hypot(*(space.position(c) - space.position(target))) <= 0.5:
            expect = v_now  # found there: the rest costs nothing
        else:
            expect = v_now - np.log2(1.0 + (d - 0.5))
        np.testing.assert_allclose(got[k], expect, rtol=1e-9, atol=1e-15)


@pytest.mark.parametrize("offset", [0.6, 0.8, 1.2])
def test_a_stop_that_surely_finds_the_source_gains_the_most(situation, offset):
    """The value is 0 for a found belief and positive otherwise, so no stop gains more than V_now and one that
    surely finds the source (P_f = 1) gains exactly V_now — also when the belief's mass lies between r and ℓ
    from the robot, where log2(D/ℓ + 2^{H−1} − ½) was negative and a stop that does not find the source won."""
    from psgsl_pgm.search._policies import _found_mass, _SpaceAware

    sit = situation
    space = sit.space
    cells, _, _ = space.candidates(sit.cell, sit.horizon)
    here = space.position(sit.cell)
    gap = np.abs(np.linalg.norm(space.position(cells) - here, axis=1) - offset)
    target = int(cells[int(np.argmin(gap))])  # a lattice stop about ``offset`` m from the robot
    near = space.disc(target, 0.15)
    post = np.zeros(sit.posterior.size)
    post[near[space.free[near]]] = 1.0
    post /= post.sum()
    olf = Situation(**{**sit.__dict__, "variant": "olfaction", "posterior": post.reshape(sit.posterior.shape),
                       "cache": {}})
    got = space_aware_gain(olf, cells).max(axis=1)
    p_f, _ = _found_mass(olf, cells)
    v_now = float(_SpaceAware(olf).v_now)
    assert v_now >= 0
    assert (got <= v_now + 1e-12).all()
    sure = p_f == 1.0
    assert sure[list(cells).index(target)]
    np.testing.assert_allclose(got[sure], v_now, rtol=0, atol=1e-12)
    assert np.argmax(got) in np.flatnonzero(sure)


@pytest.mark.parametrize("policy, gain_of, differ", [("infotaxis", infotaxis_gain, True),
                                                     ("space-aware-infotaxis", space_aware_gain, True)])
def test_the_scoring_rule_picks_the_best_gain_per_second_or_the_best_gain(situation, policy, gain_of, differ):
    from psgsl_pgm.search import SCORES, choose
    from psgsl_pgm.search._policies import _wrap

    sit = Situation(**{**situation.__dict__, "horizon": 4.0})  # far poses too: there the rules can disagree
    space = sit.space
    cells, drive, _ = space.candidates(sit.cell, sit.horizon)
    gain = gain_of(sit, cells)
    tau = travel_time(drive[:, None], _wrap(space.headings[None, :] - sit.heading), speed=sit.speed,
                      turn_time=sit.turn_time, sense_time=sit.sense_time)
    chosen = {}
    for rule in SCORES:
        dec = choose(policy, Situation(**{**sit.__dict__, "score": rule}))
        k = int(np.flatnonzero(cells == dec.cell)[0])
        h = int(np.flatnonzero(np.isclose(space.headings, dec.headings[0]))[0])
        chosen[rule] = (k, h)
        want = score_per_time(gain, tau) if rule == "per-time" else gain
        assert want[k, h] == want.max() and dec.score == pytest.approx(want.max(), rel=1e-12)
    assert (chosen["per-time"] != chosen["gain"]) == differ
    # with positive gains, the pose of the larger gain and the smaller gain per second takes at least as long
    assert gain[chosen["gain"]] >= gain[chosen["per-time"]] > 0 and tau[chosen["gain"]] >= tau[chosen["per-time"]]
    with pytest.raises(ValueError, match=r"score must be one of \('per-time', 'gain'\), got 'fastest'"):
        choose(policy, Situation(**{**sit.__dict__, "score": "fastest"}))


def test_hit_rows_follow_a_re_solved_plume_model(house_space, situation):
    """The per-run cache of hit-model rows is emptied when the plume is re-solved with a new wind estimate."""
    from psgsl_pgm.experiment import ExperimentConfig
    from psgsl_pgm.experiment._step import VariantPosteriors
    from psgsl_pgm.olfaction import PlumeModel
    from psgsl_pgm.search._policies import _hit_blocks
    from psgsl_pgm.sim import make_world

    house, space = house_space
    beliefs = VariantPosteriors(make_world(house, seed=1, warm_up=5.0), "infotaxis", ExperimentConfig())
    sit = Situation(**{**situation.__dict__, "beliefs": beliefs, "cache": {}})
    cells = space.candidates(sit.cell, 1.0)[0][:3]
    before = np.stack([blk[0] for blk in _hit_blocks(sit, cells)])
    wind = np.zeros(house.shape + (2,))
    wind[house.grid.free, 0] = 0.3
    beliefs.estimator.replace_model(PlumeModel.from_grid_map(house.grid, wind, outlets=house.outlet))
    after = np.stack([blk[0] for blk in _hit_blocks(sit, cells)])
    want = beliefs.estimator.hit_probability(space.position(cells)).reshape(len(cells), -1)
    np.testing.assert_array_equal(after, want)
    assert not np.allclose(after, before)


def test_far_candidates_cover_the_free_space_beyond_the_horizon(house_space):
    _, space = house_space
    cell = space.snap((3.0, 6.0))
    near, _, _ = space.candidates(cell, 2.0)
    cells, drive, pred = space.candidates(cell, 2.0, 1.0)
    full = dijkstra(space.graph, indices=cell)
    np.testing.assert_array_equal(cells[: len(near)], near)  # the horizon's candidates first, unchanged
    far = cells[len(near):]
    finders = space.lattice & ~space._base_lattice  # finder cells (FreeSpace.cover) are far targets too
    expect = np.flatnonzero((space.far_lattice(1.0) | finders).ravel() & np.isfinite(full) & (full > 2.0))
    np.testing.assert_array_equal(np.sort(far), expect)
    np.testing.assert_allclose(drive, full[cells], rtol=1e-12)
    rooms = {int(space.house.room_labels.ravel()[c]) for c in far}
    assert rooms == set(range(len(space.house.room_names)))  # every room is a candidate target
    path = space.path(pred, far[-1])
    assert path[0] == cell and space.nav.ravel()[path].all()


def _brute_found_cells(house, xy, r):
    """Hypotheses a robot at xy finds, written out: footprints (last object owns a cell) grown by r, else discs."""
    centres = house.grid.cell_centres().reshape(-1, 2)
    owner = np.full(centres.shape[0], -1)
    for j, m in enumerate([o.mask(house.grid) for o in house.objects]):
        owner[m.ravel()] = j
    out = (owner < 0) & (np.linalg.norm(centres - xy, axis=1) <= r)
    for j, m in enumerate([o.mask(house.grid) for o in house.objects]):
        if np.linalg.norm(centres[m.ravel()] - xy, axis=1).min() <= r:
            out |= owner == j
    return out


def _space_aware_direct(sit, cells, miss):
    """Space-aware gain by the (K, H·W) computation: q = p(s | not found at p), both gas outcomes."""
    space, post = sit.space, sit.posterior.ravel()
    ell, disc_bits = 2 * sit.found_radius, np.log2(np.pi * sit.found_radius**2 / space.resolution**2)

    def value(d, h):
        return np.log2(1.0 + d / ell + 2.0 ** (np.maximum(h - disc_bits, 0.0) - 1.0) - 0.5)

    def past(d):  # the distance past the found radius, 0 where unreachable
        return np.where(np.isfinite(d), np.maximum(d - sit.found_radius, 0.0), 0.0)

    v_now = value(post @ past(space.distances(sit.cell)), entr(post).sum() / np.log(2))
    house = space.house
    xy = space.position(cells)
    found = np.stack([_brute_found_cells(house, p, sit.found_radius) for p in xy])
    w = np.where(found, miss, 1.0)
    p_f = (1 - miss) * (found * post).sum(axis=1)
    q = post * w
    q /= q.sum(axis=1, keepdims=True)
    lik = sit.beliefs.estimator.hit_probability(xy).reshape(len(cells), -1)
    dist = past(np.stack([space.distances(c) for c in cells]))
    from psgsl_pgm.search._policies import _view_information

    phi = _view_information(sit, cells) / np.log(2)
    expected = 0.0
    for like in (lik, 1 - lik):
        joint = q * like
        z = joint.sum(axis=1)
        ph = joint / z[:, None]
        h = entr(ph).sum(axis=1) / np.log(2)
        expected = expected + z[:, None] * value((ph * dist).sum(axis=1)[:, None], h[:, None] - phi)
    return v_now - (1 - p_f[:, None]) * expected, p_f


@pytest.mark.parametrize("miss", [0.0, 0.3])
def test_gains_use_the_detection_model_footprints_and_misses(situation, miss):
    """P_f and the space-aware gain (its closed form over static rows) against the (K, H·W) computation with the
    found regions written out, for candidates beside the oven (footprint) and elsewhere (discs)."""
    from psgsl_pgm.search import DetectionModel

    house = situation.space.house
    model = DetectionModel.from_house(house, 0.5, miss_probability=miss)
    sit = Situation(**{**situation.__dict__, "detection": model, "far_spacing": 1.0, "cache": {}})
    cells, _, _ = sit.space.candidates(sit.cell, sit.horizon, 1.0)
    oven = next(o for o in house.objects if o.class_name == "oven")
    d_oven = np.linalg.norm(sit.space.position(cells) - oven.center, axis=1)
    pick = np.concatenate([np.argsort(d_oven)[:3], [0, 1, len(cells) - 1]])
    cells = cells[pick]
    got = space_aware_gain(sit, cells)
    expect, p_f = _space_aware_direct(sit, cells, miss)
    np.testing.assert_allclose(got, expect, rtol=1e-9, atol=1e-12)
    h_s = float(entr(sit.posterior).sum())
    info = infotaxis_gain(sit, cells)
    from psgsl_pgm.search._policies import _view_information, olfactory_gain

    np.testing.assert_allclose(info, p_f[:, None] * h_s + (1 - p_f[:, None]) * (
        olfactory_gain(sit, cells)[:, None] + _view_information(sit, cells)), rtol=1e-10)
    assert p_f[:3].max() > 0  # the oven's footprint is within reach of the cells beside it


@pytest.mark.parametrize("chunk", [1, 3, 8])
def test_branch_and_bound_returns_the_first_maximum_of_every_score(chunk):
    """Against the brute-force first arg max over random scores with many ties (small integers, some −inf rows)
    and valid upper bounds, many of them tight (a bound equal to the best score: the tie must still go to the
    earlier candidate), some +inf; each candidate is evaluated at most once, in chunks, from the highest bound
    down, and every candidate whose bound reaches the winning score is evaluated."""
    from psgsl_pgm.search._policies import _branch_and_bound

    rng = np.random.default_rng(11)
    pruned = 0
    for _ in range(400):
        n, n_h = int(rng.integers(1, 30)), int(rng.integers(1, 4))
        score = rng.integers(0, 4, (n, n_h)).astype(np.float64)
        score[rng.random(n) < 0.1] = -np.inf
        slack = np.where(rng.random(n) < 0.5, 0.0, rng.integers(0, 3, n).astype(np.float64))
        bound = score.max(axis=1) + slack
        bound[rng.random(n) < 0.05] = np.inf
        calls = []

        def evaluate(k):
            calls.append(k.copy())
            return score[k]

        flat, got = _branch_and_bound(bound, evaluate, n_h, chunk=chunk)
        assert flat == int(np.argmax(score))  # brute force: the first maximum, candidate order then heading
        seen = np.concatenate(calls)
        assert len(np.unique(seen)) == len(seen) and all(1 <= len(k) <= chunk for k in calls)
        assert (bound[seen][1:] <= bound[seen][:-1]).all()  # from the highest bound down
        assert set(np.flatnonzero(bound >= score.ravel()[flat])) <= set(seen.tolist())
        np.testing.assert_array_equal(got[seen], score[seen])
        assert (got[np.setdiff1d(np.arange(n), seen)] == -np.inf).all()
        pruned += len(seen) < n
    assert pruned > 100  # the bounds do prune


def test_branch_and_bound_stops_when_the_bounds_fall_below_the_best_score():
    from psgsl_pgm.search._policies import _branch_and_bound

    bound = np.array([1.0, 5.0, 4.0, 3.0, 2.0, 0.5])
    score = np.array([[1.0], [4.0], [4.0], [3.0], [2.0], [0.5]])
    calls = []

    def evaluate(k):
        calls.append(k.tolist())
        return score[k]

    flat, got = _branch_and_bound(bound, evaluate, 1, chunk=2)
    # chunk [1, 2] (best 4), then [3, 4] both below 4: stop; the tie 4 = 4 goes to candidate 1
    assert calls == [[1, 2]] and flat == 1
    np.testing.assert_array_equal(got.ravel(), [-np.inf, 4.0, 4.0, -np.inf, -np.inf, -np.inf])
    flat, _ = _branch_and_bound(np.array([4.0, 5.0, 9.0]), lambda k: np.array([[4.0], [4.0], [2.0]])[k], 1, chunk=1)
    assert flat == 0  # bound 4 equals the best score 4 of candidate 1 (evaluated first): still evaluated, and wins
