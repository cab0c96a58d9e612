"""Censored times to find: Kaplan–Meier and its bands, RMST and its interval (against lifelines and by hand),
the paired sign-flip test, the bootstrap interval and Holm's adjustment."""

import itertools

import numpy as np
import pytest
from scipy import stats

from psgsl_pgm.search._survival import (EXACT_MAX, bootstrap_mean_ci, holm, kaplan_meier, km_median,
                                        paired_comparison, rmst, sign_flip_pvalue)

lifelines = pytest.importorskip("lifelines")
Z = stats.norm.ppf(0.975)

# hand-made samples: ties of events, an event tied with a censoring, all found, none found, an event at 0
HAND = [
    ([2.0, 3.0, 5.0, 7.0, 8.0], [True, False, True, False, True]),
    ([10.0, 10.0, 20.0, 20.0, 20.0, 35.0, 50.0], [True, True, True, False, True, False, True]),
    ([4.0, 1.0, 3.0, 2.0], [True, True, True, True]),
    ([100.0, 100.0, 100.0], [False, False, False]),
    ([0.0, 5.0, 9.0, 9.0], [True, False, True, True]),
]


def _random_samples():
    rng = np.random.default_rng(12)
    for n in (1, 2, 5, 13, 40, 200):
        t = np.round(rng.exponential(300.0, n))  # rounded: ties occur
        c = np.round(rng.uniform(0.0, 900.0, n))
        yield np.minimum(t, c), t <= c


SAMPLES = HAND + list(_random_samples())


