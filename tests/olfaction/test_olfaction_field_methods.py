"""PMFS as published (GMRF wind, filament-simulated hit maps) and GrGSL, each against a case with a known answer."""

import numpy as np
import pytest

from psgsl_pgm import GridMap
from psgsl_pgm.olfaction import FilamentPMFS, GMRFWind, GrGSL, PlumeModel

# --- GMRF wind ----------------------------------------------------------------------------------------------------


def test_gmrf_recovers_a_uniform_flow_from_a_few_readings_around_an_obstacle():
    occ = np.zeros((20, 30), bool)
    occ[6:14, 12:16] = True
    gmrf = GMRFWind(GridMap(occ, 0.1))
    u = (0.35, -0.12)
    for p in [(0.25, 0.25), (2.5, 1.8), (0.5, 1.5), (2.9, 0.1)]:
        gmrf.add(p, u)
    field = gmrf.field()
    free = ~occ
    assert np.abs(field[free] - u).max() < 1e-3  # the uniform field has no smoothness cost: only the weak prior
    assert (field[occ] == 0).all()


def test_gmrf_smooths_noisy_readings_towards_the_mean_flow():
    """400 readings of a uniform flow with 0.2 m/s noise on 100 cells: the field's mean is the flow's, and its
    per-cell error is well below that of the per-cell averages of the readings (which the smoothness pools)."""
    rng = np.random.default_rng(4)
    grid = GridMap(np.zeros((10, 10), bool), 0.2)
    gmrf = GMRFWind(grid, reading_std=0.2)
    sums, counts = np.zeros((10, 10, 2)), np.zeros((10, 10, 1))
    for _ in range(400):
        p, w = rng.uniform(0.0, 2.0, 2), np.array([0.2, 0.1]) + rng.normal(0.0, 0.2, 2)
        gmrf.add(p, w)
        r, c = grid.cell_of(p)
        sums[r, c] += w
        counts[r, c] += 1
    field = gmrf.field()
    assert np.abs(field.mean(axis=(0, 1)) - [0.2, 0.1]).max() < 0.02
    seen = counts[..., 0] > 0
    rms_field = np.sqrt(((field[seen] - [0.2, 0.1]) ** 2).mean())
    rms_cells = np.sqrt(((sums[seen] / counts[seen] - [0.2, 0.1]) ** 2).mean())
    assert rms_field < 0.5 * rms_cells


def test_gmrf_walls_are_missing_edges_readings_do_not_cross_them():
    occ = np.zeros((8, 17), bool)
    occ[:, 8] = True  # two sealed rooms
    gmrf = GMRFWind(GridMap(occ, 0.1))
    gmrf.add((0.3, 0.3), (0.5, 0.0))
    field = gmrf.field()
    assert np.allclose(field[:, :8], [0.5, 0.0], atol=1e-3)
    assert (field[:, 9:] == 0).all()  # no reading reaches the right room: still air


def test_gmrf_bad_input():
    with pytest.raises(TypeError, match="GridMap"):
        GMRFWind(np.zeros((3, 3), bool))
    occ = np.zeros((3, 3), bool)
    occ[1, 1] = True
    gmrf = GMRFWind(GridMap(occ, 1.0))
    with pytest.raises(ValueError, match="free space"):
        gmrf.add((1.5, 1.5), (0.1, 0.0))
    with pytest.raises(ValueError, match="smoothness_std"):
        GMRFWind(GridMap(occ, 1.0), smoothness_std=0.0)


# --- PMFS as published ----------------------------------------------------------------------------------------------


