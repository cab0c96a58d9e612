"""Grid Infotaxis with the plume parameters (D, τ, κ) marginalised over a grid, and the grid's prior weights."""

import numpy as np
import pytest
from scipy.optimize import minimize_scalar
from scipy.special import logsumexp

from psgsl_pgm.olfaction import GridInfotaxis, PlumeModel, mixture_weights

H = 0.25
GRID = np.array([[0.03, 20.0, 0.5, 0.2],   # (D, τ, κ, weight)
                 [0.03, 20.0, 1.5, 0.3],   # same plume as the row above, another κ
                 [0.10, 50.0, 0.8, 0.5]])


def _map():
    occ = np.zeros((10, 14), bool)
    occ[5, 2:8] = True  # a wall
    wind = np.zeros((10, 14, 2))
    wind[..., 0] = 0.1
    outlets = np.zeros((10, 14), bool)
    outlets[:, 13] = True
    prior = np.ones((10, 14))
    prior[:, :4] = 3.0  # a prior that is not uniform
    return occ, wind, outlets, prior


def _readings(n=15, seed=3):
    rng = np.random.default_rng(seed)
    stops = [(0.2 + 3.0 * rng.random(), 0.2 + 2.2 * rng.random()) for _ in range(n)]
    stops = [s for s in stops if not 1.25 <= s[1] < 1.5 or s[0] >= 2.0]  # off the wall row
    return stops, rng.random(len(stops)) < 0.4


def _component(occ, wind, outlets, prior, row, beta):
    d, tau, kappa, _ = row
    return GridInfotaxis(occ, resolution=H, wind=wind, outlets=outlets, prior=prior, tempering=beta, diffusivity=d,
                         lifetime=tau, encounter_scale=kappa)


def test_marginal_posterior_equals_the_brute_force_mixture_over_the_grid():
    """p(s | g) ∝ p(s) Σ_j π_j Π_k P_θj(g_k | s)^β, each component an independent single-plume estimator; the
    posterior over θ is Σ_s p(s | g) p(θ_j | s, g); the planner's hit rows are Σ_j π_j P_θj(hit | s)."""
    occ, wind, outlets, prior = _map()
    beta = 0.6
    est = GridInfotaxis(occ, resolution=H, wind=wind, outlets=outlets, prior=prior, tempering=beta,
                        parameter_grid=GRID, diffusivity=0.03, lifetime=20.0, encounter_scale=9.0)
    parts = [_component(occ, wind, outlets, prior, row, beta) for row in GRID]
    stops, hits = _readings()
    for x, g in zip(stops, hits):
        est.update(x, bool(g))
        for p in parts:
            p.update(x, bool(g))
    assert est.n_components == 3 and len(est.plume_models) == 2  # κ shares a plume; (0.03, 20) is the model's
    assert est.plume_models[0] is est.model
    with np.errstate(divide="ignore"):
        log_prior = np.log(prior / prior[~occ].sum())
    log_prior[occ] = -np.inf
    w = GRID[:, 3] / GRID[:, 3].sum()
    joint = np.stack([np.log(wj) + p.log_likelihood_total for wj, p in zip(w, parts)])  # (J, H, W)
    brute = log_prior + logsumexp(joint, axis=0)
    brute = np.exp(brute - logsumexp(brute[~occ]))
    brute[occ] = 0.0
    np.testing.assert_allclose(est.posterior, brute, rtol=1e-12, atol=1e-300)
    np.testing.assert_allclose(est.log_likelihood_total[~occ], logsumexp(joint, axis=0)[~occ], rtol=1e-12)
    # p(θ_j | g) = Σ_s p(s) Π_k P_θj^β π_j / Σ_{s, i} (...)
    post_theta = np.array([logsumexp((log_prior + j)[~occ]) for j in joint])
    np.testing.assert_allclose(est.parameter_posterior(), np.exp(post_theta - logsumexp(post_theta)), rtol=1e-12)
    xs = np.array(stops[:4])
    np.testing.assert_allclose(est.hit_probability(xs), sum(wj * p.hit_probability(xs) for wj, p in zip(w, parts)),
                               rtol=1e-12)


