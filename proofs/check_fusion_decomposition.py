r"""Sec. "Separating the Semantic and Olfactory Estimation Processes": eq. (1) →
eq. (11), step by step, on Network B (binary S_i, constraint α) — and A ≡ B | α = 1.

The paper's chain of equalities (its equations are unlabelled between the two labelled ones; we number
them (F1)–(F10) in the paper's order). s is a configuration of S = (S_1 … S_n), o_M an object map:

(F1)  p(s | g, z, α) = Σ_M p(s | g, z, α, o_M) p(o_M | g, z, α)                    total probability
(F2)                 = Σ_M p(s | g, z, α, o_M) p(g | z, α, o_M) p(o_M | z, α) / p(g | z, α)       Bayes
(F3)                 ∝ Σ_M p(s | g, α, o_M) p(g | α, o_M) p(o_M | z, α)
                       needs  S ⟂ Z | G, α, O   and   G ⟂ Z | α, O                          d-separation
(F4)                 = Σ_M p(g | s, α, o_M) p(s | α, o_M) / p(g | α, o_M) · p(g | α, o_M) p(o_M | z, α)
(F5)                 ∝ p(g | s) Σ_M p(s | α, o_M) p(o_M | z, α)      needs  G ⟂ α, O | S         d-separation
(F6)                 ∝ p(s | g) p(g) / p(s) · Σ_M …                                                 Bayes
(F7)  uniform p(s):  ∝ p(s | g) Σ_M p(s | α, o_M) p(o_M | z, α)                            ASSUMPTION
(F8)                 = p(s | g) Σ_M p(s | z, α, o_M) p(o_M | z, α) = p(s | g) p(s | z, α)
                       needs  S ⟂ Z | α, O                                                    d-separation
(F9)  p(s | z, α) ∝ p(z, α | s) = p(z | s) p(α | s)                needs  Z ⟂ α | S          d-separation
(F10) on single-source s_c: p(s_c | g, z, α) ∝ p(s_c | g) p(s_c | z)       eq. (11)

Every step is exact in the model; the only assumption is the uniform source prior of (F7). Without it the
exact statement is p(s_c | g, z, α) ∝ p(s_c | g) p(s_c | z) / p(s_c) (what ``psgsl_pgm.fuse(..., prior=)``
computes) — checked below together with the failure of the plain product under a non-uniform prior.

In our Network B the olfactory evidence g is the set of per-cell nodes G_i (children of S_i) whose product
reproduces p(g | s_c) on single-source configurations; every independence used above holds with G = {G_i}.
The d-separation claims of Sec. "Model" are checked with pgmpy: in Network A, O_i and O_j are d-connected
(through S) and separated only by S; in Network B they are d-separated, become d-connected through α once
α is observed, and are separated again given S_i or S_j.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from _kit import assert_close, dconnected_sets, normalised, table

from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, build_network_b, network_evidence


def _problem(seed=0, n=3, k=3, uniform=True):
    return SemanticGSLProblem.random(np.random.default_rng(seed), n, k, max_observations=2, zero_fraction=0.0,
                                     uniform_prior=uniform)


def _names(problem):
    S = [f"S_{c}" for c in problem.cell_names]
    O = [f"O_{c}" for c in problem.cell_names]
    return S, O


# ------------------------------------------------------------------------------------- d-separation (Sec. Model)
@pytest.mark.parametrize("constraint", ["chain", "table"])
def test_o_i_o_j_dseparation_in_network_b(constraint):
    problem = _problem(n=4)
    b = build_network_b(problem, constraint)
    S, O = _names(problem)
    for i, j in itertools.combinations(range(problem.n), 2):
        assert not b.is_dconnected(O[i], O[j], observed=[])  # α unobserved: its collider blocks
        assert b.is_dconnected(O[i], O[j], observed=["alpha"])  # α observed: connected through α
        assert not b.is_dconnected(O[i], O[j], observed=["alpha", S[i]])  # ... separated again given S_i
        assert not b.is_dconnected(O[i], O[j], observed=["alpha", S[j]])  # ... or given S_j
        assert b.minimal_dseparator(O[i], O[j]) == set()


def test_o_i_o_j_dseparation_in_network_a():
    problem = _problem(n=4)
    a = build_network_a(problem)
    _, O = _names(problem)
    for i, j in itertools.combinations(range(problem.n), 2):
        assert a.is_dconnected(O[i], O[j], observed=[])  # the common parent S connects them
        assert a.minimal_dseparator(O[i], O[j]) == {"S"}  # and only S separates them


@pytest.mark.parametrize("constraint", ["chain", "table"])
def test_independencies_used_by_the_derivation(constraint):
    problem = _problem(n=3)
    b = build_network_b(problem, constraint)
    S, O = _names(problem)
    Z = [v for v in b.nodes() if v.startswith("Z_")]
    G = [v for v in b.nodes() if v.startswith("G_")]
    hidden_counters = [v for v in b.nodes() if v.startswith("C_")]
    assert Z and G
    assert not dconnected_sets(b, S, Z, G + ["alpha"] + O)  # (F3) S ⟂ Z | G, α, O
    assert not dconnected_sets(b, G, Z, ["alpha"] + O)  # (F3) G ⟂ Z | α, O
    assert not dconnected_sets(b, G, ["alpha"] + O, S)  # (F5) G ⟂ α, O | S
    assert not dconnected_sets(b, S, Z, ["alpha"] + O)  # (F8) S ⟂ Z | α, O
    assert not dconnected_sets(b, Z, ["alpha"], S)  # (F9) Z ⟂ α | S
    # and they are not vacuous: drop the conditioning set and each pair is d-connected
    assert dconnected_sets(b, S, Z, []) and dconnected_sets(b, G, Z, ["alpha"])
    assert dconnected_sets(b, Z, ["alpha"], [])
    assert bool(hidden_counters) == (constraint == "chain")


# --------------------------------------------------------------------------------------------- A ≡ B | α = 1
@pytest.mark.parametrize("constraint", ["chain", "table"])
@pytest.mark.parametrize("with_evidence", [False, True])
def test_network_a_equals_network_b_given_alpha(constraint, with_evidence):
    """p_B(s, o_M, z | α = 1) = p_A(S = c, o_M, z) for s = e_c, and 0 on every other configuration."""
    problem = SemanticGSLProblem.random(np.random.default_rng(3), 3, 2, m=2, max_observations=1,
                                        zero_fraction=0.0)
    a, b = build_network_a(problem), build_network_b(problem, constraint)
    S, O = _names(problem)
    Z = sorted(v for v in a.nodes() if v.startswith("Z_"))
    if with_evidence:  # condition both on all evidence: then the Z nodes are not variables
        ta = table(a, ["S"] + O, network_evidence(a))
        tb = table(b, S + O, network_evidence(b))
    else:
        ta = table(a, ["S"] + O + Z)
        tb = table(b, S + O + Z, {"alpha": "true"})
    for config in itertools.product((0, 1), repeat=problem.n):
        if sum(config) == 1:
            assert_close(tb[config], ta[config.index(1)], rtol=1e-12, what=str(config))
        else:
            assert np.all(tb[config] == 0.0)


# ------------------------------------------------------------------------------------------------ (F1) – (F10)
def _single(problem):
    """Indices of the single-source configurations e_1 … e_n in a (2,)*n table."""
    return [tuple(int(i == c) for i in range(problem.n)) for c in range(problem.n)]


@pytest.mark.parametrize("uniform", [True, False])
def test_every_step_numerically(uniform):
    problem = _problem(seed=4, n=3, k=2, uniform=uniform)
    b = build_network_b(problem, "table")
    S, O = _names(problem)
    ev = network_evidence(b)
    z = {v: s for v, s in ev.items() if v.startswith("Z_")}
    g = {v: s for v, s in ev.items() if v.startswith("G_")}
    alpha = {"alpha": "true"}
    maps = list(itertools.product(range(problem.k), repeat=problem.n))
    classes = problem.class_names

    def with_map(evidence, m):
        return {**evidence, **{O[i]: classes[m[i]] for i in range(problem.n)}}

    def p_evidence(variables_evidence, given):
        """p(all of ``variables_evidence`` observed | ``given``): the observed entry of their joint table."""
        names = sorted(variables_evidence)
        t = table(b, names, given)
        return t[(0,) * len(names)]  # state 0 = "observed"

    target = table(b, S, {**g, **z, **alpha})  # p(s | g, z, α) over all 2^n configurations
    p_o_gza = table(b, O, {**g, **z, **alpha})  # p(o_M | g, z, α)
    p_o_za = table(b, O, {**z, **alpha})  # p(o_M | z, α)
    f1 = np.zeros_like(target)
    f3 = np.zeros_like(target)
    f5 = np.zeros_like(target)
    f8 = np.zeros_like(target)
    for m in maps:
        p_s_gzao = table(b, S, with_map({**g, **z, **alpha}, m))  # p(s | g, z, α, o_M)
        p_s_gao = table(b, S, with_map({**g, **alpha}, m))  # p(s | g, α, o_M)
        assert_close(p_s_gzao, p_s_gao, what="(F3) p(s|g,z,α,o_M) = p(s|g,α,o_M)")
        p_g_zao = p_evidence(g, with_map({**z, **alpha}, m))
        p_g_ao = p_evidence(g, with_map(alpha, m))
        assert_close(p_g_zao, p_g_ao, what="(F3) p(g|z,α,o_M) = p(g|α,o_M)")
        p_s_ao = table(b, S, with_map(alpha, m))  # p(s | α, o_M)
        p_s_zao = table(b, S, with_map({**z, **alpha}, m))
        assert_close(p_s_zao, p_s_ao, what="(F8) p(s|z,α,o_M) = p(s|α,o_M)")
        f1 += p_s_gzao * p_o_gza[m]  # (F1)
        f3 += p_s_gao * p_g_ao * p_o_za[m]  # (F3), up to 1/p(g|z,α)
        f8 += p_s_zao * p_o_za[m]  # (F8) Σ_M p(s|z,α,o_M) p(o_M|z,α)
        # (F4)+(F5): p(g | s, α, o_M) = p(g | s) for every single-source s
        for c, e in enumerate(_single(problem)):
            s_ev = {S[i]: ("yes" if e[i] else "no") for i in range(problem.n)}
            assert_close(p_evidence(g, with_map({**s_ev, **alpha}, m)), p_evidence(g, s_ev),
                         what="(F5) p(g|s,α,o_M) = p(g|s)")
        f5 += p_s_ao * p_o_za[m]  # Σ_M p(s|α,o_M) p(o_M|z,α)
    assert_close(f1, target, what="(F1) total probability")
    assert_close(normalised(f3), target, what="(F2)-(F3)")
    p_s_za = table(b, S, {**z, **alpha})
    assert_close(f8, p_s_za, what="(F8) Σ_M p(s|z,α,o_M) p(o_M|z,α) = p(s|z,α)")
    assert_close(f5, f8, what="(F8) same sum with p(s|α,o_M)")

    single = _single(problem)
    g_lik = np.array([p_evidence(g, {S[i]: ("yes" if e[i] else "no") for i in range(problem.n)}) for e in single])
    assert_close(normalised(g_lik * np.array([f5[e] for e in single])), np.array([target[e] for e in single]),
                 what="(F5) p(s_c|g,z,α) ∝ p(g|s_c) Σ_M p(s_c|α,o_M) p(o_M|z,α)")
    # (F9): p(z, α | s) = p(z | s) p(α | s) for every configuration s
    for e in itertools.product((0, 1), repeat=problem.n):
        s_ev = {S[i]: ("yes" if e[i] else "no") for i in range(problem.n)}
        za = table(b, sorted(z) + ["alpha"], s_ev)[(0,) * len(z) + (1,)]  # p(z, α = true | s)
        assert_close(za, p_evidence(z, s_ev) * table(b, ["alpha"], s_ev)[1], what="(F9) Z ⟂ α | S")

    # (F10) eq. (11), with the olfactory and semantic posteriors over the cells (α given)
    post = np.array([target[e] for e in single])
    p_s_g = np.array([table(b, S, {**g, **alpha})[e] for e in single])  # p(s_c | g, α)
    p_s_z = np.array([p_s_za[e] for e in single])  # p(s_c | z, α)
    prior = np.array([table(b, S, alpha)[e] for e in single])  # p(s_c | α)
    assert_close(prior, problem.source_prior, what="p(s_c | α) is the source prior")
    assert_close(normalised(p_s_g * p_s_z / prior), post, what="(F10) general form ÷ p(s)")
    product = normalised(p_s_g * p_s_z)
    if uniform:
        assert_close(product, post, what="(F10) eq. (11) (uniform prior)")
    else:  # the uniform-prior assumption (F7) matters: the plain product is off
        assert np.max(np.abs(product / post - 1)) > 1e-3