def _corridor():
    occ = np.zeros((12, 40), bool)
    occ[0, :] = occ[-1, :] = True
    outlets = np.zeros_like(occ)
    outlets[1:-1, -1] = True
    return PlumeModel(occ, resolution=0.1, outlets=outlets, diffusivity=0.005)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_pmfs_posterior_concentrates_on_the_source_region_in_a_uniform_wind_corridor(seed):
    """Readings drawn from the filament model itself (released at the source, another seed) in a uniform 0.4 m/s
    wind along a 4 m corridor, 24 stops 0.5 m apart: the posterior puts ≥ 90 % of its mass on the 1 m region
    holding the source, and its mean lies within 0.3 m of the source along the wind. (Across the wind the two
    0.5 m children of that region both fit the narrow plume: the seeds split between them.)"""
    model = _corridor()
    source = (1.75, 0.75)
    truth = FilamentPMFS(model, seed=99, region_size=0.2, refine_fraction=0.0)  # released at the source's cell
    truth.update((0.55, 0.55), False, wind=(0.4, 0.0))
    h = truth.simulated_hit_map(source)
    rng = np.random.default_rng(seed)
    est = FilamentPMFS(model, seed=1)
    for x in [(x, y) for x in np.arange(0.25, 3.9, 0.5) for y in (0.35, 0.55, 0.85)]:
        r, c = model.cell_of(x)
        est.update(x, bool(rng.random() < h[r, c]), wind=(0.4 + 0.05 * rng.normal(), 0.05 * rng.normal()))
    assert est.posterior[:10, 10:20].sum() > 0.9  # the region x ∈ [1, 2), y ∈ [0, 1)
    assert abs(est.expected_position()[0] - source[0]) < 0.3
    assert abs(est.wind_estimate[6, 20, 0] - 0.4) < 0.05


def _straight_score(est, sim, log_odds, omega):
    """PMFS's score of the rows of ``sim`` computed in one pass on the gathered (K, N') frequencies."""
    from scipy.special import expit

    x = omega / est.confidence_weight ** 2
    cells = np.flatnonzero((x > 0) & est.geometry.free.ravel())
    x = x[cells]
    log_conf = np.log(-np.expm1(-x))
    p0 = est.prior_hit
    ell = (log_odds[cells] + (np.log(p0) - np.log1p(-p0)))[None, :]
    log_h, log_not_h = -np.logaddexp(0.0, -ell), -np.logaddexp(0.0, ell)
    h_sim = sim[:, est._block[cells]]
    with np.errstate(divide="ignore"):
        log_sim, log_not_sim = np.log(h_sim), np.log1p(-h_sim)
        log_close = np.where(expit(ell) >= h_sim, np.logaddexp(log_not_h, log_sim), np.logaddexp(log_not_sim, log_h))
        g = est.discrimination
        log_g = np.logaddexp(np.log1p(-g), np.log(g) + log_close) if g < 1 else log_close
    return np.logaddexp(-x[None, :], log_conf[None, :] + log_g).sum(axis=1)


def test_pmfs_kept_score_terms_give_the_score_bit_for_bit():
    """The score with its per-cell terms kept between readings (only the cells whose ω or ℓ moved recomputed) and
    :meth:`FilamentPMFS._score` are the score computed in one pass, bit for bit, at every reading across
    refreshes (a new simulation restarts the terms), for every region and for the first-level regions that
    :meth:`hit_variance` weighs; and two estimators, one asked for its hit variance after every reading, keep the
    same posterior."""
    model = _corridor()
    a = FilamentPMFS(model, seed=4, refresh=4, record_steps=40, warmup_steps=20, discrimination=0.8)
    b = FilamentPMFS(model, seed=4, refresh=4, record_steps=40, warmup_steps=20, discrimination=0.8)
    rng = np.random.default_rng(6)
    terms = set()
    for x in [(x, y) for x in np.arange(0.25, 3.9, 0.45) for y in (0.35, 0.85)]:
        wind = (0.4 + 0.05 * rng.normal(), 0.05 * rng.normal())
        hit = bool(rng.random() < 0.3)
        a.update(x, hit, wind=wind)
        b.update(x, hit, wind=wind)
        fresh = a._score(a._sim, None, a._log_odds, a._omega)
        assert fresh.tobytes() == _straight_score(a, a._sim, a._log_odds, a._omega).tobytes()
        assert a._score_kept(a._sim, a._log_odds, a._omega).tobytes() == fresh.tobytes()
        coarse = np.unique(a._coarse)
        kept = a._score_kept(a._sim, a._log_odds, a._omega, rows=coarse)
        assert kept.tobytes() == _straight_score(a, a._sim[coarse], a._log_odds, a._omega).tobytes()
        a.hit_variance()
        terms.add(id(a._terms))
        assert a.posterior.tobytes() == b.posterior.tobytes()
    assert len(terms) >= 3  # the simulations were refreshed, and the kept terms with them


