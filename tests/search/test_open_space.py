"""Open-space benchmark: the POMDP's definitions, the exact belief update, the policies' scores."""

import itertools

import numpy as np
import pytest
from scipy.special import k0

from psgsl_pgm.search import OpenSpaceSearch, grid_size, hit_probability, open_space_benchmark


def test_grid_size_from_the_1e3_rule():
    assert [grid_size(lambda_over_dx=l, r_dt=r) for l, r in ((1, 1), (2, 2), (3, 1))] == [19, 35, 51]


def test_hit_probability_is_loisy_eloy_mu():
    d = np.array([1.0, 2.0, np.sqrt(5.0), 7.5])
    for lam, r in ((1.0, 1.0), (2.0, 2.0), (3.0, 1.0)):
        mu = r / np.log(2 * lam) * k0(d / lam)
        np.testing.assert_allclose(hit_probability(d, lambda_over_dx=lam, r_dt=r), 1 - np.exp(-mu), rtol=1e-12)


def _brute_posterior(n, lam, r, history):
    """Bayes by a loop over candidate sources: prior ∝ P(hit at centre | s), then each (cell, hit)."""
    c = n // 2
    post = np.zeros((n, n))
    for i, j in itertools.product(range(n), range(n)):
        if (i, j) == (c, c):
            continue
        p = float(hit_probability(np.hypot(i - c, j - c), lambda_over_dx=lam, r_dt=r))
        for (a, b), hit in history:
            if (i, j) == (a, b):
                p = 0.0
                break
            q = float(hit_probability(np.hypot(i - a, j - b), lambda_over_dx=lam, r_dt=r))
            p *= q if hit else 1 - q
        post[i, j] = p
    return post / post.sum()


def test_belief_update_matches_brute_force():
    env = OpenSpaceSearch(lambda_over_dx=2.0, r_dt=2.0, n=9)
    np.testing.assert_allclose(env.belief, _brute_posterior(9, 2.0, 2.0, []), rtol=1e-10, atol=1e-15)
    history = []
    for cell, hit in (((4, 5), False), ((4, 6), True), ((3, 6), False), ((3, 5), False)):
        env.agent = np.array(cell)
        env.observe(hit)
        history.append((cell, hit))
    np.testing.assert_allclose(env.belief, _brute_posterior(9, 2.0, 2.0, history), rtol=1e-10, atol=1e-15)


def _entropy_bits(p):
    p = p[p > 0]
    return float(-(p * np.log2(p)).sum())


def test_infotaxis_and_space_aware_scores_match_a_direct_computation():
    env = OpenSpaceSearch(lambda_over_dx=1.0, r_dt=1.0, n=7)
    env.agent = np.array([3, 4])
    env.observe(False)
    cells, info = env.scores("infotaxis")
    _, space = env.scores("space-aware-infotaxis")
    rows, cols = np.mgrid[0:7, 0:7]
    for k, (a, b) in enumerate(cells):
        p_end = env.belief[a, b]
        q = env.belief.copy()
        q[a, b] = 0
        q /= q.sum()
        lik = hit_probability(np.hypot(rows - a, cols - b), lambda_over_dx=1.0, r_dt=1.0)
        exp_h, exp_v = 0.0, 0.0
        for like in (lik, 1 - lik):
            ph = (q * like).sum()
            post = q * like / ph
            h = _entropy_bits(post)
            dist = (post * (np.abs(rows - a) + np.abs(cols - b))).sum()
            exp_h += ph * h
            exp_v += ph * np.log2(dist + 2 ** (h - 1) - 0.5)
        assert info[k] == pytest.approx((1 - p_end) * exp_h, rel=1e-10)
        assert space[k] == pytest.approx((1 - p_end) * exp_v, rel=1e-10)


def test_a_known_source_is_reached_by_the_shortest_path():
    """With all the mass on one cell the optimal policy walks the Manhattan distance; space-aware
    infotaxis (D_h + 2^(H-1) - 1/2 = D) and greedy-towards-it do exactly that."""
    env = OpenSpaceSearch(lambda_over_dx=1.0, r_dt=1.0, n=9)
    target = (1, 6)
    env.belief = np.zeros((9, 9))
    env.belief[target] = 1.0
    rng = np.random.default_rng(0)
    steps = 0
    while True:
        steps += 1
        if env.move(env.choose("space-aware-infotaxis"), target, rng):
            break
        assert steps < 20
    assert steps == abs(4 - 1) + abs(4 - 6)


