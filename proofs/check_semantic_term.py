r"""Sec. "Derivation of the Distribution p(s_c | z)": from the k^n sum over object maps to the O(k) term,
eq. (15) and eq. (20), step by step on Network A (S over cells).

(T1) p(s_c | z) = Σ_M p(s_c | z, o_M) p(o_M | z) = Σ_M p(s_c | o_M) p(o_M | z)   needs S ⟂ Z | O    exact
     — k^n object maps: intractable beyond toy sizes.
(T2) p(s_c | z) ∝ p(s_c) p(z | s_c)   (∝ p(z | s_c) with the paper's uniform prior)              Bayes
(T3) p(z_n, z_¬n | s_c) = p(z_n | s_c) p(z_¬n | s_c)                  needs Z_n ⟂ Z_¬n | S        exact
(T4) p(s_c | z) ∝ p(s_c) Π_n p(z_n | s_c)                                                          exact
(T5) eq. (15), lines 1–2: p(z_n | s_c) = Σ_i p(z_n | o_ni) p(o_ni | s_c)   needs Z_n ⟂ S | O_n
(T6) eq. (15), lines 3–4: = p(z_n) Σ_i p(o_ni | z_n) / p(o_ni) · p(o_ni | s_c)      Bayes, exact
     with p(o_ni) the model's marginal and p(o_ni | z_n) the belief under that marginal.
(T7) n = c: p(o_ci | s_c) is the ontology row L (the CPD of O_c at S = c)                         exact
(T8) n ≠ c: p(o_ni | s_c) = p(o_ni | ¬s_n) = β; the paper then uses ≈ p(o_ni) (the approximation of
     ``check_marginal_approximation.py``). Exactly, p(z_n | s_c) = p(z_n | ¬s_n) for every c ≠ n, so
     Π_{n≠c} p(z_n | s_c) = Π_n p(z_n | ¬s_n) / p(z_c | ¬s_c), and
(T9) p(s_c | z) ∝ p(s_c) p(z_c | s_c) / p(z_c | ¬s_c) = p(s_c) Σ_i q_ci / β_i · L_i,   q_c ∝ β · p(z_c | o)
     — eq. (20) with p(o_ci) := β: O(k) per cell and exact.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from _kit import assert_close, normalised, table

from psgsl_pgm import semantic_source_probability
from psgsl_pgm.networks import SemanticGSLProblem, build_network_a


@pytest.fixture(scope="module")
def setup():
    base = SemanticGSLProblem.random(np.random.default_rng(9), 4, 3, max_observations=2, zero_fraction=0.0)
    problem = SemanticGSLProblem(  # semantics only: no olfactory evidence
        base.source_likelihood, base.background, cells=base.n, observation_cells=base.observation_cells,
        observation_likelihoods=base.observation_likelihoods, source_prior=base.source_prior)
    model = build_network_a(problem)
    O = [f"O_{c}" for c in problem.cell_names]
    Z = {c: sorted(v for v in model.nodes() if v.startswith(f"Z_{c}_")) for c in problem.cell_names}
    z = {v: "observed" for vs in Z.values() for v in vs}
    assert len(z) >= 3  # several cells are observed
    return problem, model, O, Z, z


def _p_observed(model, nodes, given):
    """p(all ``nodes`` observed | given)."""
    if not nodes:
        return 1.0
    return table(model, nodes, given)[(0,) * len(nodes)]


def test_dseparation_claims(setup):
    problem, model, O, Z, z = setup
    for c, zs in Z.items():
        assert all(not model.is_dconnected("S", v, observed=O) for v in zs)  # (T1) S ⟂ Z | O
        others = [v for v in z if v not in zs]
        assert not any(model.is_dconnected(a, b, observed=["S"]) for a in zs for b in others)  # (T3)
        assert all(not model.is_dconnected(v, "S", observed=[f"O_{c}"]) for v in zs)  # (T5) Z_n ⟂ S | O_n
    assert any(model.is_dconnected("S", v, observed=[]) for v in z)  # not vacuous


def test_brute_force_over_object_maps(setup):
    """(T1): Σ over all k^n maps == pgmpy's p(S | z) == the O(k) closed form (T9)."""
    problem, model, O, Z, z = setup
    p_o_z = table(model, O, z)  # p(o_M | z)
    total = np.zeros(problem.n)
    for m in itertools.product(range(problem.k), repeat=problem.n):
        o_m = {O[i]: problem.class_names[m[i]] for i in range(problem.n)}
        p_s_zo = table(model, ["S"], {**z, **o_m})
        assert_close(p_s_zo, table(model, ["S"], o_m), what="(T1) p(s|z,o_M) = p(s|o_M)")
        total += p_s_zo * p_o_z[m]
    exact = table(model, ["S"], z)
    assert_close(total, exact, what="(T1) total probability over k^n maps")
    q = problem.class_probs()  # under β
    closed = semantic_source_probability(q, problem.source_likelihood, problem.background,
                                         source_prior=problem.source_prior)
    assert_close(closed, exact, what="(T9) eq. (20) with p(o) := β is exact")


