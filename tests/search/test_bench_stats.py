"""The numbers of the benchmark's report: success intervals (Wilson, house-clustered, never a point), the RMST
ratio's interval resampled over houses, the warning on small comparisons and the exploratory label; and the
Monte Carlo sign-flip p-value's (1 + count) / (1 + N)."""

import numpy as np
import pytest
from scipy import stats

from psgsl_pgm.search._bench_report import MIN_EPISODES, _arm_stats, _markdown, _ratio
from psgsl_pgm.search._metrics import clustered_wilson, wilson_interval
from psgsl_pgm.search._survival import EXACT_MAX, nested_bootstrap, sign_flip_pvalue


@pytest.mark.parametrize("k, n", [(0, 5), (1, 5), (8, 10), (10, 10), (248, 250), (250, 250), (3, 17)])
def test_wilson_equals_scipy(k, n):
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    np.testing.assert_allclose(wilson_interval(k, n), [ci.low, ci.high], rtol=0, atol=1e-12)


def test_clustered_wilson_limits_and_never_a_point():
    rng = np.random.default_rng(1)
    y = rng.random(40) < 0.7
    # one episode per house: the design effect is 1, the plain Wilson interval
    r = clustered_wilson(y, np.arange(40))
    assert r["design_effect"] == 1.0 and r["ci95"] == pytest.approx(wilson_interval(int(y.sum()), 40), abs=1e-12)
    # houses whose 5 episodes all agree: design effect 5, the Wilson interval of the 8 houses
    houses = np.repeat(np.arange(8), 5)
    agree = np.repeat(np.array([1, 1, 0, 1, 1, 1, 0, 1], dtype=bool), 5)
    r = clustered_wilson(agree, houses)
    assert r["design_effect"] == pytest.approx(5.0, rel=1e-12) and r["n_effective"] == pytest.approx(8.0)
    assert r["ci95"] == pytest.approx(wilson_interval(6, 8), abs=1e-12)
    # the ratio-estimator variance by hand for unequal houses
    g = np.array([0, 0, 0, 1, 1, 2, 2, 2, 2, 3])
    s = np.array([1, 0, 0, 1, 1, 1, 1, 0, 1, 1], dtype=bool)
    p = s.mean()
    var = sum((s[g == h].sum() - p * (g == h).sum()) ** 2 for h in range(4)) / s.size**2
    assert clustered_wilson(s, g)["design_effect"] == pytest.approx(max(1.0, var / (p * (1 - p) / s.size)))
    # every episode found: an interval [lo, 1] with lo < 1, not "100 % [100, 100]"
    r = clustered_wilson(np.ones(250, bool), np.repeat(np.arange(50), 5))
    assert r["value"] == 1.0 and r["ci95"][1] == 1.0 and r["ci95"][0] < 0.99
    with pytest.raises(ValueError, match="bool"):
        clustered_wilson([1, 0], [0, 1])


def _rows(n_houses=4, n_seeds=3, seed=0):
    rng = np.random.default_rng(seed)
    rows = []
    for h in range(n_houses):
        slow = rng.uniform(100, 600)  # houses differ: their episodes are correlated
        for s in range(n_seeds):
            t_b = min(1000.0, slow + rng.uniform(0, 200))
            for arm, t in (("A", 0.7 * t_b + rng.uniform(0, 30)), ("B", t_b)):
                rows.append({"house": f"h{h:05d}", "seed": s, "condition": "right-ontology", "arm": arm,
                             "found": t < 1000.0, "t": t, "kind": "object", "class": "oven", "gas": "smoke",
                             "cpu": None})
    return rows


def test_rmst_ratio_is_resampled_over_houses_not_seeds():
    rows = _rows()
    a = [r for r in rows if r["arm"] == "A"]
    b = [r for r in rows if r["arm"] == "B"]
    r = _ratio(a, b)
    keys = sorted((x["house"], x["seed"]) for x in a)
    v = np.array([[next(x["t"] for x in a if (x["house"], x["seed"]) == k) for k in keys],
                  [next(x["t"] for x in b if (x["house"], x["seed"]) == k) for k in keys]])
    want = nested_bootstrap(v, [k[0] for k in keys], lambda x: x[0].mean() / x[1].mean())
    assert r["houses"] == 4 and r["n"] == 12
    assert r["ci95"] == want["ci95"] and r["value"] == pytest.approx(v[0].mean() / v[1].mean())
    by_seed = nested_bootstrap(v, [k[1] for k in keys], lambda x: x[0].mean() / x[1].mean())
    assert by_seed["ci95"] != want["ci95"]  # the test can tell the two apart


def test_arm_success_is_the_house_clustered_wilson_interval():
    rows = [r for r in _rows() if r["arm"] == "B"]
    s = _arm_stats(rows, 1000.0)
    found = np.array([r["found"] for r in rows])
    want = clustered_wilson(found, [r["house"] for r in rows])
    assert s["success_rate"]["ci95"] == want["ci95"] and s["success_rate"]["ci95"][0] < 1.0
    assert s["success_rate"]["wilson95"] == wilson_interval(int(found.sum()), found.size)


def test_report_warns_on_small_comparisons_and_labels_secondary_ones_exploratory():
    rows = _rows()  # 12 paired episodes: fewer than MIN_EPISODES
    a = [r for r in rows if r["arm"] == "A"]
    b = [r for r in rows if r["arm"] == "B"]
    p = _ratio(a, b)
    assert p["n"] < MIN_EPISODES
    settings = {"houses": sorted({r["house"] for r in rows}), "seeds": [0, 1, 2], "budget": 1000.0,
                "estimator": "infotaxis", "gases": ["smoke"], "off_rate": 0.1, "world": None, "split": "dev"}
    stats_ = {"right-ontology": {"A": _arm_stats(a, 1000.0)}}
    md = _markdown(settings, stats_, {"primary": p, "costs": {"primary ratio under no-rooms": p}}, {}, [], "0")
    warnings = [line for line in md.splitlines() if line.startswith("Warning:")]
    assert len(warnings) == 2 and all(f"rests on {p['n']} paired episodes" in w for w in warnings)
    assert "## Costs beside it (secondary, exploratory)" in md and "Split: **dev**" in md
    big = dict(p, n=MIN_EPISODES)
    md = _markdown(settings, stats_, {"primary": big, "costs": {}}, {}, [], "0")
    assert "Warning:" not in md


def test_monte_carlo_sign_flip_pvalue_is_one_plus_count_over_one_plus_n():
    d = np.ones(EXACT_MAX + 4)  # only the all-equal sign vectors reach |Σ d|: 2 of 2^20
    r = sign_flip_pvalue(d, n_resamples=10, seed=0)
    assert r["method"].startswith("monte carlo")
    assert r["p_value"] == 1 / 11  # (1 + 0) / (1 + 10): never 0
    rng = np.random.default_rng(5)
    d = rng.normal(0.2, 1.0, EXACT_MAX + 3)
    signs = np.random.default_rng(9).choice(np.array([-1.0, 1.0]), size=(500, d.size))
    count = int(np.count_nonzero(np.abs(signs @ d) >= abs(d.sum()) - 1e-12 * np.abs(d).sum()))
    assert sign_flip_pvalue(d, n_resamples=500, seed=9)["p_value"] == (1 + count) / 501