def test_one_step_log_likelihood_is_the_predictive_under_the_run_posterior_over_theta():
    """With β = 1, log_likelihood(x, g) is log P(g | s, readings so far): the next posterior is the current one
    times its exponential, renormalised (to 1e-12)."""
    occ, wind, outlets, prior = _map()
    est = GridInfotaxis(occ, resolution=H, wind=wind, outlets=outlets, prior=prior, tempering=1.0,
                        parameter_grid=GRID)
    stops, hits = _readings(seed=5)
    for x, g in zip(stops[:-1], hits[:-1]):
        est.update(x, bool(g))
    before = est.posterior.copy()
    ell = est.log_likelihood(stops[-1], bool(hits[-1]))
    est.update(stops[-1], bool(hits[-1]))
    expected = before * np.exp(ell - ell[~occ].max())
    np.testing.assert_allclose(est.posterior, expected / expected.sum(), rtol=1e-12, atol=1e-300)


def test_a_grid_of_the_models_own_parameters_is_the_single_plume_estimator_bit_for_bit():
    occ, wind, outlets, prior = _map()
    kw = dict(resolution=H, wind=wind, outlets=outlets, prior=prior, tempering=0.4, diffusivity=0.05, lifetime=30.0,
              encounter_scale=0.7)
    one = GridInfotaxis(occ, **kw)
    grid = GridInfotaxis(occ, parameter_grid=[(0.05, 30.0, 0.7, 2.0)], **kw)
    for x, g in zip(*_readings(seed=7)):
        assert np.array_equal(one.update(x, bool(g)), grid.update(x, bool(g)))
    assert np.array_equal(one.log_likelihood((1.0, 1.0), True), grid.log_likelihood((1.0, 1.0), True))
    assert grid.parameter_posterior().tolist() == [1.0]


def test_replace_model_rebuilds_every_component_on_the_new_wind():
    occ, wind, outlets, prior = _map()
    a = PlumeModel(occ, resolution=H, outlets=outlets, diffusivity=0.03, lifetime=20.0)
    b = PlumeModel(occ, resolution=H, wind=wind, outlets=outlets, diffusivity=0.03, lifetime=20.0)
    moved = GridInfotaxis.from_model(a, prior=prior, tempering=0.5, parameter_grid=GRID)
    fresh = GridInfotaxis.from_model(b, prior=prior, tempering=0.5, parameter_grid=GRID)
    for x, g in zip(*_readings(seed=9)):
        moved.update(x, bool(g))
        fresh.update(x, bool(g))
    assert not np.allclose(moved.posterior, fresh.posterior)
    moved.replace_model(b)
    np.testing.assert_allclose(moved.posterior, fresh.posterior, rtol=1e-12, atol=1e-300)
    assert all(np.array_equal(m.wind, b.wind) for m in moved.plume_models)


def test_parameter_grid_refuses_bad_input():
    occ = np.zeros((4, 5), bool)
    for bad, what in (([[0.1, 10.0, 0.5]], "parameter_grid must be \\(J, 4\\)"),
                      (np.zeros((0, 4)), "parameter_grid must be \\(J, 4\\)"),
                      ([[0.1, 10.0, -0.5, 1.0]], "positive finite"),
                      ([[0.1, 10.0, 0.5, -1.0]], "non-negative weights"),
                      ([[0.1, 10.0, 0.5, 0.0]], "positive sum"),
                      ([[0.1, np.nan, 0.5, 1.0]], "positive finite")):
        with pytest.raises(ValueError, match=what):
            GridInfotaxis(occ, resolution=0.1, parameter_grid=bad)
    with pytest.raises(TypeError, match="parameter_grid"):
        GridInfotaxis(occ, resolution=0.1, parameter_grid=[["a", "b", "c", "d"]])


