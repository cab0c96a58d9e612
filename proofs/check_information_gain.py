r"""Sec. "Information Gain Optimization": I(S; O_n) and φ_O(p), on Network A with all evidence (z, g, ζ).

Notation of ``psgsl_pgm.core._infogain``: f = p(s | g), ρ_i = Σ_γ p(γ | ζ) L_γi / β_i, q_n = p(o_n | z_n) under β,
w_c = q_c · ρ, P(c) = f_c w_c / U with U = Σ_c f_c w_c (the fused posterior), a_n = f_n / U.

(I1) I(S; O_n) = H(S) − H(S | O_n) = H(S) − Σ_i p(o_ni | ev) H(S | o_ni, ev), every term from pgmpy's exact
     joint p(S, O_n | ev); equals the core's ``semantic_information_gain(..., predictive="exact")``.   exact
(I2) learning O_n = i changes only cell n's weight: p(S = c | ev, o_ni) ∝ f_c w_c (c ≠ n), f_n ρ_i (c = n),
     and the exact predictive is p(o_ni | ev) = q_ni (1 + a_n (ρ_i − w_n)).                          exact
(I3) the paper weights H(S | o_ni) by p(o_ni | z) = q_ni (the class belief), not by the predictive of
     (I2): ``predictive="paper"`` is exactly H(S) − Σ_i q_ni H(S | o_ni, ev) — a different number
     (it ignores what the source distribution says about O_n; measured here).      APPROXIMATE (the paper)
(I4) φ_O(p) = Σ_{n ∈ F_p} I(S; O_n). Given S the O_n are independent, so I(S; O_F) ≤ Σ_{n∈F} I(S; O_n):
     the sum over the field of view is an upper bound of the joint information, not equal to it.
                                                                                         APPROXIMATE (bound)
"""

from __future__ import annotations

import numpy as np
import pytest
from _kit import assert_close, entropy, normalised, table

from psgsl_pgm import semantic_information_gain
from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, exact_information_gain, network_evidence


@pytest.fixture(scope="module", params=[1, 2])
def setup(request):
    problem = SemanticGSLProblem.random(np.random.default_rng(50 + request.param), 5, 3, m=request.param,
                                        max_observations=2, zero_fraction=0.0)
    model = build_network_a(problem)
    return problem, model, network_evidence(model)


def _core(problem, predictive):
    return semantic_information_gain(problem.class_probs(), problem.source_likelihood, problem.background,
                                     olfactory=problem.olfactory_posterior(), gas_probs=problem.gas_probs(),
                                     predictive=predictive)


def _mutual_information(joint):
    return entropy(joint.sum(axis=1)) + entropy(joint.sum(axis=0)) - entropy(joint)


def test_i1_definition_and_core(setup):
    problem, model, ev = setup
    p_s = table(model, ["S"], ev)
    gains = []
    for n in problem.cell_names:
        joint = table(model, ["S", f"O_{n}"], ev)  # p(S, O_n | ev)
        predictive = joint.sum(axis=0)
        conditional = sum(predictive[i] * entropy(table(model, ["S"], {**ev, f"O_{n}": cls}))
                          for i, cls in enumerate(problem.class_names) if predictive[i] > 0)
        gain = entropy(p_s) - conditional  # H(S) − Σ_i p(o_ni|ev) H(S|o_ni, ev)
        assert_close(gain, _mutual_information(joint), rtol=1e-9, what="(I1) two forms of I(S;O_n)")
        gains.append(gain)
    gains = np.array(gains)
    np.testing.assert_allclose(exact_information_gain(model, problem), gains, rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(_core(problem, "exact"), gains, rtol=1e-9, atol=1e-14)
    assert gains.max() > 1e-3


def test_i2_only_cell_n_changes_and_the_predictive(setup):
    problem, model, ev = setup
    f = problem.olfactory_posterior()
    q = problem.class_probs()
    rho = problem.gas_probs() @ (problem.source_likelihood / problem.background)  # ρ_i
    w = q @ rho
    u = f @ w
    for n_idx, n in enumerate(problem.cell_names):
        a_n = f[n_idx] / u
        predictive = table(model, [f"O_{n}"], ev)
        assert_close(predictive, q[n_idx] * (1 + a_n * (rho - w[n_idx])), what="(I2) exact predictive")
        for i, cls in enumerate(problem.class_names):
            weights = f * w
            weights[n_idx] = f[n_idx] * rho[i]
            assert_close(table(model, ["S"], {**ev, f"O_{n}": cls}), normalised(weights), what="(I2) update")


def test_i3_papers_weighting(setup):
    problem, model, ev = setup
    q = problem.class_probs()
    h_s = entropy(table(model, ["S"], ev))
    paper = np.array([
        h_s - sum(q[j, i] * entropy(table(model, ["S"], {**ev, f"O_{n}": cls}))
                  for i, cls in enumerate(problem.class_names))
        for j, n in enumerate(problem.cell_names)])
    np.testing.assert_allclose(_core(problem, "paper"), paper, rtol=1e-9, atol=1e-14)
    exact = exact_information_gain(model, problem)
    assert np.max(np.abs(paper - exact)) > 1e-6  # a different quantity from the mutual information


def test_i4_field_of_view_sum_bounds_the_joint_information(setup):
    problem, model, ev = setup
    single = exact_information_gain(model, problem)
    cells = problem.cell_names
    for a, b in [(0, 1), (1, 3), (2, 4)]:
        joint = table(model, ["S", f"O_{cells[a]}", f"O_{cells[b]}"], ev)
        i_joint = _mutual_information(joint.reshape(problem.n, -1))  # I(S; O_a, O_b)
        assert i_joint <= single[a] + single[b] + 1e-12
        assert i_joint >= max(single[a], single[b]) - 1e-12
        assert single[a] + single[b] - i_joint > 1e-9  # strictly below the sum: φ_O double counts
