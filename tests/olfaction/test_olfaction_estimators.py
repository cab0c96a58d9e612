"""Olfactory estimators p(s | g): exact Bayes against brute force, posterior invariants, PMFS score, bad input."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from scipy.special import logsumexp

from psgsl_pgm import GridMap
from psgsl_pgm.olfaction import (
    GridInfotaxis,
    HitProbabilityMap,
    OlfactoryEstimator,
    PlumeModel,
    PMFSEstimator,
    encounter_scale_mle,
    fit_encounter_scale,
)

H = 0.25  # resolution of the small maps


def _map(seed=0, shape=(8, 10)):
    rng = np.random.default_rng(seed)
    occ = rng.random(shape) < 0.15
    wind = rng.normal(scale=0.1, size=shape + (2,))
    outlets = np.zeros(shape, bool)
    outlets[~occ] = rng.random(int((~occ).sum())) < 0.04
    return occ, wind, outlets


def _readings(occ, n, seed):
    rng = np.random.default_rng(seed)
    free = np.argwhere(~occ)
    cells = free[rng.integers(len(free), size=n)]
    pos = (cells[:, ::-1] + rng.uniform(0.05, 0.95, size=(n, 2))) * H  # anywhere inside the cell
    return pos, cells, rng.random(n) < 0.4, rng.normal(scale=0.1, size=(n, 2))


def _dense_green(model):
    """G(x|s) for all x, s from the dense inverse (independent of the adjoint path)."""
    inv = np.linalg.inv(model.operator.toarray())
    idx = model.active_index.ravel()
    n = idx.size
    g = np.zeros((n, n))
    act = np.flatnonzero(idx >= 0)
    g[np.ix_(act, act)] = inv[np.ix_(idx[act], idx[act])] / model.geometry.resolution**2
    return g


# --- Infotaxis: exact Bayes ----------------------------------------------------------------------------------------
@pytest.mark.parametrize("beta,eps,delta", [(1.0, 0.0, 0.0), (0.5, 0.01, 0.0), (0.3, 0.2, 0.0), (0.5, 0.01, 0.05),
                                            (1.0, 0.0, 0.3)])
def test_infotaxis_posterior_equals_brute_force_tempered_bayes(beta, eps, delta):
    occ, wind, outlets = _map(1)
    prior = np.random.default_rng(2).random(occ.shape) + 0.1
    est = GridInfotaxis(occ, resolution=H, wind=wind, outlets=outlets, prior=prior, tempering=beta,
                        false_hit_rate=eps, missed_hit_rate=delta, diffusivity=0.03, lifetime=8.0,
                        encounter_scale=0.7)
    g_all = _dense_green(est.model)
    pos, cells, hits, winds = _readings(occ, 25, 3)
    log_post = np.log(np.where(occ, 0.0, prior).ravel(), where=~occ.ravel(), out=np.full(occ.size, -np.inf))
    for p, (r, c), hit, w in zip(pos, cells, hits, winds):
        out = est.update(p, hit, w)
        mu = 0.7 * g_all[r * occ.shape[1] + c]  # κ G(x | s), all s
        p_hit = eps + (1 - eps) * (1 - delta) * -np.expm1(-mu)  # P(hit | s)
        p_miss = (1 - eps) * (delta + (1 - delta) * np.exp(-mu))  # P(miss | s), not 1 − P(hit | s): no cancellation
        with np.errstate(divide="ignore"):
            log_post = log_post + beta * np.log(p_hit if hit else p_miss)
        expect = np.exp(log_post - logsumexp(log_post)).reshape(occ.shape)
        np.testing.assert_allclose(out, expect, rtol=1e-9, atol=1e-15)
    assert est.n_observations == 25
    assert est.observations[0].wind == tuple(winds[0])


def test_a_missed_hit_rate_bounds_what_one_miss_costs_and_enters_the_hit_probability():
    """δ: a reading without a hit costs a source at most −log((1 − ε) δ) nats, where without δ a source beside the
    sensor loses κG (checked on the cell itself); P(hit | s) of planning is ε + (1 − ε)(1 − δ)(1 − e^{−κG}); δ = 0
    is the model without it bit for bit; a δ outside [0, 1) is refused by name."""
    occ, wind, outlets = _map(1)
    kw = dict(resolution=H, wind=wind, outlets=outlets, false_hit_rate=0.01, diffusivity=0.03, lifetime=8.0,
              encounter_scale=40.0)
    plain = GridInfotaxis(occ, **kw)
    robust = GridInfotaxis(occ, missed_hit_rate=0.05, **kw)
    same = GridInfotaxis(occ, missed_hit_rate=0.0, **kw)
    free = np.argwhere(~occ)
    x = (free[len(free) // 2][::-1] + 0.5) * H  # a free cell's centre
    miss_plain, miss_robust = plain.log_likelihood(x, False), robust.log_likelihood(x, False)
    assert miss_plain[~occ].min() < -20.0  # without δ one miss all but excludes the cells near the sensor
    assert miss_robust[~occ].min() >= np.log(0.99 * 0.05) - 1e-12
    np.testing.assert_array_equal(same.log_likelihood(x, False), miss_plain)
    np.testing.assert_array_equal(same.log_likelihood(x, True), plain.log_likelihood(x, True))
    g = _dense_green(robust.model)
    r, c = robust.model.cell_of(x)
    expect = 0.01 + 0.99 * 0.95 * -np.expm1(-40.0 * g[r * occ.shape[1] + c])
    np.testing.assert_allclose(robust.hit_probability(np.array([x]))[0].ravel()[~occ.ravel()],
                               expect[~occ.ravel()], rtol=1e-9)
    for bad in (1.0, -0.1, float("nan")):
        with pytest.raises(ValueError, match="missed_hit_rate"):
            GridInfotaxis(occ, missed_hit_rate=bad, **kw)
    for bad in ("0.1", True, 0.1j):
        with pytest.raises(TypeError, match="missed_hit_rate"):
            GridInfotaxis(occ, missed_hit_rate=bad, **kw)


def test_infotaxis_is_order_invariant_and_likelihood_method_agrees():
    occ, wind, outlets = _map(4)
    est = GridInfotaxis(occ, resolution=H, wind=wind, outlets=outlets, tempering=0.7, diffusivity=0.03, lifetime=8.0)
    pos, _, hits, _ = _readings(occ, 15, 5)
    for p, h in zip(pos, hits):
        est.update(p, h)
    first = est.posterior.copy()
    total = est.log_likelihood_total
    est.reset()
    for i in np.random.default_rng(0).permutation(15):
        est.update(pos[i], hits[i])
    np.testing.assert_allclose(est.posterior, first, rtol=1e-12, atol=1e-300)
    manual = sum(0.7 * est.log_likelihood(p, h) for p, h in zip(pos, hits))
    np.testing.assert_allclose(total[~occ], manual[~occ], rtol=1e-12, atol=1e-12)


def test_impossible_hit_with_zero_false_hit_rate_is_refused_and_state_kept():
    occ = np.zeros((6, 13), bool)
    occ[:, 6] = True  # sealed wall
    prior = np.zeros(occ.shape)
    prior[:, :6] = 1.0  # the source is known to be in the left room
    est = GridInfotaxis(occ, resolution=H, prior=prior, false_hit_rate=0.0, lifetime=8.0)
    est.update((0.6, 0.6), False)
    before = est.posterior.copy()
    with pytest.raises(ValueError, match="zero likelihood for every candidate source"):
        est.update((2.6, 0.6), True)  # a hit in the right room: no left-room source can cause it
    np.testing.assert_array_equal(est.posterior, before)
    assert est.n_observations == 1
    # with false hits the same reading is merely uninformative about the left room
    est2 = GridInfotaxis(occ, resolution=H, prior=prior, false_hit_rate=0.01, lifetime=8.0)
    est2.update((0.6, 0.6), False)
    np.testing.assert_allclose(est2.update((2.6, 0.6), True), before, rtol=1e-12)


# --- posterior invariants (both estimators) ---------------------------------------------------------------------
def _both(occ, wind, outlets, prior=None):
    model = PlumeModel(occ, resolution=H, wind=wind, outlets=outlets, diffusivity=0.03, lifetime=8.0)
    return [GridInfotaxis.from_model(model, prior=prior), PMFSEstimator.from_model(model, prior=prior)]


@pytest.mark.parametrize("which", [0, 1])
def test_posterior_invariants_and_reset(which):
    occ, wind, outlets = _map(6)
    prior = np.random.default_rng(7).random(occ.shape)
    est = _both(occ, wind, outlets, prior)[which]
    assert isinstance(est, OlfactoryEstimator)
    start = est.posterior.copy()
    expect_prior = np.where(occ, 0, prior) / np.where(occ, 0, prior).sum()
    np.testing.assert_allclose(start, expect_prior, rtol=1e-12)
    pos, _, hits, winds = _readings(occ, 40, 8)
    for i, (p, h, w) in enumerate(zip(pos, hits, winds)):
        out = est.update(p, h, None if i % 3 == 0 else w)
        assert out.shape == occ.shape and out.dtype == np.float64
        assert np.isfinite(out).all() and (out >= 0).all()
        assert (out[occ] == 0).all() and np.isneginf(est.log_posterior[occ]).all()
        assert abs(out.sum() - 1) < 1e-12
    with pytest.raises(ValueError, match="read-only"):
        est.posterior[0, 0] = 1.0
    x, y = est.expected_position()
    assert np.isclose(x, (est.posterior * (np.arange(occ.shape[1]) + 0.5) * H).sum(), rtol=1e-12)
    assert np.isclose(y, (est.posterior.T * (np.arange(occ.shape[0]) + 0.5) * H).sum(), rtol=1e-12)
    assert est.map_cell() == tuple(np.unravel_index(np.argmax(est.posterior), occ.shape))
    est.reset()
    np.testing.assert_array_equal(est.posterior, start)
    assert est.n_observations == 0


def test_information_gain_equals_brute_force_mutual_information():
    occ, wind, outlets = _map(9)
    for est in _both(occ, wind, outlets):
        pos, _, hits, _ = _readings(occ, 6, 10)
        for p, h in zip(pos, hits):
            est.update(p, h)
        cand, cells, _, _ = _readings(occ, 8, 11)
        gain = est.information_gain(cand)
        prior = est.posterior.ravel()
        for k, (r, c) in enumerate(cells):
            g = est.model.green_rows([r * occ.shape[1] + c])[0]
            p_hit = 1 - np.exp(-est.model.encounter_scale * g)
            if isinstance(est, GridInfotaxis):
                p_hit = est.false_hit_rate + (1 - est.false_hit_rate) * p_hit
            z = prior @ p_hit

            def ent(p):
                p = p[p > 0]
                return -(p * np.log(p)).sum()

            mi = ent(prior)  # I = H(S) − Σ_g p(g) H(S | g), posterior after a hit and after a miss
            for pz, like in ((z, p_hit), (1 - z, 1 - p_hit)):
                if pz > 0:
                    mi -= pz * ent(prior * like / pz)
            assert gain[k] == pytest.approx(mi, rel=1e-9, abs=1e-13)
        assert ((gain >= 0) & (gain <= np.log(2) + 1e-12)).all()


# --- PMFS: hit map and score ------------------------------------------------------------------------------------
def test_hit_map_is_a_kernel_weighted_beta_posterior_blocked_by_walls():
    occ = np.zeros((9, 15), bool)
    occ[:, 7] = True
    occ[7, 7] = False  # one door, far from the sensor
    hm = HitProbabilityMap(GridMap(occ, 0.1), prior_hit=0.2, prior_strength=2.0,
                           kernel_sigma=0.15, cutoff=4.0)
    readings = [((2, 5), True, (0.0, 0.0)), ((2, 5), False, (0.3, 0.0)), ((3, 6), True, (0.0, -0.2))]
    weights = []
    for cell, hit, wind in readings:
        weights.append(hm.kernel(cell, wind))
        hm.observe(cell, hit, wind)
    w = np.array(weights)
    g = np.array([r[1] for r in readings], float)
    expect = (0.2 * 2.0 + g @ w) / (2.0 + w.sum(axis=0))  # Beta posterior mean with fractional counts
    np.testing.assert_allclose(hm.hit_probability.ravel(), expect, rtol=1e-13)
    np.testing.assert_allclose(hm.confidence.ravel(), -np.expm1(-w.sum(axis=0) / hm.confidence_scale), rtol=1e-13)
    assert w[0, 2 * 15 + 5] == 1.0  # full weight in the sensor's own cell
    k = w.reshape(3, 9, 15)
    assert (k[:, occ] == 0).all()
    # still air: cutoff 4σ = 0.6 m; the cells behind the wall are 0.3 m away in a straight line, but 1.2 m and
    # more along free space (through the door): exactly zero weight there, unlike on the same map without wall
    assert (k[0, :, 8:] == 0).all()
    no_wall = HitProbabilityMap(GridMap(np.zeros((9, 15), bool), 0.1), kernel_sigma=0.15, cutoff=4.0)
    assert no_wall.kernel((2, 5)).reshape(9, 15)[2, 8] == pytest.approx(np.exp(-0.5 * 4), rel=1e-12)
    # with wind the kernel reaches through the door, evaluated at the geodesic, not the straight, distance
    assert 0 < k[1, 0, 8] < np.exp(-0.5 * (1.2 / 0.45) ** 2)
    # a wind stretches the kernel along itself: along-wind weight > cross-wind weight at equal distance
    hm2 = HitProbabilityMap(GridMap(np.zeros((11, 11), bool), 0.1), kernel_sigma=0.1)
    kk = hm2.kernel((5, 5), (0.2, 0.0)).reshape(11, 11)
    assert kk[5, 7] > kk[7, 5] and kk[5, 3] == pytest.approx(kk[5, 7], rel=1e-12)
    iso = hm2.kernel((5, 5), None).reshape(11, 11)
    assert iso[5, 7] == pytest.approx(iso[7, 5], rel=1e-12) == pytest.approx(np.exp(-0.5 * 4), rel=1e-12)


def test_pmfs_posterior_equals_the_weighted_difference_score():
    """After every reading (the score is updated incrementally), against the product recomputed from scratch."""
    occ, wind, outlets = _map(12)
    est = PMFSEstimator(occ, resolution=H, wind=wind, outlets=outlets, discrimination=0.8, diffusivity=0.03,
                        lifetime=8.0)
    g_all = _dense_green(est.model)
    pos, cells, hits, winds = _readings(occ, 60, 13)
    for i, (p, h, w) in enumerate(zip(pos, hits, winds)):
        est.update(p, h, w)
        flat = np.unique(cells[: i + 1, 0] * occ.shape[1] + cells[: i + 1, 1])
        assert sorted(flat.tolist()) == sorted((est.compared_cells @ [occ.shape[1], 1]).tolist())
        h_obs = est.hit_map.hit_probability.ravel()[flat]
        conf = est.hit_map.confidence.ravel()[flat]
        h_src = 1 - np.exp(-est.model.encounter_scale * g_all[flat])  # (K, n) predicted hit maps
        score = np.prod(1 - 0.8 * conf[:, None] * np.abs(h_obs[:, None] - h_src), axis=0)  # weightedDifference
        score[occ.ravel()] = 0
        np.testing.assert_allclose(est.posterior.ravel(), score / score.sum(), rtol=1e-10, atol=1e-300)


def test_pmfs_uses_the_model_wind_when_the_reading_has_none():
    occ = np.zeros((9, 9), bool)
    wind = np.zeros((9, 9, 2))
    wind[..., 1] = 0.25
    a = PMFSEstimator(occ, resolution=0.1, wind=wind)
    b = PMFSEstimator(occ, resolution=0.1, wind=wind)
    a.update((0.45, 0.45), True)
    b.update((0.45, 0.45), True, wind=(0.0, 0.25))
    np.testing.assert_array_equal(a.hit_map.hit_probability, b.hit_map.hit_probability)
    np.testing.assert_array_equal(a.posterior, b.posterior)


def test_pmfs_reading_log_ratio_is_the_update_it_would_make():
    """For a miss and a hit at new cells, compared cells and cells next to them, after readings with and without
    wind and a "not found" factor: the log posterior after :meth:`update` minus the log posterior before equals
    the predicted ratio plus one constant (the normalisation) on every free cell; the state is unchanged."""
    occ, wind, outlets = _map(15)
    model = PlumeModel(occ, resolution=H, wind=wind, outlets=outlets, diffusivity=0.03, lifetime=8.0)
    pos, cells, hits, winds = _readings(occ, 12, 16)
    pos[5], hits[4:6], winds[5] = pos[4], (False, False), np.nan  # a repeated miss at one stop, without wind
    cond = np.where(np.random.default_rng(17).random(occ.shape) < 0.2, np.log(0.3), 0.0)

    def replay():
        e = PMFSEstimator.from_model(model, discrimination=0.8, tempering=0.4)
        for p, h, w in zip(pos, hits, winds):
            e.update(p, h, None if np.isnan(w).any() else w)
        e.condition(cond)
        return e

    est = replay()
    free = np.argwhere(~occ)
    probe = np.concatenate([pos[[0, 4, 9]], (free[[3, 20, 41]][:, ::-1] + 0.5) * H])
    before = est.log_posterior.copy()
    ratio = est.reading_log_ratio(probe)
    assert ratio.shape == (len(probe), 2) + occ.shape
    np.testing.assert_array_equal(est.log_posterior, before)  # no state change
    assert est.n_observations == len(pos)
    for k, p in enumerate(probe):
        for g in (False, True):
            after = replay()
            after.update(p, g)
            d = after.log_posterior[~occ] - before[~occ] - ratio[k, int(g)][~occ]
            np.testing.assert_allclose(d, d[0], rtol=0, atol=1e-12)
        assert np.ptp(ratio[k, 0][~occ]) > 1e-3 and np.ptp(ratio[k, 1][~occ]) > 1e-3  # not a constant


def _straight_reading_log_ratio(est, positions):
    """The PMFS reading ratio computed candidate by candidate on every cell: each compared cell's factors from
    the hit map, then the ratio, with no row shared between candidates (what the tables of the estimator
    reproduce)."""
    cells = est._flat_cells(positions)
    n = est.geometry.shape[0] * est.geometry.shape[1]
    out = np.zeros((len(cells), 2, n))
    hm = est._hitmap
    m0, p0, n0 = hm.prior_strength, hm.prior_hit, hm.confidence_scale
    compared = np.asarray(est._cells, dtype=np.int64)
    for k, flat in enumerate(cells.tolist()):
        r, c = divmod(flat, est.geometry.shape[1])
        w = hm.kernel((r, c), tuple(est.model.wind[r, c]))
        slots = np.flatnonzero(w[compared] > 0) if compared.size else np.zeros(0, np.int64)
        new = flat not in est._slot
        at = compared[slots]
        rows = est._pred[slots]
        if new:
            at = np.append(at, flat)
            row_new = -np.expm1(-est.model.encounter_scale * est.model.green_rows([flat])[0])
            rows = np.concatenate([rows, row_new[None]])
        weight = hm._weight[at]
        h_old = (p0 * m0 + hm._hits[at]) / (m0 + weight)
        conf_old = -np.expm1(-weight / n0)
        old = np.log1p(-est.discrimination * conf_old[:, None] * np.abs(h_old[:, None] - rows))
        if new:
            old[-1] = 0.0
        old = old.sum(axis=0)
        weight_new = weight + w[at]
        conf_new = -np.expm1(-weight_new / n0)
        for g in (0, 1):
            h_new = (p0 * m0 + hm._hits[at] + g * w[at]) / (m0 + weight_new)
            fac = np.log1p(-est.discrimination * conf_new[:, None] * np.abs(h_new[:, None] - rows))
            out[k, g] = est.tempering * (fac.sum(axis=0) - old)
    out[:, :, ~est.geometry.free.ravel()] = 0.0
    return out.reshape((len(cells), 2) + est.geometry.shape)


def test_pmfs_reading_log_ratio_is_the_straight_computation_bit_for_bit():
    """The ratio the estimator computes with rows shared between candidates and on the free cells only is the
    candidate-by-candidate computation on every cell, bit for bit (sign of zero included): along a run of
    readings (compared cells old and new, repeated cells, with and without wind), for candidates asked in
    several calls per state and after a new plume model."""
    occ, wind, outlets = _map(21, shape=(14, 18))
    model = PlumeModel(occ, resolution=H, wind=wind, outlets=outlets, diffusivity=0.03, lifetime=8.0)
    pos, _, hits, winds = _readings(occ, 14, 22)
    pos[6] = pos[2]
    free = np.argwhere(~occ & ~outlets)
    probe = np.concatenate([pos, (free[::7][:, ::-1] + 0.5) * H])
    est = PMFSEstimator.from_model(model, discrimination=0.85, tempering=0.6)

    def same(got, ref):
        assert got.dtype == ref.dtype and got.shape == ref.shape
        assert got.tobytes() == ref.tobytes()

    checked = 0
    for i, (p, h, w) in enumerate(zip(pos, hits, winds)):
        same(est.reading_log_ratio(probe), _straight_reading_log_ratio(est, probe))
        same(est.reading_log_ratio(probe[::-3]), _straight_reading_log_ratio(est, probe[::-3]))  # same state
        if i % 4 == 0:  # every free cell: the kept rows of the smaller calls are dropped and made again
            every = (free[:, ::-1] + 0.5) * H
            same(est.reading_log_ratio(every), _straight_reading_log_ratio(est, every))
            assert len(est._new_rows) > 2 * len(probe)
        est.update(p, h, None if i % 3 == 0 else w)
        checked += 1
    moved = PlumeModel(occ, resolution=H, wind=wind[:, ::-1] * 0.5, outlets=outlets, diffusivity=0.03,
                       lifetime=8.0)
    est.replace_model(moved)
    same(est.reading_log_ratio(probe), _straight_reading_log_ratio(est, probe))
    assert checked == len(pos) and len(est._cells) < len(pos)  # a repeated cell among them


def test_pmfs_repeated_misses_at_one_stop_saturate():
    """PMFS does not accumulate readings: after many misses at one stop one more moves the posterior (almost)
    not at all — the factor whose expected effect the closed loop's φ_G must use."""
    occ = np.zeros((8, 12), bool)
    wind = np.zeros((8, 12, 2))
    wind[..., 0] = 0.2
    est = PMFSEstimator(occ, resolution=H, wind=wind, diffusivity=0.03, tempering=0.4)
    spread = []
    for _ in range(40):
        spread.append(np.ptp(est.reading_log_ratio([(1.1, 1.1)])[0, 0]))
        est.update((1.1, 1.1), False)
    assert spread[-1] < 1e-3 * spread[0] and all(np.diff(spread) < 0)


