"""The data-driven inputs of the olfactory estimators: wind estimate, (D, τ, κ) maximum likelihood, tempering."""

import numpy as np
import pytest

from psgsl_pgm import GridMap
from psgsl_pgm.olfaction import (CalibrationRun, GridInfotaxis, MeanWindEstimator, PlumeModel, PMFSEstimator,
                                 ar1_tempering, fit_plume_parameters, profile_log_likelihood, score_tempering)


def _smooth_field(shape, rng):
    y, x = np.mgrid[0:shape[0], 0:shape[1]]
    f = np.stack([np.sin(x / 5.0 + rng.uniform(0, 6)) + 0.5, np.cos(y / 4.0 + rng.uniform(0, 6))], axis=-1)
    return f


def test_wind_estimator_is_exact_on_noiseless_readings():
    rng = np.random.default_rng(0)
    g = GridMap(np.zeros((20, 30), bool), 0.1)
    basis = np.stack([_smooth_field(g.shape, rng), _smooth_field(g.shape, rng)])
    a = np.array([0.13, -0.07])
    truth = np.tensordot(a, basis, axes=1)
    est = MeanWindEstimator(basis, g)
    for _ in range(5):
        r, c = rng.integers(0, 20), rng.integers(0, 30)
        est.add(g.centre_of((r, c)), truth[r, c])
    np.testing.assert_allclose(est.coefficients, a, rtol=1e-10)
    np.testing.assert_allclose(est.field(), truth, rtol=1e-10, atol=1e-14)


def test_wind_estimator_recovers_a_known_mean_flow_from_noisy_readings():
    """Readings = mean flow + a time-varying zero-mean eddy + sensor noise: â within 4 standard errors of a, and
    the reported covariance is that standard error (a one-line bug in the normal equations moves â by far more)."""
    rng = np.random.default_rng(1)
    g = GridMap(np.zeros((30, 40), bool), 0.1)
    phi = _smooth_field(g.shape, rng)[None] * 0.8
    a_true = 0.2
    est = MeanWindEstimator(phi, g)
    n, noise = 3000, 0.05
    sq = 0.0
    for k in range(n):
        r, c = rng.integers(0, 30), rng.integers(0, 40)
        eddy = 0.03 * np.array([np.sin(0.1 * k), np.cos(0.13 * k)])  # the eddies of the moment, zero mean
        est.add(g.centre_of((r, c)), a_true * phi[0, r, c] + eddy + rng.normal(0, noise, 2))
        sq += float(phi[0, r, c] @ phi[0, r, c])
    se = np.sqrt((noise**2 + 0.03**2 / 2) / sq)
    assert abs(est.coefficients[0] - a_true) < 4 * se
    assert np.sqrt(est.covariance[0, 0]) == pytest.approx(se, rel=0.1)
    assert est.n_readings == n


def test_wind_estimator_refuses_bad_input():
    g = GridMap(np.zeros((4, 5), bool), 0.5)
    with pytest.raises(ValueError, match="basis must have shape"):
        MeanWindEstimator(np.zeros((1, 4, 4, 2)), g)
    est = MeanWindEstimator(np.ones((1, 4, 5, 2)), g)
    with pytest.raises(ValueError, match="reading"):
        est.add((0.5, 0.5), (np.nan, 0.0))
    assert est.coefficients.tolist() == [0.0] and np.isnan(est.covariance).all()


def test_ar1_tempering_recovers_rho_of_a_synthetic_ar1_sequence():
    rng = np.random.default_rng(2)
    rho = 0.6
    seqs = []
    for _ in range(4):
        x = np.empty(5000)
        x[0] = rng.normal()
        e = rng.normal(size=5000) * np.sqrt(1 - rho**2)
        for t in range(1, 5000):
            x[t] = rho * x[t - 1] + e[t]
        seqs.append(x + 3.0)  # an offset per run: each is centred on its own mean
    est, beta = ar1_tempering(seqs)
    se = np.sqrt((1 - rho**2) / 20000)
    assert abs(est - rho) < 4 * se
    assert beta == pytest.approx((1 - est) / (1 + est), rel=1e-12)
    white = ar1_tempering([rng.normal(size=20000)])
    assert white[0] < 0.03 and white[1] > 0.94


