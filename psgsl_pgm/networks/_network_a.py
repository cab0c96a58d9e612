"""Network A (paper Fig. ``Bayes_net``A): one discrete source variable S over the n cells."""

from __future__ import annotations

import numpy as np
from pgmpy.factors.discrete import TabularCPD
from pgmpy.models import DiscreteBayesianNetwork

from ..core._problem import SemanticGSLProblem
from ._cpds import assemble, evidence_cpd, root_cpd
from ._names import G_NODE, GAMMA, SOURCE, object_node, observation_node, zeta_node

__all__ = ["build_network_a", "gas_nodes"]


def _check_problem(problem) -> None:
    if not isinstance(problem, SemanticGSLProblem):
        raise TypeError(f"problem must be a SemanticGSLProblem, got {type(problem).__name__}")


def gas_nodes(problem: SemanticGSLProblem) -> tuple[list[tuple[str, str]], list[TabularCPD]]:
    """Edges and CPDs of γ and its classifier observations ζ_j (empty when m = 1)."""
    if problem.m == 1:
        return [], []
    edges, cpds = [], [root_cpd(GAMMA, problem.gas_names, problem.gas_prior)]  # p(γ)
    for j, zeta in enumerate(problem.gas_observations):
        edges.append((GAMMA, zeta_node(j)))
        cpds.append(evidence_cpd(zeta_node(j), GAMMA, problem.gas_names, zeta))  # p(ζ_j | γ)
    return edges, cpds


def object_evidence(problem: SemanticGSLProblem, c: int) -> tuple[list[tuple[str, str]], list[TabularCPD]]:
    """Edges and CPDs of the observations Z_cj of cell index ``c`` (children of O_c)."""
    cell, o_node = problem.cell_names[c], object_node(problem.cell_names[c])
    edges, cpds = [], []
    for j, lik in enumerate(problem.observations_of(c)):
        z = observation_node(cell, j)
        edges.append((o_node, z))
        cpds.append(evidence_cpd(z, o_node, problem.class_names, lik))  # p(z_cj | o_c)
    return edges, cpds


def build_network_a(problem: SemanticGSLProblem) -> DiscreteBayesianNetwork:
    """Network A: S over cells; O_c | S (, γ); Z | O_c; G | S; with m > 1, γ → O_c and γ → ζ_j.

    CPDs: p(S = c) = ``source_prior``; p(O_c | S = c, γ) = L_γ, p(O_c | S ≠ c) = β; each observation Z_cj is
    a binary child of O_c with p(observed | o) ∝ p(z_cj | o); G is a binary child of S with
    p(observed | S = c) ∝ p(g | c). Evidence likelihoods are scaled to a maximum of 1. The evidence is
    every Z, G and ζ node = ``"observed"`` (see :func:`network_evidence`).

    Parameters
    ----------
    problem : SemanticGSLProblem

    Returns
    -------
    pgmpy.models.DiscreteBayesianNetwork
        Checked by pgmpy's ``check_model`` and by :func:`check_normalised`. State names: cell names for S,
        class names for O_c, gas names for γ.

    Raises
    ------
    TypeError
        ``problem`` is not a :class:`SemanticGSLProblem`.
    ValueError
        A CPD fails :func:`check_normalised` or pgmpy's ``check_model``.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, build_network_a
    >>> model = build_network_a(SemanticGSLProblem.random(np.random.default_rng(0), 4, 3))
    >>> sorted(model.get_children("S"))
    ['G', 'O_c0', 'O_c1', 'O_c2', 'O_c3']
    """
    _check_problem(problem)
    n, k, m = problem.n, problem.k, problem.m
    cells, classes = list(problem.cell_names), list(problem.class_names)
    edges, cpds = gas_nodes(problem)
    cpds.append(root_cpd(SOURCE, cells, problem.source_prior))  # p(S)
    edges.append((SOURCE, G_NODE))
    cpds.append(evidence_cpd(G_NODE, SOURCE, cells, problem.olfactory_likelihood))  # p(g | S)
    parents = [SOURCE] if m == 1 else [SOURCE, GAMMA]
    for c in range(n):
        o_node = object_node(cells[c])
        table = np.broadcast_to(problem.background[:, None, None], (k, n, m)).copy()  # p(O_c | S ≠ c) = β
        table[:, c, :] = problem.source_likelihood.T  # p(O_c | S = c, γ) = L_γ
        edges.extend((p, o_node) for p in parents)
        state_names = {o_node: classes, SOURCE: cells}
        if m > 1:
            state_names[GAMMA] = list(problem.gas_names)
        cpds.append(
            TabularCPD(o_node, k, table.reshape(k, n * m), evidence=parents, evidence_card=[n, m][: len(parents)],
                       state_names=state_names)
        )
        z_edges, z_cpds = object_evidence(problem, c)
        edges.extend(z_edges)
        cpds.extend(z_cpds)
    return assemble(cpds, edges)
