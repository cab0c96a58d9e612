"""Closed form == Network A == Network B (chain) == Network B (table) on many seeded random problems.

Where the closed form is exact (class prior = background β), all four agree to 1e-10 relative per cell
(every quantity is a sum of non-negative terms, so relative accuracy holds entry-wise; exact zeros —
cells excluded by a zero in the ontology or the olfactory likelihood — must be exact zeros everywhere).
"""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm.networks import (
    SemanticGSLProblem,
    build_network_a,
    build_network_b,
    check_normalised,
    exact_gas_posterior,
    exact_source_posterior,
    network_kind,
)

RTOL = 1e-10

# (seed, n, k, m, max_observations, uniform_prior): varied sizes, classes, gases and evidence counts.
CASES = [
    (0, 1, 2, 1, 1, True),
    (1, 2, 2, 1, 2, False),
    (2, 2, 3, 2, 0, False),
    (3, 3, 3, 1, 3, False),
    (4, 4, 2, 3, 1, True),
    (5, 5, 4, 1, 2, False),
    (6, 5, 5, 2, 3, False),
    (7, 6, 3, 3, 2, False),
    (8, 7, 6, 1, 4, True),
    (9, 8, 3, 2, 1, False),
    (10, 9, 4, 1, 2, False),
    (11, 10, 5, 3, 2, False),
    (12, 11, 2, 1, 3, False),
    (13, 12, 4, 2, 2, False),
    (14, 12, 3, 1, 1, True),
    (15, 6, 7, 4, 3, False),
]


def _problem(seed, n, k, m, max_obs, uniform):
    rng = np.random.default_rng(seed)
    return SemanticGSLProblem.random(rng, n, k, m, max_observations=max_obs, uniform_prior=uniform,
                                     zero_fraction=0.25)


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"seed{c[0]}-n{c[1]}-k{c[2]}-m{c[3]}")
def test_closed_form_equals_all_networks(case):
    problem = _problem(*case)
    closed = problem.closed_form_posterior()
    a = build_network_a(problem)
    chain = build_network_b(problem, "chain")
    table = build_network_b(problem, "table")
    assert [network_kind(x) for x in (a, chain, table)] == ["A", "B-chain", "B-table"]
    results = {
        "A": exact_source_posterior(a, problem),
        "A fixed": exact_source_posterior(a, problem, elimination_order="fixed"),
        "B chain": exact_source_posterior(chain, problem),
        "B chain fixed": exact_source_posterior(chain, problem, elimination_order="fixed"),
        "B table": exact_source_posterior(table, problem),
        "B table fixed": exact_source_posterior(table, problem, elimination_order="fixed"),
    }
    for name, posterior in results.items():
        np.testing.assert_allclose(posterior, closed, rtol=RTOL, atol=0, err_msg=name)
    # Network B's per-target marginals form a distribution by themselves (α admits one source only).
    assert abs(results["B chain"].sum() - 1.0) < 1e-12


@pytest.mark.parametrize("case", [c for c in CASES if c[3] > 1], ids=lambda c: f"seed{c[0]}-m{c[3]}")
def test_gas_posterior(case):
    problem = _problem(*case)
    expected = problem.closed_form_gas_posterior()
    # Independent check of the closed form: p(γ | all) ∝ p(γ|ζ) Σ_c p(s_c) p(g|c) Σ_i q_ci/β_i L_γi (all in
    # linear space from the core's class beliefs).
    q = problem.class_probs()
    w = (q / problem.background) @ problem.source_likelihood.T  # w_cγ, (n, m)
    linear = problem.gas_probs() * ((problem.source_prior * problem.olfactory_likelihood) @ w)
    np.testing.assert_allclose(expected, linear / linear.sum(), rtol=RTOL, atol=0)
    for model in (build_network_a(problem), build_network_b(problem, "chain"), build_network_b(problem, "table")):
        np.testing.assert_allclose(exact_gas_posterior(model, problem), expected, rtol=RTOL, atol=0)


def test_single_gas_posterior_is_one():
    problem = _problem(*CASES[3])
    assert exact_gas_posterior(build_network_a(problem), problem).tolist() == [1.0]


@pytest.mark.parametrize("seed", range(3))
def test_b_chain_at_moderate_n(seed):
    """Beyond the table's reach: the chain encoding still matches the closed form (n = 30)."""
    problem = SemanticGSLProblem.random(np.random.default_rng(100 + seed), 30, 4, m=1 + seed,
                                        max_observations=2)
    chain = build_network_b(problem, "chain")
    for order in ("greedy", "fixed"):
        np.testing.assert_allclose(exact_source_posterior(chain, problem, elimination_order=order),
                                   problem.closed_form_posterior(), rtol=RTOL, atol=0, err_msg=order)


