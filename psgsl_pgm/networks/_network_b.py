"""Network B (paper Fig. ``Bayes_net``B): binary S_i per cell plus the exactly-one constraint α."""

from __future__ import annotations

import numpy as np
from pgmpy.factors.discrete import TabularCPD
from pgmpy.models import DiscreteBayesianNetwork

from ..core._problem import SemanticGSLProblem
from ._cpds import assemble, evidence_cpd, root_cpd
from ._names import (
    ALPHA,
    ALPHA_STATES,
    COUNTER_STATES,
    GAMMA,
    SOURCE_STATES,
    counter_node,
    object_node,
    olfactory_node,
    source_node,
)
from ._network_a import _check_problem, gas_nodes, object_evidence

__all__ = ["MAX_TABLE_CELLS", "build_network_b", "source_bernoulli"]

#: Largest n for the "table" encoding (its CPD for α has 2^n columns).
MAX_TABLE_CELLS = 20


def source_bernoulli(problem: SemanticGSLProblem) -> np.ndarray:
    """(n,) p(S_i = yes) = π_i / (π_i + max π): the odds p_i / (1 − p_i) = π_i / max π.

    On a single-source configuration s_c, Π_i p(S_i) = p_c Π_{i≠c} (1 − p_i) = [Π_i (1 − p_i)] π_c / max π,
    i.e. ∝ π_c: the binary priors reproduce the source prior once α restricts S to one source.
    """
    pi = problem.source_prior
    return pi / (pi + pi.max())


def _counter_cpd(cell: str, prev: str | None, s_node: str) -> TabularCPD:
    """C_i = min(2, C_{i-1} + S_i) (deterministic; C_1 = S_1)."""
    node = counter_node(cell)
    s_states = list(SOURCE_STATES)
    if prev is None:
        values = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])  # C_1 = S_1
        return TabularCPD(node, 3, values, evidence=[s_node], evidence_card=[2],
                          state_names={node: list(COUNTER_STATES), s_node: s_states})
    values = np.zeros((3, 3, 2))  # [C_i, C_{i-1}, S_i]
    count = np.minimum(2, np.arange(3)[:, None] + np.arange(2)[None, :])  # min(2, C_{i-1} + S_i)
    values[count, np.arange(3)[:, None], np.arange(2)[None, :]] = 1.0
    return TabularCPD(node, 3, values.reshape(3, 6), evidence=[prev, s_node], evidence_card=[3, 2],
                      state_names={node: list(COUNTER_STATES), prev: list(COUNTER_STATES), s_node: s_states})


def _table_alpha(s_nodes: list[str]) -> TabularCPD:
    """p(α = true | s) = 1 iff exactly one S_i = yes: the textbook constraint CPD, 2^n columns."""
    n = len(s_nodes)
    configs = (np.arange(2**n)[:, None] >> np.arange(n - 1, -1, -1)[None, :]) & 1  # column j ↔ bits of j (S_1 first)
    valid = (configs.sum(axis=1) == 1).astype(np.float64)  # exactly one source
    return TabularCPD(ALPHA, 2, np.vstack([1.0 - valid, valid]), evidence=s_nodes, evidence_card=[2] * n,
                      state_names={ALPHA: list(ALPHA_STATES), **{s: list(SOURCE_STATES) for s in s_nodes}})


