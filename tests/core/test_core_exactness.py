"""The closed form against brute force (tests/core/brute_force.py): exact with the background prior, the paper's
approximation with the marginal prior, gas mixtures, voxel columns, room evidence and fusion priors."""

from dataclasses import replace

import numpy as np
import pytest

from . import brute_force as bf
from psgsl_pgm import Ontology, fuse, room_evidence, semantic_source_probability, update_class_probs

RTOL = 1e-10  # exact results: round-off only


def beliefs(problem, prior):
    """p(o_c | z_c) under ``prior``, by the library's Bayesian update (cells without observations keep it)."""
    q = np.broadcast_to(prior, (problem.n, prior.size)).copy()
    for c, obs in enumerate(problem.obs):
        for lik in obs:
            q[c] = update_class_probs(q[c][None, :], lik)[0]
    return q


def closed_form(problem, prior=None):
    prior = problem.beta if prior is None else prior
    m = problem.L.shape[0]
    lik, gas = (problem.L[0], None) if m == 1 else (problem.L, problem.gas_weights())
    semantic = semantic_source_probability(beliefs(problem, prior), lik, prior, gas_probs=gas, source_prior=problem.pi)
    olfactory = problem.pi * problem.g / (problem.pi @ problem.g)  # p(s|g) ∝ p(s) p(g|s)
    return fuse(olfactory, semantic, prior=problem.pi)


@pytest.mark.parametrize("seed", range(40))
def test_exact_against_enumeration_of_all_object_maps(seed):
    rng = np.random.default_rng(seed)
    n, k, m = int(rng.integers(1, 5)), int(rng.integers(2, 4)), int(rng.integers(1, 3))
    problem = bf.random_problem(rng, n, k, m)
    np.testing.assert_allclose(closed_form(problem), bf.enumerate_posterior(problem), rtol=RTOL, atol=0)


@pytest.mark.parametrize("seed", range(40))
def test_exact_against_full_product_on_larger_maps(seed):
    rng = np.random.default_rng(1000 + seed)
    n, k, m = int(rng.integers(5, 80)), int(rng.integers(2, 9)), int(rng.integers(1, 4))
    problem = bf.random_problem(rng, n, k, m, max_obs=4)
    np.testing.assert_allclose(closed_form(problem), bf.product_posterior(problem), rtol=RTOL, atol=1e-300)


@pytest.mark.parametrize("seed", range(30))
def test_off_ontology_likelihood_is_exact_for_the_on_off_mixture(seed):
    """Ontology.source_likelihood(off_ontology=ε) in the closed form = enumeration over the object maps and a
    latent on/off-ontology choice of the source (ε at both ends included)."""
    rng = np.random.default_rng(3000 + seed)
    n, k, m = int(rng.integers(1, 5)), int(rng.integers(2, 4)), int(rng.integers(1, 3))
    problem = bf.random_problem(rng, n, k, m)
    eps = (0.0, 1.0, float(rng.uniform()))[seed % 3]
    ontology = Ontology([f"class{i}" for i in range(k - 1)] + ["other"], [f"gas{j}" for j in range(m)],
                        problem.L, class_prior=problem.beta)
    mixed = replace(problem, L=ontology.source_likelihood(off_ontology=eps))
    np.testing.assert_allclose(closed_form(mixed), bf.enumerate_posterior(problem, off_ontology=eps), rtol=RTOL,
                               atol=0)
    if 0 < eps < 1 and n > 1:  # the latent choice matters: not the posterior of either ontology alone
        for alone in (0.0, 1.0):
            assert not np.allclose(bf.enumerate_posterior(problem, off_ontology=alone),
                                   bf.enumerate_posterior(problem, off_ontology=eps), rtol=1e-6, atol=0)


def test_marginal_prior_is_an_approximation_whose_error_shrinks_with_n():
    """Paper: p(o_ni | s_c) ≈ p(o_ni). Mean total-variation error over 20 seeded problems per n."""
    errors = []
    for n in (4, 16, 64, 256):
        tv = []
        for seed in range(20):
            rng = np.random.default_rng(seed)
            problem = bf.random_problem(rng, n, 4, 1, uniform_prior=True)
            marginal = problem.L[0] / n + (1 - 1 / n) * problem.beta  # p(o_n) = p(s_n)L + p(¬s_n)β
            tv.append(0.5 * np.abs(closed_form(problem, marginal) - bf.product_posterior(problem)).sum())
        errors.append(np.mean(tv))
    # Strictly decreasing, and roughly ∝ 1/n: each 4× more cells cut the error by at least 2×.
    assert all(b < a / 2 for a, b in zip(errors, errors[1:])), errors
    assert errors[0] > 1e-3  # it is a real approximation, not exact by accident


