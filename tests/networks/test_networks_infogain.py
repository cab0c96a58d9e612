"""The core's semantic_information_gain(predictive="exact") == I(S; O_n) from pgmpy's exact joint.

pgmpy gives p(S, O_n | z, g, ζ) in Network A (one two-variable query per cell); the mutual information is
Σ p(s, o) log p(s, o) / (p(s) p(o)). Tolerance: 1e-10 relative; plus 1e-14 nats absolute, the round-off of
that sum where the exact value is 0 (e.g. a cell whose class is already certain: its terms cancel exactly
in exact arithmetic, to ~eps in floating point).
"""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm import semantic_information_gain
from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, build_network_b, exact_information_gain

CASES = [(0, 5, 3, 1), (1, 6, 4, 2), (2, 7, 3, 3), (3, 8, 5, 1), (4, 4, 2, 2), (5, 10, 4, 1), (6, 9, 6, 2)]


def _core_gain(problem):
    return semantic_information_gain(
        problem.class_probs(), problem.source_likelihood, problem.background,
        olfactory=problem.olfactory_posterior(), gas_probs=problem.gas_probs(), predictive="exact")


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"seed{c[0]}-n{c[1]}-k{c[2]}-m{c[3]}")
def test_exact_information_gain_matches_core(case):
    seed, n, k, m = case
    problem = SemanticGSLProblem.random(np.random.default_rng(seed), n, k, m, max_observations=2)
    exact = exact_information_gain(build_network_a(problem), problem)
    assert exact.shape == (n,) and np.all(exact >= 0)
    np.testing.assert_allclose(_core_gain(problem), exact, rtol=1e-10, atol=1e-14)
    assert exact.max() > 1e-4  # the comparison is not vacuous


def test_information_gain_subset_of_cells():
    problem = SemanticGSLProblem.random(np.random.default_rng(11), 6, 3, max_observations=1)
    model = build_network_a(problem)
    full = exact_information_gain(model, problem)
    np.testing.assert_array_equal(exact_information_gain(model, problem, cells=[4, 1]), full[[4, 1]])
    with pytest.raises(ValueError, match="must index"):
        exact_information_gain(model, problem, cells=[6])


def test_information_gain_needs_network_a():
    problem = SemanticGSLProblem.random(np.random.default_rng(12), 4, 3)
    with pytest.raises(ValueError, match="needs Network A"):
        exact_information_gain(build_network_b(problem), problem)


def test_unobserved_cells_gain_more_than_certain_ones():
    """A cell whose class is known exactly has I(S; O_n) = 0; an unobserved one has I > 0."""
    lik = np.array([0.6, 0.3, 0.1])
    problem = SemanticGSLProblem(lik, [0.2, 0.3, 0.5], cells=3, observation_cells=[0],
                                 observation_likelihoods=[[1.0, 0.0, 0.0]])
    gain = exact_information_gain(build_network_a(problem), problem)
    assert gain[0] < 1e-14 and gain[1] > 1e-3 and gain[2] > 1e-3
    np.testing.assert_allclose(_core_gain(problem), gain, rtol=1e-10, atol=1e-14)
