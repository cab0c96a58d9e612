"""The robot's unknown-gas pipeline == Network A with the γ node (pgmpy) == enumeration, on small grids.

The robot turns its e-nose readings into p(γ | ζ_1:t) (:class:`psgsl_pgm.GasBelief`), weighs the semantic term's
gas mixture with it, fuses with p(s | g) and scores views with φ_O under the same mixture. In Network A the
readings are the ζ_j children of γ with CPDs p(ζ_j | γ) = the confusion column of each reading's strength bin.
Tolerance 1e-10 relative (φ_O: plus 1e-14 nats absolute, as in test_networks_infogain).
"""

from __future__ import annotations

import numpy as np
import pytest

from psgsl_pgm import GasBelief, fuse, semantic_information_gain, semantic_source_probability
from psgsl_pgm.networks import (SemanticGSLProblem, build_network_a, exact_gas_posterior, exact_information_gain,
                                exact_source_posterior)

CASES = [(0, 5, 3, 2, 3), (1, 6, 4, 3, 5), (2, 8, 3, 4, 2), (3, 4, 5, 3, 6)]  # seed, n, k, m, readings


def _robot_and_problem(seed, n, k, m, t):
    rng = np.random.default_rng(seed)
    base = SemanticGSLProblem.random(rng, n, k, m, max_observations=2)
    gases = tuple(f"gas{i}" for i in range(m))
    conf = rng.random((3, m, m)) + 2.0 * np.eye(m)
    conf /= conf.sum(axis=2, keepdims=True)
    belief = GasBelief(gases, conf, [0.0, 0.5, 1.0, np.inf])
    columns = []
    for _ in range(t):  # a reading: a label and a strength; Network A's ζ_j CPD is its likelihood column
        label, strength = gases[rng.integers(m)], float(rng.uniform(0.0, 2.0))
        columns.append(belief.likelihood(label, strength))
        belief.update(label, strength)
    problem = SemanticGSLProblem(
        base.source_likelihood, base.background, cells=n, observation_cells=base.observation_cells,
        observation_likelihoods=base.observation_likelihoods, olfactory_likelihood=base.olfactory_likelihood,
        source_prior=base.source_prior, gas_prior=np.full(m, 1.0 / m), gas_observations=np.array(columns))
    return belief, problem


def _enumerate(problem, gas_probs):
    """p(s | g, z, ζ) by a sum over (s, γ): p(γ | ζ) p(s) p(g | s) Π_n Π_j p(z_nj | O_n) summed over O_n."""
    n = problem.n
    q = problem.class_likelihood()  # Π_j p(z_cj | o), per cell
    joint = np.zeros((n, problem.m))
    for c in range(n):
        for g in range(problem.m):
            term = gas_probs[g] * problem.source_prior[c] * problem.olfactory_likelihood[c]
            for cell in range(n):
                table = problem.source_likelihood[g] if cell == c else problem.background
                term *= q[cell] @ table
            joint[c, g] = term
    return joint.sum(axis=1) / joint.sum()


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"seed{c[0]}-n{c[1]}-m{c[3]}-t{c[4]}")
def test_robot_mixture_equals_network_a_and_enumeration(case):
    belief, problem = _robot_and_problem(*case)
    model = build_network_a(problem)
    gas_probs = belief.probs
    np.testing.assert_allclose(gas_probs, problem.gas_probs(), rtol=1e-12, atol=0)
    # the robot: p(s | g, z, ζ) ∝ p(s | g) · Σ_γ p(γ | ζ) p(s | z, γ)
    semantic = semantic_source_probability(problem.class_probs(), problem.source_likelihood, problem.background,
                                           gas_probs=gas_probs)
    robot = fuse(problem.olfactory_posterior(), semantic)
    np.testing.assert_allclose(robot, exact_source_posterior(model, problem), rtol=1e-10, atol=0)
    np.testing.assert_allclose(robot, _enumerate(problem, gas_probs), rtol=1e-10, atol=0)
    # φ_O under the mixture == I(S; O_n) in Network A
    gain = semantic_information_gain(problem.class_probs(), problem.source_likelihood, problem.background,
                                     olfactory=problem.olfactory_posterior(), gas_probs=gas_probs,
                                     predictive="exact")
    np.testing.assert_allclose(gain, exact_information_gain(model, problem), rtol=1e-10, atol=1e-14)
    assert gain.max() > 1e-4


def test_gas_posterior_given_everything_differs_from_the_weight():
    """Network A's p(γ | g, z, ζ) also learns from the map; the mixture's weight is p(γ | ζ) (the paper's form),
    and the source posterior is exact with it — the two are different quantities (not a vacuous check)."""
    belief, problem = _robot_and_problem(*CASES[1])
    full = exact_gas_posterior(build_network_a(problem), problem)
    assert np.abs(full - belief.probs).max() > 1e-6