# --- construction paths ----------------------------------------------------------------------------------------------
def test_from_grid_map_duck_types_and_from_model_shares_the_cache():
    occ, wind, outlets = _map(14)
    gm = SimpleNamespace(occupancy=occ, resolution=H, origin=(1.0, -2.0))
    pos, _, hits, _ = _readings(occ, 10, 15)
    pos = pos + [1.0, -2.0]
    kw = dict(outlets=outlets, diffusivity=0.03, lifetime=8.0, tempering=0.8)
    a = GridInfotaxis.from_grid_map(gm, wind, **kw)
    b = GridInfotaxis(occ, resolution=H, origin=(1.0, -2.0), wind=wind, **kw)
    p = PMFSEstimator.from_grid_map(gm, wind, outlets=outlets, diffusivity=0.03, lifetime=8.0, kernel_sigma=0.4)
    assert p.hit_map.kernel_sigma == 0.4
    for x, h in zip(pos, hits):
        a.update(x, h)
        b.update(x, h)
        p.update(x, h)
    np.testing.assert_array_equal(a.posterior, b.posterior)
    c = GridInfotaxis.from_grid_map(gm, SimpleNamespace(velocity=wind), **kw)  # a sim.WindField-like object
    np.testing.assert_array_equal(c.model.wind, a.model.wind)
    shared = PlumeModel(occ, resolution=H, wind=wind, outlets=outlets, diffusivity=0.03, lifetime=8.0)
    e1, e2 = GridInfotaxis.from_model(shared), PMFSEstimator.from_model(shared)
    for x, h in zip(pos - [1.0, -2.0], hits):
        e1.update(x, h)
        e2.update(x, h)
    distinct = len({shared.cell_of(x) for x in pos - [1.0, -2.0]} - {tuple(c) for c in np.argwhere(outlets)})
    assert shared.n_solves == distinct  # one adjoint solve per distinct sensor cell, shared by both estimators
    with pytest.raises(TypeError, match=r"lacks \.resolution, \.origin"):
        GridInfotaxis.from_grid_map(SimpleNamespace(occupancy=occ), wind)