def test_factorisation_and_eq_pZcGivenSc(setup):
    problem, model, O, Z, z = setup
    cells = problem.cell_names
    L, beta = problem.source_likelihood[0], problem.background
    p_z_given_s = np.zeros((problem.n, problem.n))  # [n, c] = p(z_n | s_c)
    for c_idx, c in enumerate(cells):
        s_c = {"S": c}
        for n_idx, n in enumerate(cells):
            p_z_given_s[n_idx, c_idx] = _p_observed(model, Z[n], s_c)
        # (T3)/(T4): the joint p(z | s_c) factorises over cells
        assert_close(_p_observed(model, sorted(z), s_c), np.prod(p_z_given_s[:, c_idx]), what="(T3)")
    exact = table(model, ["S"], z)
    assert_close(normalised(problem.source_prior * p_z_given_s.prod(axis=0)), exact, what="(T2)+(T4)")

    for n_idx, n in enumerate(cells):
        if not Z[n]:
            continue
        p_zn_o = np.array([_p_observed(model, Z[n], {O[n_idx]: cls}) for cls in problem.class_names])
        p_o = table(model, [O[n_idx]])  # marginal p(o_n)
        p_o_zn = table(model, [O[n_idx]], {v: "observed" for v in Z[n]})  # p(o_n | z_n) under p(o_n)
        p_zn = _p_observed(model, Z[n], {})
        for c_idx, c in enumerate(cells):
            p_o_s = table(model, [O[n_idx]], {"S": c})
            assert_close(p_o_s, L if c == n else beta, rtol=1e-14, what="(T7)/(T8) p(o_n | s_c)")
            line2 = p_zn_o @ p_o_s  # Σ_i p(z_n | o_ni) p(o_ni | s_c)
            line4 = p_zn * np.sum(p_o_zn / p_o * p_o_s)  # p(z_n) Σ_i p(o_ni | z_n)/p(o_ni) p(o_ni | s_c)
            assert_close(line2, p_z_given_s[n_idx, c_idx], what="(T5) eq. (15) lines 1-2")
            assert_close(line4, p_z_given_s[n_idx, c_idx], what="(T6) eq. (15) lines 3-4")
        # (T8): p(z_n | s_c) is the same for every c ≠ n
        off = np.delete(p_z_given_s[n_idx], n_idx)
        assert_close(off, np.full(off.size, off[0]), rtol=1e-14, what="(T8) p(z_n|s_c) constant for c ≠ n")

    # (T9): Π_{n≠c} p(z_n|s_c) = Π_n p(z_n|¬s_n) / p(z_c|¬s_c) → p(s_c|z) ∝ p(s_c) p(z_c|s_c)/p(z_c|¬s_c)
    diag = np.diag(p_z_given_s)
    not_source = np.array([np.delete(p_z_given_s[i], i)[0] for i in range(problem.n)])
    assert_close(normalised(problem.source_prior * diag / not_source), exact, what="(T9) ratio form")
    q = problem.class_probs()
    assert_close(normalised(problem.source_prior * ((q / beta) @ L)), exact, what="(T9) O(k) form")