def test_ar1_tempering_refuses_sequences_without_pairs():
    with pytest.raises(ValueError, match="at least one pair"):
        ar1_tempering([[1.0], []])


def _synthetic_runs(d, tau, kappa, eps, n_rep, seed):
    occ = np.zeros((24, 32), bool)
    occ[12, 4:24] = True  # an interior wall
    wind = np.zeros((24, 32, 2))
    wind[..., 0] = 0.05
    rng = np.random.default_rng(seed)
    runs = []
    for source in ((0.85, 0.55), (2.35, 1.95), (1.05, 1.75)):
        truth = PlumeModel(occ, resolution=0.1, wind=wind, diffusivity=d, lifetime=tau, encounter_scale=kappa)
        field = truth.concentration(source)
        free = np.argwhere(~occ)
        cells = free[rng.integers(0, len(free), n_rep)]
        p = eps + (1 - eps) * -np.expm1(-kappa * field[cells[:, 0], cells[:, 1]])
        hits = rng.random(n_rep) < p
        pos = (cells[:, ::-1] + 0.5) * 0.1
        model = PlumeModel(occ, resolution=0.1, wind=wind)  # its own D, τ, κ are not used by the fit
        runs.append(CalibrationRun(model, source, pos, hits))
    return runs


@pytest.mark.slow
def test_plume_mle_recovers_parameters_of_data_simulated_from_the_model():
    d, tau, kappa, eps = 0.02, 60.0, 1.5, 0.01
    runs = _synthetic_runs(d, tau, kappa, eps, 4000, 3)
    fit = fit_plume_parameters(runs, false_hit_rate=eps)
    assert fit.diffusivity == pytest.approx(d, rel=0.15)
    assert fit.lifetime == pytest.approx(tau, rel=0.3)
    assert fit.encounter_scale == pytest.approx(kappa, rel=0.15)
    _, ll_true = profile_log_likelihood(runs, d, tau, false_hit_rate=eps)
    assert fit.log_likelihood >= ll_true  # the maximum is at least the truth's profile
    _, ll_far = profile_log_likelihood(runs, 0.1, 10.0, false_hit_rate=eps)
    assert ll_true > ll_far + 50  # and the likelihood tells a far-off plume apart


@pytest.mark.parametrize("delta", [0.0, 0.1])
def test_hit_model_fit_is_the_maximum_of_the_likelihood_and_recovers_a_missed_hit_rate(delta):
    """fit_hit_model: (κ̂, δ̂) maximise Σ log P(g_k) (no point of a fine grid around them does better; the brute-
    force sum of the per-reading terms at the fit is the returned maximum), recover (κ, δ) from 20 000 readings
    drawn from the model (seeded; δ̂ within 0.02, three standard errors), and δ = 0 gives back κ̂ of
    encounter_scale_mle with its likelihood."""
    from psgsl_pgm.olfaction import encounter_scale_mle, fit_hit_model, hit_log_likelihood

    rng = np.random.default_rng(11)
    c = rng.uniform(0.0, 6.0, 20000)
    eps, kappa = 0.01, 0.8
    hits = rng.random(c.size) < eps + (1 - eps) * (1 - delta) * -np.expm1(-kappa * c)
    k_hat, d_hat, ll = fit_hit_model(c, hits, false_hit_rate=eps)
    assert k_hat == pytest.approx(kappa, rel=0.05)
    assert abs(d_hat - delta) < 0.02
    mu = k_hat * c
    brute = np.where(hits, np.log(eps + (1 - eps) * (1 - d_hat) * (1 - np.exp(-mu))),
                     np.log((1 - eps) * (d_hat + (1 - d_hat) * np.exp(-mu)))).sum()
    assert ll == pytest.approx(brute, rel=1e-12)
    assert hit_log_likelihood(c, hits, k_hat, eps, d_hat) == pytest.approx(brute, rel=1e-12)
    grid = [(k, d) for k in k_hat * np.exp(np.linspace(-0.05, 0.05, 11))
            for d in np.clip(d_hat + np.linspace(-0.02, 0.02, 11), 0.0, 0.99)]
    assert max(hit_log_likelihood(c, hits, k, eps, d) for k, d in grid) <= ll + 1e-9
    k0 = encounter_scale_mle(c, hits, false_hit_rate=eps)
    assert ll >= hit_log_likelihood(c, hits, k0, eps) - 1e-9  # never worse than δ = 0
    if d_hat == 0.0:
        assert k_hat == k0


