"""CPD helpers shared by both networks: evidence nodes, the ontology node, the strict normalisation check and the
assembly of a checked network."""

from __future__ import annotations

import numpy as np
from pgmpy.factors.discrete import TabularCPD
from pgmpy.models import DiscreteBayesianNetwork

from ._names import EVIDENCE_STATES

__all__ = ["assemble", "check_normalised", "evidence_cpd", "root_cpd", "scaled"]

_STRICT_ATOL = 1e-12


def scaled(likelihood: np.ndarray) -> np.ndarray:
    """``likelihood / max(likelihood)`` along the last axis: a valid p(observed | parent) ≤ 1.

    Posteriors are invariant to a constant factor on a likelihood; scaling the largest entry to 1 keeps
    products of many evidence terms as far from underflow as a CPD allows.
    """
    return likelihood / likelihood.max(axis=-1, keepdims=True)


def evidence_cpd(node: str, parent: str, parent_states, likelihood: np.ndarray) -> TabularCPD:
    """Binary evidence node ``node`` | ``parent`` with p(observed | parent) = scaled ``likelihood``.

    Parameters
    ----------
    node, parent : str
        Node names.
    parent_states : sequence of str
        The parent's state names (length r).
    likelihood : (r,) ndarray
        p(evidence | parent state), any positive scale.

    Returns
    -------
    TabularCPD
        States ``("observed", "other")``; the evidence is ``observed``.
    """
    p = scaled(np.asarray(likelihood, dtype=np.float64))  # p(observed | parent) ≤ 1
    return TabularCPD(
        node,
        2,
        np.vstack([p, 1.0 - p]),
        evidence=[parent],
        evidence_card=[len(parent_states)],
        state_names={node: list(EVIDENCE_STATES), parent: list(parent_states)},
    )


def root_cpd(node: str, states, probs: np.ndarray) -> TabularCPD:
    """Root node with prior ``probs`` over ``states``."""
    return TabularCPD(node, len(states), np.asarray(probs, dtype=np.float64)[:, None], state_names={node: list(states)})


def check_normalised(model, *, atol: float = _STRICT_ATOL) -> bool:
    """Strict CPD check: every entry finite and in [0, 1], every column summing to 1 within ``atol``.

    pgmpy's ``check_model`` only checks sums to 0.01; this is the check the exports and tests rely on.

    Parameters
    ----------
    model : pgmpy.models.DiscreteBayesianNetwork
    atol : float, default 1e-12

    Returns
    -------
    bool
        True (raises otherwise).

    Raises
    ------
    ValueError
        Naming the first node whose CPD is missing, non-finite, out of [0, 1] or not normalised.

    Examples
    --------
    >>> import numpy as np
    >>> from psgsl_pgm.networks import SemanticGSLProblem, build_network_a, check_normalised
    >>> model = build_network_a(SemanticGSLProblem.random(np.random.default_rng(0), 4, 3))
    >>> check_normalised(model)
    True
    >>> cpd = model.get_cpds("S")
    >>> cpd.values[0] += 1e-6                                  # a column no longer sums to 1
    >>> try:
    ...     check_normalised(model)
    ... except ValueError as err:
    ...     print(str(err).startswith("CPD of 'S' has a column summing to 1"))
    True
    """
    for node in sorted(model.nodes()):
        cpd = model.get_cpds(node)
        if cpd is None:
            raise ValueError(f"node {node!r} has no CPD")
        values = cpd.get_values()  # (card, columns)
        if not np.all(np.isfinite(values)):
            raise ValueError(f"CPD of {node!r} has NaN or inf entries")
        if values.min() < 0.0 or values.max() > 1.0:
            raise ValueError(f"CPD of {node!r} has entries outside [0, 1]: [{values.min()}, {values.max()}]")
        error = np.abs(values.sum(axis=0) - 1.0).max()
        if error > atol:
            raise ValueError(f"CPD of {node!r} has a column summing to 1 ± {error:.3g}, more than atol = {atol:g}")
    return True


def assemble(cpds, edges) -> DiscreteBayesianNetwork:
    """The network of ``cpds`` (one per node, in that order) and ``edges``, checked by pgmpy's ``check_model`` and
    by :func:`check_normalised`."""
    model = DiscreteBayesianNetwork()
    model.add_nodes_from(cpd.variable for cpd in cpds)
    model.add_edges_from(edges)
    model.add_cpds(*cpds)
    model.check_model()
    check_normalised(model)
    return model