def test_voxel_columns_equal_the_exact_column_marginal():
    """Sec. "Voxelized Scene Representations": S over voxels, p(s_c | z) = Σ_{v∈c} p(s_v | z)."""
    rng = np.random.default_rng(7)
    shape, k = (3, 4, 5), 4
    problem = bf.random_problem(rng, int(np.prod(shape)), k, 1, uniform_prior=True)
    problem.g = np.ones(problem.n)  # semantic evidence only
    exact = bf.product_posterior(problem).reshape(shape).sum(axis=2)
    q = beliefs(problem, problem.beta).reshape(shape + (k,))
    for axis in (2, -1):
        got = semantic_source_probability(q, problem.L[0], problem.beta, column_axis=axis)
        assert got.shape == shape[:2]
        np.testing.assert_allclose(got, exact, rtol=RTOL)
    got0 = semantic_source_probability(q, problem.L[0], problem.beta, column_axis=0)
    np.testing.assert_allclose(got0, bf.product_posterior(problem).reshape(shape).sum(axis=0), rtol=RTOL)


def test_room_evidence_is_an_observation_with_likelihood_p_o_given_room_over_p_o():
    rng = np.random.default_rng(11)
    n, k, r = 30, 5, 3
    problem = bf.random_problem(rng, n, k, 1)
    table = rng.dirichlet(np.ones(k), size=r)
    labels = rng.integers(-1, r, size=n)
    factor = room_evidence(labels, table, problem.beta)
    for c in range(n):
        if labels[c] >= 0:
            problem.obs[c].append(table[labels[c]] / problem.beta)  # the reference treats it as one more z
    start = update_class_probs(problem.beta, factor)
    np.testing.assert_allclose(start[labels >= 0], table[labels[labels >= 0]], rtol=1e-12)
    q = start.copy()
    for c, obs in enumerate(problem.obs):
        for lik in obs[:-1] if labels[c] >= 0 else obs:
            q[c] = update_class_probs(q[c][None, :], lik)[0]
    semantic = semantic_source_probability(q, problem.L[0], problem.beta, source_prior=problem.pi)
    fused = fuse(problem.pi * problem.g / (problem.pi @ problem.g), semantic, prior=problem.pi)
    np.testing.assert_allclose(fused, bf.product_posterior(problem), rtol=RTOL)


def test_gas_mixture_with_gamma_dependent_background_is_not_exact():
    """The exactness claim for gas mixtures needs β independent of γ; with β_γ the mixture weights are off."""
    rng = np.random.default_rng(3)
    problem = bf.random_problem(rng, 6, 3, 2)
    problem.zeta = []
    betas = rng.dirichlet(np.ones(3), size=2)
    # reference with γ-dependent background, by enumeration
    n, k = problem.n, 3
    zl = problem.cell_lik()
    post = np.zeros(n)
    import itertools

    for o_map in itertools.product(range(k), repeat=n):
        o_map = np.array(o_map)
        for c in range(n):
            for gi in range(2):
                o_term = np.prod(np.where(np.arange(n) == c, problem.L[gi][o_map], betas[gi][o_map]))
                post[c] += problem.pi[c] * problem.g[c] * problem.gas_prior[gi] * o_term * np.prod(zl[np.arange(n), o_map])
    post /= post.sum()
    problem.beta = betas.mean(axis=0)
    assert np.abs(closed_form(problem) - post).max() > 1e-4


def test_fusion_with_non_uniform_prior_divides_it_out_once_per_extra_input():
    rng = np.random.default_rng(5)
    n = 50
    prior = rng.dirichlet(np.ones(n))
    liks = rng.random((3, n))
    posts = [prior * l / (prior @ l) for l in liks]
    expected = prior * liks.prod(axis=0)
    np.testing.assert_allclose(fuse(*posts, prior=prior), expected / expected.sum(), rtol=RTOL)