def test_fit_hit_model_refuses_bad_input_by_name():
    from psgsl_pgm.olfaction import fit_hit_model

    with pytest.raises(ValueError, match="predicted"):
        fit_hit_model([1.0, -1.0], [True, False])
    with pytest.raises(ValueError, match="predicted"):
        fit_hit_model([1.0, np.nan], [True, False])
    with pytest.raises(ValueError, match="false_hit_rate"):
        fit_hit_model([1.0, 2.0], [True, False], false_hit_rate=1.0)
    with pytest.raises(TypeError, match="fit_missed_hits"):
        fit_plume_parameters(_synthetic_runs(0.02, 60.0, 1.5, 0.01, 50, 1), fit_missed_hits="yes")


def test_replace_model_equals_a_fresh_estimator_on_the_new_model():
    occ = np.zeros((12, 16), bool)
    occ[6, 2:10] = True
    wind = np.zeros((12, 16, 2))
    wind[..., 0] = 0.1
    a = PlumeModel(occ, resolution=0.25, diffusivity=0.05, lifetime=20.0, encounter_scale=0.5)
    b = PlumeModel(occ, resolution=0.25, wind=wind, diffusivity=0.03, lifetime=50.0, encounter_scale=0.8)
    rng = np.random.default_rng(4)
    stops = [(0.3 + 3.5 * rng.random(), 0.3 + 1.0 * rng.random()) for _ in range(12)]
    hits = rng.random(12) < 0.4
    for cls in (GridInfotaxis, PMFSEstimator):
        moved, fresh = cls.from_model(a), cls.from_model(b)
        for x, h in zip(stops, hits):
            moved.update(x, bool(h), (0.1, 0.0))
            fresh.update(x, bool(h), (0.1, 0.0))
        assert not np.allclose(moved.posterior, fresh.posterior)
        moved.replace_model(b)
        np.testing.assert_allclose(moved.posterior, fresh.posterior, rtol=1e-12, atol=1e-300)
        assert moved.model is b and moved.n_observations == 12
    with pytest.raises(ValueError, match="same map"):
        GridInfotaxis.from_model(a).replace_model(PlumeModel(np.zeros((12, 16), bool), resolution=0.25))


def test_replace_model_keeps_the_not_found_factors_given_between_readings():
    """A re-solved plume keeps what :meth:`condition` folded in: the result equals a fresh estimator on the new
    model fed the same readings and the same "not found" factors in the same order."""
    occ = np.zeros((12, 16), bool)
    a = PlumeModel(occ, resolution=0.25, diffusivity=0.05, lifetime=20.0, encounter_scale=0.5)
    wind = np.zeros((12, 16, 2))
    wind[..., 1] = 0.1
    b = PlumeModel(occ, resolution=0.25, wind=wind, diffusivity=0.03, lifetime=50.0, encounter_scale=0.8)
    rng = np.random.default_rng(11)
    stops = [(0.3 + 3.5 * rng.random(), 0.3 + 2.5 * rng.random()) for _ in range(8)]
    hits = rng.random(8) < 0.4
    factors = {2: (3, 4), 5: (8, 10)}  # after reading j: the source is not in cell (r, c) or its neighbours
    for cls in (GridInfotaxis, PMFSEstimator):
        moved, fresh = cls.from_model(a), cls.from_model(b)
        for j, (x, h) in enumerate(zip(stops, hits)):
            for est in (moved, fresh):
                est.update(x, bool(h), (0.0, 0.1))
                if j in factors:
                    ll = np.zeros((12, 16))
                    r, c = factors[j]
                    ll[r - 1 : r + 2, c - 1 : c + 2] = -np.inf
                    est.condition(ll)
        moved.replace_model(b)
        np.testing.assert_allclose(moved.posterior, fresh.posterior, rtol=1e-12, atol=1e-300)
        assert moved.posterior[2:5, 3:6].max() == 0.0 and moved.posterior[7:10, 9:12].max() == 0.0


