"""Sources off the ontology (``Ontology.source_likelihood(off_ontology=ε)``) against pgmpy's exact inference in a
network that holds the on/off choice as a node of its own: S → O_c ← Ω, p(Ω = off) = ε, O_c | S = c, Ω = on ~
p(o | s) and ~ β otherwise, each cell's observations and the gas reading as evidence nodes. The closed form with
the mixed likelihood agrees to 1e-10 relative per cell."""

from __future__ import annotations

import numpy as np
import pytest
from pgmpy.factors.discrete import TabularCPD
from pgmpy.inference import VariableElimination

from psgsl_pgm import Ontology, fuse, semantic_source_probability, update_class_probs
from psgsl_pgm.networks._cpds import assemble, evidence_cpd, root_cpd

RTOL = 1e-10


def _network(pi, omega, L, beta, cell_lik, g):
    n, k = cell_lik.shape
    cells = [f"c{c}" for c in range(n)]
    classes = [f"o{i}" for i in range(k)]
    cpds = [root_cpd("S", cells, pi), root_cpd("Omega", ["on", "off"], [1.0 - omega, omega])]
    edges = []
    for c in range(n):
        cols = [L if (s == c and w == 0) else beta for s in range(n) for w in range(2)]  # Ω varies fastest
        cpds.append(TabularCPD(f"O_{c}", k, np.column_stack(cols), evidence=["S", "Omega"], evidence_card=[n, 2],
                               state_names={f"O_{c}": classes, "S": cells, "Omega": ["on", "off"]}))
        cpds.append(evidence_cpd(f"Z_{c}", f"O_{c}", classes, cell_lik[c]))
        edges += [("S", f"O_{c}"), ("Omega", f"O_{c}"), (f"O_{c}", f"Z_{c}")]
    cpds.append(evidence_cpd("G", "S", cells, g))
    edges.append(("S", "G"))
    return assemble(cpds, edges)  # pgmpy's check_model and the strict CPD sums


@pytest.mark.parametrize("seed", range(12))
def test_off_ontology_closed_form_equals_pgmpy_with_an_on_off_node(seed):
    rng = np.random.default_rng(7000 + seed)
    n, k = int(rng.integers(2, 6)), int(rng.integers(2, 5))
    omega = (0.0, 1.0, float(rng.uniform(0.02, 0.98)))[seed % 3]
    L = rng.dirichlet(np.ones(k))
    L[rng.integers(k - 1)] = 0.0  # a class that never emits
    L /= L.sum()
    beta = rng.dirichlet(np.ones(k)) * 0.9 + 0.1 / k
    cell_lik = rng.random((n, k)) ** 2 + 1e-3  # p(z_c | o): each cell's observations
    g = rng.random(n) + 0.05  # p(g | S = c)
    pi = rng.dirichlet(np.full(n, 2.0))

    model = _network(pi, omega, L, beta, cell_lik, g)
    evidence = {f"Z_{c}": "observed" for c in range(n)} | {"G": "observed"}
    factor = VariableElimination(model).query(["S"], evidence=evidence, show_progress=False)
    exact = np.array([factor.get_value(S=f"c{c}") for c in range(n)])
    assert np.isfinite(exact).all() and exact.sum() > 0  # pgmpy gives NaN on underflow

    ontology = Ontology([f"o{i}" for i in range(k - 1)] + ["other"], ["gas"], L[None], class_prior=beta)
    q = update_class_probs(np.broadcast_to(beta, (n, k)), cell_lik)  # p(o_c | z_c) under β
    semantic = semantic_source_probability(q, ontology.source_likelihood("gas", off_ontology=omega), beta,
                                           source_prior=pi)
    closed = fuse(pi * g / (pi @ g), semantic, prior=pi)  # p(s | g, z) ∝ p(s | g) p(s | z) / p(s)
    np.testing.assert_allclose(closed, exact / exact.sum(), rtol=RTOL, atol=0)