def test_fit_encounter_scale_recovers_kappa_from_model_draws():
    occ = np.zeros((30, 40), bool)
    wind = np.zeros((30, 40, 2))
    wind[..., 0] = 0.15
    model = PlumeModel(occ, resolution=0.1, wind=wind, boundary="open", diffusivity=0.03, lifetime=15.0,
                       encounter_scale=0.6)
    src = (1.05, 1.55)
    rng = np.random.default_rng(21)
    pos = rng.uniform([0.0, 0.0], [4.0, 3.0], size=(4000, 2))
    hits = model.sample_hits(pos, src, rng=rng)
    kappa = fit_encounter_scale(model, pos, hits, src)
    # score equation holds at the returned κ, and the estimate is within 4 standard errors (Fisher information)
    c = model.concentration(src)[(pos[:, 1] / 0.1).astype(int), (pos[:, 0] / 0.1).astype(int)]
    e = np.exp(-kappa * c)
    assert abs(np.sum(hits * c * e / (1 - e + 1e-300) - (~hits) * c)) < 1e-6 * np.sum(c)
    fisher = np.sum(c**2 * np.exp(-0.6 * c) / -np.expm1(-0.6 * c + 1e-300))
    assert abs(kappa - 0.6) < 4 / np.sqrt(fisher)
    with pytest.raises(ValueError, match="no hit where the model predicts gas"):
        fit_encounter_scale(model, pos[:5], np.zeros(5, bool), src)
    with pytest.raises(ValueError, match="no miss where the model predicts gas"):
        fit_encounter_scale(model, pos[:5], np.ones(5, bool), src)
    with pytest.raises(TypeError, match="false_hit_rate must be a number"):
        fit_encounter_scale(model, pos[:5], hits[:5], src, false_hit_rate="0.01")
    with pytest.raises(TypeError, match="positions must be a real numeric array"):
        fit_encounter_scale(model, [[1.0, 1.0], [2.0]], hits[:2], src)