def build_network_b(problem: SemanticGSLProblem, constraint: str = "chain") -> DiscreteBayesianNetwork:
    """Network B: binary S_i; O_i | S_i (, γ); Z | O_i; G_i | S_i; the exactly-one constraint α.

    CPDs: p(S_i = yes) = :func:`source_bernoulli` (odds ∝ π_i); p(O_i | S_i = yes, γ) = L_γ,
    p(O_i | S_i = no) = β; Z_ij | O_i as in Network A; G_i | S_i a binary evidence child with
    p(observed | yes) / p(observed | no) = p(g | i) / max p(g), which reproduces p(g | s_c) on every
    single-source configuration. α = true iff exactly one S_i = yes, encoded as

    * ``"chain"``: counters C_i = min(2, C_{i−1} + S_i) and α | C_n (α ≡ C_n = one) — linear size;
    * ``"table"``: α | S_1 … S_n, the CPD with 2^n columns (n ≤ :data:`MAX_TABLE_CELLS`).

    The evidence is every Z, G_i and ζ = ``"observed"`` and α = ``"true"`` (see :func:`network_evidence`).

    Parameters
    ----------
    problem : SemanticGSLProblem
    constraint : {"chain", "table"}, default "chain"

    Returns
    -------
    pgmpy.models.DiscreteBayesianNetwork

    Raises
    ------
    ValueError
        An unknown ``constraint``, or ``"table"`` with n > 20 cells.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, build_network_b
    >>> model = build_network_b(SemanticGSLProblem.random(np.random.default_rng(0), 3, 2))
    >>> model.get_parents("alpha"), sorted(model.get_parents("C_c2"))
    (['C_c2'], ['C_c1', 'S_c2'])
    """
    _check_problem(problem)
    if constraint not in ("chain", "table"):
        raise ValueError(f"constraint must be 'chain' or 'table', got {constraint!r}")
    n, k, m = problem.n, problem.k, problem.m
    if constraint == "table" and n > MAX_TABLE_CELLS:
        raise ValueError(
            f"constraint='table' needs a CPD with 2^n = 2^{n} columns for α; it is refused for n > "
            f"{MAX_TABLE_CELLS} cells (got n = {n}): use constraint='chain' (linear size, same posteriors)"
        )
    cells, classes = list(problem.cell_names), list(problem.class_names)
    edges, cpds = gas_nodes(problem)
    p_source = source_bernoulli(problem)
    s_nodes = [source_node(c) for c in cells]
    for i in range(n):
        s_node, o_node = s_nodes[i], object_node(cells[i])
        cpds.append(root_cpd(s_node, SOURCE_STATES, np.array([1.0 - p_source[i], p_source[i]])))  # p(S_i)
        g_node = olfactory_node(cells[i])
        edges.append((s_node, g_node))
        g_ratio = np.array([1.0, problem.olfactory_likelihood[i] / problem.olfactory_likelihood.max()])
        cpds.append(evidence_cpd(g_node, s_node, SOURCE_STATES, g_ratio))  # p(G_i | S_i): ratio p(g|i)/max
        table = np.empty((k, 2, m))
        table[:, 0, :] = problem.background[:, None]  # p(O_i | S_i = no) = β
        table[:, 1, :] = problem.source_likelihood.T  # p(O_i | S_i = yes, γ) = L_γ
        parents = [s_node] if m == 1 else [s_node, GAMMA]
        edges.extend((p, o_node) for p in parents)
        state_names = {o_node: classes, s_node: list(SOURCE_STATES)}
        if m > 1:
            state_names[GAMMA] = list(problem.gas_names)
        cpds.append(TabularCPD(o_node, k, table.reshape(k, 2 * m), evidence=parents,
                               evidence_card=[2, m][: len(parents)], state_names=state_names))
        z_edges, z_cpds = object_evidence(problem, i)
        edges.extend(z_edges)
        cpds.extend(z_cpds)
    if constraint == "chain":
        prev = None
        for i in range(n):
            node = counter_node(cells[i])
            edges.extend([(s_nodes[i], node)] + ([(prev, node)] if prev else []))
            cpds.append(_counter_cpd(cells[i], prev, s_nodes[i]))
            prev = node
        edges.append((prev, ALPHA))
        alpha = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 0.0]])  # α = true iff C_n = one
        cpds.append(TabularCPD(ALPHA, 2, alpha, evidence=[prev], evidence_card=[3],
                               state_names={ALPHA: list(ALPHA_STATES), prev: list(COUNTER_STATES)}))
    else:
        edges.extend((s, ALPHA) for s in s_nodes)
        cpds.append(_table_alpha(s_nodes))
    return assemble(cpds, edges)
