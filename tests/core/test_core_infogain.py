"""I(S; O_n) from the closed form against the exact joint p(S, O_n | evidence) (tests/core/brute_force.py)."""

import numpy as np
import pytest

from . import brute_force as bf
from psgsl_pgm import semantic_information_gain
from psgsl_pgm.core import _infogain
from .test_core_exactness import beliefs


def library_gain(problem, predictive):
    m = problem.L.shape[0]
    lik, gas = (problem.L[0], None) if m == 1 else (problem.L, problem.gas_weights())
    olfactory = problem.pi * problem.g / (problem.pi @ problem.g)
    return semantic_information_gain(
        beliefs(problem, problem.beta), lik, problem.beta, olfactory=olfactory, gas_probs=gas, predictive=predictive
    )


@pytest.mark.parametrize("predictive", ["exact", "paper"])
@pytest.mark.parametrize("seed", range(25))
def test_information_gain_matches_the_exact_joint(seed, predictive):
    rng = np.random.default_rng(seed)
    n, k, m = int(rng.integers(2, 40)), int(rng.integers(2, 7)), int(rng.integers(1, 3))
    problem = bf.random_problem(rng, n, k, m)
    got = library_gain(problem, predictive)
    want = np.array([bf.mutual_information(problem, c, predictive=predictive) for c in range(n)])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-13)


@pytest.mark.parametrize("predictive", ["exact", "paper"])
def test_series_branch_on_a_large_map_matches_the_exact_joint(predictive):
    """n = 400 cells: a_n ~ 1/n, so nearly every cell goes through the moment series."""
    rng = np.random.default_rng(99)
    problem = bf.random_problem(rng, 400, 5, 2)
    got = library_gain(problem, predictive)
    cells = rng.choice(400, size=25, replace=False)
    want = np.array([bf.mutual_information(problem, c, predictive=predictive) for c in cells])
    np.testing.assert_allclose(got[cells], want, rtol=1e-8, atol=1e-15)


@pytest.mark.parametrize("predictive", ["exact", "paper"])
def test_series_and_elementwise_branches_agree(monkeypatch, predictive):
    rng = np.random.default_rng(4)
    n, k = 3000, 12
    q = rng.dirichlet(np.ones(k) * 0.3, size=n)
    lik = rng.dirichlet(np.ones(k))
    prior = rng.dirichlet(np.ones(k) * 3)
    olf = rng.dirichlet(np.ones(n) * 0.5)
    series = semantic_information_gain(q, lik, prior, olfactory=olf, predictive=predictive)
    monkeypatch.setattr(_infogain, "_RADIUS", -1.0)  # every cell element-wise
    direct = semantic_information_gain(q, lik, prior, olfactory=olf, predictive=predictive)
    np.testing.assert_allclose(series, direct, rtol=1e-9, atol=1e-16)


def test_exact_gain_is_nonnegative_and_zero_where_nothing_can_change():
    rng = np.random.default_rng(8)
    q = rng.dirichlet(np.ones(4), size=200)
    q[:10] = np.eye(4)[0]  # already certain: learning O_n changes nothing
    olf = rng.dirichlet(np.ones(200))
    olf[10:20] = 0.0
    olf /= olf.sum()  # olfaction rules these cells out: their class is irrelevant
    gain = semantic_information_gain(q, [0.5, 0.3, 0.2, 0.0], np.full(4, 0.25), olfactory=olf, predictive="exact")
    assert np.all(gain >= 0)
    np.testing.assert_allclose(gain[:20], 0.0, atol=1e-15)
    assert np.all(gain[20:] > 0)


def test_all_cells_at_once_equals_naive_recomputation_per_cell():
    """Naive O(n²k): for each n and each outcome i, rebuild the posterior and its entropy."""
    rng = np.random.default_rng(12)
    n, k = 60, 5
    q = rng.dirichlet(np.ones(k), size=n)
    lik, prior = rng.dirichlet(np.ones(k)), rng.dirichlet(np.ones(k) * 2)
    rho = lik / prior
    u = q @ rho
    naive = np.empty(n)
    for c in range(n):
        h_cond = []
        for i in range(k):
            new = u.copy()
            new[c] = rho[i]
            h_cond.append(bf.entropy(new / new.sum()))
        naive[c] = bf.entropy(u / u.sum()) - q[c] @ np.array(h_cond)
    np.testing.assert_allclose(semantic_information_gain(q, lik, prior), naive, rtol=1e-10)
