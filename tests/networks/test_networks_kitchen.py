"""The paper's kitchen example (Sec. "Semantic Knowledge and Ontology"), worked by hand.

Ontology p(o | s): oven 0.4, microwave 0.25, refrigerator 0.3, countertop 0.05 (and "other" 0, as in the
core's ``kitchen_ontology()``). Four cells hold an oven, a microwave, a refrigerator and a countertop; the
background β is uniform over the k = 5 classes (β_i = 0.2). Each cell is seen once by a detector with
p(z | o) = 0.7 for the class it reports and 0.1 for every other class.

By hand, for the cell whose detector reported class X:
    q_c = p(o_c | z_c) ∝ β · p(z | o) → q_cX = 0.7 / (0.7 + 4·0.1) = 0.7/1.1, q_ci = 0.1/1.1 (i ≠ X)
    w_c = Σ_i q_ci/β_i · L_i = (5/1.1) · [0.7 L_X + 0.1 (1 − L_X)] = (5/1.1) · (0.1 + 0.6 L_X)
so p(s_c | z) ∝ 0.1 + 0.6 L_X:
    oven         0.1 + 0.6·0.40 = 0.34
    microwave    0.1 + 0.6·0.25 = 0.25
    refrigerator 0.1 + 0.6·0.30 = 0.28
    countertop   0.1 + 0.6·0.05 = 0.13        (sum 1.00, already normalised)
With the olfactory likelihood p(g | c) = (0.5, 1, 0.5, 1) and a uniform source prior,
p(s_c | g, z) ∝ p(s_c | g) p(s_c | z) ∝ (0.17, 0.25, 0.14, 0.13), sum 0.69:
    p(s | g, z) = (17, 25, 14, 13) / 69 = (0.246377, 0.362319, 0.202899, 0.188406).
"""

from __future__ import annotations

import numpy as np

from psgsl_pgm import fuse, kitchen_ontology, semantic_source_probability
from psgsl_pgm.networks import build_network_a, build_network_b, exact_source_posterior
from psgsl_pgm.networks._canonical import kitchen_problem

BY_HAND_SEMANTIC = np.array([0.34, 0.25, 0.28, 0.13])
BY_HAND_FUSED = np.array([17.0, 25.0, 14.0, 13.0]) / 69.0


def test_kitchen_ontology_is_the_papers():
    onto = kitchen_ontology()
    lik = dict(zip(onto.classes, onto.source_likelihood("smoke")))
    assert lik == {"oven": 0.4, "microwave": 0.25, "refrigerator": 0.3, "countertop": 0.05, "other": 0.0}


def test_semantic_term_by_hand():
    problem = kitchen_problem()
    q = problem.class_probs()
    np.testing.assert_allclose(q[0], np.array([0.7, 0.1, 0.1, 0.1, 0.1]) / 1.1, rtol=1e-14)
    semantic = semantic_source_probability(q, problem.source_likelihood, problem.background)
    np.testing.assert_allclose(semantic, BY_HAND_SEMANTIC, rtol=1e-13)


def test_fused_posterior_by_hand_closed_form_and_networks():
    problem = kitchen_problem()
    np.testing.assert_allclose(problem.olfactory_posterior(), np.array([0.5, 1, 0.5, 1]) / 3.0, rtol=1e-14)
    np.testing.assert_allclose(fuse(problem.olfactory_posterior(), BY_HAND_SEMANTIC), BY_HAND_FUSED, rtol=1e-13)
    np.testing.assert_allclose(problem.closed_form_posterior(), BY_HAND_FUSED, rtol=1e-13)
    np.testing.assert_allclose(exact_source_posterior(build_network_a(problem), problem), BY_HAND_FUSED, rtol=1e-13)
    for constraint in ("chain", "table"):
        model = build_network_b(problem, constraint)
        np.testing.assert_allclose(exact_source_posterior(model, problem), BY_HAND_FUSED, rtol=1e-13)
