r"""The approximation p(o_ni | s_c) ≈ p(o_ni) for n ≠ c (Sec. "Derivation of the Distribution p(s_c | z)")
and its error, on Network A.

(M1) for c ≠ n: p(o_ni | s_c) = p(o_ni | ¬s_n) = β_i                                              exact
(M2) law of total probability: p(o_ni) = p(s_n) p(o_ni | s_n) + p(¬s_n) p(o_ni | ¬s_n)            exact
(M3) p(¬s_n) ≫ p(s_n)  ⇒  p(o_ni | s_c) ≈ p(o_ni); the error is exactly p(o_ni) − β_i = p(s_n)(L_i − β_i),
     O(1/n) with a uniform source prior                                                      APPROXIMATE
(M4) then p(z_n | s_c) ≈ p(z_n) for n ≠ c and Π_{n∖c} p(z_n) is dropped (eq. (20)):
     the approximate weight is Σ_i q_ci / ρ_i L_i with ρ = p(o), q under ρ. Exactly (m = 1, uniform prior,
     ρ = L/n + (1 − 1/n) β):
         approx_c ∝ exact_c / (1 + (r_c − 1)/n),   r_c = p(z_c | s_c) / p(z_c | ¬s_c) = Λ_c·L / Λ_c·β,
     so approx_c / exact_c = 1 − (r_c − r̄)/n + O(1/n²), r̄ = Σ_c P_c r_c, and the total-variation error is
     Σ_c P_c |r_c − r̄| / (2n) + O(1/n²): it vanishes like 1/n.                                  measured
(M5) with ρ = β instead, the same formula is exact (``check_semantic_term.py``, (T9)).
"""

from __future__ import annotations

import numpy as np
from _kit import assert_close, normalised, table

from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, exact_source_posterior


def test_m1_m2_conditional_and_marginal_class_distributions():
    problem = SemanticGSLProblem.random(np.random.default_rng(2), 5, 3, m=1, zero_fraction=0.0)
    model = build_network_a(problem)
    L, beta = problem.source_likelihood[0], problem.background
    for n_idx, n in enumerate(problem.cell_names):
        for c in problem.cell_names:
            if c != n:
                assert_close(table(model, [f"O_{n}"], {"S": c}), beta, rtol=1e-14, what="(M1)")
        p_s = problem.source_prior[n_idx]
        marginal = table(model, [f"O_{n}"])  # p(o_n), no evidence
        assert_close(marginal, p_s * L + (1 - p_s) * beta, rtol=1e-12, what="(M2) total probability")
        assert_close(marginal - beta, p_s * (L - beta), rtol=1e-9, what="(M3) error of p(o_n|s_c) ≈ p(o_n)")
    # uniform prior: the cell average of p(o_n) is SemanticGSLProblem.marginal_class_prior()
    uniform = SemanticGSLProblem(problem.source_likelihood, beta, cells=problem.n)
    um = build_network_a(uniform)
    assert_close(table(um, ["O_c0"]), uniform.marginal_class_prior(), rtol=1e-12, what="(M2) uniform prior")


def _tiled(base, copies):
    cells = np.concatenate([base.observation_cells + base.n * t for t in range(copies)])
    return SemanticGSLProblem(
        base.source_likelihood, base.background, cells=base.n * copies, observation_cells=cells,
        observation_likelihoods=np.tile(base.observation_likelihoods, (copies, 1)),
        olfactory_likelihood=np.tile(base.olfactory_likelihood, copies))


def test_m4_exact_error_identity_and_first_order_rate():
    base = SemanticGSLProblem.random(np.random.default_rng(17), 6, 4, uniform_prior=True, max_observations=2,
                                     zero_fraction=0.1)
    constants = []
    for copies in (1, 4, 16, 64):
        problem = _tiled(base, copies)
        n = problem.n
        exact = exact_source_posterior(build_network_a(problem), problem)
        approx = problem.closed_form_posterior(class_prior="marginal")
        lam = problem.class_likelihood()
        r = (lam @ problem.source_likelihood[0]) / (lam @ problem.background)  # r_c
        assert_close(approx, normalised(exact / (1 + (r - 1) / n)), what="(M4) exact error identity")
        tv = 0.5 * np.abs(approx - exact).sum()
        first_order = np.sum(exact * np.abs(r - exact @ r)) / (2 * n)
        assert tv > 0
        assert abs(tv / first_order - 1) < 2.0 / n  # (M4) TV = Σ P|r − r̄|/(2n) · (1 + O(1/n))
        constants.append(n * first_order)
    # K = Σ_c P_c |r_c − r̄| / 2 is the same for every tiling, so TV = K/n (1 + O(1/n)): the error is Θ(1/n)
    assert_close(constants, np.full(len(constants), constants[0]), what="(M4) n · TV → K")