def test_pmfs_hit_map_confidence_and_score_by_hand():
    """One hit then one miss at one cell: ĥ there is σ(logit 0.6 + logit 0.05 − logit 0.1), its confidence
    1 − exp(−2 / 0.25), and the posterior is exp Σ_c log[1 − conf_c |ĥ_c − h_c(k)|] over the region's maps."""
    model = _corridor()
    est = FilamentPMFS(model, seed=2, refresh=1)
    est.update((1.05, 0.55), True, wind=(0.4, 0.0))
    assert est.hit_map[5, 10] == pytest.approx(0.6, abs=1e-12)
    est.update((1.05, 0.55), False, wind=(0.4, 0.0))
    logit = lambda p: np.log(p / (1 - p))  # noqa: E731
    expected = 1 / (1 + np.exp(-(logit(0.6) + logit(0.05) - logit(0.1))))
    assert est.hit_map[5, 10] == pytest.approx(expected, rel=1e-12)
    assert est.confidence[5, 10] == pytest.approx(1 - np.exp(-2 / 0.25), rel=1e-12)
    free = model.geometry.free
    conf, hm = est.confidence[free], est.hit_map[free]
    scores = {}
    for cell in [(5, 2), (5, 12), (3, 30)]:
        sim = est.simulated_hit_map(model.geometry.centre_of(cell))[free]
        scores[cell] = np.log1p(-conf * np.abs(hm - sim)).sum()
    lp = est.log_posterior
    assert lp[5, 2] - lp[5, 12] == pytest.approx(scores[(5, 2)] - scores[(5, 12)], abs=1e-9)
    assert lp[5, 2] - lp[3, 30] == pytest.approx(scores[(5, 2)] - scores[(3, 30)], abs=1e-9)