@pytest.mark.parametrize("times, found", SAMPLES)
def test_kaplan_meier_and_bands_equal_lifelines(times, found):
    times, found = np.asarray(times, float), np.asarray(found)
    km = kaplan_meier(times, found)
    ref = lifelines.KaplanMeierFitter().fit(times, found)
    np.testing.assert_array_equal(km["t"], ref.timeline)
    np.testing.assert_allclose(km["survival"], ref.survival_function_.iloc[:, 0], rtol=0, atol=1e-13)
    ci = ref.confidence_interval_.to_numpy()  # exponential Greenwood, lifelines' default
    np.testing.assert_allclose(km["lower"], ci[:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(km["upper"], ci[:, 1], rtol=0, atol=1e-12)
    med = km_median(km)
    assert (np.inf if med is None else med) == ref.median_survival_time_


@pytest.mark.parametrize("times, found", SAMPLES)
def test_rmst_equals_lifelines(times, found):
    from lifelines.utils import restricted_mean_survival_time

    times, found = np.asarray(times, float), np.asarray(found)
    ref = lifelines.KaplanMeierFitter().fit(times, found)
    for tau in (0.5 * times.max() + 1.0, times.max(), times.max() + 50.0):
        assert rmst(times, found, tau)["value"] == pytest.approx(restricted_mean_survival_time(ref, t=tau),
                                                                 rel=1e-12, abs=1e-12)


def test_km_rmst_and_greenwood_variance_by_hand():
    """T = 2, 3+, 5, 7+, 8 (+: censored), τ = 10: S = 0.8 on [2, 5), 0.8·2/3 on [5, 8), 0 from 8.
    RMST = 2 + 3·0.8 + 3·(8/15) = 6; Var = A(2)² /(5·4) + A(5)² /(3·2) with A(2) = 4, A(5) = 1.6
    (the event at 8 empties the risk set: A = 0, no term)."""
    times, found = [2.0, 3.0, 5.0, 7.0, 8.0], [True, False, True, False, True]
    km = kaplan_meier(times, found)
    np.testing.assert_allclose(km["survival"], [1.0, 0.8, 0.8, 8 / 15, 8 / 15, 0.0], rtol=1e-15)
    r = rmst(times, found, 10.0)
    var = 16 / 20 + 1.6**2 / 6
    assert r["value"] == pytest.approx(6.0, rel=1e-14)
    assert r["se"] == pytest.approx(np.sqrt(var), rel=1e-14)
    np.testing.assert_allclose(r["ci95"], [6 - Z * np.sqrt(var), 6 + Z * np.sqrt(var)], rtol=1e-14)
    # the band at t = 2 by hand: σ² = 1/(5·4), S^exp(±zσ/ln S)
    s, sig = 0.8, np.sqrt(1 / 20)
    np.testing.assert_allclose([km["lower"][1], km["upper"][1]],
                               [s ** np.exp(-Z * sig / np.log(s)), s ** np.exp(Z * sig / np.log(s))], rtol=1e-13)
    assert km_median(km) == 8.0  # S first ≤ ½ at 8 (8/15 > ½)


def test_greenwood_rmst_with_censoring_at_the_budget_only_is_the_mean_of_capped_times():
    """Administrative censoring at τ: RMST(τ) = mean(min(T, τ)), Var = var(min(T, τ)) / n (plug-in variance)."""
    rng = np.random.default_rng(3)
    for n in (3, 10, 57):
        tau = 1000.0
        t = rng.exponential(600.0, n)
        capped, found = np.minimum(t, tau), t <= tau
        r = rmst(capped, found, tau)
        assert r["value"] == pytest.approx(capped.mean(), rel=1e-12)
        assert r["se"] == pytest.approx(np.sqrt(capped.var() / n), rel=1e-10)
        lo, hi = capped.mean() - Z * r["se"], capped.mean() + Z * r["se"]
        np.testing.assert_allclose(r["ci95"], [max(lo, 0.0), min(hi, tau)], rtol=1e-12)


def test_rmst_interval_stays_within_zero_and_the_budget():
    r = rmst([10.0, 1000.0, 1000.0], [True, False, False], 1000.0)
    assert r["ci95"][1] == 1000.0 and r["ci95"][0] < r["value"] < 1000.0
    none = rmst([1000.0] * 4, [False] * 4, 1000.0)  # no event: the estimate is τ, with no spread to estimate
    assert none["value"] == 1000.0 and none["ci95"] == [1000.0, 1000.0]


def test_holm_by_hand():
    # sorted: 0.005·4 = 0.02, 0.01·3 = 0.03, 0.03·2 = 0.06, 0.04·1 = 0.04 -> running max 0.06
    np.testing.assert_allclose(holm([0.01, 0.04, 0.03, 0.005]), [0.03, 0.06, 0.06, 0.02], rtol=1e-15)
    # sorted: 0.2·3 = 0.6, 0.6·2 = 1.2 -> capped at 1, 0.7·1 = 0.7 -> running max 1
    np.testing.assert_allclose(holm([0.6, 0.2, 0.7]), [1.0, 0.6, 1.0], rtol=1e-15)
    np.testing.assert_allclose(holm([0.4, 0.45]), [0.8, 0.8], rtol=1e-15)
    assert holm([0.7]).tolist() == [0.7]
    with pytest.raises(ValueError, match="pvalues must be probabilities"):
        holm([0.1, 1.5])


def _brute_force_pvalue(d):
    obs = abs(sum(d))
    hits = [abs(sum(s * x for s, x in zip(signs, d))) >= obs - 1e-9
            for signs in itertools.product((1, -1), repeat=len(d))]
    return sum(hits) / len(hits)


def test_sign_flip_exact_equals_enumeration_by_hand():
    assert sign_flip_pvalue([1.0, 2.0, 3.0]) == {"p_value": 0.25, "method": "exact"}
    assert sign_flip_pvalue([1.0, 1.0])["p_value"] == 0.5  # sums 2, 0, 0, -2
    assert sign_flip_pvalue([0.0, 0.0, 0.0])["p_value"] == 1.0
    rng = np.random.default_rng(7)
    for n in (1, 4, 7, 10):
        d = np.round(rng.normal(0.3, 1.0, n), 1)  # rounded: ties among |Σ s d|
        assert sign_flip_pvalue(d)["p_value"] == pytest.approx(_brute_force_pvalue(d), abs=1e-15)


def test_sign_flip_monte_carlo_is_seeded_and_close_to_exact():
    rng = np.random.default_rng(8)
    d = rng.normal(0.4, 1.0, EXACT_MAX + 2)
    bits = (np.arange(2 ** d.size)[:, None] >> np.arange(d.size)) & 1
    exact = float(np.mean(np.abs((1 - 2.0 * bits) @ d) >= abs(d.sum()) * (1 - 1e-12)))
    mc = sign_flip_pvalue(d, n_resamples=40_000, seed=3)
    assert mc == sign_flip_pvalue(d, n_resamples=40_000, seed=3) and mc["method"].startswith("monte carlo")
    se = np.sqrt(exact * (1 - exact) / 40_000)
    assert abs(mc["p_value"] - exact) < 4 * se + 1 / 40_000


def test_bootstrap_interval_is_the_percentile_interval_of_resampled_means():
    v = np.array([3.0, -1.0, 4.0, 1.0, -5.0, 9.0])
    rng = np.random.default_rng(11)
    means = np.array([v[rng.integers(0, 6, 6)].mean() for _ in range(2000)])
    np.testing.assert_allclose(bootstrap_mean_ci(v, n_resamples=2000, seed=11), np.quantile(means, [0.025, 0.975]),
                               rtol=1e-14)
    assert bootstrap_mean_ci([5.0, 5.0]) == [5.0, 5.0]


def test_paired_comparison_is_the_rmst_difference_and_a_sign_flip_is_caught():
    tau = 1000.0
    a = np.array([120.0, 80.0, 1000.0, 300.0, 45.0, 60.0, 210.0])  # a faster on most seeds
    b = np.array([500.0, 1000.0, 1000.0, 280.0, 400.0, 700.0, 1000.0])
    r = paired_comparison(a, b, tau)
    ra, rb = rmst(a, a < tau, tau)["value"], rmst(b, b < tau, tau)["value"]
    assert r["value"] == pytest.approx(ra - rb, rel=1e-12) == np.mean(a - b)
    assert r["value"] < 0 and r["ci95"][1] < 0  # A − B: negative when A is faster
    assert r["p_value"] == pytest.approx(_brute_force_pvalue(a - b), abs=1e-15) and r["n"] == 7
    back = paired_comparison(b, a, tau)
    assert back["value"] == -r["value"] and back["p_value"] == r["p_value"]
    np.testing.assert_allclose(back["ci95"], [-r["ci95"][1], -r["ci95"][0]], rtol=1e-12)


@pytest.mark.parametrize("call, match", [
    (lambda: paired_comparison([1.0, 2.0], [1.0], 10.0), "paired"),
    (lambda: paired_comparison([1.0, 20.0], [1.0, 2.0], 10.0), r"times_a must be times in \[0, tau = 10\]"),
    (lambda: kaplan_meier([1.0, -2.0], [True, True]), "times must be"),
    (lambda: kaplan_meier([1.0, 2.0], [1, 0]), "found must be a bool array"),
    (lambda: rmst([1.0], [True], 0.0), "tau must be a positive"),
    (lambda: sign_flip_pvalue([]), "differences must be a non-empty"),
])
def test_bad_input_names_the_argument(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def test_survival_step_function_equals_kaplan_meier_when_censored_at_the_budget():
    from psgsl_pgm.search import kaplan_meier, survival

    rng = np.random.default_rng(7)
    budget = 1000.0
    t = np.minimum(rng.exponential(600.0, size=25).round(), budget)
    found = t < budget
    km = kaplan_meier(t, found)
    grid = np.array(km["t"])
    np.testing.assert_allclose(survival(t, found, grid), km["survival"], rtol=0, atol=1e-14)


def test_paired_difference_is_the_mean_of_differences_with_a_t_interval():
    from scipy import stats

    from psgsl_pgm.search import paired_difference

    a, b = np.array([1.0, 2.5, 4.0, 3.0]), np.array([0.5, 2.0, 1.0, 3.5])
    d = a - b
    out = paired_difference(a, b)
    half = stats.t.ppf(0.975, 3) * d.std(ddof=1) / 2.0
    assert out["n"] == 4 and out["mean"] == pytest.approx(d.mean(), rel=1e-15)
    np.testing.assert_allclose(out["ci95"], [d.mean() - half, d.mean() + half], rtol=1e-12)


# --- nested bootstrap (houses, then seeds) ---------------------------------------------------------------------
def _nested_variance(x):
    """Exact variance of the two-stage bootstrap mean for a balanced (H, S) design: with m_h the house means,
    σ²_h the within-house plug-in variances, Var = [Σ(m_h − m)²/H + Σσ²_h/(H S)] / H."""
    h, s = x.shape
    m = x.mean(axis=1)
    return (((m - m.mean()) ** 2).mean() + x.var(axis=1).mean() / s) / h


def test_nested_bootstrap_variance_formula_by_enumeration():
    import itertools

    x = np.array([[1.0, 4.0], [10.0, 13.5]])
    means = []
    for hs in itertools.product(range(2), repeat=2):  # every draw of houses, then of seeds in each: 64 outcomes
        for ss in itertools.product(itertools.product(range(2), repeat=2), repeat=2):
            means.append(np.mean([x[h, k] for h, pick in zip(hs, ss) for k in pick]))
    means = np.array(means)
    assert means.mean() == pytest.approx(x.mean(), rel=1e-12)
    assert means.var() == pytest.approx(_nested_variance(x), rel=1e-12)


def test_nested_indices_reproduce_the_exact_variance():
    from psgsl_pgm.search._survival import nested_indices

    rng = np.random.default_rng(3)
    x = rng.gamma(2.0, 50.0, size=(6, 4)) + 100.0 * np.arange(6)[:, None]  # houses differ, seeds within
    flat, groups = x.ravel(), np.repeat(np.arange(6), 4)
    draws = np.array([flat[nested_indices(groups, rng)].mean() for _ in range(40_000)])
    assert draws.mean() == pytest.approx(x.mean(), rel=5e-3)
    assert draws.var() == pytest.approx(_nested_variance(x), rel=0.03)  # MC: sd of a variance ≈ √(2/N) ≈ 0.7 %
    # ignoring the houses would give the (smaller) i.i.d. variance: the test tells them apart
    assert flat.var() / flat.size < 0.5 * _nested_variance(x)


def test_nested_bootstrap_groups_need_not_be_adjacent_and_keep_pairs():
    from psgsl_pgm.search._survival import nested_bootstrap

    a = np.array([10.0, 20.0, 30.0, 40.0, 50.0, 60.0])
    groups = np.array(["h1", "h0", "h1", "h2", "h0", "h2"])
    same = nested_bootstrap(np.stack([a, a]), groups, lambda v: v[0].mean() / v[1].mean(), n_resamples=500)
    assert same["value"] == 1.0 and same["ci95"] == [1.0, 1.0]  # pairs stay pairs
    half = nested_bootstrap(np.stack([a / 2, a]), groups, lambda v: v[0].mean() / v[1].mean(), n_resamples=500)
    assert half["ci95"] == [pytest.approx(0.5, rel=1e-12)] * 2
    r = nested_bootstrap(a, groups, n_resamples=2000, seed=1)
    assert r["value"] == pytest.approx(35.0, rel=1e-12) and r["groups"] == 3 and r["n"] == 6
    assert 10.0 <= r["ci95"][0] < 35.0 < r["ci95"][1] <= 60.0
    assert r == nested_bootstrap(a, groups, n_resamples=2000, seed=1)  # seeded


def test_nested_bootstrap_bad_input():
    from psgsl_pgm.search._survival import nested_bootstrap

    with pytest.raises(ValueError, match="groups must give one group per run"):
        nested_bootstrap([1.0, 2.0], [0])
    with pytest.raises(ValueError, match="values must be"):
        nested_bootstrap([1.0, np.nan], [0, 1])
    with pytest.raises(ValueError, match="statistic is required"):
        nested_bootstrap([[1.0, 2.0], [1.0, 2.0]], [0, 1])