def test_encounter_scale_mle_at_the_ends_of_float64():
    """κ c is what the likelihood sees: predictions near 1e308 (whose sums overflow) or 1e-300 give the fit of the
    rescaled predictions, scaled back; predictions no float64 κ can scale up are refused naming predicted."""
    c = np.array([0.9, 1.0, 0.7, 0.95, 0.8])
    hits = np.array([False, True, True, False, True])
    base = encounter_scale_mle(c, hits, false_hit_rate=0.01)
    for scale in (1.7e308, 1e-300):  # the misses sum to 3.1e308; κ ≈ 1e300
        assert encounter_scale_mle(c * scale, hits, false_hit_rate=0.01) == pytest.approx(base / scale, rel=1e-9)
    with pytest.raises(ValueError, match=r"predicted: no float64 encounter scale explains these readings \(predicted "
                                         r"values where gas was hit are at most 2.23e-309"):
        encounter_scale_mle(np.full(4, 2.2250738585e-309), [False, True, True, False], false_hit_rate=0.01)


# --- bad input -------------------------------------------------------------------------------------------------------
def test_bad_inputs_raise_with_clear_messages():
    occ = np.zeros((4, 5), bool)
    occ[1, 1] = True
    with pytest.raises(ValueError, match=r"tempering must lie in \(0, 1\]"):
        GridInfotaxis(occ, resolution=0.1, tempering=0.0)
    with pytest.raises(ValueError, match=r"false_hit_rate must lie in \[0, 1\)"):
        GridInfotaxis(occ, resolution=0.1, false_hit_rate=1.0)
    with pytest.raises(TypeError, match="tempering must be a number"):
        GridInfotaxis(occ, resolution=0.1, tempering="0.5")
    with pytest.raises(ValueError, match=r"discrimination must lie in \(0, 1\)"):
        PMFSEstimator(occ, resolution=0.1, discrimination=1.0)
    with pytest.raises(TypeError, match="unexpected keyword"):
        PMFSEstimator.from_model(PlumeModel(occ, resolution=0.1), kernel_width=0.3)
    with pytest.raises(ValueError, match="prior must have the map's shape"):
        GridInfotaxis(occ, resolution=0.1, prior=np.ones((5, 4)))
    with pytest.raises(ValueError, match="prior must be finite and non-negative"):
        GridInfotaxis(occ, resolution=0.1, prior=-np.ones((4, 5)))
    only_wall = np.zeros((4, 5))
    only_wall[1, 1] = 1.0
    with pytest.raises(ValueError, match="positive mass on at least one free cell"):
        GridInfotaxis(occ, resolution=0.1, prior=only_wall)
    with pytest.raises(TypeError, match="model must be a PlumeModel"):
        GridInfotaxis.from_model(occ)
    for est in (GridInfotaxis(occ, resolution=0.1), PMFSEstimator(occ, resolution=0.1)):
        with pytest.raises(TypeError, match="hit must be a bool"):
            est.update((0.05, 0.05), 0.7)
        with pytest.raises(TypeError, match="hit must be a bool"):
            est.update((0.05, 0.05), "yes")
        with pytest.raises(ValueError, match=r"wind must be a \(u_x, u_y\) pair"):
            est.update((0.05, 0.05), True, wind=(1.0, 2.0, 3.0))
        with pytest.raises(ValueError, match="wind must be finite"):
            est.update((0.05, 0.05), True, wind=(np.inf, 0.0))
        with pytest.raises(ValueError, match=r"occupied cell \(1, 1\)"):
            est.update((0.15, 0.15), True)
        with pytest.raises(ValueError, match="outside the map"):
            est.update((0.55, 0.05), True)
        with pytest.raises(ValueError, match=r"positions must have shape \(n, 2\)"):
            est.information_gain((0.05, 0.05))
        assert est.n_observations == 0  # nothing was applied
    hm = HitProbabilityMap(GridMap(occ, 0.1))
    with pytest.raises(ValueError, match=r"cell \(1, 1\) is occupied"):
        hm.observe((1, 1), True)
    with pytest.raises(ValueError, match="outside the 4 x 5 grid"):
        hm.kernel((4, 0))
    with pytest.raises(TypeError, match="hit must be a bool"):
        hm.observe((0, 0), 1.0)
    with pytest.raises(ValueError, match="prior_hit must lie in"):
        HitProbabilityMap(GridMap(occ, 0.1), prior_hit=1.0)