def test_pmfs_refreshes_its_simulations_every_n_readings_and_is_seeded():
    model = _corridor()
    a = FilamentPMFS(model, seed=5, refresh=3, region_size=1.0, refine_fraction=0.0, record_steps=50,
                     warmup_steps=50)
    per_refresh = a.n_regions
    counts = []
    for i in range(7):
        a.update((0.35 + 0.5 * i, 0.55), i % 3 == 0, wind=(0.3, 0.0))
        counts.append(a.n_simulations // per_refresh)
    assert counts == [1, 1, 1, 2, 2, 2, 3]  # readings 1, 4, 7
    b = FilamentPMFS(model, seed=5, refresh=3, region_size=1.0, refine_fraction=0.0, record_steps=50,
                     warmup_steps=50)
    for obs in a.observations:
        b.update(obs.position, obs.hit, wind=obs.wind)
    np.testing.assert_array_equal(a.posterior, b.posterior)


def test_pmfs_refines_the_best_regions_into_four_children():
    """Regions of 1 m (10 × 10 cells; the corridor's 12 rows make two rows of them, 8 in all), the best quarter
    (2) refined: their cells, and only theirs, take the maps of their 0.5 m children, one simulation each."""
    model = _corridor()
    est = FilamentPMFS(model, seed=5, region_size=1.0, refine_fraction=0.25, record_steps=50, warmup_steps=50)
    est.update((2.05, 0.55), True, wind=(0.4, 0.0))
    assert est.n_regions == 8
    refined = est._assign >= est.n_regions
    parents = np.unique(est._coarse[refined])
    assert parents.size == 2
    assert np.array_equal(refined, np.isin(est._coarse, parents))
    children = np.unique(est._assign[refined])
    assert children.size == np.unique(est._fine[refined]).size
    assert est.n_simulations == 8 + children.size


def test_pmfs_predicts_a_reading_by_its_simulated_hit_maps():
    model = _corridor()
    est = FilamentPMFS(model, seed=1)
    est.update((0.55, 0.55), True, wind=(0.4, 0.0))
    p = est.hit_probability([(2.05, 0.55)])[0]
    assert p[5, 7] == pytest.approx(est.simulated_hit_map(model.geometry.centre_of((5, 7)))[5, 20])
    gain = est.information_gain([(2.05, 0.55), (0.15, 0.15)])
    assert (gain >= 0).all() and (gain <= np.log(2) + 1e-12).all()


def test_pmfs_saturated_cells_keep_a_positive_factor():
    """400 hits at one cell: conf and ĥ round to 1 there, and a candidate whose simulation never reaches the cell
    would get PMFS's factor 1 − 1 · 1 = 0 in floating point; in log space it keeps its tiny positive one."""
    model = PlumeModel(np.zeros((6, 10), bool), resolution=0.1)
    est = FilamentPMFS(model, refresh=1000, record_steps=20, warmup_steps=5)
    for _ in range(400):
        est.update((0.15, 0.15), True, wind=(0.3, 0.0))
    assert est.confidence[1, 1] == 1.0 and est.hit_map[1, 1] == 1.0
    assert np.isfinite(est.log_posterior).all()


def test_pmfs_bad_input():
    model = _corridor()
    with pytest.raises(TypeError, match="PlumeModel"):
        FilamentPMFS(np.zeros((3, 3), bool))
    with pytest.raises(ValueError, match="region_size"):
        FilamentPMFS(model, region_size=-1.0)
    with pytest.raises(ValueError, match="refresh"):
        FilamentPMFS(model, refresh=0)
    with pytest.raises(TypeError, match="seed"):
        FilamentPMFS(model, seed=1.5)


# --- GrGSL ----------------------------------------------------------------------------------------------------------


def _open(n=9, res=0.25):
    return PlumeModel(np.zeros((n, n), bool), resolution=res)


def test_grgsl_hit_update_by_hand():
    """A hit at the centre of a 9 × 9 map with wind towards +x, ring two cells out: the factor of a cell is
    exp(−Δ²/2) of its ring cell's angle Δ to upwind (−x); the cells inside the ring get Δ = 0."""
    est = GrGSL(_open(), ring_radius=0.5, hit_std=1.0)
    est.update((1.125, 1.125), True, wind=(0.3, 0.0))  # cell (4, 4)
    lp = est.log_posterior
    ref = lp[4, 2]  # the ring cell straight upwind: Δ = 0
    assert lp[4, 0] == pytest.approx(ref, abs=1e-12)  # beyond it, along the same path
    assert lp[4, 5] == pytest.approx(ref, abs=1e-12)  # inside the ring
    assert lp[4, 6] - ref == pytest.approx(-np.pi ** 2 / 2, rel=1e-12)  # straight downwind: Δ = π
    assert lp[2, 4] - ref == pytest.approx(-(np.pi / 2) ** 2 / 2, rel=1e-12)  # cross-wind
    assert lp[2, 2] - ref == pytest.approx(-(np.pi / 4) ** 2 / 2, rel=1e-12)  # diagonal upwind


def test_grgsl_miss_points_towards_the_last_hit_and_a_windless_hit_changes_nothing():
    est = GrGSL(_open(), ring_radius=0.5, miss_std=2.0)
    p0 = est.update((1.125, 1.125), True, wind=(0.0, 0.0)).copy()  # no significant wind: no update
    np.testing.assert_array_equal(p0, est.prior)
    est.update((1.625, 1.125), False, wind=(0.3, 0.0))  # cell (4, 6); the last hit at (4, 4), towards −x
    lp = est.log_posterior
    ref = lp[4, 4]  # the ring cell towards the last hit: Δ = 0
    assert lp[4, 7] - ref == pytest.approx(-np.pi ** 2 / 8, rel=1e-12)  # inside the ring: Δ = π, σ = 2
    assert lp[4, 8] - ref == pytest.approx(-np.pi ** 2 / 8, rel=1e-12)  # the ring cell away from the last hit
    assert lp[2, 6] - ref == pytest.approx(-(np.pi / 2) ** 2 / 8, rel=1e-12)
    assert lp[4, 0] == pytest.approx(ref, abs=1e-12)


def test_grgsl_evidence_goes_around_walls():
    """Behind a wall the factor follows the shortest free path, not the straight line."""
    occ = np.zeros((9, 15), bool)
    occ[0:7, 7] = True  # a wall with a gap at the top rows 7-8
    est = GrGSL(PlumeModel(occ, resolution=0.25), ring_radius=0.5)
    est.update((1.375, 0.375), True, wind=(-0.3, 0.0))  # cell (1, 5), wind towards −x: upwind is +x
    lp = est.log_posterior
    # (1, 10) is straight upwind but reached only through the gap: its path leaves the ring upwards (cross-wind)
    assert lp[1, 6] == pytest.approx(lp[1, 3] + 0.5 * np.pi ** 2, rel=1e-12)  # inside the ring, and downwind
    assert lp[1, 10] < lp[1, 6] - 0.5  # a straight line would give it the factor of straight upwind


def test_grgsl_bad_input():
    with pytest.raises(TypeError, match="PlumeModel"):
        GrGSL(np.zeros((3, 3), bool))
    with pytest.raises(ValueError, match="hit_std"):
        GrGSL(_open(), hit_std=0.0)