def test_infotaxis_steps_onto_a_neighbour_holding_the_mass():
    env = OpenSpaceSearch(lambda_over_dx=1.0, r_dt=1.0, n=5)
    env.belief = np.zeros((5, 5))
    env.belief[2, 3] = 0.6
    env.belief[1, 2] = 0.4
    assert tuple(env.choose("infotaxis")) == (2, 3)
    assert tuple(env.choose("greedy")) == (2, 3)


def test_benchmark_is_seeded_and_counts_moves():
    a = open_space_benchmark("infotaxis", lambda_over_dx=1.0, r_dt=1.0, episodes=5, seed=3)
    b = open_space_benchmark("infotaxis", lambda_over_dx=1.0, r_dt=1.0, episodes=5, seed=3)
    np.testing.assert_array_equal(a["steps"], b["steps"])
    assert a["n"] == 19 and a["p_not_found"] == 0.0 and (a["steps"] >= 1).all()
    assert a["mean_steps"] == pytest.approx(a["steps"].mean())
    capped = open_space_benchmark("greedy", lambda_over_dx=1.0, r_dt=1.0, episodes=40, seed=3, max_steps=1)
    assert (capped["steps"] == 1).all()
    assert 0.0 < capped["p_not_found"] < 1.0  # a first move finds the source only sometimes
    assert capped["mean_steps"] == 1.0 and capped["median"] == 1.0


@pytest.mark.parametrize("kwargs, exc", [
    (dict(policy="random"), ValueError),
    (dict(episodes=0), ValueError),
    (dict(episodes=2.5), TypeError),
    (dict(lambda_over_dx=-1.0), ValueError),
    (dict(r_dt=True), TypeError),
])
def test_bad_arguments(kwargs, exc):
    args = dict(policy="infotaxis", lambda_over_dx=1.0, r_dt=1.0, episodes=1, seed=0) | kwargs
    policy = args.pop("policy")
    with pytest.raises(exc):
        open_space_benchmark(policy, **args)


def test_illegal_move_is_refused():
    env = OpenSpaceSearch(lambda_over_dx=1.0, r_dt=1.0, n=5)
    with pytest.raises(ValueError, match="legal move"):
        env.move((0, 0), (1, 1), np.random.default_rng(0))


@pytest.mark.parametrize("miss", [0.0, 0.3])
def test_not_found_update_leaves_the_modelled_mass_and_matches_the_success_rule(miss):
    """The open-space loop uses the closed loop's detection model: "not found" multiplies the agent's cell by m,
    P_end = (1 − m) p(new cell), and the success rule finds a source only in the agent's own cell."""
    env = OpenSpaceSearch(lambda_over_dx=2.0, r_dt=2.0, n=9, miss_probability=miss)
    env.agent = np.array([4, 5])
    before = env.belief.copy()
    env.observe(True)
    lik = env.likelihood(env.agent, True)
    w = np.ones_like(before)
    w[4, 5] = miss
    expect = before * w * lik
    np.testing.assert_allclose(env.belief, expect / expect.sum(), rtol=1e-12, atol=1e-300)
    a = before[4, 5] * lik[4, 5]
    share = miss * a / (miss * a + (before * lik).sum() - a)
    np.testing.assert_allclose(env.belief[4, 5], share, rtol=1e-12, atol=1e-300)
    o = env.outcomes()
    np.testing.assert_allclose(o["p_end"], (1 - miss) * env.belief[o["cells"][:, 0], o["cells"][:, 1]], rtol=1e-15)
    det = env.detection
    for x in o["cells"]:  # success rule vs the hypotheses each move can find, every source cell
        xy = env._xy(x)
        row = det.rows(xy).toarray()[0]
        for s in range(env.n * env.n):
            assert det.found(xy, s)[0] == row[s] == (s == x[0] * env.n + x[1])


def test_a_detector_that_misses_needs_more_steps_and_is_seeded():
    a = open_space_benchmark("infotaxis", lambda_over_dx=1.0, r_dt=1.0, episodes=20, seed=5, miss_probability=0.5)
    b = open_space_benchmark("infotaxis", lambda_over_dx=1.0, r_dt=1.0, episodes=20, seed=5, miss_probability=0.5)
    c = open_space_benchmark("infotaxis", lambda_over_dx=1.0, r_dt=1.0, episodes=20, seed=5)
    np.testing.assert_array_equal(a["steps"], b["steps"])
    assert a["steps"].sum() > c["steps"].sum()
    with pytest.raises(ValueError, match="miss_probability"):
        OpenSpaceSearch(lambda_over_dx=1.0, r_dt=1.0, miss_probability=1.0)