@pytest.mark.parametrize("kind", ["infotaxis", "analytic-plume"])
def test_condition_unread_then_a_reading_is_the_same_posterior_bit_for_bit(kind):
    """The closed loop's "not found" factor without reading the conditioned posterior back (``_condition``), then
    the next reading: the same posterior and log posterior, bit for bit, as :meth:`condition` (which normalises
    it at once); read right after ``_condition`` it is the one ``condition`` returns; a factor that rules out
    every cell is refused by both and changes nothing."""
    occ, wind, outlets = _map(15)
    model = PlumeModel(occ, resolution=H, wind=wind, outlets=outlets, diffusivity=0.03, lifetime=8.0)
    pos, _, hits, winds = _readings(occ, 6, 23)
    rng = np.random.default_rng(29)
    conds = [np.where(rng.random(occ.shape) < 0.2, np.log(0.3), 0.0) for _ in pos]

    def make():
        return (GridInfotaxis.from_model(model, false_hit_rate=0.05) if kind == "infotaxis"
                else PMFSEstimator.from_model(model, tempering=0.4))

    eager, lazy = make(), make()
    for p, h, w, c in zip(pos, hits, winds, conds):
        eager.condition(c)
        lazy._condition(c)
        eager.update(p, h, w)
        lazy.update(p, h, w)
        np.testing.assert_array_equal(lazy.posterior, eager.posterior)
        np.testing.assert_array_equal(lazy.log_posterior, eager.log_posterior)
    returned = eager.condition(conds[0])
    lazy._condition(conds[0])
    np.testing.assert_array_equal(lazy.posterior, returned)
    before = lazy.posterior.copy()
    with pytest.raises(ValueError, match="zero likelihood"):
        lazy._condition(np.full(occ.shape, -np.inf))
    np.testing.assert_array_equal(lazy.posterior, before)