def test_score_tempering_recovers_the_exponent_of_sources_drawn_from_the_tempered_posterior():
    rng = np.random.default_rng(5)
    lam0, n_cells = 0.4, 300
    scores, priors, truth = [], [], []
    for _ in range(600):
        s = rng.normal(0.0, 6.0, n_cells)
        lp = np.full(n_cells, -np.log(n_cells))
        lp[:10] = -np.inf  # cells off the support
        p = np.exp(np.where(np.isfinite(lp), lam0 * s, -np.inf))
        truth.append(rng.choice(n_cells, p=p / p.sum()))
        scores.append(s)
        priors.append(lp)
    lam = score_tempering(scores, priors, truth)
    assert lam == pytest.approx(lam0, rel=0.08)
    # the maximiser: the objective is lower on either side
    from scipy.special import logsumexp

    def obj(x):
        return sum(x * s[t] + lp[t] - logsumexp(lp + x * s) for s, lp, t in zip(scores, priors, truth))
    assert obj(lam) > obj(lam * 1.05) and obj(lam) > obj(lam / 1.05)
    with pytest.raises(ValueError, match="inside the support"):
        score_tempering([np.zeros(3)], [np.array([0.0, -np.inf, 0.0])], [1])


def test_pmfs_tempering_scales_the_log_score():
    occ = np.zeros((8, 10), bool)
    a = PMFSEstimator(occ, resolution=0.25)
    b = PMFSEstimator(occ, resolution=0.25, tempering=0.3)
    for x, h in (((0.6, 0.6), True), ((1.6, 1.1), False), ((2.1, 0.4), True)):
        a.update(x, h, (0.1, 0.0))
        b.update(x, h, (0.1, 0.0))
    np.testing.assert_allclose(b.score, a.score, rtol=1e-12)
    la, lb = a.log_posterior, b.log_posterior
    np.testing.assert_allclose(lb - lb.max(), 0.3 * (la - la.max()), rtol=1e-10, atol=1e-12)


def test_log_conditioning_is_the_sum_of_the_not_found_factors_and_reset_forgets_it():
    occ = np.zeros((6, 8), bool)
    model = PlumeModel(occ, resolution=0.25, diffusivity=0.05, lifetime=20.0, encounter_scale=0.5)
    est = GridInfotaxis.from_model(model)
    np.testing.assert_array_equal(est.log_conditioning, np.zeros((6, 8)))
    a = np.zeros((6, 8))
    a[1, 2] = -np.inf
    b = np.log(np.full((6, 8), 0.5))
    b[4, 4] = 0.0
    est.condition(a)
    est.update((1.0, 1.0), True, (0.1, 0.0))
    est.condition(b)
    np.testing.assert_array_equal(est.log_conditioning, a + b)
    assert not est.log_conditioning.flags.writeable
    est.reset()
    np.testing.assert_array_equal(est.log_conditioning, np.zeros((6, 8)))


def test_hit_residuals_use_the_missed_hit_rate():
    """r_n = (g_n − p_n) / sqrt(p_n (1 − p_n)) with p_n = ε + (1 − ε)(1 − δ)(1 − exp(−κ c_n)): δ changes them."""
    from types import SimpleNamespace

    from psgsl_pgm.olfaction import PlumeFit, hit_residuals

    c = np.array([0.0, 0.5, 2.0, 8.0])
    run = SimpleNamespace(predicted=lambda d, t: c, hits=np.array([False, True, False, True]))
    eps, kappa, delta = 0.02, 0.7, 0.3
    fit = PlumeFit(0.01, 30.0, kappa, -1.0, missed_hit_rate=delta)
    p = eps + (1 - eps) * (1 - delta) * (1 - np.exp(-kappa * c))
    expected = (run.hits - p) / np.sqrt(p * (1 - p))
    np.testing.assert_allclose(hit_residuals([run], fit, false_hit_rate=eps)[0], expected, rtol=1e-12)
    plain = hit_residuals([run], PlumeFit(0.01, 30.0, kappa, -1.0), false_hit_rate=eps)[0]
    assert not np.allclose(plain, expected)
