"""The paper's approximation p(o_ni | s_c) ≈ p(o_ni) (class prior = the marginal p(o)), measured against
the exact posterior of Network A, shrinks like 1/n.

With ρ = p(o) = L/n + (1 − 1/n) β (uniform source prior, m = 1), Λ_c = Π_j p(z_cj | o), a_c = Λ_c · β,
b_c = Λ_c · L, r_c = b_c / a_c, the closed form's weight is Σ_i q_ci/ρ_i L_i ∝ b_c / (Λ_c · ρ)
= b_c / (a_c (1 + (r_c − 1)/n)) — the exact weight b_c / a_c divided by 1 + (r_c − 1)/n. Hence, to first
order, approx_c / exact_c = 1 − (r_c − r̄)/n with r̄ = Σ_c P_c r_c, and the total-variation error is
TV ≈ Σ_c P_c |r_c − r̄| / (2n).
"""

from __future__ import annotations

import numpy as np

from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, exact_source_posterior


def _tiled(base: SemanticGSLProblem, copies: int) -> SemanticGSLProblem:
    """``copies`` copies of ``base``'s cells (same evidence pattern), uniform prior: only n changes."""
    n0 = base.n
    cells = np.concatenate([base.observation_cells + n0 * t for t in range(copies)])
    return SemanticGSLProblem(
        base.source_likelihood, base.background, cells=n0 * copies, observation_cells=cells,
        observation_likelihoods=np.tile(base.observation_likelihoods, (copies, 1)),
        olfactory_likelihood=np.tile(base.olfactory_likelihood, copies))


def _ratio_r(problem):
    lam = problem.class_likelihood()
    return (lam @ problem.source_likelihood[0]) / (lam @ problem.background)  # r_c = b_c / a_c


def test_marginal_prior_error_shrinks_like_one_over_n():
    base = SemanticGSLProblem.random(np.random.default_rng(5), 8, 4, uniform_prior=True, max_observations=2,
                                     zero_fraction=0.0)
    sizes, tv, max_rel, predicted = [], [], [], []
    for copies in (1, 2, 4, 8, 16, 32):
        problem = _tiled(base, copies)
        exact = exact_source_posterior(build_network_a(problem), problem)
        approx = problem.closed_form_posterior(class_prior="marginal")
        np.testing.assert_allclose(problem.closed_form_posterior(), exact, rtol=1e-10, atol=0)  # ρ = β exact
        r = _ratio_r(problem)
        # exact identity: approx ∝ exact / (1 + (r − 1)/n)
        corrected = exact / (1.0 + (r - 1.0) / problem.n)
        np.testing.assert_allclose(approx, corrected / corrected.sum(), rtol=1e-10, atol=0)
        sizes.append(problem.n)
        tv.append(0.5 * np.abs(approx - exact).sum())
        max_rel.append(np.max(np.abs(approx / exact - 1.0)))
        predicted.append(np.sum(exact * np.abs(r - exact @ r)) / (2 * problem.n))  # first-order TV
    sizes, tv, max_rel, predicted = map(np.asarray, (sizes, tv, max_rel, predicted))
    assert np.all(np.diff(tv) < 0) and np.all(np.diff(max_rel) < 0)  # the error shrinks with n ...
    assert tv[0] > 1e-3  # ... from a visible size
    scaled = tv * sizes  # ... like 1/n: n·TV settles to the first-order constant
    assert np.all(np.abs(np.diff(scaled)) < 0.02 * scaled[-1])
    assert np.all(np.abs(tv / predicted - 1.0) < 1.0 / sizes)  # the 1st-order formula, off by O(1/n) only


def test_marginal_prior_error_shrinks_on_random_problems():
    """Not just tiles: median TV over 8 random problems per size decreases with n (m = 1, uniform prior)."""
    medians = []
    for n in (5, 20, 80):
        errors = []
        for seed in range(8):
            problem = SemanticGSLProblem.random(np.random.default_rng(1000 * n + seed), n, 3, uniform_prior=True,
                                                max_observations=2)
            exact = exact_source_posterior(build_network_a(problem), problem)
            errors.append(0.5 * np.abs(problem.closed_form_posterior(class_prior="marginal") - exact).sum())
        medians.append(np.median(errors))
    assert medians[0] > medians[1] > medians[2]
    assert medians[2] < medians[0] / 4  # 16× more cells: well below a quarter of the error
