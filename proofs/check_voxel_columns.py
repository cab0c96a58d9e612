r"""Sec. "Voxelized Scene Representations": a 2-D cell is a vertical column of voxels.

(V1) p(s_c | z) = Σ_{v ∈ c} p(s_v | z)
     S ranges over voxels; "the source is in column c" is the disjoint union of {S = v}, v ∈ c — exact.
     Checked with a deterministic child K = column(S) added to Network A: pgmpy's p(K | z) equals the
     voxel sum and the core's ``semantic_source_probability(..., column_axis=2, source_prior=...)``.
(V2) each p(s_v | z) is eq. (20) over voxels (exact with p(o) := β).
(V3) fusion with a 2-D olfactory method: when p(g | v) = p(g | column of v),
     p(s_c | g, z) ∝ p(s_c | g) p(s_c | z) / p(s_c) over columns — exact.
(V4) when p(g | v) varies inside a column (a 3-D olfactory model), fusing the column sums is not exact —
     fuse per voxel first, then sum. The gap is measured (non-zero).                         APPROXIMATE
"""

from __future__ import annotations

import numpy as np
from _kit import assert_close, normalised, table
from pgmpy.factors.discrete import TabularCPD

from psgsl_pgm import fuse, semantic_source_probability
from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, network_evidence

SHAPE = (2, 3, 3)  # 6 columns × 3 heights = 18 voxels


def _with_column_node(problem):
    """Network A over voxels plus K = column(S), a deterministic child of S."""
    model = build_network_a(problem)
    columns = [f"col{i}" for i in range(SHAPE[0] * SHAPE[1])]
    column_of = np.arange(problem.n) // SHAPE[2]  # C-order voxels: the last axis is the height
    values = (column_of[None, :] == np.arange(len(columns))[:, None]).astype(float)
    model.add_node("K")
    model.add_edge("S", "K")
    model.add_cpds(TabularCPD("K", len(columns), values, evidence=["S"], evidence_card=[problem.n],
                              state_names={"K": columns, "S": list(problem.cell_names)}))
    model.check_model()
    return model


def _problem(olfactory):
    base = SemanticGSLProblem.random(np.random.default_rng(31), int(np.prod(SHAPE)), 4, m=2, max_observations=2,
                                     shape=SHAPE)
    return SemanticGSLProblem(
        base.source_likelihood, base.background, cells=base.n, observation_cells=base.observation_cells,
        observation_likelihoods=base.observation_likelihoods, olfactory_likelihood=olfactory,
        source_prior=base.source_prior, gas_prior=base.gas_prior, gas_observations=base.gas_observations,
        shape=SHAPE)


def test_v1_v2_column_sum_semantics_only():
    problem = _problem(None)
    model = _with_column_node(problem)
    evidence = {v: s for v, s in network_evidence(model).items() if v != "G"}
    voxel = table(model, ["S"], evidence).reshape(SHAPE)
    column = table(model, ["K"], evidence).reshape(SHAPE[:2])
    assert_close(column, voxel.sum(axis=2), what="(V1) p(s_c|z) = Σ_{v∈c} p(s_v|z)")
    q = problem.class_probs().reshape(*SHAPE, problem.k)
    prior = problem.source_prior.reshape(SHAPE)
    kwargs = dict(gas_probs=problem.gas_probs(), source_prior=prior)
    core_voxel = semantic_source_probability(q, problem.source_likelihood, problem.background, **kwargs)
    core_column = semantic_source_probability(q, problem.source_likelihood, problem.background, column_axis=2,
                                              **kwargs)
    assert_close(core_voxel, voxel, what="(V2) eq. (20) per voxel")
    assert_close(core_column, column, what="(V1) core column_axis")


def test_v3_fusion_with_column_olfaction_is_exact():
    g_column = np.random.default_rng(32).uniform(0.05, 1.0, size=SHAPE[:2])
    problem = _problem(np.repeat(g_column.ravel(), SHAPE[2]))
    model = _with_column_node(problem)
    column = table(model, ["K"], network_evidence(model)).reshape(SHAPE[:2])
    prior_c = problem.source_prior.reshape(SHAPE).sum(axis=2)
    semantic_c = table(model, ["K"], {v: s for v, s in network_evidence(model).items() if v != "G"})
    olfactory_c = normalised(prior_c * g_column)  # p(s_c | g)
    assert_close(fuse(olfactory_c, semantic_c.reshape(SHAPE[:2]), prior=prior_c), column,
                 what="(V3) column fusion exact")


def test_v4_fusion_with_voxel_olfaction_needs_voxels():
    g_voxel = np.random.default_rng(33).uniform(0.05, 1.0, size=SHAPE)
    problem = _problem(g_voxel.ravel())
    model = _with_column_node(problem)
    evidence = network_evidence(model)
    column = table(model, ["K"], evidence).reshape(SHAPE[:2])
    voxel_fused = table(model, ["S"], evidence).reshape(SHAPE).sum(axis=2)
    assert_close(voxel_fused, column, what="fuse per voxel, then sum: exact")
    assert_close(problem.closed_form_posterior().reshape(SHAPE).sum(axis=2), column, what="closed form per voxel")
    prior_v = problem.source_prior.reshape(SHAPE)
    prior_c = prior_v.sum(axis=2)
    olfactory_c = (prior_v * g_voxel).sum(axis=2)
    semantic_c = table(model, ["K"], {v: s for v, s in evidence.items() if v != "G"}).reshape(SHAPE[:2])
    column_fused = fuse(normalised(olfactory_c), semantic_c, prior=prior_c)
    gap = np.max(np.abs(column_fused / column - 1))
    assert gap > 1e-3  # (V4) fusing column sums is only an approximation here