def test_zero_prior_cells_agree_between_networks():
    """Cells with source prior 0 get posterior exactly 0 in both networks (closed form is not used here)."""
    base = SemanticGSLProblem.random(np.random.default_rng(21), 6, 3, m=2)
    prior = base.source_prior.copy()
    prior[[1, 4]] = 0.0
    problem = SemanticGSLProblem(
        base.source_likelihood, base.background, cells=6, observation_cells=base.observation_cells,
        observation_likelihoods=base.observation_likelihoods, olfactory_likelihood=base.olfactory_likelihood,
        source_prior=prior / prior.sum(), gas_prior=base.gas_prior, gas_observations=base.gas_observations)
    a = exact_source_posterior(build_network_a(problem), problem)
    b = exact_source_posterior(build_network_b(problem), problem)
    assert a[1] == 0.0 and a[4] == 0.0 and b[1] == 0.0 and b[4] == 0.0
    np.testing.assert_allclose(b, a, rtol=RTOL, atol=0)
    weights = np.exp(problem.log_joint_weights()).sum(axis=1)  # p(S = c, evidence) up to a constant
    np.testing.assert_allclose(a, weights / weights.sum(), rtol=RTOL, atol=0)


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: f"seed{c[0]}")
def test_every_model_is_valid_and_strictly_normalised(case):
    problem = _problem(*case)
    for model in (build_network_a(problem), build_network_b(problem, "chain"), build_network_b(problem, "table")):
        assert model.check_model()
        assert check_normalised(model)
        for cpd in model.get_cpds():
            assert all(isinstance(s, str) for states in cpd.state_names.values() for s in states)


def test_voxel_column_sum():
    """3-D problem: S over voxels (4×3 columns × 3 heights); Σ_{v∈c} p(s_v | ·) == the core's column form.

    Sec. "Voxelized Scene Representations": p(s_c | z) = Σ_{v ∈ c} p(s_v | z). The olfactory likelihood is
    per column (p(g | v) = p(g | column of v)); the exact voxel posterior of Network A, summed over each
    column, must equal fuse(p(s | g) over columns, semantic_source_probability(..., column_axis=2,
    source_prior=voxel prior), prior=column prior).
    """
    from psgsl_pgm import fuse, semantic_source_probability

    shape = (4, 3, 3)
    rng = np.random.default_rng(7)
    base = SemanticGSLProblem.random(rng, int(np.prod(shape)), 4, m=2, max_observations=2, shape=shape)
    column_g = rng.uniform(0.05, 1.0, size=shape[:2])
    problem = SemanticGSLProblem(
        base.source_likelihood, base.background, cells=base.n, observation_cells=base.observation_cells,
        observation_likelihoods=base.observation_likelihoods,
        olfactory_likelihood=np.repeat(column_g.ravel(), shape[2]), source_prior=base.source_prior,
        gas_prior=base.gas_prior, gas_observations=base.gas_observations, shape=shape)
    voxel_exact = exact_source_posterior(build_network_a(problem), problem).reshape(shape)
    column_exact = voxel_exact.sum(axis=2)  # Σ_{v ∈ c} p(s_v | g, z, ζ)

    voxel_prior = problem.source_prior.reshape(shape)
    column_prior = voxel_prior.sum(axis=2)
    olfactory = column_prior * column_g / np.sum(column_prior * column_g)  # p(s_c | g) over columns
    semantic = semantic_source_probability(
        problem.class_probs().reshape(*shape, problem.k), problem.source_likelihood, problem.background,
        gas_probs=problem.gas_probs(), column_axis=2, source_prior=voxel_prior)  # Σ_{v∈c} p(s_v | z, ζ)
    np.testing.assert_allclose(column_exact, fuse(olfactory, semantic, prior=column_prior), rtol=RTOL, atol=0)
    # and the voxel posterior itself is the closed form
    np.testing.assert_allclose(voxel_exact.ravel(), problem.closed_form_posterior(), rtol=RTOL, atol=0)


def test_closed_form_with_zero_prior_cells():
    """Zero-prior cells: the closed form must equal the networks (0 there)."""
    base = SemanticGSLProblem.random(np.random.default_rng(22), 5, 3)
    prior = base.source_prior.copy()
    prior[2] = 0.0
    problem = SemanticGSLProblem(
        base.source_likelihood, base.background, cells=5, observation_cells=base.observation_cells,
        observation_likelihoods=base.observation_likelihoods, olfactory_likelihood=base.olfactory_likelihood,
        source_prior=prior / prior.sum())
    exact = exact_source_posterior(build_network_a(problem), problem)
    np.testing.assert_allclose(problem.closed_form_posterior(), exact, rtol=RTOL, atol=0)