def test_mixture_weights_maximise_the_marginal_likelihood():
    """Two components: the weight equals a bounded 1-D maximisation of Σ_r log Σ_j π_j exp(β ℓ_rj); three: the
    optimality conditions mean_r exp(β ℓ_rj) / Σ_i π_i exp(β ℓ_ri) ≤ 1, = 1 where π_j > 0."""
    rng = np.random.default_rng(0)
    ell = rng.normal(-30.0, 4.0, size=(12, 2))
    beta = 0.3

    def neg(w):
        return -np.sum(logsumexp(beta * ell + np.log([w, 1 - w]), axis=1))

    best = minimize_scalar(neg, bounds=(1e-12, 1 - 1e-12), method="bounded", options={"xatol": 1e-12}).x
    np.testing.assert_allclose(mixture_weights(ell, tempering=beta), [best, 1 - best], atol=1e-7)
    ell3 = np.column_stack([ell, ell[:, 0] - 5.0])  # the third never better than the first: weight 0
    w = mixture_weights(ell3, tempering=beta)
    ratio = np.mean(np.exp(beta * ell3 - logsumexp(beta * ell3 + np.log(np.maximum(w, 1e-300)), axis=1,
                                                  keepdims=True)), axis=0)
    assert w.sum() == pytest.approx(1.0, abs=1e-14) and w[2] < 1e-6
    np.testing.assert_allclose(ratio[w > 1e-6], 1.0, atol=1e-8)
    assert (ratio <= 1 + 1e-8).all()
    with pytest.raises(ValueError, match="log_likelihoods must be \\(R, J\\)"):
        mixture_weights(np.zeros((0, 2)))
    with pytest.raises(ValueError, match="no NaN"):
        mixture_weights([[np.nan, 0.0]])
    with pytest.raises(ValueError, match="every run needs"):
        mixture_weights([[-np.inf, -np.inf], [0.0, 0.0]])
    with pytest.raises(ValueError, match="tempering must lie"):
        mixture_weights([[0.0, 0.0]], tempering=0.0)


@pytest.mark.parametrize("eps, delta", [(0.01, 0.0), (0.0, 0.0), (0.05, 0.3), (0.4, 0.1)])
@pytest.mark.parametrize("grid", [None, GRID], ids=["one plume", "grid"])
def test_the_information_gain_bound_needs_no_row_and_bounds_every_cell(eps, delta, grid):
    """The bound of one forward solve per plume is above I(S; hit) computed from the rows at every free cell,
    for peaked and flat posteriors, with false and missed hits, and for a mixture over plume parameters; and it
    is not vacuous: upwind of the posterior's mass it is a hundredth of ln 2."""
    occ, wind, outlets, prior = _map()
    est = GridInfotaxis(occ, resolution=H, wind=wind, outlets=outlets, prior=prior, parameter_grid=grid,
                        false_hit_rate=eps, missed_hit_rate=delta, diffusivity=0.03, lifetime=20.0)
    stops, hits = _readings()
    free = np.argwhere(~occ & ~outlets)
    xy = (free[:, ::-1] + 0.5) * H
    for k, (stop, hit) in enumerate(zip(stops, hits)):
        post = est.update(stop, bool(hit))
        if k % 5:
            continue
        gain = est.information_gain(xy, posterior=post)
        bound = est.information_gain_bound(post)[free[:, 0], free[:, 1]]
        assert (gain <= bound).all(), float((gain - bound).max())
        assert (bound <= np.log(2) + 1e-9).all()
    east = np.zeros(occ.shape)
    east[6:10, 10:13] = 1.0 / 12  # the source somewhere by the east outlets, the wind blowing east
    gain = est.information_gain(xy, posterior=east)
    bound = est.information_gain_bound(east)
    assert (gain <= bound[free[:, 0], free[:, 1]]).all()
    if grid is None:  # 2.5-3 m upwind of the mass (Péclet ≈ 8-10) a reading is worth little, and the bound says so
        assert bound[6:10, :2].max() < 0.01 * np.log(2)
    with pytest.raises(ValueError, match="map's shape"):
        est.information_gain_bound(east[:, :-1])
    with pytest.raises(ValueError, match="sums to 1"):  # Jensen and the chord hold for a distribution only
        est.information_gain_bound(2.0 * east)
